"""Where a mover can be over a whole time interval, without sampling the interval.

The check's bisection bounds how fast the clearance changes by the robot's speed plus the
fastest mover's, so a long interval (a wait of an hour at the goal, a last row at t = 1e300)
is halved until the evaluations run out, however far the movers keep. Over any interval,
though, a mover's reference point stays on a known polyline: a path mover on its path (all
of it, whatever the interval), a trajectory mover on its rows between the interval's ends
(and nowhere outside its time range). The robot's reference point stays on the segment
between its poses at the ends (rows are linear in x and y), its body within its
circumradius of that point. Their distance, less the bodies' extents, is a lower bound of
the bodies' distance at every instant of the interval. A mover that stands still all the
interval (a ``once`` mover at either end of its path) does not move the clearance either.
"""

from __future__ import annotations

import math

import numpy as np

from ..scene.scene import Mover, Scene
from ..typed import FloatArray

__all__ = ["moving_window", "near_movers", "one_period_end"]


def near_movers(scene: Scene, pa: FloatArray, pb: FloatArray, ta: FloatArray, tb: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The movers that may come near the robot over each interval: their fastest speed and
    their longest period.

    A mover counts unless it stands still all the interval (:func:`moving_window`) or keeps
    ``robot.mover_clearance`` from the robot throughout it (its reach, the module docstring).
    The clearance to the others and to the static world then changes no faster than the
    robot's own speed plus that speed; and where the robot stands still, it repeats after
    that period.

    Parameters
    ----------
    scene : Scene
    pa, pb : (k, 2) float
        The robot's reference point at the intervals' ends (it moves straight between them).
    ta, tb : (k,) float
        The intervals, ``ta <= tb``.

    Returns
    -------
    speed : (k,) float
        0 where no mover counts.
    period : (k,) float
        0 where no mover counts, inf where one that counts does not repeat (:attr:`Mover.period`).
    """
    mid = 0.5 * (pa + pb)
    reach = 0.5 * np.hypot(*(pb - pa).T) + scene.robot.circumradius + scene.robot.mover_clearance
    speed, period = np.zeros(len(mid)), np.zeros(len(mid))
    for mv in scene.movers:
        lo, hi = moving_window(mv)
        moving = (lo < tb) & (hi > ta)
        if not moving.any():
            continue
        d = _path_distance(mv, mid) if mv.trajectory is None else _rows_distance(mv.trajectory, mid, ta, tb)
        near = moving & (d - mv.extent < reach)
        speed[near] = np.maximum(speed[near], mv.max_speed)
        period[near] = np.maximum(period[near], mv.period)
    return speed, period


#: Halvings enough to bring any finite float interval below any positive period (the
#: exponents span about 2,100 powers of two): a bound on :func:`one_period_end`'s loop.
_MAX_HALVINGS = 2200


def one_period_end(a: FloatArray, b: FloatArray, period: FloatArray) -> FloatArray:
    """For each interval ``[a, b]``, the earliest end ``0.5 (a + m)``, halving from ``b``, that
    still leaves a whole ``period``: a point the check's bisection of ``[a, b]`` samples too,
    so an interval ended there is bisected as the whole one was.

    The end stays ``b`` (the interval is bisected whole, as without the cut) where the period
    is not positive, or where the halving reaches the float spacing at ``a`` before it leaves
    less than a period (a period about that spacing or below: around t = 1e17 for a 10 s
    period), where an interval ended there could not be split further. Each interval takes at most
    :data:`_MAX_HALVINGS` halvings."""
    out = np.array(b, dtype=float, copy=True)
    for i in range(len(out)):
        out[i] = _halve_to_period(float(a[i]), float(b[i]), float(period[i]))
    return out


def _halve_to_period(a: float, b: float, period: float) -> float:
    """:func:`one_period_end` for one interval."""
    if not period > 0:
        return b
    end = b
    for _ in range(_MAX_HALVINGS):
        mid = 0.5 * (a + end)
        if not a < mid < end:  # the float spacing at a is about the period: no bisection point
            return b
        if mid - a < period:
            return end
        end = mid
    return b


def moving_window(mv: Mover) -> tuple[float, float]:
    """When ``mv`` moves: before and after it stands still (a ``once`` path mover at its
    path's ends) or is absent (a trajectory mover outside its rows); ``(inf, inf)``: never."""
    if mv.trajectory is not None:
        return mv.time_range
    if mv.speed == 0:
        return (math.inf, math.inf)
    if mv.mode != "once":
        return (-math.inf, math.inf)
    length = float(np.hypot(*np.diff(mv.path, axis=0).T).sum())
    return (-mv.offset / mv.speed, (length - mv.offset) / mv.speed)


def _path_distance(mv: Mover, points: FloatArray) -> FloatArray:
    """Distance from each point to a path mover's whole polyline (closed for a loop)."""
    pts = mv._polyline
    if len(pts) == 1:
        return np.hypot(*(points - pts[0]).T)
    return _segments_distance(points[:, None], pts[None, :-1], pts[None, 1:]).min(axis=1)


def _rows_distance(tr: FloatArray, points: FloatArray, ta: FloatArray, tb: FloatArray) -> FloatArray:
    """Distance from each point to the trajectory mover's polyline between ``ta`` and ``tb``
    (its positions there, its rows in between); inf where it is absent all the interval."""
    t, xy = tr[:, 0], tr[:, 1:3]
    a, b = np.maximum(ta, t[0]), np.minimum(tb, t[-1])
    present = a <= b
    out = np.full(len(points), np.inf)
    if not present.any():
        return out
    a, b, p = a[present], b[present], points[present]
    ends = [np.column_stack([np.interp(x, t, xy[:, 0]), np.interp(x, t, xy[:, 1])]) for x in (a, b)]
    lo, hi = np.searchsorted(t, a, side="right"), np.searchsorted(t, b, side="left")
    inner = np.maximum(hi - lo, 0)  # rows strictly inside each interval
    count = inner + 2  # each interval's polyline: its start, those rows, its end
    first = np.concatenate([[0], np.cumsum(count)[:-1]])
    verts = np.empty((int(count.sum()), 2))
    verts[first] = ends[0]
    verts[first + count - 1] = ends[1]
    owner = np.repeat(np.arange(len(a)), inner)
    within = np.arange(len(owner)) - np.repeat(np.cumsum(inner) - inner, inner)  # 0.. inner-1
    verts[first[owner] + 1 + within] = xy[lo[owner] + within]
    segs = count - 1
    seg_owner = np.repeat(np.arange(len(a)), segs)
    start = np.repeat(first, segs) + np.arange(len(seg_owner)) - np.repeat(np.cumsum(segs) - segs, segs)
    d = _segments_distance(p[seg_owner], verts[start], verts[start + 1])
    out[present] = np.minimum.reduceat(d, np.cumsum(segs) - segs)
    return out


def _segments_distance(c: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """Distance from points ``c`` to segments ``a``-``b`` (broadcast, last axis x, y)."""
    ab = b - a
    den = np.maximum((ab * ab).sum(-1), 1e-300)
    f = np.clip(((c - a) * ab).sum(-1) / den, 0.0, 1.0)
    return np.hypot(*np.moveaxis(a + f[..., None] * ab - c, -1, 0))
