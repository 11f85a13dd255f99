"""Independent verification of a trajectory against docs/formats.md section 3.

This module shares no collision code with the planner: it measures with shapely (static
obstacles, box and footprint shapes) and closed-form disc distances, and it checks *every instant*, not
samples. Between two evaluated times the clearance d(t) changes no faster than the speed
of the robot's fastest point plus the fastest mover, L; an interval ``[a, b]`` with
``d(a) + d(b) >= L (b - a)`` therefore holds no collision, and any other interval is
bisected. Between rows, L counts only the movers that may come near and move (:mod:`.reach`:
a mover stays on its path, or on its rows), so a wait of hours far from every mover is
decided at once. Times at which a mover appears or vanishes are evaluated exactly. An interval
still undecided below ``min_interval`` seconds is a touching contact, which the contract
allows.

Clearances: the distance to static obstacles is measured against ``robot.clearance`` and
the distance to movers against ``robot.mover_clearance`` (the bounds without one): every
clearance below is the distance minus the distance required, so the same argument proves
that the required distances are kept at every instant. With a query's ``hold`` the goal
pose is checked from the last row until ``hold`` seconds after it as a wait.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from ..scene.scene import Box, Disc, MapObstacle, Query, Scene
from ..typed import FloatArray
from .depth import Edges, convex_outline, overlap_depth
from .reach import near_movers, one_period_end
from .rows import rows_problem, wrap

__all__ = ["CheckReport", "check_trajectory"]


@dataclass(frozen=True)
class CheckReport:
    """Result of :func:`check_trajectory`.

    Attributes
    ----------
    valid : bool
    reason : str
        Why not, naming the time and what was hit; empty when valid.
    min_clearance : float
        Smallest clearance evaluated (to bounds, static obstacles and movers), above the
        required distance (``robot.clearance``, ``robot.mover_clearance``) where there is one.
    max_speed : float
        Largest configuration speed between rows.
    evaluations : int
        Number of times the clearance was evaluated.
    time : float or None
        When the reported violation happens: the earliest one (a collision's onset, to
        within ``exact_below``); None when valid or when the rows themselves are malformed.
    """

    valid: bool
    reason: str = ""
    min_clearance: float = math.inf
    max_speed: float = 0.0
    evaluations: int = 0
    time: float | None = None


def _grid_region(grid: MapObstacle):
    """The blocked region of a map, from its cell values (not the planner's rectangles).

    Nav2's values are read once (``maps.nav2_values``, tested against an oracle of its
    own); what the checker verifies is the planner's collision model of them, so it
    derives the region again: cell value 100, or -1 unless unknown is free, each row's
    runs of such cells as boxes, and their union.
    """
    values = np.asarray(grid.values)
    blocked = values == 100
    if not grid.unknown_free:
        blocked = blocked | (values == -1)
    h, w = blocked.shape
    res = grid.info.resolution
    ox, oy = grid.info.origin
    edges = np.diff(np.pad(blocked.astype(np.int8), ((0, 0), (1, 1))), axis=1)
    rows, starts = np.nonzero(edges > 0)
    _, stops = np.nonzero(edges < 0)
    if len(rows) == 0:
        return shapely.Polygon()
    boxes = shapely.box(ox + starts * res, oy + (h - 1 - rows) * res, ox + stops * res, oy + (h - rows) * res)
    return shapely.union_all(boxes)


class _World:
    """Shapely / closed-form model of the scene, evaluated at arrays of poses and times."""

    def __init__(self, scene: Scene, tol: float = 1e-9):
        self.scene = scene
        self.robot = scene.robot
        self.tol = tol  # an overlap's depth is measured to within it (see depth.overlap_depth)
        self.keep_static = float(scene.robot.clearance)
        self.keep_mover = float(scene.robot.mover_clearance)
        # after each clearance / swept_clearance: the bodies' own smallest distance per pose or
        # interval (no required distance; negative: the overlap's depth, see depth.overlap_depth)
        # and what it is against
        self.last_gap: tuple[FloatArray, list] = (np.zeros(0), [])
        polys = []
        self.discs = []
        for ob in scene.obstacles:
            if isinstance(ob, Disc):
                self.discs.append((np.array(ob.center, float), ob.radius))
            elif isinstance(ob, Box):
                polys.append(shapely.Polygon(ob.vertices()))
            elif isinstance(ob, MapObstacle):
                polys.append(_grid_region(ob))
            else:
                polys.append(shapely.Polygon(ob.points, [h for h in ob.holes]))
        self.static = shapely.union_all(polys) if polys else None
        self._static_edges: Edges | None = None
        if self.static is not None:
            shapely.prepare(self.static)
        # the body's outline about the reference point: a box's corners or the footprint (a
        # concave one swept as the union of its triangles' swept hulls, a convex one as a box)
        self.local = self.triangles = None
        if self.robot.shape == "box":
            hl, hw = 0.5 * self.robot.size[0], 0.5 * self.robot.size[1]
            self.local = np.array([[hl, hw], [-hl, hw], [-hl, -hw], [hl, -hw]])
        elif self.robot.shape == "footprint":
            self.local = np.array(self.robot.footprint, dtype=float)
            outline = shapely.Polygon(self.local)
            if not outline.is_valid:
                raise ValueError("the robot's footprint is not a simple polygon")
            if not convex_outline(self.local):
                tris = shapely.get_parts(shapely.constrained_delaunay_triangles(outline))
                self.triangles = [np.asarray(t.exterior.coords)[:3] for t in tris]
        # a box, a convex footprint and their swept hulls are convex: an overlap by a rounding
        # is proven without measuring it (depth.overlap_depth; a concave body could hide a
        # spike in the band the proof leaves unexamined, and is measured)
        self.convex = self.local is not None and self.triangles is None
        # overlaps deeper than tol: left at the first point found deeper (the verdict's
        # need), or measured to within this fraction of their depth (the deepest's report)
        self.relative: float | None = None

    @property
    def static_edges(self) -> Edges:
        """The static obstacles' outline, indexed when an overlap is first measured."""
        if self._static_edges is None:
            self._static_edges = Edges(self.static)
        return self._static_edges

    def robot_geoms(self, poses: FloatArray):
        if self.robot.shape == "disc":
            return shapely.points(poses[:, 0], poses[:, 1])
        c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
        local = self.local
        xs = poses[:, None, 0] + c[:, None] * local[:, 0] - s[:, None] * local[:, 1]
        ys = poses[:, None, 1] + s[:, None] * local[:, 0] + c[:, None] * local[:, 1]
        return shapely.polygons(np.stack([xs, ys], -1))

    def _shape_distance(self, geoms, other, measure_depth: bool):
        """Signed-ish distance between robot geometries and a shapely geometry."""
        d = shapely.distance(geoms, other)
        if self.robot.shape == "disc":
            d = _signed(d, other, geoms, shapely.contains_xy(other, shapely.get_x(geoms), shapely.get_y(geoms)))
            d = d - self.robot.radius
            return d
        if measure_depth:
            zero = d <= 0
            if np.any(zero):
                d = d.copy()
                d[zero] = -overlap_depth(geoms[zero], other, self.tol, self.static_edges, self.convex, self.relative)
        return d

    def bounds_clearance(self, poses):
        xmin, ymin, xmax, ymax = self.scene.bounds
        if self.robot.shape == "disc":
            r = self.robot.radius
            x, y = poses[:, 0], poses[:, 1]
            return np.min([x - r - xmin, xmax - x - r, y - r - ymin, ymax - y - r], axis=0)
        if self.robot.shape == "footprint":  # the outline's vertices, turned
            c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
            lx, ly = self.local[:, 0], self.local[:, 1]
            wx, wy = c * lx - s * ly, s * lx + c * ly  # (n, k)
            x, y = poses[:, 0], poses[:, 1]
            return np.min(
                [x + wx.min(1) - xmin, xmax - x - wx.max(1), y + wy.min(1) - ymin, ymax - y - wy.max(1)], axis=0
            )
        c, s = np.abs(np.cos(poses[:, 2])), np.abs(np.sin(poses[:, 2]))
        hl, hw = 0.5 * self.robot.size[0], 0.5 * self.robot.size[1]
        ex, ey = c * hl + s * hw, s * hl + c * hw
        x, y = poses[:, 0], poses[:, 1]
        return np.min([x - ex - xmin, xmax - x - ex, y - ey - ymin, ymax - y - ey], axis=0)

    def clearance(self, poses: FloatArray, times: FloatArray) -> tuple[FloatArray, list]:
        """Clearance at each (pose, time) and, for each, the name of the nearest thing."""
        geoms = self.robot_geoms(poses)
        parts = [self.bounds_clearance(poses)]
        names = ["the bounds"]
        if self.static is not None:
            parts.append(self._shape_distance(geoms, self.static, True) - self.keep_static)
            names.append("a static obstacle")
        for center, radius in self.discs:
            parts.append(self._shape_distance(geoms, shapely.Point(center), False) - radius - self.keep_static)
            names.append(f"the static disc at {center.tolist()}")
        for mv in self.scene.movers:
            xy, present = mv.state(times)
            if mv.shape == "disc":
                if self.robot.shape == "disc":
                    d = np.hypot(*(xy - poses[:, :2]).T) - self.robot.radius - mv.radius
                else:
                    d = shapely.distance(geoms, shapely.points(xy[:, 0], xy[:, 1]))
                    inside = shapely.contains_xy(geoms, xy[:, 0], xy[:, 1])
                    d = _signed(d, geoms, shapely.points(xy[:, 0], xy[:, 1]), inside) - mv.radius
            else:
                w, h = mv.size
                boxes = shapely.box(xy[:, 0] - w / 2, xy[:, 1] - h / 2, xy[:, 0] + w / 2, xy[:, 1] + h / 2)
                if self.robot.shape == "disc":
                    d = shapely.distance(geoms, boxes)
                    inside = shapely.contains_xy(boxes, poses[:, 0], poses[:, 1])
                    d = _signed(d, boxes, geoms, inside) - self.robot.radius
                else:
                    d = shapely.distance(geoms, boxes)
                    zero = d <= 0
                    if np.any(zero):
                        d[zero] = -overlap_depth(geoms[zero], boxes[zero], self.tol, convex=self.convex,
                                                                relative=self.relative)
            parts.append(np.where(present, d - self.keep_mover, np.inf))
            names.append(f"mover {mv.name!r}")
        stack = np.vstack(parts)
        which = np.argmin(stack, axis=0)
        cols = np.arange(stack.shape[1])
        keeps = np.array([self.keep_of(n) for n in names])
        gaps = stack + keeps[:, None]  # the bodies' own distance (negative: overlap)
        deepest = np.argmin(gaps, axis=0)
        self.last_gap = (gaps[deepest, cols], [names[i] for i in deepest])
        return stack[which, cols], [names[i] for i in which]

    def keep_of(self, name: str) -> float:
        """The distance required from the thing called ``name``."""
        return 0.0 if name == "the bounds" else self.keep_mover if name.startswith("mover") else self.keep_static


    def swept_clearance(self, pa, pb, heading, ta, tb):
        """Exact smallest clearance over intervals in which the robot translates.

        Parameters
        ----------
        pa, pb : (k, 2) float
            Reference point at the interval's ends.
        heading : (k,) float or None
            The (constant) heading of a box or footprint robot.
        ta, tb : (k,) float

        Returns
        -------
        clearance : (k,) float
            NaN where a mover does not move in a straight line over the interval (the
            caller decides those by bisection).
        names : list of str

        Notes
        -----
        Over a translation the robot sweeps the convex hull of its two end footprints (a
        box), the union of those hulls for each triangle of a footprint (concave ones
        included: the sweep of a union is the union of the sweeps) or the segment of its
        centre widened by its radius (a disc), and the body's
        distance to anything is the distance of that swept set; a mover moving straight is
        handled in the robot's frame, where it sweeps likewise.
        """
        k = len(pa)
        out = np.full(k, np.inf)
        names = ["-"] * k
        disc = self.robot.shape == "disc"
        r = self.robot.radius
        if disc:
            centre = shapely.linestrings(np.stack([pa, pb], axis=1))
            body = None
        else:
            c, sn = np.cos(heading), np.sin(heading)
            rot = np.stack([np.stack([c, -sn], -1), np.stack([sn, c], -1)], -2)  # (k, 2, 2)
            corners = np.einsum("kij,mj->kmi", rot, self.local)  # (k, m, 2) about the reference
            if self.triangles is None:
                swept = shapely.convex_hull(shapely.multipoints(np.concatenate([corners + pa[:, None], corners + pb[:, None]], 1)))
            else:
                swept = None
                for tri in self.triangles:
                    tc = np.einsum("kij,mj->kmi", rot, tri)
                    hull = shapely.convex_hull(shapely.multipoints(np.concatenate([tc + pa[:, None], tc + pb[:, None]], 1)))
                    swept = hull if swept is None else shapely.union(swept, hull)
            body = shapely.polygons(corners)  # at the origin, for the movers

        gap = np.full(k, np.inf)
        gap_names = ["-"] * k

        def take(d, name):
            better = d < out
            out[better] = d[better]
            for i in np.nonzero(better)[0]:
                names[i] = name
            g = d + self.keep_of(name)
            deeper = g < gap
            gap[deeper] = g[deeper]
            for i in np.nonzero(deeper)[0]:
                gap_names[i] = name

        # bounds: the clearance is linear along a translation, extreme at the ends
        take(np.minimum(self.bounds_clearance(self._poses(pa, heading)), self.bounds_clearance(self._poses(pb, heading))), "the bounds")
        if self.static is not None:
            if disc:
                d = shapely.distance(centre, self.static) - r
            else:
                d = shapely.distance(swept, self.static)
                zero = d <= 0
                if np.any(zero):
                    d[zero] = -overlap_depth(swept[zero], self.static, self.tol, self.static_edges, self.convex,
                                                             self.relative)
            take(d - self.keep_static, "a static obstacle")
        for center, radius in self.discs:
            if disc:
                d = _segment_point_distance(pa, pb, center) - r - radius
            else:
                d = shapely.distance(swept, shapely.Point(center)) - radius
            take(d - self.keep_static, f"the static disc at {center.tolist()}")
        for mv in self.scene.movers:
            ma, pres_a = mv.state(ta)
            mb, pres_b = mv.state(tb)
            mm, pres_m = mv.state(0.5 * (ta + tb))
            present = pres_a | pres_b | pres_m
            if not present.any():
                continue
            straight = np.hypot(*(mm - 0.5 * (ma + mb)).T) <= 1e-9 * (1.0 + np.hypot(*(mb - ma).T))
            qa, qb = ma - pa, mb - pb  # the mover relative to the robot's reference point
            d = _relative_swept_distance(mv, qa, qb, disc, r, body, self.tol, self.convex, self.relative)
            d = np.where(present, d - self.keep_mover, np.inf)
            d = np.where(straight | ~present, d, np.nan)
            nan = np.isnan(d)
            take(np.where(nan, np.inf, d), f"mover {mv.name!r}")
            out[nan] = np.nan
        self.last_gap = (gap, gap_names)
        return out, names

    def _poses(self, p, heading):
        return p if heading is None else np.column_stack([p, heading])


def _relative_swept_distance(mv, qa, qb, disc: bool, r: float, body, tol: float, convex: bool = False,
                             relative: float | None = None):  # fmt: skip
    """Distance between the robot (a disc of radius ``r`` at the origin, or the box or
    footprint ``body`` at the origin) and mover ``mv`` translating from ``qa`` to ``qb`` relative to
    it: the mover's swept set (k,); negative where they overlap."""
    if disc and mv.shape == "disc":
        d = _segment_point_distance(qa, qb, np.zeros(2)) - r - mv.radius
    elif disc:
        w, h = mv.size
        rel = np.concatenate([qa[:, None] + [[s1 * w / 2, s2 * h / 2] for s1, s2 in ((1, 1), (-1, 1), (-1, -1), (1, -1))],
                              qb[:, None] + [[s1 * w / 2, s2 * h / 2] for s1, s2 in ((1, 1), (-1, 1), (-1, -1), (1, -1))]], 1)  # fmt: skip
        hull = shapely.convex_hull(shapely.multipoints(rel))
        d = shapely.distance(hull, shapely.Point(0.0, 0.0)) - r
        inside = shapely.contains_xy(hull, 0.0, 0.0)
        d = _signed(d + r, hull, shapely.Point(0.0, 0.0), inside) - r
    elif mv.shape == "disc":
        d = shapely.distance(shapely.linestrings(np.stack([qa, qb], 1)), body) - mv.radius
    else:
        w, h = mv.size
        box = np.array([[w / 2, h / 2], [-w / 2, h / 2], [-w / 2, -h / 2], [w / 2, -h / 2]])
        hull = shapely.convex_hull(shapely.multipoints(np.concatenate([qa[:, None] + box, qb[:, None] + box], 1)))
        d = shapely.distance(hull, body)
        zero = d <= 0
        if np.any(zero):
            d[zero] = -overlap_depth(body[zero], hull[zero], tol, convex=convex, relative=relative)
    return d


def _signed(d: FloatArray, regions, points, inside) -> FloatArray:
    """``d`` (distances from ``points`` to ``regions``, elementwise or broadcast) with the
    points ``inside`` their region given minus their distance to its boundary: a signed
    distance, so that an overlap's depth (a disc centred there must move that far, plus
    its radius, to get out) is reported in metres, not as a sentinel."""
    d = np.array(d, dtype=float, copy=True).reshape(np.shape(inside))
    if np.any(inside):
        regions = np.broadcast_to(np.asarray(regions, dtype=object), d.shape)
        points = np.broadcast_to(np.asarray(points, dtype=object), d.shape)
        depth = shapely.distance(shapely.boundary(regions[inside]), points[inside])
        d[inside] = -np.where(np.isnan(depth), 0.0, depth)  # a point region: no boundary
    return d


def _segment_point_distance(a: FloatArray, b: FloatArray, c) -> FloatArray:
    """Distance from point(s) c to segments a-b. a, b (k, 2)."""
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", c - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0.0, 1.0)
    return np.hypot(*(a + t[:, None] * ab - c).T)


def check_trajectory(
    scene: Scene,
    waypoints: FloatArray,
    query: Query | None = None,
    tol: float = 1e-9,
    min_interval: float = 1e-7,
    max_evaluations: int = 5_000_000,
    exact_below: float = 1e-3,
    deepest: bool = True,
) -> CheckReport:
    """Check a trajectory against docs/formats.md section 3 (and ``query``'s start and goal).

    Parameters
    ----------
    scene : Scene
    waypoints : (n, 3) or (n, 4) float
        Rows ``[t, x, y(, heading)]``.
    query : Query, optional
        When given, the first row must be its start at its t0 and the last row its goal.
    tol : float
        Penetration depth (metres) and relative speed excess tolerated as rounding.
    min_interval : float
        Undecided intervals shorter than this (seconds) count as touching.
    exact_below : float
        Undecided intervals shorter than this (seconds) in which the robot does not turn
        are decided exactly (the swept footprint's distance), so a long touching contact
        does not need endless bisection.
    deepest : bool
        For an invalid trajectory, search it for the bodies' deepest overlap (as many more
        evaluations as the check took, within ``DEEPEST_MIN_EVALUATIONS`` and
        ``DEEPEST_EVALUATIONS``), which the reason reports; the verdict is
        the same without it (the planner's own stages, which need only the verdict).

    Returns
    -------
    CheckReport
    """
    robot = scene.robot
    w = np.asarray(waypoints, dtype=float)
    problem = rows_problem(robot, w, query)
    if problem is not None:
        return CheckReport(False, problem[0], time=problem[1])
    if query is not None:
        hold = float(getattr(query, "hold", 0.0) or 0.0)
        if hold > 0:  # the robot parks at the goal: the rows end with a wait of `hold`
            w = np.vstack([w, np.r_[w[-1, 0] + hold, w[-1, 1:]]])
    return _Checker(scene, w, tol, min_interval, exact_below).run(max_evaluations, deepest)


#: The deepest overlap of a trajectory found invalid is searched to within this fraction of
#: its depth (each overlap measured to within it too; the report prints 3 digits), or until the evaluations of the
#: clearance allowed are spent: as many as the check took, at least DEEPEST_MIN_EVALUATIONS
#: and at most DEEPEST_EVALUATIONS (a long slide at an even depth: then the report says the
#: depth is the deepest found). The search costs at most a few times the check.
DEEPEST_RELATIVE = 1e-2
DEEPEST_MIN_EVALUATIONS = 2_000
DEEPEST_EVALUATIONS = 20_000


def _with_deepest(reason: str, overlap, deepest: tuple[float, str, str], searched) -> str:
    """A contact's ``reason`` with the bodies' deepest overlap: a collision's penetration is
    the deepest overlap with what it hits (its depth at the onset, where the first contact is
    found, follows) or, when something else overlaps deeper, that follows it. Unless the
    search finished, the depth is the deepest found: "at least"."""
    depth, name, when = deepest
    certain = searched is not None and searched[0]
    told, which = (f"{depth:.3g}", "the deepest") if certain else (f"at least {depth:.3g}", "the deepest found")
    if reason.startswith("collides") and overlap is not None and name == overlap[1]:
        if f"{depth:.3g}" == f"{overlap[0]:.3g}":
            return reason
        head = reason[: reason.rindex("(penetration ")]
        return head + f"(penetration {told} {when}, {which}; {overlap[0]:.3g} at the onset)"
    told = f"{told} deep against {name} {when}, {which} overlap"
    return reason[:-1] + f"; {told})" if reason.startswith("collides") else reason + f" ({told})"


class _Checker:
    """One check of well-formed rows: the speed bound, then clearance by bisection.

    Every interval between samples is decided (a Lipschitz bound: the clearance changes at
    most ``robot speed + fastest mover speed`` per second) or bisected until none is left
    that begins before the earliest violation found so far: the report is the first
    violation in time, not the first one met.
    """

    def __init__(self, scene: Scene, w: FloatArray, tol: float, min_interval: float, exact_below: float):
        self.scene, self.robot = scene, scene.robot
        self.tol, self.min_interval, self.exact_below = tol, min_interval, exact_below
        self.t = w[:, 0]
        self.dt = np.diff(self.t)
        self.p = w[:, 1:]
        p, robot = self.p, self.robot
        seg = np.hypot(*np.diff(p[:, :2], axis=0).T)
        if robot.dof == 3:
            seg = seg + np.abs(wrap(np.diff(p[:, 2]))) * robot.circumradius
        self.speed = seg / self.dt if len(self.dt) else np.zeros(0)
        self.vmax_seen = float(self.speed.max(initial=0.0))
        self.first: list = [math.inf, "", None]  # time, reason and overlap (depth, name) of the earliest violation
        self.deepest: tuple[float, str, str] | None = None  # the deepest overlap: depth, against what, when
        self.searched: tuple[bool, int] | None = None  # the search of the deepest: finished, evaluations
        self.world = _World(scene, tol)
        self.evaluations = 0
        self.min_clear = math.inf

    def found(self, time: float, reason: str, overlap: tuple[float, str] | None = None) -> None:
        if time < self.first[0]:
            self.first[:] = [float(time), reason, overlap]

    def overlapped(self, gap: FloatArray, names: list, whens) -> None:
        """Note the deepest overlap of the bodies among ``gap`` (the world's ``last_gap``)."""
        if gap.size == 0:
            return
        k = int(np.argmin(gap))
        depth = -float(gap[k])
        if depth > self.tol and (self.deepest is None or depth > self.deepest[0]):
            self.deepest = (depth, names[k], whens(k))

    def contact(self, name: str, d: float, when: str, time: float) -> None:
        """A violation found: its reason, and the bodies' overlap there (if they overlap)."""
        depth = -(d + self.world.keep_of(name))
        self.found(time, self.hit(name, d, when), (depth, name) if depth > self.tol else None)

    def hit(self, name: str, d: float, when: str) -> str:
        """What a negative clearance means: a collision, or a required distance missed."""
        world, tol = self.world, self.tol
        keep = world.keep_of(name)
        if keep > 0 and d + keep >= -tol:
            which = "robot.mover_clearance" if name.startswith("mover") else "robot.clearance"
            return f"comes within {d + keep:.3g} m of {name} {when}, closer than {which}={keep:g}"
        return f"collides with {name} {when} (penetration {-(d + keep):.3g})"

    def pose_at(self, times, seg_idx):
        t, dt, p = self.t, self.dt, self.p
        f = (times - t[seg_idx]) / dt[seg_idx]
        delta = p[seg_idx + 1] - p[seg_idx]
        if self.robot.dof == 3:
            delta[:, 2] = wrap(delta[:, 2])
        return p[seg_idx] + f[:, None] * delta

    def report(self, note: str = "") -> CheckReport:
        if not self.first[1]:
            return CheckReport(True, "", self.min_clear, self.vmax_seen, self.evaluations)
        reason, overlap, deepest = self.first[1], self.first[2], self.deepest
        if reason.startswith(("collides", "comes within")) and deepest is not None:
            reason = _with_deepest(reason, overlap, deepest, self.searched)
        return CheckReport(False, reason + note, self.min_clear, self.vmax_seen, self.evaluations, self.first[0])

    def search_deepest(self, lip: FloatArray, budget: int | None = None) -> None:
        """Search the whole trajectory for the bodies' deepest overlap (for the report: the
        first contact in time is found at its onset, a tiny depth, and the bisection looks no
        further). Branch and bound on the Lipschitz bound ``lip`` (per segment): an interval
        ``[a, b]`` overlaps at most ``(g(a) + g(b)) / 2 + lip (b - a) / 2`` deep; intervals
        that could hold one more than ``DEEPEST_RELATIVE`` deeper than the deepest found are
        halved, until none is left (``searched`` True) or ``budget`` evaluations are spent
        (default: as many as the check took, within ``DEEPEST_MIN_EVALUATIONS`` and
        ``DEEPEST_EVALUATIONS``); each overlap measured to within ``DEEPEST_RELATIVE``."""
        if budget is None:
            budget = min(DEEPEST_EVALUATIONS, max(DEEPEST_MIN_EVALUATIONS, self.evaluations))
        self.world.relative = DEEPEST_RELATIVE
        times, seg = self._event_times()
        g = self._overlaps(times, seg)
        a_t, b_t, a_g, b_g, a_s = times[:-1], times[1:], g[:-1], g[1:], seg[:-1]
        spent = len(times)
        while a_t.size:
            best = max(self.tol, self.deepest[0] if self.deepest is not None else 0.0)
            bound = 0.5 * (a_g + b_g) + 0.5 * lip[a_s] * (b_t - a_t)
            need = (bound > best * (1.0 + DEEPEST_RELATIVE)) & ((b_t - a_t) >= self.min_interval)
            a_t, b_t, a_g, b_g, a_s = a_t[need], b_t[need], a_g[need], b_g[need], a_s[need]
            if spent + a_t.size > budget:
                break
            m_t = 0.5 * (a_t + b_t)
            m_g = self._overlaps(m_t, a_s) if a_t.size else m_t
            spent += a_t.size
            a_t, b_t = np.concatenate([a_t, m_t]), np.concatenate([m_t, b_t])
            a_g, b_g = np.concatenate([a_g, m_g]), np.concatenate([m_g, b_g])
            a_s = np.concatenate([a_s, a_s])
        self.searched = (a_t.size == 0, spent)
        self.evaluations += spent

    def _overlaps(self, times, seg_of) -> FloatArray:
        """The bodies' deepest overlap at ``times`` (negative: apart), noted in ``deepest``."""
        self.world.clearance(self.pose_at(times, seg_of), times)
        self.overlapped(*self.world.last_gap, lambda k: f"at t={float(times[k])!r}")
        return -self.world.last_gap[0]

    def run(self, max_evaluations: int, deepest: bool = True) -> CheckReport:
        t, dt, p, robot, tol = self.t, self.dt, self.p, self.robot, self.tol
        # speed: the first segment over vmax (the report is the first violation in time, so
        # a collision found before it below takes its place)
        fast = np.nonzero(self.speed > robot.vmax * (1 + tol))[0]
        if fast.size:
            i = int(fast[0])
            self.found(
                t[i],
                f"speed {self.speed[i]:.9g} exceeds vmax {robot.vmax:g} between t={float(t[i])!r} and t={float(t[i + 1])!r}",
            )
        if len(dt) == 0:  # one pose: its overlap measured as the deepest's search would
            self.world.relative = DEEPEST_RELATIVE if deepest else None
            d, names = self.world.clearance(p[:1], t[:1])
            if d[0] < -tol:
                return CheckReport(False, self.hit(names[0], float(d[0]), f"at t={float(t[0])!r}"), float(d[0]), 0.0, 1, float(t[0]))
            return CheckReport(True, "", float(d[0]), 0.0, 1)
        a_t, b_t, a_d, b_d, a_s = self._initial_intervals()
        vm = max((mv.max_speed for mv in self.scene.movers), default=0.0)
        turn = np.abs(wrap(np.diff(p[:, 2]))) if robot.dof == 3 else np.zeros(len(dt))
        body = self.speed  # the fastest point of the body, per segment
        if robot.dof == 3 and robot.shape == "disc":  # a disc's turn in place moves none of it
            body = np.hypot(*np.diff(p[:, :2], axis=0).T) / dt
            turn = np.zeros(len(dt))
        lip = body + vm  # per segment
        # per interval: the movers that cannot come near, or stand still, do not count, so a
        # long wait far from them is not halved until the evaluations run out
        a_l, b_t, b_d = self._interval_lip(a_t, b_t, a_d, b_d, a_s, body, lip)
        while a_t.size:
            need = (a_d + b_d < a_l * (b_t - a_t)) & (a_t < self.first[0])
            need &= (b_t - a_t) >= self.min_interval
            a_t, b_t, a_d, b_d, a_s, a_l = a_t[need], b_t[need], a_d[need], b_d[need], a_s[need], a_l[need]
            if a_t.size == 0:
                break
            # near contact, bisection would go on for ever along a touching stretch: where
            # the robot only translates, decide the interval exactly instead
            near = (b_t - a_t) < self.exact_below
            if robot.dof == 3:
                near &= turn[a_s] == 0.0
            if near.any():
                keep = self._decide_exactly(a_t, b_t, a_s, np.nonzero(near)[0])
                a_t, b_t, a_d, b_d, a_s, a_l = a_t[keep], b_t[keep], a_d[keep], b_d[keep], a_s[keep], a_l[keep]
                if a_t.size == 0:
                    break
            m_t = 0.5 * (a_t + b_t)  # none between two floats (t > 1e9): never split, never decided
            short = np.any((m_t <= a_t) | (m_t >= b_t))
            if self.evaluations > max_evaluations or short:
                if self.first[1]:
                    return self.report(" (an earlier near-grazing contact could not be decided)")
                why = "an interval as short as the float spacing" if short else "too many evaluations"
                return CheckReport(
                    False, f"could not decide: {why} (near-grazing contact)", self.min_clear,
                    self.vmax_seen, self.evaluations,
                )  # fmt: skip
            m_d = self._sample(m_t, a_s)
            a_t, b_t = np.concatenate([a_t, m_t]), np.concatenate([m_t, b_t])
            a_d, b_d = np.concatenate([a_d, m_d]), np.concatenate([m_d, b_d])
            a_s, a_l = np.concatenate([a_s, a_s]), np.concatenate([a_l, a_l])
        if deepest and self.first[1].startswith(("collides", "comes within")):
            self.search_deepest(lip)
        return self.report()

    def _interval_lip(self, a_t, b_t, a_d, b_d, a_s, body, lip):
        """Each interval's bound on the clearance's speed, and its end: the segment's ``lip``,
        or, where the bisection would need it, the robot's own speed plus the movers' that may
        come near (:func:`gfuzzy.check.reach.near_movers`), the bound its parts inherit. Where
        the robot stands still and those movers repeat, one period is the whole interval's
        clearance: the interval ends after it (at a point of its bisection)."""
        out = lip[a_s]
        idx = np.nonzero(a_d + b_d < out * (b_t - a_t))[0]
        if idx.size:
            pa, pb = self.pose_at(a_t[idx], a_s[idx]), self.pose_at(b_t[idx], a_s[idx])
            speed, period = near_movers(self.scene, pa[:, :2], pb[:, :2], a_t[idx], b_t[idx])
            out[idx] = body[a_s[idx]] + speed
            still = np.all(self.p[a_s[idx]] == self.p[a_s[idx] + 1], axis=1) & (speed > 0)
            longer = still & (b_t[idx] - a_t[idx] > period)
            if longer.any():
                cut = idx[longer]
                b_t, b_d = b_t.copy(), b_d.copy()
                b_t[cut] = one_period_end(a_t[cut], b_t[cut], period[longer])
                b_d[cut] = self._sample(b_t[cut], a_s[cut])
        return out, b_t, b_d

    def _sample(self, times, seg_of) -> FloatArray:
        """Clearances at ``times`` (sorted or not); the earliest violation among them is noted."""
        d, names = self.world.clearance(self.pose_at(times, seg_of), times)
        self.overlapped(*self.world.last_gap, lambda k: f"at t={float(times[k])!r}")
        self.evaluations += len(times)
        self.min_clear = min(self.min_clear, float(d.min()))
        bad = np.nonzero(d < -self.tol)[0]
        if bad.size:
            k = int(bad[np.argmin(times[bad])])
            self.contact(names[k], float(d[k]), f"at t={float(times[k])!r}", times[k])
        return d

    def _initial_intervals(self):
        """Samples at every row and every time a mover appears or vanishes; the intervals
        between consecutive ones (each lies within one segment)."""
        times, seg_of = self._event_times()
        d = self._sample(times, seg_of)
        return times[:-1], times[1:], d[:-1], d[1:], seg_of[:-1]

    def _event_times(self) -> tuple[FloatArray, np.ndarray]:
        """Every row's time and every time a mover appears or vanishes, sorted, with the
        segment each lies in."""
        t = self.t
        events = [t]
        for mv in self.scene.movers:
            ta, tb = mv.time_range
            for te in (ta, tb):
                if t[0] < te < t[-1]:
                    events.append(np.array([te]))
        times = np.unique(np.concatenate(events))
        return times, np.clip(np.searchsorted(t, times, side="right") - 1, 0, len(self.dt) - 1)

    def _decide_exactly(self, a_t, b_t, a_s, idx) -> np.ndarray:
        """Decide intervals ``idx`` by the swept footprint's exact clearance; the mask of
        the intervals still undecided."""
        pa, pb = self.pose_at(a_t[idx], a_s[idx]), self.pose_at(b_t[idx], a_s[idx])
        head = None if self.robot.dof == 2 else pa[:, 2]
        ex, ex_names = self.world.swept_clearance(pa[:, :2], pb[:, :2], head, a_t[idx], b_t[idx])
        gap, gap_names = self.world.last_gap
        decided = ~np.isnan(ex)
        self.overlapped(
            np.where(decided, gap, np.inf), gap_names,
            lambda k: f"between t={float(a_t[idx[k]])!r} and t={float(b_t[idx[k]])!r}",
        )  # fmt: skip
        self.evaluations += len(idx)
        bad = np.nonzero(decided & (ex < -self.tol))[0]
        if bad.size:
            k = int(bad[np.argmin(a_t[idx[bad]])])
            self.min_clear = min(self.min_clear, float(ex[k]))
            # the first interval found in violation: the contact's onset lies in it, not its span
            when = f"starting between t={float(a_t[idx[k]])!r} and t={float(b_t[idx[k]])!r}"
            self.contact(ex_names[k], float(ex[k]), when, a_t[idx[k]])
        if decided.any():
            self.min_clear = min(self.min_clear, float(np.nanmin(ex)))
        keep = np.ones(len(a_t), dtype=bool)
        keep[idx[decided]] = False
        return keep
