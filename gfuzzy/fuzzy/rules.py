"""Fuzzy rule bases and their text files: partitions, the chromosome, the packaged bases.

A rule base (:class:`RuleBase`) pairs a partition of each input (*curve*, *distance*)
and of the output (*speed*) with one allele per pair of input sets; docs/speed-layer.md
describes the file format. :mod:`gfuzzy.fuzzy.fuzzy` infers with it; the learning subpackage
(:mod:`gfuzzy.learning.learn`) learns one.

Conventions
-----------
* Inputs and output live on ``[0, 1]``. Every partition is a Ruspini partition of
  triangles: the feet of set ``i`` are the peaks of its neighbours (the end sets
  mirror theirs outside ``[0, 1]``), so memberships sum to one everywhere.
* The chromosome is ``genes[i * n_distance + j]`` for curve set ``i`` and distance
  set ``j``; ``0`` means *no rule*, ``k >= 1`` means *speed is output set k - 1*.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError, SceneError
from ..typed import ArrayLike, FloatArray, PathType

__all__ = [
    "LABELS",
    "UNEQUAL_PEAKS",
    "Partition",
    "RuleBase",
    "expert_rules",
    "learned_rules",
    "parse_rules",
    "format_rules",
    "load_rules",
    "save_rules",
]

#: Set labels by partition size, from the lowest value to the highest.
LABELS: dict[int, tuple[str, ...]] = {
    3: ("L", "Z", "H"),
    5: ("VL", "L", "Z", "H", "VH"),
    7: ("VVL", "VL", "L", "Z", "H", "VH", "VVH"),
}

#: Peaks of the unequal partitions: narrow sets near 0 (near-straight paths,
#: near bends), where small differences matter most, wide ones near 1. All are
#: multiples of 0.05 so they fall on the default grids exactly.
UNEQUAL_PEAKS: dict[int, tuple[float, ...]] = {
    3: (0.0, 0.3, 1.0),
    5: (0.0, 0.1, 0.3, 0.6, 1.0),
    7: (0.0, 0.05, 0.15, 0.3, 0.5, 0.75, 1.0),
}

_DATA = "data"
_EXPERT_FILE = "rules_expert.txt"
_LEARNED_FILE = "rules_learned.txt"


# --------------------------------------------------------------------------
# Membership functions and rule bases
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class Partition:
    """A Ruspini partition of ``[0, 1]`` into triangular fuzzy sets.

    Parameters
    ----------
    peaks : tuple of float, length 3, 5 or 7
        Strictly increasing peaks, the first 0 and the last 1. Set ``i`` is the
        triangle ``(peaks[i-1], peaks[i], peaks[i+1])``; the end sets mirror
        their inner foot outside ``[0, 1]`` (so each is a full triangle whose
        centre sits on the universe's edge).

    Raises
    ------
    ValueError
        If the peaks are not as above.
    """

    peaks: tuple[float, ...]

    def __post_init__(self) -> None:
        peaks = tuple(float(p) for p in self.peaks)
        object.__setattr__(self, "peaks", peaks)
        if len(peaks) not in LABELS:
            raise InputError(f"a partition has 3, 5 or 7 sets, not {len(peaks)}")
        if not all(math.isfinite(p) for p in peaks):
            raise InputError("partition peaks must be finite")
        if peaks[0] != 0.0 or peaks[-1] != 1.0:
            raise InputError("partition peaks must start at 0 and end at 1")
        if any(b <= a for a, b in zip(peaks, peaks[1:], strict=False)):
            raise InputError("partition peaks must be strictly increasing")

    @classmethod
    def uniform(cls, n: int) -> Partition:
        """``n`` sets with equal base lengths (peaks ``linspace(0, 1, n)``)."""
        if n not in LABELS:
            raise InputError(f"a partition has 3, 5 or 7 sets, not {n}")
        return cls(tuple(i / (n - 1) for i in range(n)))

    @classmethod
    def unequal(cls, n: int) -> Partition:
        """``n`` sets with unequal base lengths (:data:`UNEQUAL_PEAKS`)."""
        if n not in UNEQUAL_PEAKS:
            raise InputError(f"a partition has 3, 5 or 7 sets, not {n}")
        return cls(UNEQUAL_PEAKS[n])

    @property
    def size(self) -> int:
        """Number of sets."""
        return len(self.peaks)

    @property
    def labels(self) -> tuple[str, ...]:
        """Set labels, lowest first (:data:`LABELS`)."""
        return LABELS[self.size]

    @property
    def triangles(self) -> FloatArray:
        """Feet and peaks, ``(n, 3) float``: rows ``(a, b, c)`` with ``a < b < c``."""
        p = np.asarray(self.peaks)
        left = np.concatenate(([2 * p[0] - p[1]], p[:-1]))
        right = np.concatenate((p[1:], [2 * p[-1] - p[-2]]))
        return np.stack([left, p, right], axis=1)

    def membership(self, x: ArrayLike) -> FloatArray:
        """Membership degrees of ``x`` in every set.

        Parameters
        ----------
        x : (m,) float
            Values; clipped to ``[0, 1]``.

        Returns
        -------
        (m, n) float
            Degrees in ``[0, 1]``; each row sums to 1.
        """
        x = np.clip(np.asarray(x, dtype=float).reshape(-1), 0.0, 1.0)
        return _triangles(x[:, None], self.triangles)

    def spec(self) -> str:
        """The partition as written in a rule file: ``uniform 7``, ``unequal 5``
        or ``peaks 0 0.2 ... 1``."""
        n = self.size
        if self == Partition.uniform(n):
            return f"uniform {n}"
        if self == Partition.unequal(n):
            return f"unequal {n}"
        return "peaks " + " ".join(repr(p) for p in self.peaks)


def _triangles(x: FloatArray, tri: FloatArray) -> FloatArray:
    """Triangle memberships, ``x`` broadcast against rows of ``tri`` ``(n, 3)``."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    up = (x - a) / (b - a)
    down = (c - x) / (c - b)
    return np.clip(np.minimum(up, down), 0.0, 1.0)


_UNIFORM7 = Partition.uniform(7)
_UNIFORM5 = Partition.uniform(5)


@dataclass(frozen=True)
class RuleBase:
    """A Mamdani rule base over *curve* x *distance* -> *speed*: the chromosome.

    Parameters
    ----------
    genes : tuple of int, length ``curve.size * distance.size``
        Row-major: ``genes[i * distance.size + j]`` is the rule for curve set
        ``i`` and distance set ``j``; 0 = no rule, ``k`` in ``1..speed.size`` =
        *speed is* ``speed.labels[k - 1]``.
    curve, distance, speed : Partition
        The partitions of the two inputs and of the output (defaults 7, 5, 7
        uniform sets). They travel with the genes: an allele means nothing
        without them.

    Raises
    ------
    ValueError
        If the genes do not fit the partitions.
    """

    genes: tuple[int, ...]
    curve: Partition = _UNIFORM7
    distance: Partition = _UNIFORM5
    speed: Partition = _UNIFORM7

    def __post_init__(self) -> None:
        genes = tuple(int(g) for g in np.asarray(self.genes).reshape(-1))
        object.__setattr__(self, "genes", genes)
        n = self.curve.size * self.distance.size
        if len(genes) != n:
            raise InputError(
                f"expected {n} genes ({self.curve.size} x {self.distance.size}), got {len(genes)}"
            )
        bad = [g for g in genes if not 0 <= g <= self.speed.size]
        if bad:
            raise InputError(f"genes must be in 0..{self.speed.size}, got {bad[0]}")

    @classmethod
    def from_matrix(
        cls,
        matrix: ArrayLike,
        curve: Partition = _UNIFORM7,
        distance: Partition = _UNIFORM5,
        speed: Partition = _UNIFORM7,
    ) -> RuleBase:
        """Build from a ``(curve.size, distance.size) int`` matrix of alleles."""
        m = np.asarray(matrix)
        if m.shape != (curve.size, distance.size):
            raise InputError(f"matrix shape {m.shape} != {(curve.size, distance.size)}")
        return cls(tuple(int(g) for g in m.reshape(-1)), curve, distance, speed)

    @property
    def matrix(self) -> np.ndarray:
        """Alleles as a ``(curve.size, distance.size) int`` array (a copy)."""
        return np.array(self.genes, dtype=np.int64).reshape(self.curve.size, self.distance.size)

    @property
    def n_rules(self) -> int:
        """Number of rules (non-zero alleles)."""
        return sum(1 for g in self.genes if g)

    def table(self) -> str:
        """The rule base as a table: rows curve labels, columns distance labels,
        entries speed labels or ``-`` for no rule."""
        corner = "curve\\dist"
        cols = self.distance.labels
        width = max(4, max(len(s) for s in self.speed.labels) + 1)
        head = f"{corner:<11}" + "".join(f"{c:<{width}}" for c in cols).rstrip()
        rows = [head]
        m = self.matrix
        for i, lab in enumerate(self.curve.labels):
            cells = [self.speed.labels[g - 1] if g else "-" for g in m[i]]
            rows.append(f"{lab:<11}" + "".join(f"{c:<{width}}" for c in cells).rstrip())
        return "\n".join(rows)

    def __str__(self) -> str:
        return self.table()


# --------------------------------------------------------------------------
# Rule files
# --------------------------------------------------------------------------

_HEADER = """\
# gfuzzy fuzzy speed rule base (Mamdani: min AND, max aggregation, centroid).
# Inputs in [0, 1]: curve = turning ahead / max_turn, dist = distance to the bend / look-ahead.
# Output: speed as a fraction of vmax. Rows: curve sets; columns: distance sets;
# entries: speed set, '-' = no rule. Partitions: 'uniform N', 'unequal N' or 'peaks ...'.
"""


def format_rules(rulebase: RuleBase, comment: str = "") -> str:
    """The text of a rule file for ``rulebase`` (see :func:`parse_rules`).

    Parameters
    ----------
    rulebase : RuleBase
    comment : str
        Extra lines written as ``#`` comments after the standard header.
    """
    lines = [_HEADER.rstrip("\n")]
    lines += [f"# {c}".rstrip() for c in comment.splitlines()]
    lines += [
        f"curve: {rulebase.curve.spec()}",
        f"distance: {rulebase.distance.spec()}",
        f"speed: {rulebase.speed.spec()}",
        "",
        "rules:",
        rulebase.table(),
    ]
    return "\n".join(lines) + "\n"


def _parse_partition(spec: str, file: str, place: str) -> Partition:
    words = spec.split()
    try:
        if len(words) == 2 and words[0] in ("uniform", "unequal"):
            n = int(words[1])
            return Partition.uniform(n) if words[0] == "uniform" else Partition.unequal(n)
        if len(words) >= 2 and words[0] == "peaks":
            return Partition(tuple(float(w) for w in words[1:]))
    except ValueError as exc:
        raise SceneError(file, place, str(exc)) from None
    raise SceneError(file, place, f"expected 'uniform N', 'unequal N' or 'peaks ...', got {spec!r}")


def parse_rules(text: str, file: str = "<string>") -> RuleBase:
    """Parse the text of a rule file.

    The format (``#`` starts a comment, blank lines are ignored)::

        curve: uniform 7
        distance: unequal 5
        speed: uniform 7
        rules:
        curve\\dist  VL   L    Z    H    VH
        VVL         VVH  VVH  VVH  VVH  VVH
        ...

    The first row after ``rules:`` names the distance sets (its first word is
    free); then one row per curve set, in order, each naming its set and giving
    one speed label or ``-`` per distance set.

    Parameters
    ----------
    text : str
    file : str
        Name used in error messages.

    Returns
    -------
    RuleBase

    Raises
    ------
    SceneError
        On any malformed line, naming the file and ``line N``.
    """
    parts, rows, last_line = _rule_sections(text, file)
    curve, distance, speed = parts["curve"], parts["distance"], parts["speed"]
    body = _rule_rows(rows, last_line, curve, distance, file)
    return RuleBase(tuple(_rule_genes(body, curve, distance, speed, file)), curve, distance, speed)


def _rule_sections(text: str, file: str):
    """The partitions (``key: value`` lines) and the raw rows after ``rules:``."""
    parts: dict[str, Partition] = {}
    rows: list[tuple[int, list[str]]] = []
    in_rules = False
    last_line = 0
    for number, raw in enumerate(text.splitlines(), start=1):
        last_line = number
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        place = f"line {number}"
        if in_rules:
            rows.append((number, line.split()))
            continue
        key, sep, value = line.partition(":")
        key = key.strip()
        if not sep:
            raise SceneError(file, place, f"expected 'key: value' or 'rules:', got {line!r}")
        if key == "rules":
            if value.strip():
                raise SceneError(file, place, "nothing may follow 'rules:' on its line")
            in_rules = True
            continue
        if key not in ("curve", "distance", "speed"):
            raise SceneError(
                file, place, f"unknown key {key!r} (expected curve, distance, speed or rules)"
            )
        if key in parts:
            raise SceneError(file, place, f"duplicate key {key!r}")
        parts[key] = _parse_partition(value, file, place)
    for key in ("curve", "distance", "speed"):
        if key not in parts:
            raise SceneError(file, "", f"missing '{key}:' partition")
    if not in_rules:
        raise SceneError(file, "", "missing 'rules:' section")
    return parts, rows, last_line


def _rule_rows(rows, last_line: int, curve: Partition, distance: Partition, file: str):
    """The table's rows after its header, checked against the partitions' sizes."""
    if not rows:
        raise SceneError(file, f"line {last_line}", "empty rule table")
    number, header = rows[0]
    if tuple(header[1:]) != distance.labels:
        raise SceneError(
            file,
            f"line {number}",
            f"table header must name the distance sets {' '.join(distance.labels)}, got {' '.join(header[1:])!r}",
        )
    body = rows[1:]
    if len(body) != curve.size:
        where = f"line {body[-1][0]}" if body else f"line {number}"
        raise SceneError(
            file, where, f"expected {curve.size} rows (one per curve set), got {len(body)}"
        )
    return body


def _rule_genes(body, curve: Partition, distance: Partition, speed: Partition, file: str) -> list[int]:
    """One allele per table entry (0 for ``-``), row by row."""
    code = {lab: k + 1 for k, lab in enumerate(speed.labels)}
    code["-"] = 0
    genes: list[int] = []
    for (number, words), label in zip(body, curve.labels, strict=True):
        place = f"line {number}"
        if words[0] != label:
            raise SceneError(
                file, place, f"expected the row of curve set {label!r}, got {words[0]!r}"
            )
        if len(words) - 1 != distance.size:
            raise SceneError(file, place, f"expected {distance.size} entries, got {len(words) - 1}")
        for col, word in enumerate(words[1:], start=1):
            if word not in code:
                raise SceneError(
                    file,
                    f"{place}, column {col}",
                    f"unknown speed label {word!r} (expected one of {' '.join(speed.labels)} or -)",
                )
            genes.append(code[word])
    return genes


def load_rules(path: PathType) -> RuleBase:
    """Read a rule file (format in :func:`parse_rules`).

    Raises
    ------
    SceneError
        If the file cannot be read or is malformed.
    """
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(str(path), "", f"cannot read rule file: {exc}") from None
    return parse_rules(text, str(path))


def save_rules(rulebase: RuleBase, path: PathType, comment: str = "") -> None:
    """Write ``rulebase`` as a rule file (read back by :func:`load_rules`)."""
    Path(path).write_text(format_rules(rulebase, comment), encoding="utf-8")


@functools.cache
def _packaged(name: str) -> RuleBase:
    # Beside this module: works for source trees, wheels and editable installs alike.
    return load_rules(Path(__file__).resolve().parent.parent / _DATA / name)


def expert_rules() -> RuleBase:
    """The default, hand-written rule base shipped in ``gfuzzy/data/rules_expert.txt``:
    slow for sharp, near bends; fast on straights and far bends."""
    return _packaged(_EXPERT_FILE)


def learned_rules() -> RuleBase:
    """The rule base learned by :func:`learn_rules` (``tools/learn_rules.py``),
    shipped in ``gfuzzy/data/rules_learned.txt``."""
    return _packaged(_LEARNED_FILE)

