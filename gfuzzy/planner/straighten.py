"""Fewer corners for a differential drive: a stop saved at every corner dropped.

A differential drive stops at every corner to turn in place (docs/speed-layer.md), and a
roadmap's path has many small ones: a path through a k-nearest roadmap zig-zags by a few
degrees at every vertex. :func:`straighten` shortcuts the corners greedily, keeping only
motions the static geometry certifies, so the speed layer brakes and turns less often.
"""

from __future__ import annotations

import math

import numpy as np

from ..poses import wrap_angle
from ..timespace.drive import SAME_HEADING, pick_turn
from ..typed import FloatArray

__all__ = ["straighten", "corners", "drive_path", "LOOK_AHEAD"]

#: Corners tried ahead of the current one (the farthest first).
LOOK_AHEAD = 40
#: A turn is cut into rows of at most this (rad): rows turn along the shorter arc.
_ROW_TURN = 0.5 * math.pi


def corners(path: FloatArray) -> FloatArray | None:
    """The xy points where a differential drive's path turns (its ends included), or None
    when the path drives backwards somewhere.

    Parameters
    ----------
    path : (n, 3) float
        Turns in place and straight moves, no repeated pose.

    Returns
    -------
    (k, 2) float or None
    """
    d = np.diff(path[:, :2], axis=0)
    moving = np.hypot(d[:, 0], d[:, 1]) > 1e-9
    along = np.cos(path[:-1, 2]) * d[:, 0] + np.sin(path[:-1, 2]) * d[:, 1]
    if np.any(moving & (along < 0)):
        return None
    xy = path[np.concatenate([[True], moving]), :2]
    if len(xy) > 2:  # drop the points where the path goes straight on
        u = np.diff(xy, axis=0)
        cross = u[:-1, 0] * u[1:, 1] - u[:-1, 1] * u[1:, 0]
        dot = np.sum(u[:-1] * u[1:], axis=1)
        bend = np.abs(np.arctan2(cross, dot)) > SAME_HEADING
        xy = xy[np.concatenate([[True], bend, [True]])]
    return xy


def _turn_rows(x: float, y: float, h: float, dh: float) -> list:
    """Rows of a turn in place by ``dh`` (signed), each at most ``_ROW_TURN``."""
    n = max(1, int(math.ceil(abs(dh) / _ROW_TURN - 1e-12)))
    return [np.array([x, y, float(wrap_angle(h + dh * i / n))]) for i in range(1, n + 1)]


def _ending(geometry, out: list, h: float, goal) -> FloatArray | None:
    """``out`` (rows arriving at ``goal``'s position with heading ``h``) closed by the turn
    in place to ``goal``'s heading, its last row exactly ``goal``; None when that turn is
    not free either way."""
    g = np.asarray(goal, dtype=float)
    dh = pick_turn(geometry, float(g[0]), float(g[1]), h, float(g[2]))
    if dh is None:
        return None
    path = np.array(out + (_turn_rows(float(g[0]), float(g[1]), h, dh) if dh else []))
    path[-1] = g
    return path


def _straight_free(geometry, a: list, b: list) -> bool:
    """Static certification of a straight move (a disc's body ignores the heading)."""
    if geometry.robot.shape == "disc":
        return geometry.motion_free(a[:2], b[:2])
    return geometry.motion_free(a, b)


def straighten(geometry, path: FloatArray, look_ahead: int = LOOK_AHEAD) -> FloatArray:
    """A path through fewer of ``path``'s corners, every motion certified statically.

    From each kept corner the farthest corner ahead (at most ``look_ahead`` on) is taken
    whose straight is free and the turn in place towards it too (the shorter arc when its
    sweep is free, else the longer); the goal's heading is turned to at the end.

    Parameters
    ----------
    geometry : StaticGeometry
        The scene's static collision model (its robot a differential drive).
    path : (n, 3) float
        A certified path of turns in place and straight moves, no repeated pose.
    look_ahead : int

    Returns
    -------
    (m, 3) float
        The straightened path, start and goal poses exactly ``path``'s; ``path`` itself when
        nothing is saved or a corner cannot be left (e.g. a path that reverses).
    """
    path = np.asarray(path, dtype=float)
    pts = corners(path) if len(path) > 2 else None
    if pts is None or len(pts) <= 2:
        return path
    out = [path[0]]
    i, h = 0, float(path[0, 2])
    while i < len(pts) - 1:
        x, y = float(pts[i, 0]), float(pts[i, 1])
        for j in range(min(len(pts) - 1, i + look_ahead), i, -1):
            hn = math.atan2(pts[j, 1] - y, pts[j, 0] - x)
            dh = pick_turn(geometry, x, y, h, hn)
            if dh is None:
                continue
            turned = [x, y, float(wrap_angle(h + dh))] if dh else [x, y, h]
            end = [float(pts[j, 0]), float(pts[j, 1]), turned[2]]
            if _straight_free(geometry, turned, end):
                break
        else:
            return path
        if dh:
            out += _turn_rows(x, y, h, dh)
        out.append(np.array(end))
        i, h = j, end[2]
    straight = _ending(geometry, out, h, path[-1])
    return straight if straight is not None and len(corners(straight)) < len(pts) else path


def drive_path(geometry, start: FloatArray, via: FloatArray, goal: FloatArray, reverse: bool = False,
               prefer=None) -> FloatArray | None:  # fmt: skip
    """A differential drive's path through via-points: straight moves joined by turns in
    place, each turn along the shorter arc when its sweep is free, else the longer one.
    With ``reverse`` (the robot may drive backwards) each straight is driven forwards or
    backwards: the one whose heading is nearer ``prefer(xy)`` at its start (a callable
    giving a heading, e.g. the corridor's the GA refined: backwards where the search
    backed), else the one needing the smaller turn; the other when that turn is not free.

    Parameters
    ----------
    geometry : StaticGeometry
    start, goal : (3,) float
    via : (m, 2) float

    Returns
    -------
    (n, 3) float or None
        None when a turn in place is not free either way (the straights are left to the
        caller's certification).
    """
    pts = np.vstack([np.asarray(start, dtype=float)[None, :2], np.asarray(via, dtype=float).reshape(-1, 2),
                     np.asarray(goal, dtype=float)[None, :2]])  # fmt: skip
    pts = pts[np.concatenate([[True], np.hypot(*np.diff(pts, axis=0).T) > 1e-12])]
    out = [np.asarray(start, dtype=float)]
    h = float(start[2])
    for a, b in zip(pts[:-1], pts[1:], strict=True):
        ahead = math.atan2(b[1] - a[1], b[0] - a[0])
        ways = [ahead, float(wrap_angle(ahead + math.pi))] if reverse else [ahead]
        near = h if prefer is None else float(prefer(a))
        ways.sort(key=lambda hn: abs(float(wrap_angle(hn - near))))
        turns = (pick_turn(geometry, float(a[0]), float(a[1]), h, hn) for hn in ways)
        dh = next((d for d in turns if d is not None), None)
        if dh is None:
            return None
        if dh:
            out += _turn_rows(float(a[0]), float(a[1]), h, dh)
            h = float(out[-1][2])
        out.append(np.array([b[0], b[1], h]))
    return _ending(geometry, out, h, goal)
