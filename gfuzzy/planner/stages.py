"""The stages after the search: GA refinement and the fuzzy speed layer.

Each stage takes the current answer's geometric path, changes it (the GA moves its
via-points; the speed layer bounds its speed), and times the result again among the movers
(:mod:`gfuzzy.planner.retime`). A stage whose result cannot be shown safe, or is slower than the
answer it would replace by more than ``PlanOptions.refine_max_slowdown``, is dropped and
the earlier answer stands: the stages never return an invalid trajectory. Each stage
reports what it did in a frozen report (:class:`RefineReport`, :class:`SpeedReport`) kept
on the :class:`~gfuzzy.planner.planner.PlanResult` (``refine_report``, ``speed_report``); their
``to_dict()`` forms are the trajectory file's ``stats["refine"]`` and ``stats["speed_layer"]``,
the keys it has always had.

The stages see the scene and its static geometry through a :class:`StageContext`, never
the planner: data flows one way (docs/architecture.md).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Protocol

import numpy as np

from ..check.check import check_trajectory
from ..collision.geometry import StaticGeometry, mover_distance
from ..poses import interpolate_segment, path_length_xy, wrap_angle
from ..scene.scene import Query, Robot, Scene
from ..settings import AMAX_PER_VMAX
from ..status import Status
from ..timespace.drive import SAME_HEADING
from ..trajectory import Trajectory
from ..typed import FloatArray
from .driveblend import BlendRetime, retime_blend
from .driveretime import retime_drive
from .retime import ProfileRetime, retime_path, retime_profile

if TYPE_CHECKING:
    from ..fuzzy.rules import RuleBase
    from ..ga import GAOptions

__all__ = ["StageContext", "RefineReport", "SpeedReport", "apply_stages", "GA_RETRY_KNOTS", "GA_FEASIBLE_KNOTS", "HEADING_STEP"]

log = logging.getLogger(__name__)

#: A default refinement that finds nothing with the paper's 12 knots tries once more with
#: this many: on a long winding corridor the chords between 12 knots cut through walls and
#: no individual is feasible. (An explicit ``PlanOptions.ga`` runs once, as given.)
GA_RETRY_KNOTS = 24
#: ... and, when neither try found any feasible individual, once more with this many: a
#: corridor that hugs walls by millimetres (office-polygons' sw-to-ne on its roadmap, 5 mm)
#: is cut into them by the chords of 12 and 24 knots alike; 48 follow its corners.
GA_FEASIBLE_KNOTS = 48
#: Spacing (metres) of the corridor samples a box robot's headings are looked up in.
HEADING_STEP = 0.02


@dataclass(frozen=True)
class StageContext:
    """What the stages need of a query's planner: the scene and its static geometry.

    Attributes
    ----------
    scene : Scene
    geometry : StaticGeometry
        The scene's static collision model (shared with the search, built once).
    """

    scene: Scene
    geometry: StaticGeometry

    @property
    def robot(self) -> Robot:
        return self.scene.robot


@dataclass(frozen=True)
class RefineReport:
    """What the GA refinement did (``PlanResult.refine_report``).

    Attributes
    ----------
    applied : bool
        The refined answer replaced the search's.
    reason : str
        Why not, when not applied.
    knots : int or None
        Knots of the last GA run (None: the GA did not run).
    generations : int or None
    ga_seconds : float or None
    before, after : mapping or None
        ``length``, ``smoothness``, ``min_clearance``, ``duration`` of the corridor and of
        the refined answer (``after`` only when applied).
    """

    applied: bool
    reason: str = ""
    knots: int | None = None
    generations: int | None = None
    ga_seconds: float | None = None
    before: Mapping | None = None
    after: Mapping | None = None

    def to_dict(self) -> dict:
        """The ``stats["refine"]`` form (the trajectory file's keys)."""
        return _present(self, ("applied", "knots", "generations", "ga_seconds", "before", "after", "reason"))


@dataclass(frozen=True)
class SpeedReport:
    """What the fuzzy speed layer did (``PlanResult.speed_report``).

    Attributes
    ----------
    applied : bool
    amax : float
        The acceleration bound used (the robot's, or ``AMAX_PER_VMAX * vmax``).
    reason : str
        Why not, when not applied.
    profile_seconds : float or None
        Duration of the speed profile alone, without the movers (applied in part: of the
        blend, its hasty legs at the search's pace).
    stops : int or None
        Stops the timing among the movers added (when applied; in part: those inside the
        layered legs and the waits inside the hasty ones).
    before, after : mapping or None
        ``duration``, ``max_speed``, ``mean_speed`` (when applied).
    corners : mapping or None
        A differential drive's: ``before``, the corners (turns in place inside the path) of
        the answer's path, and ``after``, those of the path the layer timed (it straightens
        the path first).
    hasty : mapping or None
        A differential drive's, when no timing of the whole layered path exists among the
        movers and the layer applies to part of it (:mod:`gfuzzy.planner.driveblend`):
        ``legs`` driven at the search's pace (no fuzzy or acceleration bound) ``of`` the
        path's legs, their ``length`` of the path's ``total`` (metric length, a turn in place
        counted as r * angle, m), and ``spans``, for each hasty leg the times ``[t0, t1]`` the
        answer drives it (outside them the answer keeps ``amax``). None: the layer holds on
        the whole path.
    """

    applied: bool
    amax: float
    reason: str = ""
    profile_seconds: float | None = None
    stops: int | None = None
    before: Mapping | None = None
    after: Mapping | None = None
    corners: Mapping | None = None
    hasty: Mapping | None = None

    @property
    def whole(self) -> bool:
        """Applied to the whole path (every leg within the fuzzy bound and ``amax``)."""
        return self.applied and not self.hasty

    def to_dict(self) -> dict:
        """The ``stats["speed_layer"]`` form (the trajectory file's keys)."""
        keys = ("applied", "amax", "profile_seconds", "reason", "stops", "before", "after", "corners", "hasty")
        return _present(self, keys)


def _present(report, keys) -> dict:
    out = {}
    for key in keys:
        value = getattr(report, key)
        if value is None or (key == "reason" and not value):
            continue
        out[key] = dict(value) if isinstance(value, Mapping) else value
    return out


def _dedupe(poses: FloatArray) -> FloatArray:
    """Drop consecutive repeated poses (waits) from a trajectory's path."""
    keep = np.concatenate([[True], np.any(np.abs(np.diff(poses, axis=0)) > 1e-12, axis=1)])
    return poses[keep]


def _straight(xy: FloatArray) -> bool:
    """Whether the polyline ``xy`` (n, 2) runs straight from its first point to its last
    (its length is the chord's, to 1e-9 of it): the GA moves via-points off that line and
    shortens nothing (zara-crowd's cross-flow: 48 knots, 2.9 s, 'nothing better')."""
    return path_length_xy(xy) <= float(np.hypot(*(xy[-1] - xy[0]))) * (1 + 1e-9)


def _heading_lookup(corridor: FloatArray):
    """Heading of the corridor pose nearest to each point (box robots keep the
    corridor's headings, which fit its doors)."""
    from scipy.spatial import cKDTree

    # the corridor densely resampled, so the nearest sample is the nearest corridor point
    dense = [corridor[:1]]
    for a, b in zip(corridor[:-1], corridor[1:], strict=True):
        k = max(1, int(np.ceil(np.hypot(*(b[:2] - a[:2])) / HEADING_STEP)))
        dense.append(interpolate_segment(a, b, np.arange(1, k + 1) / k))
    dense = np.vstack(dense)
    tree = cKDTree(dense[:, :2])

    def heading(points: FloatArray) -> FloatArray:
        return dense[tree.query(points)[1], 2]

    return heading


def _clearance_functions(ctx: StageContext, corridor: FloatArray):
    """The GA's clearance functions along ``corridor``: (poses_of, static_clearance,
    static_segment, mover_clearance)."""
    scene, robot, geometry = ctx.scene, ctx.robot, ctx.geometry
    heading = _heading_lookup(corridor) if robot.dof == 3 else None
    # a differential drive with a body that turns (box, footprint) drives each segment at
    # the segment's own heading and turns in place at its ends (_drive_segment)
    drive = robot.unicycle and robot.shape != "disc"

    def poses_of(xy: FloatArray) -> FloatArray:
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        if heading is None:
            return xy
        return np.column_stack([xy, heading(xy)])

    def static_clearance(xy: FloatArray) -> FloatArray:
        return geometry.clearance(poses_of(xy))

    # The GA's segments join a few hundred lattice nodes: each node's clearance (an FCL
    # distance query) is asked once and handed to the sphere tracing as its end clearance.
    end_clearance: dict[tuple[float, ...], float] = {}

    def pose_clearance(pose: list) -> float:
        key = tuple(pose)
        c = end_clearance.get(key)
        if c is None:
            c = end_clearance[key] = geometry.clearance1(pose)
        return c

    def static_segment(a: FloatArray, b: FloatArray):
        """Certify each segment exactly (sphere tracing), with the poses the final path
        will have, so narrow passages do not defeat sampling."""
        k = len(a)
        ends = poses_of(np.concatenate([a, b])).tolist()  # one heading lookup for both ends
        if drive:
            mn = np.array([_drive_segment(geometry, p, q, pose_clearance, robot.reverse)
                           for p, q in zip(ends[:k], ends[k:], strict=True)])  # fmt: skip
        else:
            mn = np.array([_traced(geometry, p, q, pose_clearance) for p, q in zip(ends[:k], ends[k:], strict=True)])
        return np.where(mn >= 0, 0.0, -1.0), mn

    # The GA evaluates the mover clearance at every sample of every candidate, so the robot
    # is first taken as its circumscribed disc (cheap, a lower bound), and a box or footprint robot, only
    # where that bound is negative, as the box at the corridor's heading (the separating-axis
    # bound).
    # The re-timing afterwards decides safety with the exact shapes.
    disc = replace(robot, shape="disc", radius=robot.circumradius, size=(0.0, 0.0), footprint=())

    mover_states = _StateTable(scene.movers)  # the GA asks at the times of one grid

    def mover_clearance(xy: FloatArray, t: FloatArray) -> FloatArray:
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        t = np.asarray(t, dtype=float)
        out = np.full(len(xy), np.inf)
        for mv, (pos, present) in zip(scene.movers, mover_states(t), strict=True):
            if not present.any():
                continue
            d = mover_distance(disc, xy, mv.shape, mv.radius, mv.size, pos)
            if heading is not None:  # near a mover, the box at the corridor's heading
                near = np.nonzero(present & (d < 0.0))[0]
                if near.size:
                    poses = np.column_stack([xy[near], heading(xy[near])])
                    box = mover_distance(robot, poses, mv.shape, mv.radius, mv.size, pos[near], exact=False)
                    d[near] = np.maximum(d[near], box)
            out = np.minimum(out, np.where(present, d, np.inf))
        return out - robot.mover_clearance  # the GA's clearance is what is left above it

    return poses_of, static_clearance, static_segment, mover_clearance


class _StateTable:
    """``[mv.state(t) for mv in movers]``, each time's state computed once: a mover's state
    at a time does not depend on the other times asked with it, so the rows of earlier
    answers are the answer."""

    def __init__(self, movers):
        self.movers = movers
        self.times = np.empty(0)
        self.rows = [(np.empty((0, 2)), np.empty(0, dtype=bool)) for _ in movers]

    def __call__(self, t: FloatArray) -> list:
        t = np.atleast_1d(np.asarray(t, dtype=float))  # as Mover.state
        if not np.all(np.isfinite(t)):
            return [mv.state(t) for mv in self.movers]
        idx = np.searchsorted(self.times, t)
        if not (len(self.times) and np.array_equal(self.times.take(idx, mode="clip"), t)):
            new = np.unique(t)
            new = new[~np.isin(new, self.times)]
            times = np.concatenate([self.times, new])
            order = np.argsort(times, kind="stable")
            self.times = times[order]
            self.rows = [
                (np.concatenate([pos, p])[order], np.concatenate([present, q])[order])
                for (pos, present), (p, q) in zip(self.rows, (mv.state(new) for mv in self.movers), strict=True)
            ]
            idx = np.searchsorted(self.times, t)
        return [(pos[idx], present[idx]) for pos, present in self.rows]


def _traced(geometry: StaticGeometry, p: list, q: list, pose_clearance) -> float:
    """``geometry.motion_clearance(p, q)`` with the end clearances from ``pose_clearance``
    (the same values ``motion_clearance`` would compute: ``clearance1`` of the same poses),
    asked only where it would ask them: ``q``'s not when ``p`` collides, nor when p == q.
    A motion from or to a pose touching the bounds (clearance 0), which the tracing cannot
    leave, is certified as the roadmap certifies it (``motion_free``: clearance 0)."""
    ca = pose_clearance(p)
    if ca < 0:
        return -1.0
    cb = None if p == q else pose_clearance(q)
    clear = geometry.motion_clearance(p, q, ca=ca, cb=cb)
    if clear < 0 and min(ca, pose_clearance(q)) == 0.0 and geometry.motion_free(p, q, ca=ca, cb=cb):
        return 0.0  # an end touching the bounds, which the tracing cannot leave (drive-tight's back-out)
    return clear


def _drive_segment(geometry: StaticGeometry, p: list, q: list, pose_clearance, reverse: bool = False) -> float:
    """A differential drive's segment p -> q (poses at the corridor's headings): the straight
    at its own heading, and the turns in place at both ends between the corridor's heading
    and the segment's; the smallest clearance, -1 when one is not certified free. With
    ``reverse`` the straight may be driven backwards (at the heading opposite to its
    direction): the better of the two (drive-tight's back-out: forwards, the cart parked
    nose against the bounds turned round in a 0.44 m arm, and no individual was feasible).

    At a via-point the robot turns from the heading of the segment before to that of the
    segment after; that arc lies within the two arcs from each to the corridor's heading
    there, which the two segments certify: the GA's objective then agrees with what the
    refined path's certification (turns in place included) asks of it.
    """
    if p[:2] == q[:2]:
        return _traced(geometry, p, p, pose_clearance)
    ahead = math.atan2(q[1] - p[1], q[0] - p[0])
    best = -1.0
    for h in (ahead, float(wrap_angle(ahead + math.pi))) if reverse else (ahead,):
        if abs(float(wrap_angle(h - p[2]))) <= SAME_HEADING:
            h = p[2]  # no turn, as drive_path's pick_turn (a search's lane is off its axis by 1e-12 m)
        a, b = [p[0], p[1], h], [q[0], q[1], h]
        clear = _traced(geometry, a, b, pose_clearance)
        for end, turned in ((p, a), (q, b)):
            if clear < 0:
                break
            clear = min(clear, _traced(geometry, end, turned, pose_clearance))
        best = max(best, clear)
    return best


def _accept(ctx: StageContext, traj: Trajectory, query_like, before: Trajectory, max_slowdown: float):
    """Independent check, and not much slower than the answer it replaces."""
    rep = check_trajectory(ctx.scene, traj.waypoints, query_like, deepest=False)
    if not rep.valid:
        return False, f"failed the independent check ({rep.reason})"
    limit = before.duration * (1.0 + max_slowdown) + 1e-9
    if traj.duration > limit:
        return False, f"slower than the unrefined answer ({traj.duration:.2f} s > {limit:.2f} s)"
    return True, ""


def _run_ga(ctx: StageContext, traj: Trajectory, opts, funcs, deadline):
    """The GA on the corridor: the given options, or the paper's, then ``GA_RETRY_KNOTS``
    knots, then (if no try found a feasible individual) ``GA_FEASIBLE_KNOTS``, until
    ``deadline``. Returns (GA result, options of the last run, seconds, whether any try had
    a feasible individual)."""
    from ..ga import GAOptions, refine_path

    robot = ctx.robot
    _, static_clearance, static_segment, mover_clearance = funcs
    t_ga = time.perf_counter()
    knots = (GAOptions().n_knots, GA_RETRY_KNOTS, GA_FEASIBLE_KNOTS)
    tries = [opts.ga] if opts.ga is not None else [GAOptions(n_knots=k) for k in knots]
    res = None
    movers = mover_clearance if ctx.scene.movers else None
    if movers is not None and float(np.min(movers(traj.poses[:, :2], traj.times))) < 0:
        # the GA's mover bound (the robot's disc, or its box at the corridor's heading) refuses
        # the search's own answer, which the exact search accepted: near it no individual is
        # feasible (building-floor-unicycle: 'nothing better' after 12, 24 and 48 knots). The
        # GA then refines against the static obstacles alone, and the movers are left to the
        # re-timing of the refined path (exact, with waits), which _refine keeps only if
        # checked and not much slower
        movers = None
    feasible = False  # whether any try had a feasible individual
    for i, ga_opts in enumerate(tries):
        if i == 2 and feasible:
            break  # an earlier try found feasible paths, none better: more knots are not tried
        res = refine_path(
            traj.poses[:, :2],
            traj.times,
            robot.circumradius if robot.dof == 3 else robot.radius,
            static_clearance,
            movers,
            ga_opts,
            seed=opts.seed,
            static_segment=static_segment,
            deadline=deadline,
        )
        feasible = feasible or bool(np.isfinite(res.fitness_history).any())
        if res.improved or res.out_of_time:
            break
    return res, ga_opts, time.perf_counter() - t_ga, feasible


def _refine(ctx: StageContext, traj: Trajectory, query, opts, deadline) -> tuple[Trajectory, RefineReport]:
    corridor = _dedupe(traj.poses)
    if len(corridor) < 3 or _straight(corridor[:, :2]):
        return traj, RefineReport(False, "the path is a straight segment already")
    funcs = _clearance_functions(ctx, corridor)
    res, ga_opts, seconds, feasible = _run_ga(ctx, traj, opts, funcs, deadline)
    before = {
        "length": res.length_before,
        "smoothness": res.smoothness_before,
        "min_clearance": res.clearance_before,
        "duration": traj.duration,
    }
    report = RefineReport(False, "", ga_opts.n_knots, res.generations, seconds, before)
    if res.out_of_time:
        why = f"the planning budget ({opts.time_limit:g} s, --time-limit) ran out while the GA refined: the search's answer is kept"
        return traj, replace(report, reason=why)
    if not res.improved and not feasible:  # no try had a feasible individual
        why = (f"the GA found no feasible path near the corridor (up to {ga_opts.n_knots} knots: every individual "
               "came within the clearance of a wall or a mover, or cut a corner the corridor rounds)")
        return traj, replace(report, reason=why)
    if not res.improved:
        return traj, replace(report, reason="the GA found nothing better than the corridor")
    if ctx.robot.unicycle:  # straight segments through the via-points, turns in place
        from .straighten import drive_path

        path = drive_path(ctx.geometry, traj.poses[0], res.path[1:-1], traj.poses[-1], ctx.robot.reverse,
                          lambda xy: funcs[0](xy)[0, 2])  # the corridor's heading: backwards where it backed
        if path is None:
            return traj, replace(report, reason="a refined turn in place could not be certified free of static obstacles")
    else:
        path = funcs[0](res.path)  # poses_of: a box robot takes the corridor's headings
        if ctx.robot.dof == 3:  # the ends keep their exact poses
            path[0], path[-1] = traj.poses[0], traj.poses[-1]
        path[0, :2], path[-1, :2] = traj.poses[0, :2], traj.poses[-1, :2]
    for a, b in zip(path[:-1], path[1:], strict=True):
        if not ctx.geometry.motion_free(a, b):
            return traj, replace(report, reason="a refined segment could not be certified free of static obstacles")
    horizon = max(opts.horizon or 0.0, 2.0 * traj.duration + 30.0)
    rt = retime_path(ctx.scene, path, query.t0, opts.dt, horizon, deadline=deadline, hold=query.hold,
                     backend=opts.backend)  # fmt: skip
    if rt.status is not Status.SOLVED:
        return traj, replace(report, reason=f"the refined path could not be timed among the movers ({rt.message})")
    ok, why = _accept(ctx, rt.trajectory, query, traj, opts.refine_max_slowdown)
    if not ok:
        return traj, replace(report, reason=why)
    after = {
        "length": res.length_after,
        "smoothness": res.smoothness_after,
        "min_clearance": res.clearance_after,
        "duration": rt.trajectory.duration,
    }
    return rt.trajectory, replace(report, applied=True, after=after)


def _speed_layer(ctx: StageContext, traj: Trajectory, query, opts, deadline) -> tuple[Trajectory, SpeedReport]:
    from ..fuzzy.fuzzy import FuzzyOptions, expert_rules, speed_limit

    robot = ctx.robot
    amax = robot.amax if robot.amax is not None else AMAX_PER_VMAX * robot.vmax
    path = _dedupe(traj.poses)
    if len(path) < 2:
        return traj, SpeedReport(False, amax, "the start is the goal")
    rules = opts.rules if opts.rules is not None else expert_rules()
    horizon = max(opts.horizon or 0.0, 3.0 * traj.duration + 30.0)
    corners = None
    if robot.unicycle:  # straights from rest to rest, turns in place from rest to rest
        rt, corners = _drive_layer(ctx, path, query, opts, amax, horizon, rules, deadline)
    else:
        s_xy, v_xy = speed_limit(path[:, :2], robot.vmax, amax, rules, FuzzyOptions())
        rt = retime_profile(scene=ctx.scene, path=path, s_xy=s_xy, v_xy=v_xy, t0=query.t0,
                            dt=opts.dt, amax=amax, horizon=horizon, deadline=deadline, hold=query.hold,
                            backend=opts.backend)  # fmt: skip
    report = SpeedReport(False, amax, profile_seconds=rt.profile_duration, corners=corners)
    if rt.status is Status.TIMEOUT:
        return traj, replace(report, reason="the time limit passed while timing the speed-limited path among the movers")
    if rt.status is not Status.SOLVED:
        why = f"the speed-limited path could not be timed among the movers ({rt.message})"
        return traj, replace(report, reason=why)
    rep = check_trajectory(ctx.scene, rt.trajectory.waypoints, query, deepest=False)
    if not rep.valid:
        return traj, replace(report, reason=f"failed the independent check ({rep.reason})")
    figures = replace(
        report, applied=True, stops=len(rt.waits), before=_speed_figures(traj), after=_speed_figures(rt.trajectory)
    )
    if isinstance(rt, BlendRetime) and rt.hasty is not None and rt.hasty.any():
        total = float(rt.legs[-1])
        hasty = {"legs": int(rt.hasty.sum()), "of": len(rt.hasty), "length": rt.hasty_length, "total": total,
                 "spans": [[float(a), float(b)] for a, b in rt.hasty_spans]}  # fmt: skip
        figures = replace(figures, hasty=hasty)
    return rt.trajectory, figures


def _drive_layer(ctx: StageContext, path, query, opts, amax, horizon, rules, deadline):
    """A differential drive's speed layer: its path straightened first (a stop saved at every
    corner dropped, :func:`gfuzzy.planner.straighten.straighten`), timed among the movers; the
    path as it was when the straightened one cannot be timed. Returns (RetimeResult,
    ``{"before": corners of the path, "after": corners of the path timed}``)."""
    from .straighten import corners, straighten

    def count(p):
        c = corners(p)
        return len(c) - 2 if c is not None else len(p) - 2

    straight = straighten(ctx.geometry, path)
    tries = [straight, path] if straight is not path else [path]
    for candidate in tries:
        rt = retime_drive(ctx.scene, candidate, query.t0, opts.dt, amax, horizon, rules, deadline=deadline,
                          hold=query.hold, backend=opts.backend)  # fmt: skip
        if rt.status is Status.SOLVED:
            return rt, {"before": count(path), "after": count(candidate)}
    # no timing of the whole layered path: the layer where it fits, haste where a mover forces it
    for candidate in tries:
        if time.perf_counter() > deadline:
            break
        rt = retime_blend(ctx.scene, candidate, query.t0, opts.dt, amax, horizon, rules, deadline=deadline,
                          hold=query.hold, backend=opts.backend)  # fmt: skip
        if rt.status is Status.SOLVED:
            return rt, {"before": count(path), "after": count(candidate)}
    if time.perf_counter() > deadline:  # the last answer's why, but the time ran out
        rt = ProfileRetime(Status.TIMEOUT, None, "the time limit passed", profile_duration=rt.profile_duration)
    return rt, {"before": count(path), "after": count(tries[-1])}


def _speed_figures(traj: Trajectory) -> dict:
    moving = traj.speeds()[traj.speeds() > 0]
    return {
        "duration": traj.duration,
        "max_speed": float(moving.max(initial=0.0)),
        "mean_speed": float(moving.mean()) if moving.size else 0.0,
    }


class StageSettings(Protocol):
    """What the stages read of the query's options (``gfuzzy.PlanOptions`` has all of it).

    The stages depend on these attributes only, never on the planner's types: data flows
    one way (docs/architecture.md).
    """

    refine: bool
    speed_layer: bool
    seed: int
    dt: float
    horizon: float | None
    refine_max_slowdown: float
    ga: GAOptions | None
    rules: RuleBase | None
    backend: str  # the retiming searches' implementation, as the search's ("compiled" or "reference")


@dataclass(frozen=True)
class StageOutcome:
    """The trajectory after the stages, and what each stage that ran did."""

    trajectory: Trajectory
    refine_report: RefineReport | None = None
    speed_report: SpeedReport | None = None


def apply_stages(
    ctx: StageContext,
    traj: Trajectory,
    query: Query,
    opts: StageSettings,
    deadline: float,
) -> StageOutcome:
    """Run the GA refinement and/or the speed layer on a solved answer (the goal pose
    parked ``query.hold`` seconds after the arrival, checked as well).

    Parameters
    ----------
    ctx : StageContext
    traj : Trajectory
        The search's answer to ``query``.
    query : Query
        Start, goal, ``t0`` and ``hold`` of the answer.
    opts : StageSettings
        ``refine``, ``speed_layer`` and their settings (a ``PlanOptions``).
    deadline : float
        ``time.perf_counter()`` value past which no stage starts more work.

    Returns
    -------
    StageOutcome
        The stages' trajectory (``traj`` itself when no stage applied) and the reports of
        the stages that ran.
    """
    reports: dict[str, RefineReport | SpeedReport] = {}
    if opts.refine:
        traj, reports["refine_report"] = _refine(ctx, traj, query, opts, deadline)
    if opts.speed_layer:
        traj, reports["speed_report"] = _speed_layer(ctx, traj, query, opts, deadline)
    for name, report in reports.items():
        if not report.applied:
            log.info("%s not applied: %s", "refine" if name == "refine_report" else "speed layer", report.reason)
    return StageOutcome(traj, **reports)
