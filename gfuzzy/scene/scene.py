"""Scene files: bounds, robot, static obstacles, movers and queries (docs/formats.md section 1).

:func:`load_scene` reads a YAML file with ``yaml.safe_load`` semantics, validates every
field and returns an immutable :class:`Scene`. Anything wrong raises
:class:`~gfuzzy.errors.SceneError` naming the file and the place in it, e.g.
``movers[2].path[1]``.
"""

from __future__ import annotations

import copy
import hashlib
import json
import logging
import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, SceneError, not_utf8
from ..poses import as_number, pose_words
from ..status import Status
from ..typed import FloatArray
from . import yamldoc
from .maps import MapObstacle, load_map
from .meshes import mesh_footprint
from .sanity import warn_beyond_maps, warn_units
from .yamldoc import _V, MAX_MAGNITUDE, NAME_RE, _join, _kind, _load_yaml, _one_key

log = logging.getLogger(__name__)

__all__ = [
    "Robot",
    "Disc",
    "Box",
    "Polygon",
    "MapObstacle",
    "Mover",
    "Query",
    "Expect",
    "Scene",
    "load_scene",
    "parse_scene",
]

MODES = ("loop", "bounce", "once")
KINEMATICS = ("holonomic", "unicycle")
STATUSES = tuple(s.value for s in Status)  # the file format spells them as strings


# --------------------------------------------------------------------------- shapes


@dataclass(frozen=True)
class Robot:
    """The robot: a disc (poses ``[x, y]``), a box or a footprint polygon (poses
    ``[x, y, heading]``). :mod:`gfuzzy.collision.shapes` holds the geometry of each shape.

    Attributes
    ----------
    shape : {"disc", "box", "footprint"}
    radius : float
        Disc radius (0 otherwise).
    size : (2,) tuple
        Box ``(length, width)``, length along the heading ((0, 0) otherwise).
    vmax : float
        Bound on configuration speed (euclidean xy speed + |heading rate| * circumradius).
    amax : float or None
        Optional acceleration bound, used by the speed layer.
    clearance : float
        Distance every answer keeps from static obstacles (not from the bounds), metres.
    mover_clearance : float
        Distance every answer keeps from every present mover, metres.
    kinematics : {"holonomic", "unicycle"}
        ``unicycle``: a differential drive; poses are ``[x, y, heading]`` for every shape and
        answers are waits, turns in place and straight moves along the heading.
    wmax : float or None
        Unicycle: bound on |turning rate| (rad/s); None: vmax / circumradius.
    reverse : bool
        Unicycle: may it drive backwards.
    footprint : tuple of (x, y)
        A footprint robot's simple polygon in its own frame (x forward, y left),
        counter-clockwise; empty for a disc or a box.
    """

    shape: str
    radius: float
    size: tuple[float, float]
    vmax: float
    amax: float | None = None
    clearance: float = 0.0
    mover_clearance: float = 0.0
    kinematics: str = "holonomic"
    wmax: float | None = None
    reverse: bool = False
    footprint: tuple[tuple[float, float], ...] = ()

    @property
    def unicycle(self) -> bool:
        """True for a differential drive (``kinematics: unicycle``, CONTRACT section 6)."""
        return self.kinematics == "unicycle"

    @property
    def turn_rate(self) -> float:
        """Largest turning rate a unicycle may use, rad/s: ``wmax`` (default vmax / r),
        never above vmax / r (the speed bound of a turn in place)."""
        bound = self.vmax / self.circumradius
        return bound if self.wmax is None else min(float(self.wmax), bound)

    @property
    def circumradius(self) -> float:
        """Radius of the smallest disc about the reference point holding the whole robot."""
        if self.shape == "disc":
            return self.radius
        if self.shape == "footprint":
            return max(math.hypot(x, y) for x, y in self.footprint)
        return 0.5 * math.hypot(*self.size)

    @property
    def half_turn_symmetric(self) -> bool:
        """Whether the robot is the same body turned by pi about its reference point: a
        disc, a box, a footprint whose vertices negated are its vertices in the same cyclic
        order (exactly; the same vertex set in another order is another polygon)."""
        if self.shape != "footprint":
            return True
        fp = [tuple(p) for p in self.footprint]
        neg = [(-x + 0.0, -y + 0.0) for x, y in fp]
        return any(neg == fp[k:] + fp[:k] for k in range(len(fp)))

    @property
    def inradius(self) -> float:
        """Radius of the largest disc about the reference point inside the robot (0 when
        the reference point is outside a footprint)."""
        if self.shape == "footprint":
            return footprint_inradius(self.footprint)
        return self.radius if self.shape == "disc" else 0.5 * min(self.size)

    @property
    def dof(self) -> int:
        """Length of a pose: 2 for a holonomic disc, 3 for a box or any unicycle."""
        return 3 if self.unicycle else self.space_dof

    @property
    def space_dof(self) -> int:
        """Dimension of the roadmap's configuration space: 2 for a disc (R^2), 3 otherwise
        (SE(2)); a unicycle disc has 3-number poses on an R^2 roadmap."""
        return 2 if self.shape == "disc" else 3

    def corners(self, poses: FloatArray) -> FloatArray:
        """Corners of a box robot (or a footprint's vertices), counter-clockwise.

        Parameters
        ----------
        poses : (n, 3) float

        Returns
        -------
        (n, 4, 2) float
            (n, k, 2) for a footprint of k vertices.
        """
        poses = np.asarray(poses, dtype=float).reshape(-1, 3)
        if self.shape == "footprint":
            local = np.array(self.footprint, dtype=float)
        else:
            hl, hw = 0.5 * self.size[0], 0.5 * self.size[1]
            local = np.array([[hl, hw], [-hl, hw], [-hl, -hw], [hl, -hw]])
        c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
        rot = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)  # (n, 2, 2)
        return poses[:, None, :2] + np.einsum("nij,kj->nki", rot, local)


def footprint_inradius(points) -> float:
    """Distance from the origin to the outline of the simple polygon ``points`` (k, 2)
    when the origin is strictly inside it, else 0 (crossing-number test)."""
    P = np.asarray(points, dtype=float)
    Q = np.roll(P, -1, axis=0)
    crosses = (P[:, 1] > 0) != (Q[:, 1] > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_at = P[:, 0] + (0.0 - P[:, 1]) * (Q[:, 0] - P[:, 0]) / (Q[:, 1] - P[:, 1])
    inside = int(np.count_nonzero(crosses & (x_at > 0))) % 2 == 1
    e = Q - P
    t = np.clip(-(P * e).sum(1) / np.maximum((e * e).sum(1), 1e-300), 0.0, 1.0)
    dist = float(np.hypot(*(P + t[:, None] * e).T).min())
    return dist if inside and dist > 0 else 0.0


@dataclass(frozen=True)
class Disc:
    """A static disc obstacle."""

    center: tuple[float, float]
    radius: float


@dataclass(frozen=True)
class Box:
    """A static box obstacle rotated by ``angle`` radians about its center."""

    center: tuple[float, float]
    size: tuple[float, float]
    angle: float = 0.0

    def vertices(self) -> FloatArray:
        """(4, 2) float: corners, counter-clockwise."""
        hx, hy = 0.5 * self.size[0], 0.5 * self.size[1]
        c, s = math.cos(self.angle), math.sin(self.angle)
        local = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
        return local @ np.array([[c, s], [-s, c]]) + np.asarray(self.center)


@dataclass(frozen=True)
class Polygon:
    """A static simple polygon; ``holes`` only arise from mesh footprints.

    Attributes
    ----------
    points : (n, 2) float, counter-clockwise
    holes : tuple of (k, 2) float
    source : str
        ``"polygon"`` for a scene polygon, or the mesh file it came from.
    """

    points: FloatArray = field(compare=False)
    holes: tuple = field(default=(), compare=False)
    source: str = "polygon"


@dataclass(frozen=True)
class Mover:
    """A moving obstacle: a disc, or an axis-aligned box that does not rotate.

    Either ``path`` (constant ``speed`` along a polyline, ``mode`` loop / bounce / once,
    ``offset`` arc length travelled at t = 0) or ``trajectory`` (``[t, x, y]`` rows,
    linear between rows, present only from the first to the last t).
    """

    name: str
    shape: str  # "disc" | "box"
    radius: float  # disc radius, 0 for a box
    size: tuple[float, float]  # box (w, h), (0, 0) for a disc
    path: FloatArray | None = field(default=None, compare=False)
    speed: float = 0.0
    mode: str = "loop"
    offset: float = 0.0
    trajectory: FloatArray | None = field(default=None, compare=False)

    @property
    def extent(self) -> float:
        """Circumradius of the mover's shape about its reference point."""
        return self.radius if self.shape == "disc" else 0.5 * math.hypot(*self.size)

    @property
    def time_range(self) -> tuple[float, float]:
        """Times between which the mover exists (infinite for a path mover)."""
        if self.trajectory is None:
            return (-math.inf, math.inf)
        return (float(self.trajectory[0, 0]), float(self.trajectory[-1, 0]))

    @property
    def max_speed(self) -> float:
        """Largest speed the mover ever has."""
        if self.trajectory is None:
            return self.speed
        tr = self.trajectory
        if len(tr) < 2:
            return 0.0
        d = np.hypot(*np.diff(tr[:, 1:], axis=0).T)
        return float(np.max(d / np.diff(tr[:, 0])))

    @property
    def period(self) -> float:
        """Period of the motion (inf when it is not periodic or stands still)."""
        if self.trajectory is not None or self.mode == "once" or self.speed == 0:
            return math.inf
        length = float(self._cumlen[-1])
        return (length if self.mode == "loop" else 2 * length) / self.speed

    @property
    def rest_time(self) -> float:
        """Time from which the mover stands still for ever: a ``once`` mover at its path's end,
        -inf for speed 0, inf for one that keeps moving or a trajectory mover (it leaves)."""
        if self.trajectory is not None or (self.mode != "once" and self.speed > 0):
            return math.inf
        return (float(self._cumlen[-1]) - self.offset) / self.speed if self.speed > 0 else -math.inf

    @property
    def _polyline(self) -> FloatArray:
        pts = self.path
        if self.mode == "loop" and np.any(pts[0] != pts[-1]):
            pts = np.vstack([pts, pts[:1]])
        return pts

    @property
    def _cumlen(self) -> FloatArray:
        pts = self._polyline
        return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])

    def bbox(self) -> tuple[float, float, float, float]:
        """Box swept by the mover's reference point over all time (without its shape)."""
        pts = self.path if self.trajectory is None else self.trajectory[:, 1:]
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))

    def arc_position(self, times: FloatArray) -> FloatArray:
        """Arc length along the (closed, for loop) polyline at ``times``; path movers only."""
        cum = self._cumlen
        length = cum[-1]
        s = self.offset + self.speed * np.asarray(times, dtype=float)
        if self.mode == "loop":
            return np.mod(s, length)
        if self.mode == "bounce":
            s = np.mod(s, 2 * length)
            return np.where(s > length, 2 * length - s, s)
        return np.clip(s, 0.0, length)

    def state(self, times: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Positions and presence at ``times``.

        Parameters
        ----------
        times : (n,) float

        Returns
        -------
        xy : (n, 2) float
            Reference point; for a trajectory mover outside its time range, the
            position clamped to its first or last row.
        present : (n,) bool
        """
        times = np.atleast_1d(np.asarray(times, dtype=float))
        if self.trajectory is not None:
            tr = self.trajectory
            x = np.interp(times, tr[:, 0], tr[:, 1])
            y = np.interp(times, tr[:, 0], tr[:, 2])
            present = (times >= tr[0, 0]) & (times <= tr[-1, 0])
            return np.stack([x, y], axis=-1), present
        pts, cum = self._polyline, self._cumlen
        s = self.arc_position(times)
        x = np.interp(s, cum, pts[:, 0])
        y = np.interp(s, cum, pts[:, 1])
        return np.stack([x, y], axis=-1), np.ones(times.shape, dtype=bool)


@dataclass(frozen=True)
class Expect:
    """Expectations of a regression run; every field optional."""

    status: str | None = None
    max_duration: float | None = None
    max_delay_factor: float | None = None


@dataclass(frozen=True)
class Query:
    """A planning query; ``start``/``goal`` have the robot's pose length.

    ``hold`` (seconds): the robot parks at the goal this long after arriving, and the
    answer keeps the goal pose safe over ``[arrival, arrival + hold]``.
    """

    name: str
    start: tuple[float, ...]
    goal: tuple[float, ...]
    t0: float = 0.0
    expect: Expect | None = None
    hold: float = 0.0


@dataclass(frozen=True)
class Scene:
    """A validated scene.

    Attributes
    ----------
    name : str
    bounds : (4,) tuple
        ``(xmin, ymin, xmax, ymax)``.
    robot : Robot
    obstacles : tuple of Disc, Box, Polygon
    movers : tuple of Mover
    queries : tuple of Query
    source : str
        The file it was read from (``"<string>"`` when parsed from text).
    static_hash : str
        SHA-256 of everything a roadmap depends on (bounds, robot shape, its static
        clearance when not 0, obstacles, mesh contents); editing movers or queries keeps it.
    raw : dict
        The validated document, for round trips.
    """

    name: str
    bounds: tuple[float, float, float, float]
    robot: Robot
    obstacles: tuple
    movers: tuple
    queries: tuple
    source: str = "<string>"
    static_hash: str = ""
    raw: dict = field(default_factory=dict, compare=False, repr=False)
    shape_hash: str = field(default="", compare=False, repr=False)  # static_hash without the clearance

    def query(self, name: str) -> Query:
        """The query called ``name``; raises KeyError listing the names there are."""
        for q in self.queries:
            if q.name == name:
                return q
        names = ", ".join(q.name for q in self.queries) or "none"
        raise KeyError(f"no query {name!r} in {self.source} (queries: {names})")

    def mover_states(self, times: FloatArray) -> tuple[FloatArray, FloatArray]:
        """All movers' positions and presence at ``times``.

        Parameters
        ----------
        times : (n,) float

        Returns
        -------
        xy : (m, n, 2) float
        present : (m, n) bool
        """
        times = np.atleast_1d(np.asarray(times, dtype=float))
        m = len(self.movers)
        xy = np.empty((m, times.size, 2))
        present = np.empty((m, times.size), dtype=bool)
        for i, mover in enumerate(self.movers):
            xy[i], present[i] = mover.state(times)
        return xy, present

    def to_dict(self) -> dict:
        """The scene as a plain document that :func:`parse_scene` reads back."""
        return json.loads(json.dumps(self.raw))

    def with_clearances(self, clearance: float | None = None, mover_clearance: float | None = None) -> Scene:
        """This scene with the robot's clearances replaced (None keeps a value).

        A new static clearance changes :attr:`static_hash`: roadmaps built for the other
        clearance no longer match.

        Raises
        ------
        ValueError
            When a value is negative or not finite.
        """
        robot = self.robot
        new = {}
        for key, value in (("clearance", clearance), ("mover_clearance", mover_clearance)):
            if value is None:
                continue
            number = as_number(value)  # not "0.1", not True; a Decimal or a 0-d array is one
            if number is None or not (math.isfinite(number) and 0.0 <= number <= MAX_MAGNITUDE):
                raise InputError(f"robot.{key} must be a non-negative finite number, got {value!r}")
            new[key] = number
        robot = replace(robot, **new)
        raw = copy.deepcopy(self.raw)
        if isinstance(raw.get("robot"), dict):
            raw["robot"].update(new)
        base = self.shape_hash or self.static_hash
        return replace(self, robot=robot, raw=raw, static_hash=_static_hash(base, robot.clearance))


#: The least span (metres, along x or y) of a polygon: one spanning less has an area below
#: the 1e-12 m² a polygon needs, and is refused as too small before its shape is examined.
MIN_POLYGON_SPAN = 1e-6


def _check_polygon(v: _V, pts: FloatArray, place: str) -> FloatArray:
    import shapely

    if len(pts) < 3:
        v.fail(place, f"a polygon needs at least 3 points, got {len(pts)}")
    extent = float(np.ptp(pts, axis=0).max())
    if extent <= MIN_POLYGON_SPAN:  # below the area's bound whatever its shape: GEOS saw 1e-300 m cross itself
        v.fail(place, f"polygon is degenerate: too small (it spans {extent:g} m; more than {MIN_POLYGON_SPAN:g} m needed)")
    if np.allclose(pts[0], pts[-1]) and len(pts) > 3:
        pts = pts[:-1]
    # a refused ring whose points lie on one line folds back on itself: say so, not that it
    # crosses itself (only the message: a sliver 1.5e-9 thick is a polygon as before)
    spread = np.linalg.svd(pts - pts.mean(axis=0), compute_uv=False)
    collinear = spread[1] <= 1e-9 * spread[0]
    ring = shapely.LinearRing(pts)
    poly = shapely.Polygon(pts)
    if not ring.is_simple or not poly.is_valid or poly.area <= 1e-12:
        if collinear:
            v.fail(place, "polygon is degenerate: its points are collinear (zero area)")
        if not ring.is_simple:
            v.fail(place, "polygon is self-intersecting")
        v.fail(place, "polygon is degenerate (zero area)")
    x, y = pts[:, 0], pts[:, 1]
    signed = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    return pts if signed > 0 else pts[::-1].copy()


def _parse_robot(v: _V, rd) -> tuple[Robot, dict]:
    """``robot:``: the Robot, and its shape as it enters the static hash."""
    rd = v.mapping(
        rd,
        "robot",
        required=("vmax",),
        optional=("disc", "box", "footprint", "amax", "clearance", "mover_clearance", "kinematics", "wmax", "reverse"),
    )
    given = [k for k in ("disc", "box", "footprint") if k in rd]
    if len(given) != 1:
        v.fail("robot", "give exactly one of disc, box or footprint" + (f", not {' and '.join(given)}" if given else ""))
    footprint: tuple = ()
    if "disc" in rd:
        robot_shape, radius, size = "disc", v.number(rd["disc"], "robot.disc", positive=True), (0.0, 0.0)
    elif "box" in rd:
        robot_shape, radius = "box", 0.0
        size = v.vector(rd["box"], "robot.box", 2, positive=True)
    else:
        robot_shape, radius, size = "footprint", 0.0, (0.0, 0.0)
        pts = _check_polygon(v, v.points(rd["footprint"], "robot.footprint", min_rows=3), "robot.footprint")
        footprint = tuple((float(x), float(y)) for x, y in pts)
    vmax = v.number(rd["vmax"], "robot.vmax", positive=True)
    amax = v.number(rd["amax"], "robot.amax", positive=True) if "amax" in rd else None
    clear = v.number(rd.get("clearance", 0.0), "robot.clearance", nonneg=True)
    mover_clear = v.number(rd.get("mover_clearance", 0.0), "robot.mover_clearance", nonneg=True)
    kin = rd.get("kinematics", "holonomic")
    if kin not in KINEMATICS:
        v.fail("robot.kinematics", f"unknown kinematics {kin!r} (allowed: {', '.join(KINEMATICS)})")
    for key in ("wmax", "reverse"):
        if key in rd and kin != "unicycle":
            v.fail(f"robot.{key}", "only for kinematics: unicycle")
    wmax = v.number(rd["wmax"], "robot.wmax", positive=True) if "wmax" in rd else None
    reverse = rd.get("reverse", False)
    if not isinstance(reverse, bool):
        v.fail("robot.reverse", f"expected true or false, got {_kind(reverse)}")
    robot = Robot(robot_shape, radius, size, vmax, amax, clear, mover_clear, kin, wmax, reverse, footprint)
    shape_repr = {"shape": robot_shape, "radius": radius, "size": list(size)}
    if footprint:  # only then: the static hash of disc and box scenes is unchanged
        shape_repr["footprint"] = [list(p) for p in footprint]
    return robot, shape_repr


def _parse_obstacles(v: _V, doc: dict, folder: Path, hasher) -> list:
    """``obstacles:``; mesh files' bytes go into ``hasher`` (the static hash)."""
    obstacles: list = []
    obs_doc = doc.get("obstacles") or []
    if "obstacles" in doc and doc["obstacles"] is not None and not isinstance(doc["obstacles"], list):
        v.fail("obstacles", f"expected a list, got {_kind(doc['obstacles'])}")
    for i, item in enumerate(obs_doc):
        place = f"obstacles[{i}]"
        kind, spec = _one_key(v, item, place, ("box", "disc", "polygon", "mesh", "map"))
        kplace = _join(place, kind)
        if kind == "map":
            grid = load_map(spec, kplace, v.file, folder)
            hasher.update(bytes.fromhex(grid.digest))
            obstacles.append(grid)
        elif kind == "box":
            spec = v.mapping(spec, kplace, required=("center", "size"), optional=("angle",))
            obstacles.append(
                Box(
                    v.vector(spec["center"], _join(kplace, "center"), 2),
                    v.vector(spec["size"], _join(kplace, "size"), 2, positive=True),
                    v.number(spec.get("angle", 0.0), _join(kplace, "angle")),
                )
            )
        elif kind == "disc":
            spec = v.mapping(spec, kplace, required=("center", "radius"))
            obstacles.append(
                Disc(
                    v.vector(spec["center"], _join(kplace, "center"), 2),
                    v.number(spec["radius"], _join(kplace, "radius"), positive=True),
                )
            )
        elif kind == "polygon":
            pts = _check_polygon(v, v.points(spec, kplace, 2, min_rows=3), kplace)
            obstacles.append(Polygon(pts))
        else:
            polys, data = mesh_footprint(v, spec, kplace, folder)
            hasher.update(hashlib.sha256(data).digest())
            for p in polys:
                ext = np.asarray(p.exterior.coords)[:-1]
                holes = tuple(np.asarray(r.coords)[:-1] for r in p.interiors)
                obstacles.append(Polygon(ext, holes, source=spec["file"]))

    return obstacles


def _parse_movers(v: _V, doc: dict) -> list:
    """``movers:``, names unique."""
    movers: list = []
    mov_doc = doc.get("movers") or []
    if doc.get("movers") is not None and not isinstance(doc["movers"], list):
        v.fail("movers", f"expected a list, got {_kind(doc['movers'])}")
    names: set = set()
    for i, md in enumerate(mov_doc):
        movers.append(_parse_mover(v, md, f"movers[{i}]", names))
    return movers


def _parse_mover(v: _V, md, place: str, names: set) -> Mover:
    """One mover: a path mover (speed, mode, offset) or a trajectory mover."""
    if not isinstance(md, dict):
        v.fail(place, f"expected a mapping, got {_kind(md)}")
    timed = "trajectory" in md
    mixed = [k for k in ("path", "speed", "mode", "offset") if k in md]
    if timed and mixed:  # say so, rather than "unknown key" for the first path key
        v.fail(place, f"give either path (with speed and mode) or trajectory, not both (it has trajectory and {', '.join(mixed)})")
    v.mapping(
        md,
        place,
        required=("name",) + (("trajectory",) if timed else ("speed", "path", "mode")),
        optional=("disc", "box") + (() if timed else ("offset",)),
    )
    mname = v.name(md["name"], _join(place, "name"))
    if mname in names:
        v.fail(_join(place, "name"), f"duplicate mover name {mname!r}")
    names.add(mname)
    if ("disc" in md) == ("box" in md):
        v.fail(place, "give exactly one of disc or box")
    if "disc" in md:
        mshape, mrad, msize = "disc", v.number(md["disc"], _join(place, "disc"), positive=True), (0.0, 0.0)
    else:
        mshape, mrad = "box", 0.0
        msize = v.vector(md["box"], _join(place, "box"), 2, positive=True)
    if timed:
        tr = v.timed_rows(md["trajectory"], _join(place, "trajectory"), mname)
        return Mover(mname, mshape, mrad, msize, trajectory=tr)
    else:
        path = v.points(md["path"], _join(place, "path"), 2, min_rows=2)
        if np.sum(np.hypot(*np.diff(path, axis=0).T)) <= 0:
            v.fail(_join(place, "path"), "path has zero length")
        speed = v.number(md["speed"], _join(place, "speed"), nonneg=True)
        mode = md["mode"]
        if mode not in MODES:
            v.fail(_join(place, "mode"), f"unknown mode {mode!r} (allowed: {', '.join(MODES)})")
        offset = v.number(md.get("offset", 0.0), _join(place, "offset"))
        return Mover(mname, mshape, mrad, msize, path=path, speed=speed, mode=mode, offset=offset)


def _parse_queries(v: _V, doc: dict, robot: Robot) -> list:
    """``queries:``, names unique, poses of the robot's dimension."""
    queries: list = []
    q_doc = doc.get("queries") or []
    if doc.get("queries") is not None and not isinstance(doc["queries"], list):
        v.fail("queries", f"expected a list, got {_kind(doc['queries'])}")
    qnames: set = set()
    for i, qd in enumerate(q_doc):
        place = f"queries[{i}]"
        v.mapping(qd, place, required=("name", "start", "goal"), optional=("t0", "hold", "expect"))
        qname = v.name(qd["name"], _join(place, "name"))
        if qname in qnames:
            v.fail(_join(place, "name"), f"duplicate query name {qname!r}")
        qnames.add(qname)
        start = v.vector(qd["start"], _join(place, "start"), robot.dof, words=pose_words(robot.dof, robot))
        goal = v.vector(qd["goal"], _join(place, "goal"), robot.dof, words=pose_words(robot.dof, robot))
        t0 = v.number(qd.get("t0", 0.0), _join(place, "t0"))
        hold = v.number(qd.get("hold", 0.0), _join(place, "hold"), nonneg=True)
        expect = None
        if "expect" in qd:
            eplace = _join(place, "expect")
            ed = v.mapping(qd["expect"], eplace, optional=("status", "max_duration", "max_delay_factor"))
            status = ed.get("status")
            if status is not None and status not in STATUSES:
                v.fail(_join(eplace, "status"), f"unknown status {status!r} (allowed: {', '.join(STATUSES)})")
            md_ = ed.get("max_duration")
            mdf = ed.get("max_delay_factor")
            expect = Expect(
                status,
                None if md_ is None else v.number(md_, _join(eplace, "max_duration"), nonneg=True),
                None if mdf is None else v.number(mdf, _join(eplace, "max_delay_factor"), positive=True),
            )
        queries.append(Query(qname, start, goal, t0, expect, hold))

    return queries


def parse_scene(doc: Any, file: str = "<string>", folder: str | os.PathLike | None = None) -> Scene:
    """Validate a scene document (as from YAML) and build a :class:`Scene`.

    Parameters
    ----------
    doc : dict
        The document as YAML gives it, or built in code: tuples, numpy arrays and numpy
        numbers are read as the lists and numbers they hold.
    file : str
        Name used in error messages.
    folder : path-like, optional
        Folder that mesh paths are relative to (default: the current directory).

    Raises
    ------
    SceneError
        On any bad input, naming ``file`` and the place in it.
    """
    v = _V(file)
    doc = yamldoc.plain_document(doc, file)
    folder = Path(folder) if folder is not None else Path.cwd()
    v.mapping(
        doc,
        "",
        required=("version", "name", "robot"),
        optional=("bounds", "obstacles", "movers", "queries"),
    )
    if doc["version"] != 1 or isinstance(doc["version"], bool):
        v.fail("version", f"unsupported version {doc['version']!r} (this reads version 1)")
    name = v.name(doc["name"], "name", NAME_RE)
    if "bounds" in doc:
        bounds = v.vector(doc["bounds"], "bounds", 4)
        if not (bounds[0] < bounds[2] and bounds[1] < bounds[3]):
            v.fail("bounds", f"inverted or empty bounds {list(bounds)} (need xmin < xmax, ymin < ymax)")

    robot, robot_repr = _parse_robot(v, doc["robot"])
    hasher = hashlib.sha256()
    obstacles = _parse_obstacles(v, doc, folder, hasher)
    grids = [o for o in obstacles if isinstance(o, MapObstacle)]
    if "bounds" in doc:
        warn_beyond_maps(file, bounds, grids)
    else:
        if not grids:
            v.fail("bounds", "missing required key (it may be left out only when the scene has a map)")
        ext = np.array([g.extent for g in grids])
        bounds = (float(ext[:, 0].min()), float(ext[:, 1].min()), float(ext[:, 2].max()), float(ext[:, 3].max()))
    warn_units(file, robot)
    movers = _parse_movers(v, doc)
    queries = _parse_queries(v, doc, robot)

    static = {
        "bounds": list(bounds),
        "robot": robot_repr,
        "obstacles": [_static_repr(o) for o in obstacles],
    }
    hasher.update(json.dumps(static, sort_keys=True).encode())
    shape_hash = hasher.hexdigest()
    return Scene(
        name=name,
        bounds=bounds,
        robot=robot,
        obstacles=tuple(obstacles),
        movers=tuple(movers),
        queries=tuple(queries),
        source=file,
        static_hash=_static_hash(shape_hash, robot.clearance),
        raw=copy.deepcopy(doc),
        shape_hash=shape_hash,
    )


def _static_hash(shape_hash: str, clearance: float) -> str:
    """The roadmap's scene hash: the shapes', plus the static clearance when it is not 0
    (so roadmaps built before clearances existed still match a scene without one)."""
    if clearance == 0.0:
        return shape_hash
    return hashlib.sha256(f"{shape_hash}:clearance={float(clearance)!r}".encode()).hexdigest()


def _static_repr(o) -> dict:
    if isinstance(o, MapObstacle):
        return {"map": o.digest, "unknown_free": o.unknown_free}
    if isinstance(o, Disc):
        return {"disc": [list(o.center), o.radius]}
    if isinstance(o, Box):
        return {"box": [list(o.center), list(o.size), o.angle]}
    return {"polygon": np.round(o.points, 12).tolist(), "holes": [np.round(h, 12).tolist() for h in o.holes]}


def load_scene(path: str | os.PathLike) -> Scene:
    """Read and validate a scene file.

    Parameters
    ----------
    path : path-like
        A YAML scene file (docs/formats.md section 1).

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        If the file cannot be read or anything in it is wrong; the message names the
        file and the place, e.g. ``scene.yaml: movers[2].path[1]: expected 2 numbers, got 3``.
    """
    file = str(path)
    try:
        raw = Path(path).read_bytes()
    except OSError as exc:
        raise SceneError(file, "", f"cannot read: {exc.strerror or exc}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise SceneError(file, "", not_utf8(raw, exc)) from None
    doc = _load_yaml(text, file)
    return parse_scene(doc, file=file, folder=Path(path).resolve().parent)
