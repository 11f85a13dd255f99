"""What a trajectory's rows must be before any geometry is looked at (docs/formats.md section 3).

Rows of ``[t, x, y(, heading)]``, finite, at strictly increasing times; a differential
drive's rows keep its rule (CONTRACT section 6): each pair a wait, a turn in place within
``wmax`` or a straight move along the heading (forward unless ``robot.reverse``); with a
query, the first row its start at its ``t0`` and the last its goal.
:func:`gfuzzy.check.check.check_trajectory` asks :func:`rows_problem` first; like it, this
module shares no code with the planner.
"""

from __future__ import annotations

import math

import numpy as np

from ..poses import row_words
from ..typed import FloatArray

__all__ = ["RowProblem", "pose_equal", "rows_problem", "unicycle_problem", "wrap"]

#: What is wrong with the rows, and when (None: the rows' shape or numbers, not a time).
RowProblem = tuple[str, "float | None"]


def wrap(a):
    """Angles wrapped into [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def pose_equal(a, b, tol=1e-6) -> bool:
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.shape != b.shape:
        return False
    diff = b - a
    if a.size == 3:
        diff[2] = wrap(diff[2])
    return bool(np.all(np.abs(diff) <= tol))


def rows_problem(robot, w: FloatArray, query) -> RowProblem | None:
    """The rows' shape, finiteness, increasing times, and the query's ends (None: fine)."""
    if w.ndim != 2 or w.shape[1] != robot.dof + 1 or len(w) == 0:
        return f"waypoints must be rows of {row_words(robot.dof, robot)}", None
    if not np.all(np.isfinite(w)):
        return "waypoints contain a non-finite number", None
    t = w[:, 0]
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.nonzero(dt <= 0)[0][0]) + 1
        return f"t does not increase strictly at row {i} (t={float(t[i])!r})", float(t[i])
    if getattr(robot, "kinematics", "holonomic") == "unicycle":
        bad = unicycle_problem(robot, w)
        if bad is not None:
            return bad
    if query is not None:
        if abs(t[0] - query.t0) > 1e-6:
            return f"first row is at t={float(t[0])!r}, the query departs at t0={query.t0!r}", float(t[0])
        if not pose_equal(w[0, 1:], query.start):
            return f"first row {w[0, 1:].tolist()} is not the start {list(query.start)}", float(t[0])
        if not pose_equal(w[-1, 1:], query.goal):
            return f"last row {w[-1, 1:].tolist()} is not the goal {list(query.goal)}", float(t[-1])
    return None


#: A unicycle's rows: a turn in place keeps x and y within this (m); a straight move keeps
#: its heading within this (rad). The lateral bound is the contract's 1e-6 m.
UNICYCLE_XY_TOL = 1e-9
UNICYCLE_HEADING_TOL = 1e-9
UNICYCLE_LATERAL_TOL = 1e-6


def unicycle_problem(robot, w: FloatArray, tol: float = 1e-6) -> RowProblem | None:
    """The first pair of rows that is not a wait, a turn in place within ``wmax`` or a
    straight move along the heading (forward unless ``robot.reverse``), or None.

    Measured here from the rows alone (CONTRACT section 6), sharing nothing with the planner.
    """
    t, x, y, h = w[:, 0], w[:, 1], w[:, 2], w[:, 3]
    dt = np.diff(t)
    dx, dy = np.diff(x), np.diff(y)
    dh = wrap(np.diff(h))
    if robot.shape == "footprint":  # its farthest vertex from the reference point
        r = max(math.hypot(px, py) for px, py in robot.footprint)
    else:
        r = robot.radius if robot.shape == "disc" else 0.5 * math.hypot(*robot.size)
    wmax = robot.wmax if robot.wmax is not None else robot.vmax / r
    still = (np.abs(dx) <= UNICYCLE_XY_TOL) & (np.abs(dy) <= UNICYCLE_XY_TOL)
    turning = np.abs(dh) > UNICYCLE_HEADING_TOL
    c, sn = np.cos(h[:-1]), np.sin(h[:-1])
    lateral = np.abs(-sn * dx + c * dy)
    along = c * dx + sn * dy
    for i in range(len(dt)):
        when = f"between t={float(t[i])!r} and t={float(t[i + 1])!r}"
        if still[i]:
            if turning[i] and abs(dh[i]) / dt[i] > wmax * (1 + tol):
                rate = abs(dh[i]) / dt[i]
                return f"turns at {rate:.9g} rad/s, faster than wmax {wmax:g}, {when}", float(t[i])
            continue
        if turning[i]:
            return f"turns while moving (a unicycle turns only in place) {when}", float(t[i])
        if lateral[i] > UNICYCLE_LATERAL_TOL:
            return f"slides sideways by {lateral[i]:.3g} m (a unicycle moves along its heading) {when}", float(t[i])
        if along[i] < 0 and not robot.reverse:
            return f"drives backwards (robot.reverse is false) {when}", float(t[i])
    return None
