"""A query's ends checked before any roadmap or search: malformed poses are bad input
(:func:`check_pose`), poses out of bounds or in an obstacle make an ``invalid_query``
(:func:`query_problem`). Both are re-exported by :mod:`gfuzzy.planner.planner`. A goal a
mover comes to rest on for ever is no answer at any horizon (:func:`goal_taken`)."""

from __future__ import annotations

import math

import numpy as np

from ..collision.exact import TOUCH_TOL
from ..collision.geometry import StaticGeometry, mover_distance
from ..errors import InputError
from ..poses import number_array, pose_words
from ..settings import MAX_MAGNITUDE
from ..timespace.timespace import NO_FIRST_MOTION
from ..typed import FloatArray

__all__ = ["check_pose", "query_problem", "goal_taken", "first_motion_hint"]


def check_pose(pose, dof: int, label: str, robot=None) -> FloatArray:
    """``pose`` as a (dof,) float array; InputError naming ``label`` when it is malformed.

    A pose that is not ``dof`` finite numbers is bad input, like a bad scene file; a
    well-formed pose that collides or lies out of bounds is a query answered
    ``invalid_query`` (see :func:`query_problem`). ``robot`` (optional) names its kind in
    the message.
    """
    want = pose_words(dof, robot)
    arr = number_array(pose)
    if arr is None:  # a string, a boolean (even among numbers), None, ragged rows: as in a scene file
        shown = pose.tolist() if isinstance(pose, np.ndarray) else pose
        raise InputError(f"{label}: expected {dof} finite numbers {want}, got {shown!r}")
    if arr.ndim != 1 or arr.shape != (dof,):
        got = f"{arr.size} numbers" if arr.ndim == 1 else f"shape {arr.shape}"
        raise InputError(f"{label}: expected {dof} finite numbers {want}, got {got}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{label}: expected {dof} finite numbers {want}, got {arr.tolist()}")
    if np.abs(arr).max() > MAX_MAGNITUDE:  # as a scene file's: int() of a cell index overflowed
        raise InputError(f"{label}: number too large ({np.abs(arr).max():g}; at most {MAX_MAGNITUDE:g} in magnitude)")
    return arr.copy()


def query_problem(geometry: StaticGeometry, start, goal) -> str:
    """Why a query is ``invalid_query`` (start or goal malformed, out of bounds or in a
    static obstacle), or "" when it is not. Needs no roadmap."""
    dof = geometry.robot.dof
    for label, pose in (("start", start), ("goal", goal)):
        pose = np.asarray(pose, dtype=float).reshape(-1)
        if pose.shape != (dof,) or not np.all(np.isfinite(pose)) or np.abs(pose).max() > MAX_MAGNITUDE:
            return f"{label} must be {dof} finite numbers of at most {MAX_MAGNITUDE:g} in magnitude"
        keep = geometry.robot.clearance
        c = geometry.clearance1(pose)  # the bounds and the obstacles less keep
        to_obstacles = geometry.obstacle_clearance(pose) if c < 0 else math.inf
        # the bounds measured from the corners, or (when the obstacles are clear) as
        # clearance1 measures them: the two can differ by a rounding
        out = max(-float(geometry.bounds_clearance(pose[None])[0]), -c if to_obstacles - keep >= 0 else 0.0)
        if out > 0:  # by how much: a pose meant to touch the bounds can miss by a rounding
            return f"{label} {pose.tolist()} is out of bounds (by {out:.3g} m)"
        if c < 0:
            if to_obstacles < 0:
                return f"{label} {pose.tolist()} collides with a static obstacle"
            return f"{label} {pose.tolist()} is closer than robot.clearance={keep:g} to a static obstacle"
    return ""


def goal_taken(scene, goal, searched_to: float) -> str:
    """Why no answer arrives at ``goal`` however long the horizon: a mover that comes to
    rest on it for ever (a ``once`` mover at its path's end, a path mover of speed 0) by
    ``searched_to`` (the search found no arrival before it), overlapping the robot there
    or closer than ``robot.mover_clearance``; or "".

    Said of a search the horizon cut, instead of "a longer one may find one", which
    sent a user after a horizon that could not help.
    """
    pose = np.asarray(goal, dtype=float)[None]
    keep = scene.robot.mover_clearance
    for mv in scene.movers:
        if mv.rest_time == math.inf:  # it keeps moving, or leaves
            continue
        rest = max(mv.rest_time, 0.0)
        xy = mv.state(np.array([rest]))[0]
        if rest <= searched_to and float(mover_distance(scene.robot, pose, mv.shape, mv.radius, mv.size, xy)[0]) < keep - TOUCH_TOL:
            return (f"the goal is taken for ever from t={rest:.3g} s: mover {mv.name!r} comes to rest there "
                    f"({'mode once' if mv.speed > 0 else 'speed 0'}), so no horizon finds a trajectory")  # fmt: skip
    return ""


def first_motion_hint(robot, dt: float, message: str = NO_FIRST_MOTION) -> str:
    """What a search's ``message`` gains when it found no first motion (``NO_FIRST_MOTION``)
    and the time step is long for the robot (half a step, ``vmax * dt / 2``, beyond its
    circumradius), or "".

    The movers are kept ``(vmax + their speed) * dt / 2`` farther off, for the motion between
    two samples: a robot of 200 m/s at dt 0.07 kept every mover 7 m off, and in a 5 m room
    "the start is too close to a mover at t0" was said of a start metres from any mover;
    dt 0.001 solves it.
    """
    step = robot.vmax * dt
    if message != NO_FIRST_MOTION or step / 2 <= robot.circumradius:
        return ""
    return (f"; a step of {dt:g} s moves this robot up to {step:.3g} m, and the movers are kept "
            f"{step / 2:.3g} m farther off for it: a smaller --dt (PlanOptions.dt) may find one")  # fmt: skip
