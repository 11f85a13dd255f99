"""The stages after the search: GA refinement and the fuzzy speed layer.

Each stage takes the current answer's geometric path, changes it (the GA moves its
via-points; the speed layer bounds its speed), and times the result again among the movers
(:mod:`gfuzzy.retime`). A stage whose result cannot be shown safe, or is slower than the
answer it would replace by more than ``PlanOptions.refine_max_slowdown``, is dropped and
the earlier answer stands: the stages never return an invalid trajectory. Each stage
reports its before/after figures in ``PlanResult.stats``.
"""

from __future__ import annotations

import logging
import time
from dataclasses import replace

import numpy as np

from .check import check_trajectory
from .geometry import mover_distance, wrap_angle
from .retime import retime_path, retime_profile
from .scene import Query
from .trajectory import Trajectory
from .typing import FloatArray

__all__ = ["apply_stages"]

log = logging.getLogger(__name__)


def _dedupe(poses: FloatArray) -> FloatArray:
    """Drop consecutive repeated poses (waits) from a trajectory's path."""
    keep = np.concatenate([[True], np.any(np.abs(np.diff(poses, axis=0)) > 1e-12, axis=1)])
    return poses[keep]


def _heading_lookup(corridor: FloatArray):
    """Heading of the corridor pose nearest to each point (box robots keep the
    corridor's headings, which fit its doors)."""
    from scipy.spatial import cKDTree

    # the corridor densely resampled, so the nearest sample is the nearest corridor point
    dense = [corridor[:1]]
    for a, b in zip(corridor[:-1], corridor[1:], strict=True):
        k = max(1, int(np.ceil(np.hypot(*(b[:2] - a[:2])) / 0.02)))
        f = np.arange(1, k + 1)[:, None] / k
        seg = a + f * np.r_[b[:2] - a[:2], wrap_angle(b[2] - a[2])]
        seg[:, 2] = wrap_angle(seg[:, 2])
        dense.append(seg)
    dense = np.vstack(dense)
    tree = cKDTree(dense[:, :2])

    def heading(points: FloatArray) -> FloatArray:
        return dense[tree.query(points)[1], 2]

    return heading


def _clearance_functions(planner, corridor: FloatArray):
    scene, robot, geometry = planner.scene, planner.robot, planner.geometry
    heading = _heading_lookup(corridor) if robot.dof == 3 else None

    def poses_of(xy: FloatArray) -> FloatArray:
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        if heading is None:
            return xy
        return np.column_stack([xy, heading(xy)])

    def static_clearance(xy: FloatArray) -> FloatArray:
        return geometry.clearance(poses_of(xy))

    def static_segment(a: FloatArray, b: FloatArray):
        """Certify each segment exactly (sphere tracing), with the poses the final path
        will have, so narrow passages do not defeat sampling."""
        pa, pb = poses_of(a), poses_of(b)
        mn = np.array([geometry.motion_clearance(p, q) for p, q in zip(pa, pb, strict=True)])
        return np.where(mn >= 0, 0.0, -1.0), mn

    # The GA evaluates the mover clearance at every sample of every candidate, so the robot
    # is first taken as its circumscribed disc (cheap, a lower bound), and a box robot, only
    # where that bound is negative, as the box at the corridor's heading (the separating-axis
    # bound).
    # The re-timing afterwards decides safety with the exact shapes.
    disc = replace(robot, shape="disc", radius=robot.circumradius, size=(0.0, 0.0))

    states: dict = {}  # the GA asks at the same times every generation: movers' states once

    def mover_states(t: FloatArray) -> list:
        key = t.tobytes()
        got = states.get(key)
        if got is None:
            if len(states) > 64:
                states.clear()
            got = states[key] = [mv.state(t) for mv in scene.movers]
        return got

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


def _accept(planner, traj: Trajectory, query_like, before: Trajectory, max_slowdown: float):
    """Independent check, and not much slower than the answer it replaces."""
    rep = check_trajectory(planner.scene, traj.waypoints, query_like)
    if not rep.valid:
        return False, f"failed the independent check ({rep.reason})"
    limit = before.duration * (1.0 + max_slowdown) + 1e-9
    if traj.duration > limit:
        return False, f"slower than the unrefined answer ({traj.duration:.2f} s > {limit:.2f} s)"
    return True, ""


def _refine(planner, traj: Trajectory, query, opts, deadline) -> tuple[Trajectory, dict]:
    from .ga import GAOptions, refine_path

    scene, robot = planner.scene, planner.robot
    corridor = _dedupe(traj.poses)
    info: dict = {"applied": False}
    if len(corridor) < 3:
        info["reason"] = "the path is a straight segment already"
        return traj, info
    poses_of, static_clearance, static_segment, mover_clearance = _clearance_functions(planner, corridor)
    t_ga = time.perf_counter()
    # The paper's 12 knots first; on a long winding corridor the chords between 12 knots
    # cut through walls and no individual is feasible, so a default run tries twice as many.
    tries = [opts.ga] if opts.ga is not None else [GAOptions(), GAOptions(n_knots=24)]
    for ga_opts in tries:
        res = refine_path(
            traj.poses[:, :2],
            traj.times,
            robot.circumradius if robot.dof == 3 else robot.radius,
            static_clearance,
            mover_clearance if scene.movers else None,
            ga_opts,
            seed=opts.seed,
            static_segment=static_segment,
        )
        if res.improved:
            break
    info.update(
        knots=ga_opts.n_knots,
        generations=res.generations,
        ga_seconds=time.perf_counter() - t_ga,
        before={
            "length": res.length_before,
            "smoothness": res.smoothness_before,
            "min_clearance": res.clearance_before,
            "duration": traj.duration,
        },
    )
    if not res.improved:
        info["reason"] = "the GA found nothing better than the corridor"
        return traj, info
    path = poses_of(res.path)
    if robot.dof == 3:  # the ends keep their exact poses
        path[0], path[-1] = traj.poses[0], traj.poses[-1]
    path[0, :2], path[-1, :2] = traj.poses[0, :2], traj.poses[-1, :2]
    for a, b in zip(path[:-1], path[1:], strict=True):
        if not planner.geometry.motion_free(a, b):
            info["reason"] = "a refined segment could not be certified free of static obstacles"
            return traj, info
    horizon = max(opts.horizon or 0.0, 2.0 * traj.duration + 30.0)
    rt = retime_path(scene, path, query.t0, opts.dt, horizon, deadline=deadline, hold=query.hold)
    if rt.status != "solved":
        info["reason"] = f"the refined path could not be timed among the movers ({rt.message})"
        return traj, info
    ok, why = _accept(planner, rt.trajectory, query, traj, opts.refine_max_slowdown)
    if not ok:
        info["reason"] = why
        return traj, info
    new = rt.trajectory
    info["applied"] = True
    info["after"] = {
        "length": res.length_after,
        "smoothness": res.smoothness_after,
        "min_clearance": res.clearance_after,
        "duration": new.duration,
    }
    return new, info


def _speed_layer(planner, traj: Trajectory, query, opts, deadline) -> tuple[Trajectory, dict]:
    from .fuzzy import FuzzyOptions, expert_rules, speed_limit

    robot = planner.robot
    amax = robot.amax if robot.amax is not None else 2.0 * robot.vmax
    path = _dedupe(traj.poses)
    info: dict = {"applied": False, "amax": amax}
    if len(path) < 2:
        info["reason"] = "the start is the goal"
        return traj, info
    rules = opts.rules if opts.rules is not None else expert_rules()
    s_xy, v_xy = speed_limit(path[:, :2], robot.vmax, amax, rules, FuzzyOptions())
    horizon = max(opts.horizon or 0.0, 3.0 * traj.duration + 30.0)
    rt = retime_profile(scene=planner.scene, path=path, s_xy=s_xy, v_xy=v_xy, t0=query.t0,
                        dt=opts.dt, amax=amax, horizon=horizon, deadline=deadline, hold=query.hold)  # fmt: skip
    info["profile_seconds"] = rt.profile_duration
    if rt.status != "solved":
        info["reason"] = f"the speed-limited path could not be timed among the movers ({rt.message})"
        return traj, info
    rep = check_trajectory(planner.scene, rt.trajectory.waypoints, query)
    if not rep.valid:
        info["reason"] = f"failed the independent check ({rep.reason})"
        return traj, info
    info.update(
        applied=True,
        stops=len(rt.waits),
        before=_speed_figures(traj),
        after=_speed_figures(rt.trajectory),
    )
    return rt.trajectory, info


def _speed_figures(traj: Trajectory) -> dict:
    moving = traj.speeds()[traj.speeds() > 0]
    return {
        "duration": traj.duration,
        "max_speed": float(moving.max(initial=0.0)),
        "mean_speed": float(moving.mean()) if moving.size else 0.0,
    }


def apply_stages(planner, result, start, goal, t0, opts, t_begin, hold: float = 0.0):
    """Run the GA refinement and/or the speed layer on a solved result (the goal pose
    parked ``hold`` seconds after the arrival, checked as well)."""
    deadline = t_begin + opts.time_limit
    query = Query("stage", tuple(start), tuple(goal), t0, hold=hold)
    traj = result.trajectory
    stats = dict(result.stats)
    if opts.refine:
        traj, stats["refine"] = _refine(planner, traj, query, opts, deadline)
    if opts.speed_layer:
        traj, stats["speed_layer"] = _speed_layer(planner, traj, query, opts, deadline)
    for key in ("refine", "speed_layer"):
        if key in stats and not stats[key]["applied"]:
            log.info("%s not applied: %s", key.replace("_", " "), stats[key].get("reason", ""))
    return replace(
        result,
        trajectory=traj,
        planning_seconds=time.perf_counter() - t_begin,
        stats=stats,
    )
