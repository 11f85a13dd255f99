"""Reading YAML documents: a safe loader (duplicate keys refused, alias expansion
bounded) and a validator whose every error is a :class:`~gfuzzy.errors.SceneError`
naming the file and the place in it. The scene file (:mod:`gfuzzy.scene.scene`) and the
files made from pedestrian tracks (:mod:`gfuzzy.scene.tracks`) are read with them.
"""

from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from ..errors import SceneError
from ..settings import MAX_MAGNITUDE

#: Names of scenes, movers and queries: letters, digits, ``_ . -``.
NAME_RE = re.compile(r"^[A-Za-z0-9_.-]+$")


def name_from_stem(stem: str, fallback: str) -> str:
    """A scene name made from a file's stem: each run of characters a name cannot hold
    (spaces, non-ASCII letters, ...) becomes ``-`` (``my map`` -> ``my-map``); ``fallback``
    when nothing is left."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", stem).strip("-") or fallback
#: Largest number of YAML nodes a scene may expand to (aliases counted each time used).
MAX_NODES = 2_000_000


# --------------------------------------------------------------------------- YAML


class _Loader(yaml.SafeLoader):
    """safe_load, plus: duplicate keys are errors and alias expansion is bounded."""


def _construct_mapping(loader: _Loader, node: yaml.MappingNode, deep: bool = False) -> dict:
    seen = set()
    for key_node, _ in node.value:
        if key_node.tag == "tag:yaml.org,2002:merge":
            continue  # `<<` merges: explicit keys may override merged ones
        key = loader.construct_object(key_node, deep=True)
        try:
            hashable = key in seen
        except TypeError as exc:
            raise yaml.constructor.ConstructorError(
                None, None, "unhashable mapping key", key_node.start_mark
            ) from exc
        if hashable:
            raise yaml.constructor.ConstructorError(
                None, None, f"duplicate key {key!r}", key_node.start_mark
            )
        seen.add(key)
    return loader.construct_mapping(node, deep=deep)


_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)
# YAML 1.1 (PyYAML) reads `1e-3`, `5e3` and `1.5e3` as strings: its floats need a dot and a
# signed exponent. YAML 1.2 (yaml-language-server, the schema's editors; yaml-cpp, which
# Nav2 reads map files with) and JSON read them as numbers, and so do we.
_EXPONENT_FLOAT = re.compile(r"^[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)[eE][-+]?[0-9]+$")
_Loader.add_implicit_resolver("tag:yaml.org,2002:float", _EXPONENT_FLOAT, list("-+.0123456789"))


class _Dumper(yaml.SafeDumper):
    """safe_dump that quotes a string the loader would read as a number (``"1e3"``)."""


_Dumper.add_implicit_resolver("tag:yaml.org,2002:float", _EXPONENT_FLOAT, list("-+.0123456789"))


def dump_yaml(data, **kwargs) -> str:
    """``yaml.safe_dump(data, **kwargs)`` whose every string reads back as a string here."""
    return yaml.dump(data, Dumper=_Dumper, **kwargs)


def _expanded_size(node: yaml.Node, memo: dict) -> int:
    key = id(node)
    if key in memo:
        if memo[key] < 0:
            raise ValueError("recursive YAML alias")
        return memo[key]
    memo[key] = -1
    if isinstance(node, yaml.SequenceNode):
        size = 1 + sum(_expanded_size(n, memo) for n in node.value)
    elif isinstance(node, yaml.MappingNode):
        size = 1 + sum(_expanded_size(k, memo) + _expanded_size(v, memo) for k, v in node.value)
    else:
        size = 1
    memo[key] = size
    return size


def _load_yaml(text: str, file: str) -> Any:
    loader = None
    try:
        loader = _Loader(text)
        node = loader.get_single_node()
        if node is None:
            raise SceneError(file, "", "the file is empty")
        size = _expanded_size(node, {})
        if size > MAX_NODES:
            raise SceneError(
                file, "", f"YAML expands to {size} nodes (aliases), more than {MAX_NODES}"
            )
        return loader.construct_document(node)
    except SceneError:
        raise
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        what = exc.problem or exc.context or "invalid YAML"
        raise SceneError(file, where, f"invalid YAML: {what}") from None
    except (yaml.YAMLError, ValueError, RecursionError) as exc:
        raise SceneError(file, "", f"invalid YAML: {exc}") from None
    finally:
        if loader is not None:
            loader.dispose()


#: How deep a scene document may nest (a scene needs a handful of levels): one built in code
#: that nests deeper, or contains itself, is refused here, not with a RecursionError.
MAX_DEPTH = 100


def plain_document(doc: Any, file: str = "<string>") -> Any:
    """``doc`` as YAML would have given it, for a scene built in code: tuples and numpy arrays
    as lists, numpy numbers and booleans as Python's (``np.int64(2)`` -> 2); anything else
    as it is, for the validator to judge.

    Raises
    ------
    SceneError
        Lists or mappings nested over ``MAX_DEPTH`` levels (naming the top-level key).
    """
    place = "top level"
    try:
        if isinstance(doc, dict):
            out = {}
            for place, value in doc.items():  # the top-level key, for the message
                out[place] = _plain(value, MAX_DEPTH - 1)
            return out
        return _plain(doc, MAX_DEPTH)
    except _TooDeep:
        raise SceneError(file, str(place), f"nested over {MAX_DEPTH} levels deep (a list or mapping that holds itself?)") from None


class _TooDeep(Exception):
    pass


def _plain(doc: Any, left: int) -> Any:
    if left <= 0 and isinstance(doc, (dict, list, tuple, np.ndarray)):
        raise _TooDeep
    if isinstance(doc, dict):
        return {k: _plain(v, left - 1) for k, v in doc.items()}
    if isinstance(doc, (list, tuple)):
        return [_plain(v, left - 1) for v in doc]
    if isinstance(doc, (np.ndarray, np.generic)):
        return doc.tolist()
    return doc


def plain_name(name: str, flow: bool = False) -> str:
    """``name`` as a YAML scalar that reads back as that string: plain when it does, else
    double-quoted (a scene written for ``12.yaml``, ``true.yaml`` or ``1e3.yaml`` had the
    name 12, True or 1000.0, and was refused as it was written). With ``flow``, plain only
    when it also reads back inside a flow collection (``{file: NAME}``), where ``,``,
    ``[]`` and ``{}`` end a plain scalar."""
    try:
        plain = _load_yaml(f"{name}\n", "<name>") == name
        if plain and flow:
            plain = _load_yaml(f"[{name}]\n", "<name>") == [name]
    except SceneError:
        plain = False
    return name if plain else json.dumps(name)


# --------------------------------------------------------------------------- validation


class _V:
    """Validation helpers bound to one file."""

    def __init__(self, file: str):
        self.file = file

    def fail(self, place: str, message: str):
        raise SceneError(self.file, place, message)

    def mapping(self, value, place, required=(), optional=()):
        if not isinstance(value, dict):
            self.fail(place or "top level", f"expected a mapping, got {_kind(value)}")
        for key in value:
            if not isinstance(key, str):
                self.fail(place or "top level", f"key {key!r} is not a string")
            if key not in required and key not in optional:
                allowed = ", ".join(list(required) + list(optional))
                self.fail(_join(place, key), f"unknown key (allowed: {allowed})")
        for key in required:
            if key not in value:
                self.fail(_join(place, key), "missing required key")
        return value

    def number(self, value, place, positive=False, nonneg=False):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(place, f"expected a number, got {_kind(value)}")
        try:
            value = float(value)
        except OverflowError:
            self.fail(place, "number too large")
        if not math.isfinite(value):
            self.fail(place, f"expected a finite number, got {value}")
        if abs(value) > MAX_MAGNITUDE:
            self.fail(place, f"number too large ({value:g}; at most {MAX_MAGNITUDE:g} in magnitude)")
        if positive and value <= 0:
            self.fail(place, f"must be positive, got {value:g}")
        if nonneg and value < 0:
            self.fail(place, f"must not be negative, got {value:g}")
        return value

    def vector(self, value, place, length, positive=False, words=""):
        """A list of ``length`` numbers; ``words`` (a pose's: :func:`gfuzzy.poses.pose_words`)
        say in the message what they hold."""
        words = f" {words}" if words else ""
        if not isinstance(value, list):
            self.fail(place, f"expected a list of {length} numbers{words}, got {_kind(value)}")
        if len(value) != length:
            self.fail(place, f"expected {length} numbers{words}, got {len(value)}")
        return tuple(
            self.number(v, f"{place}[{i}]", positive=positive) for i, v in enumerate(value)
        )

    def points(self, value, place, width=2, min_rows=1):
        if not isinstance(value, list):
            self.fail(place, f"expected a list of points, got {_kind(value)}")
        if len(value) < min_rows:
            self.fail(place, f"expected at least {min_rows} rows, got {len(value)}")
        rows = [self.vector(v, f"{place}[{i}]", width) for i, v in enumerate(value)]
        return np.array(rows, dtype=float).reshape(-1, width)

    def timed_rows(self, value, place, mover: str):
        """A mover's ``[t, x, y]`` rows (at least one): t strictly increasing, and no faster
        from row to row than ``MAX_MAGNITUDE`` m/s, the bound of every number in a scene (a
        path mover's ``speed`` included). Rows closer in time than that (1e-300 s apart, say)
        are a jump, not a motion: the planner's bound on where a mover is within a time step
        (its speed times half a step) would cover the whole scene, and a query would be
        answered as if the mover stood next to the start."""
        tr = self.points(value, place, 3, min_rows=1)
        gap = np.diff(tr[:, 0])
        bad = np.nonzero(gap <= 0)[0]
        if bad.size:
            j = int(bad[0]) + 1
            self.fail(f"{place}[{j}][0]", f"time {tr[j, 0]:g} does not increase (previous row has {tr[j - 1, 0]:g})")
        moved = np.hypot(*np.diff(tr[:, 1:], axis=0).T)
        fast = np.nonzero(moved > MAX_MAGNITUDE * gap)[0]  # both bounded by the scene's numbers: no overflow
        if fast.size:
            j = int(fast[0]) + 1
            self.fail(
                f"{place}[{j}]",
                f"mover {mover!r} moves {moved[j - 1]:g} m in {gap[j - 1]:g} s from the previous row (t={float(tr[j - 1, 0])!r} "
                f"to {float(tr[j, 0])!r}): faster than {MAX_MAGNITUDE:g} m/s, a jump rather than a motion (rows too close in time?)",
            )
        return tr

    def name(self, value, place, pattern=None):
        if not isinstance(value, str) or not value.strip():
            hint = "; quote a name that reads as a number or a boolean (name: '2e3')" if isinstance(
                value, (int, float, bool)) else ""  # fmt: skip
            self.fail(place, f"expected a non-empty string, got {_kind(value)}{hint}")
        if pattern is not None and not pattern.match(value):
            self.fail(place, f"{value!r} must match [a-zA-Z0-9_.-]+")
        if any(ord(c) < 32 for c in value):
            self.fail(place, "control characters are not allowed")
        return value


def _kind(value) -> str:
    if value is None:
        return "nothing"
    if isinstance(value, bool):
        return f"a boolean ({value})"
    if isinstance(value, (int, float)):
        return f"a number ({value})"
    if isinstance(value, str):
        return f"a string ({value[:30]!r})"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, dict):
        return "a mapping"
    return type(value).__name__


def _join(place: str, key) -> str:
    if isinstance(key, int):
        return f"{place}[{key}]"
    return f"{place}.{key}" if place else str(key)


def _one_key(v: _V, item, place, keys):
    if not isinstance(item, dict):
        v.fail(place, f"expected a mapping with one of {', '.join(keys)}, got {_kind(item)}")
    if len(item) != 1:
        v.fail(place, f"expected exactly one of {', '.join(keys)}, got {len(item)} keys")
    key = next(iter(item))
    if key not in keys:
        v.fail(_join(place, key), f"unknown obstacle kind (allowed: {', '.join(keys)})")
    return key, item[key]


def leaves_folder(rel: str) -> bool:
    """Whether a relative path (``os.path.relpath``'s answer) climbs out of its folder:
    its first part is ``..`` (a file named ``..map.yaml`` stays inside)."""
    return Path(rel).parts[:1] == ("..",)


def _inside(v: _V, folder: Path, rel, place: str, what: str, absolute: bool = False) -> Path:
    """A file name (a map's, a mesh's) joined to ``folder`` and resolved; refused when it
    is not a non-empty string, holds a NUL or starts with ``~``, and when it is absolute
    unless ``absolute`` (a map YAML's ``image``, which Nav2 takes either way). Whether the
    result stays inside a folder is the caller's test."""
    if not isinstance(rel, str) or not rel:
        v.fail(place, f"expected a file name, got {_kind(rel)}")
    if "\0" in rel:
        v.fail(place, "file name contains a NUL character")
    if (os.path.isabs(rel) and not absolute) or rel.startswith("~"):
        v.fail(place, f"{what} path {rel!r} must be relative")
    return (folder / rel).resolve()
