"""Poses and polylines of poses: the one place their arithmetic lives.

A pose is ``[x, y]`` (disc robot) or ``[x, y, heading]`` (box and polygon robots); a
path is an ``(n, d)`` array of poses joined by straight motions, the heading turning
along the shorter arc. Everything that measures, interpolates or cuts such a path uses
these functions, so the planner, the re-timing and the trajectory agree to the last bit
on where a robot is. (:mod:`gfuzzy.check.check` deliberately keeps its own copies: it is the
independent verifier and shares no geometry with the planner.)

This module imports nothing from gfuzzy: it is the bottom of the import graph.
"""

from __future__ import annotations

import decimal
import numbers

import numpy as np

from .typed import FloatArray

__all__ = [
    "as_number",
    "number_array",
    "pose_words",
    "row_words",
    "wrap_angle",
    "metric_distance",
    "interpolate_segment",
    "arc_length",
    "pose_at",
    "split_counts",
    "discretise",
    "path_length_xy",
]


def as_number(value) -> float | None:
    """``value`` as a float when it is one number (a ``numbers.Real``, a ``Decimal`` or a 0-d
    numeric array), else None: a boolean, a string, None or a sequence is no number, as in a
    scene file."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, decimal.Decimal)):
        return None
    return float(value)


def number_array(value) -> FloatArray | None:
    """``value`` (numbers, or nested sequences of numbers of one shape) as a float array, or
    None when any element is no number (:func:`as_number`): numpy would take
    ``[0.5, True]`` as ``[0.5, 1.0]`` and ``["0", "1"]`` as numbers."""
    if isinstance(value, np.ndarray) and value.dtype.kind in "iuf":
        return value.astype(float, copy=False)
    try:
        arr, cells = np.asarray(value), np.asarray(value, dtype=object)
    except (TypeError, ValueError):  # rows of other lengths
        return None
    if arr.dtype.kind in "iuf":  # numbers, unless numpy took a boolean among them for one
        kinds = set(map(type, cells.reshape(-1)))
        return None if bool in kinds or np.bool_ in kinds else arr.astype(float, copy=False)
    out = np.empty(cells.shape, dtype=float)
    flat = out.reshape(-1)
    for i, v in enumerate(cells.reshape(-1)):
        x = as_number(v)
        if x is None:
            return None
        flat[i] = x
    return out


def pose_words(dof: int, robot=None) -> str:
    """What a pose of ``dof`` numbers holds, for messages: ``[x, y, heading] for this disc
    robot (unicycle)``; without ``robot``, which robots take such poses."""
    want = "[x, y]" if dof == 2 else "[x, y, heading]"
    if robot is None:
        return want + (" for a disc robot" if dof == 2 else " for a box or footprint robot or a unicycle")
    unicycle = getattr(robot, "kinematics", "holonomic") != "holonomic"
    return want + f" for this {robot.shape} robot" + (f" ({robot.kinematics})" if unicycle else "")


def row_words(dof: int, robot=None) -> str:
    """What a trajectory row of a ``dof``-number pose holds, for messages: the time, then
    the pose as :func:`pose_words` puts it (``[t, x, y, heading] for this disc robot
    (unicycle)``)."""
    return "[t, " + pose_words(dof, robot)[1:]


def wrap_angle(a):
    """Wrap angles to [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def metric_distance(a: FloatArray, b: FloatArray, circumradius: float) -> FloatArray:
    """Contract metric between poses: xy distance + |shorter heading change| * r.

    Parameters
    ----------
    a, b : (..., 2) or (..., 3) float
    circumradius : float

    Returns
    -------
    (...,) float
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    d = np.hypot(b[..., 0] - a[..., 0], b[..., 1] - a[..., 1])
    if a.shape[-1] == 3:
        d = d + np.abs(wrap_angle(b[..., 2] - a[..., 2])) * circumradius
    return d


def interpolate_segment(a: FloatArray, b: FloatArray, f: FloatArray) -> FloatArray:
    """Poses at fractions ``f`` of straight motions a -> b (heading along the shorter arc).

    Parameters
    ----------
    a, b : (d,) float, or (k, d) float (one motion per fraction)
    f : (k,) float in [0, 1]

    Returns
    -------
    (k, d) float
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    f = np.asarray(f, dtype=float)[:, None]
    delta = b - a
    if a.shape[-1] == 3:
        delta[..., 2] = wrap_angle(delta[..., 2])
    out = a + f * delta
    if a.shape[-1] == 3:
        out[:, 2] = wrap_angle(out[:, 2])
    return out


def arc_length(path: FloatArray, circumradius: float = 0.0) -> FloatArray:
    """Cumulative contract-metric length along a path.

    Parameters
    ----------
    path : (n, d) float
    circumradius : float
        Weight of heading change (ignored for ``d == 2``).

    Returns
    -------
    (n,) float
        0 at the first pose, the path's length at the last.
    """
    path = np.asarray(path, dtype=float)
    return np.concatenate([[0.0], np.cumsum(metric_distance(path[:-1], path[1:], circumradius))])


def pose_at(knots: FloatArray, poses: FloatArray, x: FloatArray) -> FloatArray:
    """Poses of a polyline at parameter values ``x`` (times or arc lengths).

    Linear between consecutive knots, the heading along the shorter arc; ``x`` outside
    ``[knots[0], knots[-1]]`` extrapolates the first or last piece (callers clamp first
    when they need to). A zero-length piece gives its first pose.

    Parameters
    ----------
    knots : (n,) float, non-decreasing, n >= 2
        Parameter value of each pose.
    poses : (n, d) float
    x : (k,) float

    Returns
    -------
    (k, d) float
    """
    knots = np.asarray(knots, dtype=float)
    poses = np.asarray(poses, dtype=float)
    x = np.asarray(x, dtype=float)
    i = np.clip(np.searchsorted(knots, x, side="right") - 1, 0, len(poses) - 2)
    seg = knots[i + 1] - knots[i]
    f = np.where(seg > 0, (x - knots[i]) / np.where(seg > 0, seg, 1.0), 0.0)
    delta = poses[i + 1] - poses[i]
    if poses.shape[1] == 3:
        delta[:, 2] = wrap_angle(delta[:, 2])
    out = poses[i] + f[:, None] * delta
    if poses.shape[1] == 3:
        out[:, 2] = wrap_angle(out[:, 2])
    return out


def split_counts(lengths: FloatArray, step: float) -> FloatArray:
    """Number of equal pieces each motion of ``lengths`` is cut into, each at most ``step``.

    The rule the speed guarantee rests on (docs/formats.md section 3): ``k = max(1,
    ceil(len / step))``, and one more when rounding leaves ``len / k`` above ``step``.
    The roadmap-time graph and the path-velocity chain both cut edges with it.

    Parameters
    ----------
    lengths : (e,) float
        Metric lengths, >= 0.
    step : float
        Largest metric length of a piece (``vmax * dt``), > 0.

    Returns
    -------
    (e,) int64
        At most ``2**40`` each: a count that large is refused by every caller's bound on
        points (``settings.MAX_POINTS``), and a step of 1e-308 made ``inf`` cast to a
        negative int64 (a ValueError traceback, not that refusal).
    """
    lengths = np.asarray(lengths, dtype=float)
    with np.errstate(over="ignore"):  # a length / 1e-308 is inf: clipped
        k = np.clip(np.ceil(lengths / step), 1, 2**40).astype(np.int64)
    return np.where(lengths / k > step, k + 1, k)


def discretise(path: FloatArray, circumradius: float, step: float) -> tuple[FloatArray, FloatArray]:
    """Cut a path into points at most one step (``step`` metres of the metric) apart.

    Parameters
    ----------
    path : (n, d) float
        Poses joined by straight motions.
    circumradius : float
    step : float
        Largest metric distance per step (vmax * dt).

    Returns
    -------
    poses : (m, d) float
        Includes every corner of the path, so the chain never cuts a corner.
    s : (m,) float
        Their arc lengths.
    """
    path = np.asarray(path, dtype=float)
    s_path = arc_length(path, circumradius)
    seg = np.diff(s_path)
    pieces = [np.array([0.0])]
    moving = seg > 0  # repeated poses (zero-length motions) add no point
    k = np.zeros(len(seg), dtype=np.int64)
    k[moving] = split_counts(seg[moving], step)
    for a, length, n in zip(s_path[:-1], seg, k, strict=True):
        if n:
            pieces.append(a + length * np.arange(1, n + 1) / n)
    s = np.concatenate(pieces)
    s[-1] = s_path[-1]
    keep = np.concatenate([[True], np.diff(s) > 0])  # zero-length segments of the input
    s = s[keep]
    return pose_at(s_path, path, s), s


def path_length_xy(path: FloatArray) -> float:
    """Euclidean length of a path's xy polyline."""
    path = np.asarray(path, dtype=float)
    return float(np.sum(np.hypot(*np.diff(path[:, :2], axis=0).T)))

