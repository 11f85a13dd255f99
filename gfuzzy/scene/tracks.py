"""Pedestrian tracks as movers: read recorded tracks, write them as a scene.

The two input formats (eth, csv) are read by :mod:`gfuzzy.scene.trackfiles`.

Rows of different people may interleave; each person's times must strictly increase in
file order. :func:`read_tracks` returns :class:`Tracks`; :func:`tracks_scene` clips them to
a time window and a region and returns a :class:`TrackScene`, whose ``doc`` is a scene
document (:func:`gfuzzy.scene.scene.parse_scene` reads it) and whose :meth:`TrackScene.to_yaml`
writes it. ``gfuzzy tracks`` is the command line of both. Reading lives in
:mod:`gfuzzy.scene.trackfiles` (its names are re-exported here).
"""

from __future__ import annotations

import logging
import math
import numbers
import os
import statistics
from dataclasses import dataclass
from itertools import pairwise
from pathlib import Path

from ..errors import InputError, SceneError
from ..poses import pose_words
from ..settings import MAX_MAGNITUDE, MAX_RECORDED_TIME
from .scene import NAME_RE, STATUSES, Scene
from .trackfiles import ANNOTATION_PERIOD, Track, Tracks, _id_key, read_tracks
from .yamldoc import dump_yaml, leaves_folder, plain_name

__all__ = [
    "ANNOTATION_PERIOD",
    "Track",
    "Tracks",
    "TrackSceneOptions",
    "TrackScene",
    "read_tracks",
    "tracks_scene",
]

log = logging.getLogger(__name__)

#: Margin (m) around the pedestrians' extent when no region is given.
REGION_MARGIN = 0.5
#: How many of the file's usual periods between a person's rows they may go unseen and stay one mover.
GAP_PERIODS = 5
#: Walking speeds (m/s) beyond which the units are likely wrong (people walk 0.5-2 m/s): no
#: step of anyone faster than the first (times in milliseconds read as seconds), or the
#: median of the people's mean speeds faster than the second (positions in centimetres).
PLAUSIBLE_SPEEDS = (0.02, 15.0)



# ---------------------------------------------------------------------------------- clipping


def _lerp(a, b, u: float):
    return tuple(a[i] + u * (b[i] - a[i]) for i in range(3))


def _clip_time(rows, t_lo: float, t_hi: float) -> list:
    """Rows (t, x, y) restricted to [t_lo, t_hi], with rows interpolated at the boundaries."""
    out: list = []
    for a, b in pairwise(rows):
        if b[0] < t_lo or a[0] > t_hi:
            continue
        u0 = max(0.0, (t_lo - a[0]) / (b[0] - a[0]))
        u1 = min(1.0, (t_hi - a[0]) / (b[0] - a[0]))
        p, q = _lerp(a, b, u0), _lerp(a, b, u1)
        if not out or out[-1] != p:
            out.append(p)
        if q != p:
            out.append(q)
    if not out:  # a track of a single row, or one only touching the window
        out = [r for r in rows if t_lo <= r[0] <= t_hi]
    return out


def _clip_segment(p, q, region) -> tuple[float, float] | None:
    """Liang-Barsky: the parameter interval [u0, u1] of the segment p -> q inside the region."""
    xmin, ymin, xmax, ymax = region
    dx, dy = q[1] - p[1], q[2] - p[2]
    u0, u1 = 0.0, 1.0
    for den, num in ((-dx, p[1] - xmin), (dx, xmax - p[1]), (-dy, p[2] - ymin), (dy, ymax - p[2])):
        if den == 0:
            if num < 0:
                return None
            continue
        u = num / den
        if den < 0:
            u0 = max(u0, u)
        else:
            u1 = min(u1, u)
    if u0 > u1:
        return None
    return u0, u1


def _clip_region(rows, region) -> list[list]:
    """The runs of a track inside the region (rows interpolated where it crosses the border)."""
    xmin, ymin, xmax, ymax = region
    if len(rows) == 1:
        _, x, y = rows[0]
        return [rows] if xmin <= x <= xmax and ymin <= y <= ymax else []
    runs: list[list] = []
    cur: list = []
    for a, b in pairwise(rows):
        span = _clip_segment(a, b, region)
        if span is None:
            if cur:
                runs.append(cur)
                cur = []
            continue
        u0, u1 = span
        p, q = _lerp(a, b, u0), _lerp(a, b, u1)
        if u0 > 0.0 and cur:
            runs.append(cur)
            cur = []
        if not cur or cur[-1] != p:
            cur.append(p)
        if q != p:
            cur.append(q)
        if u1 < 1.0:
            runs.append(cur)
            cur = []
    if cur:
        runs.append(cur)
    # rounding must not push a row out of the region either
    return [
        [(t, min(max(x, xmin), xmax), min(max(y, ymin), ymax)) for t, x, y in run] for run in runs
    ]


def _round_rows(rows) -> list:
    """Rows rounded to the millimetre and millisecond; a row whose time no longer increases
    is dropped (scene trajectories need strictly increasing times)."""
    out: list = []
    for t, x, y in rows:
        r = (round(t, 3), round(x, 3), round(y, 3))
        if out and r[0] <= out[-1][0]:
            continue
        out.append(r)
    return out


@dataclass
class _Mover:
    name: str
    pid: str
    rows: list  # (t, x, y), t relative to the window start

    @property
    def duration(self) -> float:
        return self.rows[-1][0] - self.rows[0][0]

    def position_at(self, t: float):
        rows = self.rows
        if not rows[0][0] <= t <= rows[-1][0]:
            return None
        for a, b in pairwise(rows):
            if a[0] <= t <= b[0]:
                u = (t - a[0]) / (b[0] - a[0])
                return a[1] + u * (b[1] - a[1]), a[2] + u * (b[2] - a[2])
        return rows[-1][1], rows[-1][2]


# ---------------------------------------------------------------------------------- scenes


@dataclass(frozen=True)
class TrackSceneOptions:
    """How tracks become a scene.

    Attributes
    ----------
    t_start : float or None
        Start of the time window, seconds of the recording (None: the first time in the
        file). Scene time 0 is this instant.
    duration : float or None
        Length of the window in seconds (None: up to the last time in the file).
    region : (4,) tuple or None
        ``(xmin, ymin, xmax, ymax)`` after scaling and the offset: the scene's bounds; tracks are clipped
        to it. None: the static scene's bounds, or the people's extent in the window plus
        :data:`REGION_MARGIN`, rounded out to 0.1 m.
    scale : float
        Multiplies every x and y of the file (e.g. 0.01 for centimetres).
    offset : (2,) tuple
        ``(dx, dy)`` added to every x and y after ``scale``: where the file's origin lies in
        the scene's frame (a detector's frame whose origin is not the map's).
    radius : float
        Radius of each person's disc mover, metres.
    max_movers : int or None
        Keep the movers present longest in the window (ties: smaller id first).
    max_gap : float or None
        A person unseen for longer than this (seconds between two of their rows: a tracker
        that lost them) is absent in between: the rows before and after become two movers,
        not one walking a straight line through the gap; each cut is logged. None:
        :data:`GAP_PERIODS` times the person's own median time between consecutive rows (2 s
        for annotations 0.4 s apart; sparse hand-written keyframes are never cut).
        ``math.inf``: never cut.
    name : str
        The scene's name.
    robot_radius, vmax, amax : float or None
        A disc robot; None: the static scene's robot, or 0.2 m, 1.5 m/s, 3.0 m/s².
    kinematics : {None, "holonomic", "unicycle"}
        The robot's drive (None: the static scene's robot's, or holonomic); ``holonomic``
        drops a static differential drive's ``wmax`` and ``reverse``.
    reverse : bool
    wmax : float or None
        A differential drive's ``reverse: true`` and turning-rate bound (rad/s); only for a
        robot whose kinematics is unicycle (InputError otherwise, as in a scene file).
    """

    t_start: float | None = None
    duration: float | None = None
    region: tuple[float, float, float, float] | None = None
    scale: float = 1.0
    offset: tuple[float, float] = (0.0, 0.0)
    radius: float = 0.25
    max_movers: int | None = None
    max_gap: float | None = None
    name: str = "pedestrians"
    robot_radius: float | None = None
    vmax: float | None = None
    amax: float | None = None
    kinematics: str | None = None
    reverse: bool = False
    wmax: float | None = None

    def __post_init__(self):
        if self.kinematics not in (None, "holonomic", "unicycle"):
            raise InputError(f"kinematics must be holonomic or unicycle, got {self.kinematics!r}")
        for key in ("t_start", "duration", "scale", "radius", "robot_radius", "vmax", "amax", "wmax"):
            value = getattr(self, key)
            if value is not None and not math.isfinite(value):
                raise InputError(f"{key} must be finite, got {value!r}")
            bound = MAX_RECORDED_TIME if key == "t_start" else MAX_MAGNITUDE  # a recording's own clock
            if value is not None and abs(value) > bound:  # else refused as the written scene's number
                raise InputError(f"{key} must be at most {bound:g} in magnitude, got {value:g}")
        for key in ("duration", "scale", "radius", "robot_radius", "vmax", "amax", "wmax"):
            value = getattr(self, key)
            if value is not None and value <= 0:
                raise InputError(f"{key} must be positive, got {value!r}")
        try:
            off = tuple(self.offset)
        except TypeError:  # one number
            off = (self.offset,)
        if len(off) != 2 or not all(
            isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v) and abs(v) <= MAX_MAGNITUDE
            for v in off
        ):
            raise InputError(f"offset must be two finite numbers dx dy of at most {MAX_MAGNITUDE:g} in magnitude, "
                             f"got {self.offset!r}")  # fmt: skip
        object.__setattr__(self, "offset", tuple(float(v) for v in off))
        if self.max_movers is not None and self.max_movers < 1:  # 0 wrote a scene without the recording's people
            raise InputError(f"max_movers must be at least 1, got {self.max_movers!r}")
        gap = self.max_gap
        if gap is not None and (isinstance(gap, bool) or not (isinstance(gap, numbers.Real) and gap > 0)):
            raise InputError(f"max_gap must be positive (inf: never cut), got {self.max_gap!r}")
        if self.region is not None:
            r = tuple(float(v) for v in self.region)
            if (
                len(r) != 4
                or not all(math.isfinite(v) and abs(v) <= MAX_MAGNITUDE for v in r)
                or not (r[0] < r[2] and r[1] < r[3])
            ):
                raise InputError(
                    f"region must be xmin ymin xmax ymax with xmin < xmax, ymin < ymax (at most {MAX_MAGNITUDE:g} "
                    f"in magnitude), got {self.region!r}"
                )
            object.__setattr__(self, "region", r)
        if not NAME_RE.match(self.name):
            raise InputError(f"name must be letters, digits, _ . - (got {self.name!r})")


@dataclass(frozen=True)
class TrackScene:
    """A scene made from tracks.

    Attributes
    ----------
    doc : dict
        The scene document (``version``, ``name``, ``bounds``, ``robot``, ``obstacles``,
        ``movers``, ``queries``), as :func:`gfuzzy.scene.scene.parse_scene` reads it.
    window : (2,) tuple
        The time window, seconds of the recording.
    region : (4,) tuple
        The scene's bounds.
    source : str
        The tracks' file.
    fps, frame_step
        As in :class:`Tracks`.
    """

    doc: dict
    window: tuple[float, float]
    region: tuple[float, float, float, float]
    source: str
    fps: float | None = None
    frame_step: int | None = None

    @property
    def movers(self) -> int:
        """Number of movers."""
        return len(self.doc["movers"])

    def to_yaml(self, command: str | None = None) -> str:
        """The scene as YAML text, trajectories wrapped in flow style, with a header comment
        saying where it came from (``command``: how it was made, written on line 2)."""
        doc = self.doc
        t0, t1 = self.window
        radius = doc["movers"][0]["disc"] if doc["movers"] else None
        head = [
            f"# Generated by `gfuzzy tracks` from {os.path.basename(self.source)}; do not edit by hand."
        ]
        if command:
            head.append(f"#   {command}")
        if self.frame_step is not None and self.fps is not None:
            head.append(
                f"# {self.fps:g} frames/s (frame step {self.frame_step} = {self.frame_step / self.fps:g} s);"
                f" window {t0:g} s .. {t1:g} s of the recording (t = 0 here is {t0:g} s there)."
            )
        else:
            head.append(
                f"# Window {t0:g} s .. {t1:g} s of the recording (t = 0 here is {t0:g} s there)."
            )
        shape = f" of radius {radius:g}" if radius is not None else ""
        head += [
            f"# {self.movers} pedestrians as disc movers{shape}, clipped to the window and the region;",
            "# each exists only between its first and last row.",
        ]
        out = head + [
            "version: 1",
            f"name: {plain_name(doc['name'])}",
            f"bounds: {_row(doc['bounds'])}",
            "robot:",
        ]
        for key, value in doc["robot"].items():
            out.append(f"  {key}: {_value(value)}")
        if doc["obstacles"]:
            out.append("obstacles:")
            out += [f"  - {_flow(item)}" for item in doc["obstacles"]]
        else:
            out.append("obstacles: []")
        if doc["movers"]:
            out.append("movers:")
            for m in doc["movers"]:
                out.append(f"  - name: {plain_name(m['name'])}")
                out.append(f"    disc: {_num(m['disc'])}")
                out.append("    trajectory: " + _flow_rows(m["trajectory"], "    "))
        else:
            out.append("movers: []")
        if doc.get("queries"):
            out.append("queries:")
            for q in doc["queries"]:
                out.append(f"  - name: {plain_name(q['name'])}")
                out += [
                    f"    start: {_row(q['start'])}",
                    f"    goal: {_row(q['goal'])}",
                    f"    t0: {_num(q['t0'])}",
                ]
                if q.get("expect"):
                    out.append("    expect:")
                    for key, value in q["expect"].items():
                        out.append(
                            f"      {key}: {value if isinstance(value, str) else f'{value:g}'}"
                        )
        return "\n".join(out) + "\n"


def _num(v: float) -> str:
    v = float(v)
    return repr(v if v != 0 else 0.0)  # never "-0.0"


def _row(r) -> str:
    return "[" + ", ".join(_num(v) for v in r) + "]"


def _value(v) -> str:
    if isinstance(v, bool) or v is None:
        return _flow(v)
    if isinstance(v, (int, float)):
        return _num(v)
    if isinstance(v, (list, tuple)) and all(isinstance(x, (int, float)) for x in v):
        return _row(v)
    return _flow(v)


def _flow(item) -> str:
    # dumped inside a list: a plain scalar dumped alone ends with the document-end marker
    # ("unicycle\n...": a robot's `kinematics: unicycle` made the scene unreadable)
    text = dump_yaml([item], default_flow_style=True, width=10**9, sort_keys=False).strip()
    return text[1:-1]


def _flow_rows(rows, indent: str, width: int = 100) -> str:
    """A YAML flow sequence of rows, wrapped over several lines."""
    parts = [_row(r) for r in rows]
    lines, cur = [], "["
    for i, p in enumerate(parts):
        piece = p + ("," if i < len(parts) - 1 else "]")
        if len(cur) + len(piece) + 1 > width - len(indent) and cur != "[":
            lines.append(cur)
            cur = indent + "  " + piece
        else:
            cur = cur + ("" if cur.endswith("[") else " ") + piece
    lines.append(cur)
    return "\n".join(lines)


def _static_obstacles(static: Scene, folder: Path) -> list:
    """The static scene's obstacles, with mesh and map paths made relative to ``folder``."""
    src_folder = Path(static.source).resolve().parent
    out = []
    for i, item in enumerate(static.raw.get("obstacles") or []):
        item = dict(item)
        kind = next((k for k in ("mesh", "map") if k in item), None)
        if kind is not None:
            spec = dict(item[kind])
            target = (src_folder / spec["file"]).resolve()
            rel = os.path.relpath(target, folder.resolve())
            if leaves_folder(rel):
                raise SceneError(
                    static.source,
                    f"obstacles[{i}].{kind}.file",
                    f"{target} would lie outside the new scene's folder {folder}; write the scene beside it",
                )
            spec["file"] = Path(rel).as_posix()
            item[kind] = spec
        out.append(item)
    return out


def _default_region(tracks: list, t_lo: float, t_hi: float):
    xs, ys = [], []
    for rows in tracks:
        clipped = _clip_time(rows, t_lo, t_hi)
        xs += [r[1] for r in clipped]
        ys += [r[2] for r in clipped]
    if not xs:
        return None
    m = REGION_MARGIN
    return (
        math.floor((min(xs) - m) * 10) / 10,
        math.floor((min(ys) - m) * 10) / 10,
        math.ceil((max(xs) + m) * 10) / 10,
        math.ceil((max(ys) + m) * 10) / 10,
    )


def _window(tracks: Tracks, options: TrackSceneOptions):
    """Each person's rows, scaled and offset, with times relative to the window's start; the window."""
    src = tracks.source
    first, last = tracks.time_range
    t_lo = first if options.t_start is None else options.t_start
    t_hi = last if options.duration is None else t_lo + options.duration
    if t_hi <= t_lo:
        raise SceneError(
            src,
            "",
            f"the window {t_lo:g} s .. {t_hi:g} s is empty (the recording ends at {last:g} s)",
        )
    if t_hi - t_lo > MAX_MAGNITUDE:  # the scene's times start at the window's start
        raise SceneError(
            src,
            "",
            f"the window {t_lo:g} s .. {t_hi:g} s is longer than {MAX_MAGNITUDE:g} s: give --t-start and --duration",
        )
    scale, (dx, dy) = options.scale, options.offset
    rel = {
        tr.id: [(t - t_lo, x * scale + dx, y * scale + dy) for t, x, y in tr.rows.tolist()]
        for tr in sorted(tracks.tracks, key=lambda tr: _id_key(tr.id))
    }
    duration = t_hi - t_lo
    counts = [len(_clip_time(rows, 0.0, duration)) for rows in rel.values()]
    if not any(n >= 2 for n in counts):
        once = sum(n == 1 for n in counts)  # every row a different person's: say so, not "nobody"
        raise SceneError(
            src,
            "",
            _seen_once(once, f"in the window {t_lo:g} s .. {t_hi:g} s") if once else
            f"no pedestrian in the window {t_lo:g} s .. {t_hi:g} s (the recording spans {first:g} .. {last:g} s)",
        )
    return rel, t_lo, t_hi


def _seen_once(n: int, where: str) -> str:
    """The error for a window (or region) whose ``n`` people are each seen at one instant only."""
    return (f"{n} pedestrian(s) {where}, each seen at one instant only: a mover needs two rows or more "
            "(someone standing still: a row at the first time and one at the last)")


def robot_dof(static: Scene | None, robot_radius: float | None, kinematics: str | None = None) -> int:
    """The pose length of the scene's robot: 3 for a box, a footprint or any unicycle, 2 for
    a holonomic disc. Its shape: the static scene's robot's, or the disc of ``robot_radius``
    that replaces it; its drive: ``kinematics``, or without it the static robot's."""
    if kinematics is None:
        unicycle = static is not None and static.robot.unicycle
    else:
        unicycle = kinematics == "unicycle"
    disc = static is None or robot_radius is not None or static.robot.shape == "disc"
    return 3 if unicycle or not disc else 2


def _robot_doc(options: TrackSceneOptions, static: Scene | None):
    """The ``robot:`` mapping (the static scene's, or a disc keeping its speed and
    clearances, with the options' drive), its pose dimension, and its inradius."""
    base = dict(static.raw["robot"]) if static is not None else {"vmax": 1.5, "amax": 3.0}
    if static is not None and options.robot_radius is None:
        robot, inradius = base, static.robot.inradius
    else:
        robot = {"disc": options.robot_radius if options.robot_radius is not None else 0.2}
        robot.update({k: v for k, v in base.items() if k not in ("disc", "box", "footprint")})
        inradius = robot["disc"]
    for key in ("vmax", "amax"):
        if getattr(options, key) is not None:
            robot[key] = getattr(options, key)
    if options.kinematics == "holonomic":  # a static differential drive made holonomic
        for key in ("kinematics", "wmax", "reverse"):
            robot.pop(key, None)
    elif options.kinematics == "unicycle":
        robot["kinematics"] = "unicycle"
    if options.wmax is not None:
        robot["wmax"] = options.wmax
    if options.reverse:
        robot["reverse"] = True
    if robot.get("kinematics") != "unicycle":  # the scene file's rule: only a differential drive's
        for key, flag in (("wmax", "--wmax"), ("reverse", "--reverse")):
            if getattr(options, key):
                raise InputError(f"{key} ({flag}) needs a differential drive: kinematics unicycle (--kinematics "
                                 "unicycle, or a --static scene whose robot is one)")  # fmt: skip
    robot = {
        k: float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else v
        for k, v in robot.items()
    }
    return robot, robot_dof(static, options.robot_radius, options.kinematics), inradius


def _query_docs(start, goal, query_name, expect, dof, inradius, region, src) -> list:
    """The ``queries:`` list: one query from ``start`` to ``goal`` at t0 = 0, or none."""
    queries = []
    if (start is None) != (goal is None):
        raise InputError("start and goal go together")
    if start is None and expect:  # else dropped without a word: there is no query to fill in
        raise InputError("expect (--expect, --max-duration) fills in the query of start and goal (--start, --goal): give them too")
    if start is not None:
        if not NAME_RE.match(query_name):
            raise InputError(f"query name must be letters, digits, _ . - (got {query_name!r})")
        start, goal = [float(v) for v in start], [float(v) for v in goal]
        for label, pose in (("start", start), ("goal", goal)):
            if len(pose) != dof:
                raise InputError(f"{label}: expected {dof} numbers {pose_words(dof)}, got {len(pose)}")
            x, y = pose[:2]
            if not (
                region[0] + inradius <= x <= region[2] - inradius
                and region[1] + inradius <= y <= region[3] - inradius
            ):
                raise SceneError(
                    src,
                    "",
                    f"{label} {x:g} {y:g} does not fit in the region {' '.join(f'{v:g}' for v in region)}",
                )
        query = {"name": query_name, "start": start, "goal": goal, "t0": 0.0}
        if expect:
            unknown = set(expect) - {"status", "max_duration", "max_delay_factor"}
            if unknown or expect.get("status", "solved") not in STATUSES:
                raise InputError(f"expect: not allowed: {expect!r}")
            query["expect"] = dict(expect)
        queries.append(query)

    return queries


def _split_gaps(pid: str, rows, max_gap: float | None, own: list, t_lo: float) -> list[list]:
    """``rows`` cut where two consecutive rows are more than ``max_gap`` seconds apart (None:
    :data:`GAP_PERIODS` times the median time between the person's ``own`` rows, the whole
    track's); each cut logged at the recording's time (the rows' times are relative to the
    window's start ``t_lo``)."""
    if max_gap is None:
        steps = [b[0] - a[0] for a, b in pairwise(own)]
        max_gap = GAP_PERIODS * statistics.median(steps) if steps else math.inf
    runs = [[rows[0]]]
    for a, b in pairwise(rows):
        if b[0] - a[0] > max_gap:
            log.warning("ped-%s unseen for %g s from t = %g s (more than %g s): absent in between, the rows "
                        "before and after are separate movers (--max-gap)", pid, b[0] - a[0], t_lo + a[0], max_gap)
            runs.append([])
        runs[-1].append(b)
    return runs


def _movers(rel: dict, t_lo: float, duration: float, region, options: TrackSceneOptions, src) -> list:
    """Every person's runs inside the window and the region, as movers, in order of
    appearance (the ``max_movers`` present longest when that is set). A person inside
    whose every run is one row once rounded to 1 ms is dropped with a warning (at the
    recording's time: ``rel``'s are relative to the window's start ``t_lo``)."""
    movers: list[_Mover] = []
    once = 0
    taken = {f"ped-{pid}" for pid in rel}  # each person's own name (a part's 'ped-<id>-<k>' is no other's)
    for pid, own in rel.items():
        rows = _clip_time(own, 0.0, duration)
        seen = _split_gaps(pid, rows, options.max_gap, own, t_lo) if rows else []
        runs = [_round_rows(run) for part in seen for run in _clip_region(part, region)]
        kept = [run for run in runs if len(run) >= 2]
        if runs and not kept:  # a person seen once is not a motion: dropped, but never silently
            once += 1
            log.warning("ped-%s is seen at one instant only in the window (t = %g s): dropped (a mover needs two "
                        "rows or more)", pid, t_lo + runs[0][0][0])
        k = 1
        for i, run in enumerate(kept):  # numbered as kept, past another person's name (id '4-2': 4's is 4-3)
            if i:
                k += 1
                while f"ped-{pid}-{k}" in taken:
                    k += 1
            movers.append(_Mover(f"ped-{pid}-{k}" if i else f"ped-{pid}", pid, run))
    if not movers:
        where = f"inside the region {' '.join(f'{v:g}' for v in region)}"
        raise SceneError(src, "", _seen_once(once, f"{where} during the window") if once else
                         f"no pedestrian {where} during the window")  # fmt: skip
    if options.max_movers is not None and len(movers) > options.max_movers:
        keep = sorted(movers, key=lambda m: (-m.duration, _id_key(m.pid), m.rows[0][0]))[
            : options.max_movers
        ]
        kept = {id(m) for m in keep}
        movers = [m for m in movers if id(m) in kept]
    movers.sort(key=lambda m: (m.rows[0][0], _id_key(m.pid), m.name))
    return movers


def _warn_units(movers: list, src: str) -> None:
    """Log when the people's speeds say the file's units are not seconds and metres
    (``PLAUSIBLE_SPEEDS``): too slow when every step of every person is (times in
    milliseconds slow all of them a thousandfold; a queue, or a plaza of people standing
    still with one walker, has brisk steps and is no alarm); too fast when the mean speeds'
    median (each mover's path length over its duration) is."""
    speeds, fast = [], 0.0
    for m in movers:
        if m.duration > 0:
            steps = [(math.hypot(b[1] - a[1], b[2] - a[2]), b[0] - a[0]) for a, b in pairwise(m.rows)]
            speeds.append(sum(d for d, _ in steps) / m.duration)
            fast = max([fast] + [d / dt for d, dt in steps if dt > 0])
    if not speeds:
        return
    median = statistics.median(speeds)
    if fast < PLAUSIBLE_SPEEDS[0]:
        log.warning("%s: the people's steps are at most %.3g m/s (pedestrians walk 0.5-2 m/s): are the times in seconds? "
                    "(t in milliseconds: divide it by 1000; frame numbers: --format eth --fps)", src, fast)  # fmt: skip
    elif median > PLAUSIBLE_SPEEDS[1]:
        log.warning("%s: the people walk at a median %.3g m/s (pedestrians walk 0.5-2 m/s): are the positions in metres "
                    "(centimetres: --scale 0.01) and the times in seconds?", src, median)  # fmt: skip


def _warn_overlaps(queries: list, movers: list, distance: float) -> None:
    """Log a start or goal closer than ``distance`` to a person at t0 = 0."""
    for q in queries:
        for label in ("start", "goal"):
            x, y = q[label][:2]
            for m in movers:
                p = m.position_at(0.0)
                if p and math.hypot(p[0] - x, p[1] - y) < distance:
                    log.warning("the %s overlaps %s at t0 = 0", label, m.name)



def tracks_scene(
    tracks: Tracks,
    options: TrackSceneOptions | None = None,
    *,
    static: Scene | None = None,
    folder: str | os.PathLike | None = None,
    start=None,
    goal=None,
    query_name: str = "cross",
    expect: dict | None = None,
) -> TrackScene:
    """Clip tracks to a time window and a region, and make them the movers of a scene.

    Each person becomes a disc mover ``ped-<id>`` with a timed trajectory, times relative
    to the window's start. A track is cut at the window's ends and at the region's border
    (rows interpolated there); a person who leaves the region and comes back, or is unseen
    for more than ``max_gap``, becomes ``ped-<id>``, ``ped-<id>-2``, ... Rows are rounded to 1 mm and 1 ms (a row whose time no
    longer increases is dropped) and a mover left with fewer than two rows is dropped.

    Parameters
    ----------
    tracks : Tracks
    options : TrackSceneOptions, optional
    static : Scene, optional
        A scene whose robot, static obstacles and bounds (as the default region) are used.
    folder : path-like, optional
        The folder the scene will be written to (mesh paths of ``static`` are rewritten
        relative to it); default the current directory.
    start, goal : sequence of float, optional
        A query from ``start`` to ``goal`` at t0 = 0, named ``query_name``; both or neither.
    expect : dict, optional
        The query's ``expect`` mapping (``status``, ``max_duration``, ``max_delay_factor``).

    Returns
    -------
    TrackScene

    Raises
    ------
    SceneError
        No person in the window (or in the region), or a start/goal outside the region;
        the message names the tracks' file.
    InputError
        ``start`` without ``goal``, a query name or expectation that is not allowed.
    """
    options = options or TrackSceneOptions()
    src = tracks.source
    rel, t_lo, t_hi = _window(tracks, options)
    duration = t_hi - t_lo
    region = options.region
    if region is None and static is not None:
        region = tuple(static.bounds)
    if region is None:
        region = _default_region(list(rel.values()), 0.0, duration)
    region = tuple(float(v) for v in region)
    robot, dof, inradius = _robot_doc(options, static)
    queries = _query_docs(start, goal, query_name, expect, dof, inradius, region, src)
    movers = _movers(rel, t_lo, duration, region, options, src)
    _warn_units(movers, src)
    _warn_overlaps(queries, movers, inradius + options.radius)
    doc = {
        "version": 1,
        "name": options.name,
        "bounds": list(region),
        "robot": robot,
        "obstacles": _static_obstacles(static, Path(folder or ".")) if static is not None else [],
        "movers": [
            {"name": m.name, "disc": float(options.radius), "trajectory": [list(r) for r in m.rows]}
            for m in movers
        ],
        "queries": queries,
    }
    return TrackScene(doc, (t_lo, t_hi), region, src, tracks.fps, tracks.frame_step)
