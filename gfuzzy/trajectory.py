"""Timed trajectories and their files (docs/formats.md section 2).

A :class:`Trajectory` is a table of rows ``[t, x, y]`` (disc robot) or
``[t, x, y, heading]`` (box robot), t strictly increasing; between rows the robot moves
linearly in x and y and in heading along the shorter arc.
"""

from __future__ import annotations

import csv
import io
import json
import math
import numbers
import os
import sys
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from .atomic import write_atomic
from .errors import InputError, SceneError, not_utf8
from .poses import metric_distance, number_array, pose_at
from .settings import MAX_MAGNITUDE
from .status import Status
from .typed import FloatArray

__all__ = ["Trajectory", "load_trajectory", "TrajectoryFile", "executed_rows", "replan_entries"]


@dataclass(frozen=True, eq=False)
class Trajectory:
    """A timed trajectory.

    Two trajectories are equal when their waypoints are equal, row for row and bit for bit,
    and so are their circumscribed radii.

    Attributes
    ----------
    waypoints : (n, 3) or (n, 4) float
        Rows ``[t, x, y(, heading)]``, n >= 1 (any sequence of such rows is taken as a float
        array).
    circumradius : float
        The robot's circumscribed radius (weights heading change in the metric).

    Raises
    ------
    InputError
        Rows that are no table of numbers ``[t, x, y(, heading)]`` (none, of another width,
        or holding a string or a boolean).
    """

    waypoints: FloatArray
    circumradius: float = 0.0

    def __post_init__(self) -> None:
        rows = number_array(self.waypoints)
        if rows is None:  # numpy would take "0" or True for a number, as a scene file does not
            raise InputError("waypoints: expected rows of numbers [t, x, y(, heading)] of one width (no strings or booleans)")
        if rows.ndim != 2 or len(rows) == 0 or rows.shape[1] not in (3, 4):
            raise InputError(f"waypoints: expected rows [t, x, y] or [t, x, y, heading], at least one; got shape {rows.shape}")
        object.__setattr__(self, "waypoints", rows)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Trajectory):
            return NotImplemented
        return self.circumradius == other.circumradius and np.array_equal(
            self.waypoints, other.waypoints
        )

    __hash__ = None  # mutable numpy contents: equal trajectories need not stay equal

    @property
    def times(self) -> FloatArray:
        return self.waypoints[:, 0]

    @property
    def poses(self) -> FloatArray:
        return self.waypoints[:, 1:]

    @property
    def t0(self) -> float:
        return float(self.waypoints[0, 0])

    @property
    def t_end(self) -> float:
        return float(self.waypoints[-1, 0])

    @property
    def duration(self) -> float:
        """Last t minus first t."""
        return self.t_end - self.t0

    def segment_lengths(self) -> FloatArray:
        """(n-1,) float: contract-metric length of each row-to-row motion."""
        p = self.poses
        return metric_distance(p[:-1], p[1:], self.circumradius)

    @property
    def length(self) -> float:
        """Path length in the contract metric."""
        return float(np.sum(self.segment_lengths()))

    @property
    def xy_length(self) -> float:
        """Euclidean length of the xy path."""
        return float(np.sum(np.hypot(*np.diff(self.poses[:, :2], axis=0).T)))

    def speeds(self) -> FloatArray:
        """(n-1,) float: configuration speed of each row-to-row motion."""
        return self.segment_lengths() / np.diff(self.times)

    def delay_factor(self, vmax: float, roadmap_distance: float) -> float:
        """duration * vmax / roadmap_distance (1.0 when the start is the goal)."""
        if roadmap_distance <= 0:
            return 1.0
        return self.duration * vmax / roadmap_distance

    def at(self, t) -> FloatArray:
        """Pose(s) at time(s) ``t`` (clamped to the trajectory's time range).

        Parameters
        ----------
        t : float or array of float, any shape

        Returns
        -------
        (d,) float for a number; an array of shape ``t.shape + (d,)`` otherwise
        """
        shape = np.shape(t)
        tt = np.clip(np.asarray(t, dtype=float).reshape(-1), self.t0, self.t_end)
        times, poses = self.times, self.poses
        if len(times) == 1:
            out = np.repeat(poses[:1], len(tt), axis=0)
        else:
            out = pose_at(times, poses, tt)
        return out.reshape(*shape, poses.shape[1])

    def to_csv(self) -> str:
        """CSV text with header ``t,x,y`` or ``t,x,y,heading``."""
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(["t", "x", "y"] + (["heading"] if self.waypoints.shape[1] == 4 else []))
        for row in self.waypoints:
            w.writerow([repr(float(v)) for v in row])
        return buf.getvalue()


@dataclass(frozen=True, eq=False)
class TrajectoryFile:
    """The contents of a trajectory JSON file (any status).

    Equal when every field is: the waypoints row for row and the extra keys included.
    """

    scene: str
    query: str
    status: str
    message: str
    duration: float | None
    roadmap_distance: float | None
    delay_factor: float | None
    planning_seconds: float
    waypoints: FloatArray | None = None
    extra: dict = field(default_factory=dict)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, TrajectoryFile):
            return NotImplemented
        head = [f.name for f in fields(self) if f.name != "waypoints"]
        if any(getattr(self, n) != getattr(other, n) for n in head):
            return False
        a, b = self.waypoints, other.waypoints
        return (a is None and b is None) or (
            a is not None and b is not None and np.array_equal(a, b)
        )

    __hash__ = None

    def to_dict(self) -> dict:
        doc = {
            "version": 1,
            "scene": self.scene,
            "query": self.query,
            "status": self.status,
            "message": self.message,
            "duration": self.duration,
            "roadmap_distance": self.roadmap_distance,
            "delay_factor": self.delay_factor,
            "planning_seconds": self.planning_seconds,
        }
        if self.waypoints is not None:
            doc["waypoints"] = [[float(v) for v in row] for row in self.waypoints]
        doc.update(self.extra)
        return doc

    def save(self, path: str | os.PathLike) -> None:
        """Write JSON (``.json``) or CSV (``.csv``: solved answers only), atomically."""
        path = Path(path)
        if path.suffix.lower() == ".csv":
            if self.waypoints is None:
                raise ValueError(f"{path}: a {self.status} answer has no waypoints to write as CSV")
            write_atomic(path, Trajectory(self.waypoints).to_csv())
        else:
            write_atomic(path, json.dumps(_finite(self.to_dict()), indent=1) + "\n")


def _finite(obj):
    """JSON has no NaN or inf: write them as null."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_finite(v) for v in obj]
    return obj


def load_trajectory(path: str | os.PathLike) -> TrajectoryFile:
    """Read a trajectory JSON file (docs/formats.md section 2).

    The file's other keys (a plan's ``stats``; a navigate run's ``replans``,
    ``min_separation``, ``executed``, ``replan_log``, ...) are kept, as read, in ``extra``:
    a saved :class:`TrajectoryFile` loads back equal (unless it held NaN or inf, written as null).

    Raises
    ------
    SceneError
        Unreadable, not JSON (a CSV export gets a hint), or not of the contract's form
        (naming the place), t not strictly increasing included.
    """
    file = str(path)
    try:
        data = Path(path).read_bytes()
        text = data.decode("utf-8-sig")  # a BOM (a Windows editor's) is read past, as in a scene
    except OSError as exc:
        raise SceneError(file, "", f"cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise SceneError(file, "", not_utf8(data, exc)) from None
    try:
        doc = json.loads(text)
    except (json.JSONDecodeError, RecursionError) as exc:  # RecursionError: arrays nested past Python's stack
        if Path(path).suffix.lower() == ".csv" or text.lstrip().startswith("t,x,y"):
            # the CSV export is a common mix-up: it has rows but no status
            beside = Path(path).with_suffix(".json")
            raise SceneError(
                file, "", f"this is a CSV export; a trajectory file is the JSON that `gfuzzy plan -o` "
                f"writes beside it ({beside}), which has the status the CSV lacks"
            ) from None
        raise SceneError(file, "", f"invalid JSON: {exc}") from None
    if not isinstance(doc, dict):
        raise SceneError(file, "", "expected a JSON object")
    for key in ("version", "status"):
        if key not in doc:
            raise SceneError(file, key, "missing required key")
    if doc["version"] != 1:
        raise SceneError(file, "version", f"unsupported version {doc['version']!r}")
    if not isinstance(doc["status"], str) or doc["status"] not in {s.value for s in Status}:
        raise SceneError(file, "status", f"unknown status {doc['status']!r}")
    wps = None
    if doc["status"] == Status.SOLVED:
        wps = _rows(doc.get("waypoints"), file, "waypoints")

    def num(key):  # null (NaN or inf written) or absent: None; a list or a string is bad input
        v = doc.get(key)
        if v is not None and not (_finite_number(v) or isinstance(v, float)):  # NaN, inf: as before
            raise SceneError(file, key, f"expected a number, got {_short(v)}")
        return None if v is None else float(v)

    def text(key):  # str() read a list [1] as the name "[1]"; null is as absent
        v = doc.get(key)
        if v is not None and not isinstance(v, str):
            raise SceneError(file, key, f"expected a string, got {_short(v)}")
        return v or ""

    return TrajectoryFile(
        scene=text("scene"),
        query=text("query"),
        status=doc["status"],
        message=text("message"),
        duration=num("duration"),
        roadmap_distance=num("roadmap_distance"),
        delay_factor=num("delay_factor"),
        planning_seconds=num("planning_seconds") or 0.0,
        waypoints=wps,
        extra={k: v for k, v in doc.items() if k not in _CONTRACT_KEYS},
    )


# the keys TrajectoryFile holds as fields; any other key of a file is an extra
_CONTRACT_KEYS = frozenset(("version", "scene", "query", "status", "message", "duration", "roadmap_distance",
                            "delay_factor", "planning_seconds", "waypoints"))


def _finite_number(v, bound: float = sys.float_info.max) -> bool:
    """Whether ``v`` is one real number (not a boolean) of at most ``bound`` in magnitude:
    NaN and infinities are not, nor a JSON integer past a float's range (``abs`` first:
    ``math.isfinite`` of a 400-digit integer raises OverflowError)."""
    return isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_)) and abs(v) <= bound


def _short(v) -> str:
    """``repr(v)``, cut to 80 characters for an error message."""
    text = repr(v)
    return text if len(text) <= 80 else text[:77] + "..."


def _rows(rows, file: str, key: str) -> FloatArray:
    """A file's ``key`` (``waypoints``, or a navigate run's ``executed``) as a float table,
    read by the contract's rules: a non-empty list of rows ``[t, x, y(, heading)]`` of one
    width, finite numbers (no strings or booleans), the pose's at most ``MAX_MAGNITUDE`` in
    magnitude (as a scene's), t strictly increasing; else a SceneError naming the row."""
    if not isinstance(rows, list) or not rows:
        raise SceneError(file, key, "expected a non-empty list of rows [t, x, y] or [t, x, y, heading]")
    width = len(rows[0]) if isinstance(rows[0], list) else -1
    if width not in (3, 4):
        raise SceneError(file, f"{key}[0]", "rows must be [t, x, y] or [t, x, y, heading]")
    for i, row in enumerate(rows):
        if not isinstance(row, list) or len(row) != width:
            raise SceneError(file, f"{key}[{i}]", f"expected {width} numbers, as {key}[0] has")
        for j, v in enumerate(row):
            if not _finite_number(v):
                raise SceneError(file, f"{key}[{i}][{j}]", f"expected a finite number, got {_short(v)}")
            if j and abs(v) > MAX_MAGNITUDE:  # a pose as a scene's numbers; t may pass it (a plan from t0 = 1e9)
                raise SceneError(file, f"{key}[{i}][{j}]", f"number too large ({_short(v)}; at most {MAX_MAGNITUDE:g} in magnitude)")
    table = np.asarray(rows, dtype=float)
    back = np.nonzero(np.diff(table[:, 0]) <= 0)[0]
    if back.size:  # section 2: t strictly increasing; without it the rows are no trajectory
        j = int(back[0]) + 1
        raise SceneError(
            file, f"{key}[{j}][0]", f"t={float(table[j, 0])!r} does not increase (the row before has t={float(table[j - 1, 0])!r})"
        )
    return table


def executed_rows(tf: TrajectoryFile, file: str) -> FloatArray | None:
    """The rows a navigate run that did not arrive executed (its ``executed`` key, read as
    ``waypoints`` are), or None when the file has none. ``file`` names it in errors.

    Raises
    ------
    SceneError
        ``executed`` present but not such a table, naming the row (``executed[3]``).
    """
    if tf.waypoints is not None or "executed" not in tf.extra:
        return None
    return _rows(tf.extra["executed"], file, "executed")


def replan_entries(log, file: str) -> list[dict]:
    """A navigate run's ``replan_log`` (the predictions ``render``'s GIF and ``export``'s
    MCAP draw), read by its rules, sorted by ``t``: a list of mappings, each with ``t`` (a
    finite number, at most ``MAX_MAGNITUDE`` in magnitude), ``predicted`` (rows of 5 finite
    numbers ``[x, y, vx, vy, radius]``, radius >= 0) and ``plan`` (rows ``[t, x, y(, heading)]``
    of one width, finite numbers); the last two may be missing or empty. ``file`` names
    the file in errors.

    Raises
    ------
    SceneError
        Naming the entry and the number (``replan_log[3].predicted[1][2]``).
    """
    def seq(v) -> bool:  # as read from JSON, or built in Python (NavResult.log, numpy rows)
        return isinstance(v, (list, tuple)) or (isinstance(v, np.ndarray) and v.ndim >= 1)

    if not seq(log):
        raise SceneError(file, "replan_log", f"expected a list of replans, got {type(log).__name__}")
    for i, e in enumerate(log):
        where = f"replan_log[{i}]"
        if not isinstance(e, dict):
            raise SceneError(file, where, "expected a mapping with t, predicted and plan")
        t = e.get("t")
        if not _finite_number(t, MAX_MAGNITUDE):
            raise SceneError(file, f"{where}.t", f"expected a finite number of at most {MAX_MAGNITUDE:g} in magnitude, got {_short(t)}")
        for key, widths in (("predicted", (5,)), ("plan", (3, 4))):
            rows = e.get(key, [])
            if not seq(rows):
                raise SceneError(file, f"{where}.{key}", f"expected a list of rows, got {_short(rows)}")
            for j, row in enumerate(rows):
                want = widths if j == 0 or key == "predicted" else (len(rows[0]),)
                if not seq(row) or len(row) not in want:
                    n = " or ".join(map(str, want))
                    raise SceneError(file, f"{where}.{key}[{j}]", f"expected a row of {n} numbers, got {_short(row)}")
                for k, v in enumerate(row):
                    if not _finite_number(v, MAX_MAGNITUDE):
                        raise SceneError(file, f"{where}.{key}[{j}][{k}]", f"expected a finite number of at most {MAX_MAGNITUDE:g} in magnitude, got {_short(v)}")
                if key == "predicted" and row[4] < 0:
                    raise SceneError(file, f"{where}.{key}[{j}][4]", f"a radius must be >= 0, got {row[4]!r}")
    return sorted(log, key=lambda e: float(e["t"]))
