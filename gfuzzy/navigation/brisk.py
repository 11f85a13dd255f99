"""The navigator's plan at full speed up to its first wait (:func:`brisk`), and its last
move into the goal at full speed (:func:`brisk_arrival`, always on).

The time-space search moves in whole steps of ``dt``, so a plan runs a little under the
robot's speed bound; the navigator answers with the same path at full speed up to its
first wait when that keeps the gaps its search kept.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from ..poses import metric_distance
from ..trajectory import Trajectory
from ..typed import FloatArray

if TYPE_CHECKING:
    from .navigator import Navigator

__all__ = ["brisk", "brisk_arrival"]


def brisk(nav: Navigator, t: float, pose: FloatArray, traj: Trajectory, obs: FloatArray,
          infl: Callable[[], FloatArray], ghosts: bool) -> Trajectory:  # fmt: skip
    """``traj`` with its motion up to its first wait (or to its end) at full speed, when
    that keeps the gaps its search kept; ``traj`` otherwise (a disc robot's plan only).

    The search moves one step of ``dt`` between two points of the graph's edges, cut
    into pieces of at most one step's length: every edge (and the robot's connection
    into the graph, from wherever it is) takes a whole number of steps, so the robot
    runs at ``vmax`` times its length over that rounded up, 5-10 % slower on the
    roadmap's short edges. Along the same path at ``vmax`` the robot reaches the first
    wait sooner and waits there until the plan goes on (at the goal: arrives sooner).
    Checked every ``MOTION_SAMPLE`` s until the plan's own time at that point (after
    it, the two are the same) against everyone walking on at constant velocity with
    the inflation ``infl()`` (k, S) of the plan's search (called only then) and, when it
    kept off people's ways (``ghosts``), against the ghosts it kept off.
    """
    w = traj.waypoints
    if nav.robot.unicycle or nav.robot.dof != 2 or nav.robot.shape != "disc" or len(w) < 2:
        return traj
    step = np.hypot(*np.diff(w[:, 1:3], axis=0).T)
    still = np.nonzero(step <= 1e-9)[0]
    k = int(still[0]) if len(still) else len(step)  # rows 0..k move, row k starts the wait (or ends)
    if k < 1:
        return traj
    times = t + np.concatenate([[0.0], np.cumsum(step[:k])]) / nav.vplan
    if w[k, 0] - times[-1] < 1e-6:
        return traj
    rows = w.copy()
    rows[: k + 1, 0] = times
    fast = Trajectory(rows, traj.circumradius)
    return fast if _keeps(nav, t, pose, fast, float(w[k, 0]), obs, infl, ghosts) else traj


def _keeps(nav: Navigator, t: float, pose: FloatArray, fast: Trajectory, until: float, obs: FloatArray,
           infl_of: Callable[[], FloatArray], ghosts: bool) -> bool:  # fmt: skip
    """Whether ``fast`` keeps, until ``until``, the gaps ``infl_of()`` from everyone seen walking
    on and, when the plan kept off people's ways (``ghosts``), from the ghosts it kept off."""
    if not len(obs):
        return True
    infl = infl_of()
    rows_g, infl_g = nav._path_ghosts(pose, obs) if ghosts and nav.options.path_space > 0 else (None, None)
    return nav._keeps_gaps(fast, t, until, obs, infl) and (
        rows_g is None or not len(rows_g) or nav._keeps_gaps(fast, t, until, rows_g, infl_g))


def brisk_arrival(nav: Navigator, t: float, pose: FloatArray, traj: Trajectory, obs: FloatArray,
                  infl: Callable[[], FloatArray], ghosts: bool, since: float) -> Trajectory:  # fmt: skip
    """``traj`` with its first move at full speed (a holonomic robot of any shape) when
    that move ends at the goal and takes longer than ``since`` (the time since the last call, the period
    at which the robot is replanned): the robot is within a step of the goal, and the
    search gives the sliver left a whole step of ``dt``. Replanned every period shorter
    than ``dt``, the robot covered only ``period / dt`` of what was left at each call and
    crept into the goal (in an empty room, ``dt`` 0.4 s and calls every 0.25 s: 8 m in
    11.0 s, 19.5 s at ``dt`` 1, for plans of 8.4 and 9 s). With ``dt`` at most the period
    the move ends before the next call: the plan is left as it is."""
    w, cr = traj.waypoints, nav.robot.circumradius
    if (nav.robot.unicycle or len(w) < 2 or w[1, 0] - t <= since + 1e-9
            or float(metric_distance(w[1, 1:], nav.goal, cr)) > nav.options.goal_tolerance):
        return traj
    arrive = t + float(metric_distance(w[0, 1:], w[1, 1:], cr)) / nav.vplan  # the same motion, sooner
    if w[1, 0] - arrive < 1e-6:
        return traj
    rows = w.copy()
    rows[1, 0] = arrive
    fast = Trajectory(rows, cr)
    return fast if _keeps(nav, t, pose, fast, float(w[1, 0]), obs, infl, ghosts) else traj
