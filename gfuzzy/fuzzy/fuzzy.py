"""The fuzzy speed layer: a Mamdani controller that bounds the speed along a path.

After Antonelli, Chiaverini and Fusco, "A fuzzy-logic-based approach for mobile
robot path tracking", IEEE Transactions on Fuzzy Systems 15(2), 2007: the robot
looks ahead along its path, measures how much the path turns there (*curve*) and
how far away that bend is (*distance*), and a fuzzy rule base turns the pair into
a cruise speed. Sharp, near bends give a low speed, straights and far bends a high
one. The rule base (:mod:`gfuzzy.fuzzy.rules`) is a chromosome (one allele per pair of input
sets); :mod:`gfuzzy.learning.learn` learns one by a genetic algorithm in three
self-organising stages, outside the planning package's import graph.

Pipeline of :func:`speed_limit`::

    path (n, 2) --curve_ahead--> curve, distance in [0, 1] at arc lengths s
                --Mamdani (min AND, max aggregation, centroid)--> speed fraction
                --x vmax, forward-backward pass with amax--> v(s)

Conventions
-----------
* Inputs and output live on ``[0, 1]``. Every partition is a Ruspini partition of
  triangles: the feet of set ``i`` are the peaks of its neighbours (the end sets
  mirror theirs outside ``[0, 1]``), so memberships sum to one everywhere.
* The chromosome is ``genes[i * n_distance + j]`` for curve set ``i`` and distance
  set ``j``; ``0`` means *no rule*, ``k >= 1`` means *speed is output set k - 1*.
* Rule files and partitions: :mod:`gfuzzy.fuzzy.rules` (re-exported here); profile maths
  (the acceleration bound, timing): :mod:`gfuzzy.fuzzy.profile` (re-exported here).
* When no rule fires the raw controller output is ``FuzzyOptions.min_speed``.
"""

from __future__ import annotations

import functools
import logging
import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..typed import ArrayLike, FloatArray
from .profile import clean_path as _clean_path
from .profile import limit_acceleration, profile_times
from .rules import (
    LABELS,
    UNEQUAL_PEAKS,
    Partition,
    RuleBase,
    expert_rules,
    format_rules,
    learned_rules,
    load_rules,
    parse_rules,
    save_rules,
)

logger = logging.getLogger(__name__)
logger.addHandler(logging.NullHandler())

__all__ = [
    "LABELS",
    "UNEQUAL_PEAKS",
    "Partition",
    "RuleBase",
    "FuzzyOptions",
    "SpeedController",
    "curve_ahead",
    "infer_exact",
    "limit_acceleration",
    "speed_limit",
    "profile_times",
    "expert_rules",
    "learned_rules",
    "parse_rules",
    "format_rules",
    "load_rules",
    "save_rules",
]

# --------------------------------------------------------------------------
# Inference
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class FuzzyOptions:
    """Settings of the fuzzy speed layer.

    The partitions are not here: they belong to the :class:`RuleBase` (a rule
    file names them), since the chromosome means nothing without them.

    Attributes
    ----------
    lookahead : float
        Look-ahead distance along the path, metres; the distance input is the
        distance to the bend divided by it.
    max_turn : float
        Turning (radians) that maps to curve = 1; more is clipped.
    min_speed : float
        Lowest speed fraction of vmax away from the path's ends, and the raw
        controller output when no rule fires.
    ds : float
        Arc-length step of the speed profile, metres (path vertices are added).
    surface_resolution : int
        Grid points per input axis of the precomputed control surface (61 puts
        grid nodes on every peak of the standard partitions).
    output_resolution : int
        Points of the output universe used by the centroid.
    exact : bool
        Evaluate the controller exactly at every sample instead of
        interpolating the surface bilinearly.
    """

    lookahead: float = 1.5
    max_turn: float = math.pi
    min_speed: float = 0.1
    ds: float = 0.05
    surface_resolution: int = 61
    output_resolution: int = 601
    exact: bool = False

    def __post_init__(self) -> None:
        for name in ("lookahead", "max_turn", "ds"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise InputError(f"{name} must be positive and finite, got {value}")
        if not 0.0 < self.min_speed <= 1.0:
            raise InputError(f"min_speed must be in (0, 1], got {self.min_speed}")
        if self.surface_resolution < 2 or self.output_resolution < 2:
            raise InputError("resolutions must be at least 2")


_CHUNK = 1024


def infer_exact(
    curve: ArrayLike,
    dist: ArrayLike,
    rulebase: RuleBase | None = None,
    options: FuzzyOptions | None = None,
) -> FloatArray:
    """Mamdani inference evaluated exactly at every input pair.

    Fuzzification by the triangles of the rule base's partitions, ``min`` for
    AND (and for implication), ``max`` aggregation, and the centroid of the
    aggregated output. The aggregated membership is sampled on
    ``options.output_resolution`` points of ``[0, 1]`` plus the points where
    each output set meets its firing level, and its centroid is that of the
    piecewise-linear interpolant (the same construction as scikit-fuzzy's
    ``ControlSystemSimulation``, so the two agree to rounding).

    Parameters
    ----------
    curve, dist : (m,) float
        Normalised inputs, broadcast together; clipped to ``[0, 1]``.
    rulebase : RuleBase, optional
        Default :func:`expert_rules`.
    options : FuzzyOptions, optional

    Returns
    -------
    (m,) float
        Raw centroid in ``[0, 1]``; ``options.min_speed`` where no rule fires.
    """
    rb = expert_rules() if rulebase is None else rulebase
    opt = FuzzyOptions() if options is None else options
    c, d = np.broadcast_arrays(np.asarray(curve, dtype=float), np.asarray(dist, dtype=float))
    shape = c.shape
    c, d = c.reshape(-1), d.reshape(-1)
    out = np.empty(c.size)
    for lo in range(0, c.size, _CHUNK):
        sl = slice(lo, lo + _CHUNK)
        act = _activations(rb, c[sl], d[sl])
        out[sl] = _centroid(act, rb.speed.triangles, opt.output_resolution, opt.min_speed)
    return out.reshape(shape)


def _activations(rb: RuleBase, c: FloatArray, d: FloatArray) -> FloatArray:
    """Firing level of every output set, ``(m, speed.size)``."""
    fire = np.minimum(rb.curve.membership(c)[:, :, None], rb.distance.membership(d)[:, None, :])
    fire = fire.reshape(c.size, -1)
    genes = np.asarray(rb.genes)
    act = np.zeros((c.size, rb.speed.size))
    for k in range(1, rb.speed.size + 1):
        cols = genes == k
        if cols.any():
            act[:, k - 1] = fire[:, cols].max(axis=1)
    return act


def _centroid(act: FloatArray, tri: FloatArray, resolution: int, fallback: float) -> FloatArray:
    """Centroid of ``max_k min(act_k, tri_k)`` over ``[0, 1]`` for each row of ``act``."""
    m, k = act.shape
    grid = np.linspace(0.0, 1.0, resolution)
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    # The cut points make the clipped sets exactly piecewise linear on the samples.
    rise = a + act * (b - a)
    fall = c - act * (c - b)
    extra = np.clip(np.concatenate([rise, fall], axis=1), 0.0, 1.0)
    x = np.sort(np.concatenate([np.broadcast_to(grid, (m, resolution)), extra], axis=1), axis=1)
    y = np.zeros_like(x)
    for j in range(k):
        if np.any(act[:, j] > 0):
            mu = np.clip(
                np.minimum((x - a[j]) / (b[j] - a[j]), (c[j] - x) / (c[j] - b[j])), 0.0, 1.0
            )
            np.maximum(y, np.minimum(mu, act[:, j : j + 1]), out=y)
    x1, x2, y1, y2 = x[:, :-1], x[:, 1:], y[:, :-1], y[:, 1:]
    dx = x2 - x1
    area = np.sum(dx * (y1 + y2), axis=1) / 2.0
    moment = np.sum(dx * (x1 * (2 * y1 + y2) + x2 * (y1 + 2 * y2)), axis=1) / 6.0
    fired = area > 0
    return np.where(fired, moment / np.where(fired, area, 1.0), fallback)


@functools.lru_cache(maxsize=32)
def _surface(rb: RuleBase, n: int, resolution: int, min_speed: float) -> FloatArray:
    axis = np.linspace(0.0, 1.0, n)
    cc, dd = np.meshgrid(axis, axis, indexing="ij")
    opt = FuzzyOptions(surface_resolution=n, output_resolution=resolution, min_speed=min_speed)
    surf = infer_exact(cc, dd, rb, opt)
    surf.setflags(write=False)
    return surf


class SpeedController:
    """A rule base made ready for fast evaluation on arrays.

    The control surface is computed once on an ``n x n`` grid of
    (curve, distance) and cached per (rule base, resolutions); :meth:`infer`
    interpolates it bilinearly.

    Parameters
    ----------
    rulebase : RuleBase, optional
        Default :func:`expert_rules`.
    options : FuzzyOptions, optional
    """

    def __init__(self, rulebase: RuleBase | None = None, options: FuzzyOptions | None = None):
        self.rulebase = expert_rules() if rulebase is None else rulebase
        self.options = FuzzyOptions() if options is None else options
        lone = np.eye(self.rulebase.speed.size)[[0, -1]]
        lo, hi = _centroid(lone, self.rulebase.speed.triangles, self.options.output_resolution, 0.0)
        #: Centroids of the lowest and highest output set fired alone: a Mamdani
        #: centroid never reaches 0 or 1, so :meth:`speed_fraction` maps these to 0 and 1.
        self.output_range = (float(lo), float(hi))

    @property
    def surface(self) -> FloatArray:
        """Raw controller output on the grid, ``(n, n) float``, indexed ``[curve, distance]``."""
        o = self.options
        return _surface(self.rulebase, o.surface_resolution, o.output_resolution, o.min_speed)

    def infer_exact(self, curve: ArrayLike, dist: ArrayLike) -> FloatArray:
        """Raw output evaluated exactly (:func:`infer_exact`), ``(m,) float``."""
        return infer_exact(curve, dist, self.rulebase, self.options)

    def infer(self, curve: ArrayLike, dist: ArrayLike) -> FloatArray:
        """Raw output by bilinear interpolation of :attr:`surface`.

        Parameters
        ----------
        curve, dist : (m,) float
            Broadcast together; clipped to ``[0, 1]``.

        Returns
        -------
        (m,) float
        """
        if self.options.exact:
            return self.infer_exact(curve, dist)
        surf = self.surface
        n = surf.shape[0]
        c, d = np.broadcast_arrays(np.asarray(curve, dtype=float), np.asarray(dist, dtype=float))
        u = np.clip(c, 0.0, 1.0) * (n - 1)
        w = np.clip(d, 0.0, 1.0) * (n - 1)
        i = np.minimum(u.astype(np.int64), n - 2)
        j = np.minimum(w.astype(np.int64), n - 2)
        fu, fw = u - i, w - j
        top = surf[i, j] * (1 - fw) + surf[i, j + 1] * fw
        bottom = surf[i + 1, j] * (1 - fw) + surf[i + 1, j + 1] * fw
        return top * (1 - fu) + bottom * fu

    def speed_fraction(self, curve: ArrayLike, dist: ArrayLike) -> FloatArray:
        """Speed as a fraction of vmax: the raw output rescaled so that the lowest
        output set alone gives 0 and the highest alone gives 1, then clipped to
        ``[options.min_speed, 1]``. ``(m,) float``."""
        lo, hi = self.output_range
        raw = self.infer(curve, dist)
        return np.clip((raw - lo) / (hi - lo), self.options.min_speed, 1.0)



# --------------------------------------------------------------------------
# Path features and the speed profile
# --------------------------------------------------------------------------


def curve_ahead(
    path_xy: ArrayLike,
    s: ArrayLike,
    lookahead: float,
    max_turn: float = math.pi,
    spread: float | None = None,
) -> tuple[FloatArray, FloatArray]:
    """The bend ahead of each arc-length position: how sharp and how far.

    For position ``s`` the window is ``[s, s + lookahead]``. *curve* is the
    absolute turning of the path within the window, divided by ``max_turn`` and
    clipped to 1; turning accumulates, so a finely sampled arc counts as much as
    one sharp corner. Each vertex's turning is spread evenly over
    ``+-min(spread, half of each adjacent segment)`` around it, which makes the
    turning a continuous function of arc length: a sampled arc then reads as
    its curvature integral, without the jitter of vertices entering and leaving
    the window. The bend is the point where the window's turning reaches half
    its total; *distance* is its arc-length distance from ``s`` divided by
    ``lookahead`` (1 when the window does not turn).

    Parameters
    ----------
    path_xy : (n, 2) float
        Polyline; repeated points are ignored.
    s : (m,) float
        Arc-length positions, metres.
    lookahead : float
        Window length, metres.
    max_turn : float
        Turning (radians) that maps to curve = 1.
    spread : float, optional
        Largest half-width over which a vertex's turning is spread, metres
        (default ``0.1 * lookahead``).

    Returns
    -------
    curve : (m,) float
        In ``[0, 1]``.
    dist : (m,) float
        In ``[0, 1]``.

    Raises
    ------
    ValueError
        If the path is not ``(n, 2)`` finite or ``lookahead``, ``max_turn`` or
        ``spread`` is not positive.
    """
    spread = 0.1 * lookahead if spread is None else spread
    if not (lookahead > 0 and max_turn > 0 and spread > 0):
        raise InputError("lookahead, max_turn and spread must be positive")
    p, sp = _clean_path(path_xy)
    s = np.asarray(s, dtype=float)
    if p.shape[0] < 3:
        return np.zeros_like(s), np.ones_like(s)
    seg = np.diff(sp)
    heading = np.arctan2(*np.diff(p, axis=0).T[::-1])
    turn = np.abs(np.angle(np.exp(1j * np.diff(heading))))
    half = np.minimum(np.minimum(seg[:-1], seg[1:]) / 2, spread)
    # Cumulative turning A(s): piecewise linear, rising by turn[i] across
    # [sv[i] - half[i], sv[i] + half[i]]; the ramps never overlap.
    sv = sp[1:-1]
    before = np.concatenate(([0.0], np.cumsum(turn)[:-1]))
    knots_x = np.stack([sv - half, sv + half], axis=1).reshape(-1)
    knots_y = np.stack([before, before + turn], axis=1).reshape(-1)
    a0 = np.interp(s, knots_x, knots_y)
    total = np.interp(s + lookahead, knots_x, knots_y) - a0
    # First point where A reaches a0 + total / 2, by inverting A on its knots.
    target = a0 + 0.5 * total
    k = np.clip(np.searchsorted(knots_y, target, side="left"), 1, knots_y.size - 1)
    rise = knots_y[k] - knots_y[k - 1]
    frac = np.divide(target - knots_y[k - 1], rise, out=np.zeros_like(target), where=rise > 0)
    bend = knots_x[k - 1] + frac * (knots_x[k] - knots_x[k - 1])
    turning = total > 1e-12
    curve = np.where(turning, np.minimum(total / max_turn, 1.0), 0.0)
    dist = np.where(turning, np.clip((bend - s) / lookahead, 0.0, 1.0), 1.0)
    return curve, dist




def _samples(sp: FloatArray, ds: float) -> FloatArray:
    """Arc lengths every ``ds`` plus the path's vertices."""
    length = sp[-1]
    n = max(2, int(math.ceil(length / ds)) + 1)
    s = np.union1d(np.linspace(0.0, length, n), sp)
    return s[np.concatenate(([True], np.diff(s) > 1e-9 * max(1.0, length)))]


def speed_limit(
    path_xy: ArrayLike,
    vmax: float,
    amax: float,
    rulebase: RuleBase | None = None,
    options: FuzzyOptions | None = None,
) -> tuple[FloatArray, FloatArray]:
    """The fuzzy speed bound along a path, made feasible for ``amax``.

    Stable interface for re-timing: ``v[i]`` is the largest allowed speed at
    arc length ``s[i]``. Between samples interpolate ``v**2`` linearly (constant
    acceleration on each interval): that interpolant respects ``amax`` exactly,
    whereas interpolating ``v`` linearly can exceed it up to twice near rest.
    :func:`profile_times` gives the time at each sample when the profile is
    driven at its limit.

    Steps: sample the path every ``options.ds`` (plus its vertices), measure the
    bend ahead (:func:`curve_ahead`), evaluate the controller
    (:meth:`SpeedController.speed_fraction`, clipped to ``[min_speed, 1]``),
    scale by ``vmax``, then the forward-backward pass (:func:`limit_acceleration`)
    starting and ending at rest.

    Parameters
    ----------
    path_xy : (n, 2) float
        Polyline, metres.
    vmax : float
        Speed bound, m/s.
    amax : float
        Acceleration bound, m/s^2.
    rulebase : RuleBase, optional
        Default :func:`expert_rules`.
    options : FuzzyOptions, optional

    Returns
    -------
    s : (k,) float
        Increasing arc lengths from 0 to the path length (``k = 1`` for a path
        of zero length).
    v : (k,) float
        Speed bound: ``0`` at both ends, in ``(0, vmax]`` in between, and
        ``|v[i+1]**2 - v[i]**2| <= 2 amax (s[i+1] - s[i])``.

    Raises
    ------
    ValueError
        If the path is malformed or ``vmax``/``amax`` is not positive.

    References
    ----------
    G. Antonelli, S. Chiaverini, G. Fusco, "A fuzzy-logic-based approach for
    mobile robot path tracking", IEEE Trans. Fuzzy Systems 15(2):211-221, 2007.
    """
    if not (math.isfinite(vmax) and vmax > 0 and math.isfinite(amax) and amax > 0):
        raise InputError(f"vmax and amax must be positive and finite, got {vmax}, {amax}")
    ctl = SpeedController(rulebase, options)
    p, sp = _clean_path(path_xy)
    if sp[-1] <= 0:
        return np.zeros(1), np.zeros(1)
    s = _samples(sp, ctl.options.ds)
    curve, dist = curve_ahead(p, s, ctl.options.lookahead, ctl.options.max_turn)
    return s, _profile(s, curve, dist, vmax, amax, ctl)




def _profile(
    s: FloatArray,
    curve: FloatArray,
    dist: FloatArray,
    vmax: float,
    amax: float,
    ctl: SpeedController,
) -> FloatArray:
    return limit_acceleration(s, vmax * ctl.speed_fraction(curve, dist), amax)


