"""The speed layer of a differential drive: straights and turns in place, each from rest.

A differential drive's path (``kinematics: unicycle``, CONTRACT section 6) is a sequence of
turns in place and straight moves along the heading. Such a robot cannot turn while it
moves, so it is at rest wherever a straight meets a turn (and wherever it reverses its
direction of travel or of turning): every straight is an accelerate-cruise-decelerate
profile that ends at rest at the coming turn, and every turn in place a turning-rate
profile that starts and ends at rest.

The profile is one speed bound along the path's *metric* arc length (xy distance plus
``r |heading change|``, the contract's configuration speed, ``r`` the circumscribed radius):

* along a straight, the fuzzy controller's bound (:func:`gfuzzy.fuzzy.fuzzy.speed_limit`
  on the xy polyline, whose corners are the turns in place): the coming turn's angle and
  distance brake the robot as they brake a holonomic one at a bend, within ``vmax``;
* along a turn in place, ``r * turn_rate`` (``|w| <= turn_rate``, at most ``wmax``);
* zero at every stop, then the forward-backward pass of
  :func:`gfuzzy.fuzzy.profile.limit_acceleration` with ``amax``: along a straight that is
  the linear acceleration bound, along a turn the angular one, ``amax / r`` rad/s^2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..poses import wrap_angle
from ..typed import FloatArray
from .fuzzy import FuzzyOptions, RuleBase, speed_limit
from .profile import limit_acceleration

__all__ = ["DriveProfile", "drive_profile", "STILL_XY", "SAME_HEADING"]

#: A segment moving less than this (m) is a turn in place.
STILL_XY = 1e-9
#: A segment turning less than this (rad) keeps its heading.
SAME_HEADING = 1e-9


@dataclass(frozen=True)
class DriveProfile:
    """A differential drive's speed bound along its path.

    Attributes
    ----------
    s : (k,) float
        Increasing metric arc lengths (xy distance + r |heading change|), 0 to the length.
    v : (k,) float
        Metric speed bound at ``s``; ``v**2`` is linear in ``s`` between samples (constant
        acceleration), 0 at both ends and at every stop.
    knots : (n,) float
        Metric arc length of each path pose.
    stops : (m,) float
        Arc lengths of the stops inside the path: where a straight meets a turn in place,
        or the direction of travel or of turning changes.
    turning : (n - 1,) bool
        Which path segments are turns in place.
    """

    s: FloatArray
    v: FloatArray
    knots: FloatArray
    stops: FloatArray
    turning: FloatArray


def _segments(path: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """xy length, signed heading change, turn flags and direction signs of each segment."""
    d = np.diff(path[:, :2], axis=0)
    seg_xy = np.hypot(d[:, 0], d[:, 1])
    dh = wrap_angle(np.diff(path[:, 2]))
    turning = seg_xy <= STILL_XY
    mixed = ~turning & (np.abs(dh) > SAME_HEADING)
    if np.any(mixed):
        i = int(np.argmax(mixed))
        raise InputError(f"segment {i} of the path turns while it moves: not a differential drive's path")
    along = np.cos(path[:-1, 2]) * d[:, 0] + np.sin(path[:-1, 2]) * d[:, 1]
    sign = np.where(turning, np.sign(dh), np.sign(along))
    return seg_xy, dh, turning, sign


def drive_profile(
    path: FloatArray,
    circumradius: float,
    vmax: float,
    amax: float,
    turn_rate: float,
    rulebase: RuleBase | None = None,
    options: FuzzyOptions | None = None,
) -> DriveProfile:
    """The speed bound of a differential drive along ``path``.

    Parameters
    ----------
    path : (n, 3) float
        Poses ``[x, y, heading]``, no two consecutive the same; each segment a turn in place
        or a straight move along the heading.
    circumradius : float
        ``r`` of the metric (the robot's circumscribed radius), > 0.
    vmax : float
        Speed bound along a straight, m/s.
    amax : float
        Bound on the metric acceleration (m/s^2; ``amax / r`` rad/s^2 in a turn).
    turn_rate : float
        Bound on ``|w|`` in a turn in place, rad/s.
    rulebase : RuleBase, optional
        The fuzzy rules (default the expert rules).
    options : FuzzyOptions, optional
        ``options.ds`` is also the profile's sample spacing.

    Returns
    -------
    DriveProfile

    Raises
    ------
    InputError
        If a segment both moves and turns, or a bound is not positive.
    """
    path = np.asarray(path, dtype=float)
    opts = FuzzyOptions() if options is None else options
    if path.ndim != 2 or path.shape[1] != 3 or len(path) < 2:
        raise InputError(f"a differential drive's path is (n >= 2, 3) poses, got shape {path.shape}")
    for name, value in (("circumradius", circumradius), ("vmax", vmax), ("amax", amax), ("turn_rate", turn_rate)):
        if not (math.isfinite(value) and value > 0):
            raise InputError(f"{name} must be positive and finite, got {value}")
    seg_xy, dh, turning, sign = _segments(path)
    seg_m = np.where(turning, np.abs(dh) * circumradius, seg_xy)
    knots = np.concatenate([[0.0], np.cumsum(seg_m)])
    cum_xy = np.concatenate([[0.0], np.cumsum(seg_xy)])
    # samples: every segment cut into pieces of at most ds (at least two, so that a short
    # segment between two stops still has a sample where it moves)
    pieces = np.maximum(2, np.ceil(seg_m / opts.ds)).astype(int)
    seg_of = np.repeat(np.arange(len(seg_m)), pieces)
    frac = np.concatenate([np.arange(k) / k for k in pieces])
    s = np.append(knots[seg_of] + frac * seg_m[seg_of], knots[-1])
    seg_of = np.append(seg_of, len(seg_m) - 1)
    frac = np.append(frac, 1.0)
    cap = np.full(len(s), turn_rate * circumradius)
    straight = ~turning[seg_of]
    if np.any(straight):
        xy = path[:, :2][np.concatenate([[True], ~turning])]  # the xy polyline: its corners are the turns
        s_xy, v_xy = speed_limit(xy, vmax, amax, rulebase, opts)
        sx = cum_xy[seg_of] + frac * seg_xy[seg_of]
        fuzzy = np.sqrt(np.interp(sx, s_xy, np.asarray(v_xy) ** 2))
        cap[straight] = np.minimum(fuzzy[straight], vmax)
    change = (turning[1:] != turning[:-1]) | (sign[1:] != sign[:-1])
    stops = knots[1:-1][change]
    cap[np.isin(s, stops)] = 0.0
    # inside a segment the bound stays positive (the fuzzy bound is 0 only at the xy ends)
    inner = (s > 0) & (s < knots[-1]) & ~np.isin(s, stops)
    cap = np.where(inner, np.maximum(cap, 1e-3 * vmax), cap)
    v = limit_acceleration(s, cap, amax)
    return DriveProfile(s=s, v=v, knots=knots, stops=stops, turning=turning)
