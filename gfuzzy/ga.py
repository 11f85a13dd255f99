"""Genetic-algorithm refinement of a roadmap path's via-points.

A path found on a probabilistic roadmap zig-zags between random vertices. This module
straightens and smooths it with a genetic algorithm while keeping it clear of the static
obstacles and of the moving ones, following the genetic-fuzzy planner's GA stage
(paper sections 3.1 coding, 3.3 fitness, 4.2 operators, 5.3 parameters):

* **Coding** ("reducing dimensions"): ``n_knots`` knots sit at equal arc length along the
  input path. At each knot a search line runs perpendicular to the path, its origin placed
  dynamically at the knot. A gene is an integer *level*; the via-point lies on the knot's
  search line at offset ``(level - levels // 2) * step``. The gene :data:`REMOVED` drops the
  via-point. The chromosome length is fixed; the decoded path is start, the kept via-points,
  goal.
* **Fitness** is a *cost*, lower is better: ``w_length * fit_length + w_security *
  fit_security + w_smooth * fit_smooth``, each part dimensionless (see :func:`fitness_parts`).
  An individual whose clearance bound falls below zero anywhere is infeasible (cost ``inf``).
* **Operators**: roulette-wheel selection with elitism, single-point crossover (Pc 0.62),
  mutation (Pm 0.1) in three kinds (:class:`Mutation`: shift up, shift down, remove), and the
  smooth operator (probability 0.2, :func:`smooth`), population 50, up to 2000 generations,
  early stop after ``patience`` generations without improvement.

The module is independent of the rest of the planner: it takes a polyline and two clearance
callables. See ``docs/ga.md`` for the design and its reasons.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from .rng import create_rng
from .typing import ArrayLike, BoolArray, FloatArray, IntArray

__all__ = [
    "REMOVED",
    "GAOptions",
    "GAResult",
    "Mutation",
    "PathCoding",
    "PathEvaluator",
    "Evaluation",
    "FitnessParts",
    "refine_path",
    "fitness_parts",
    "roulette_select",
    "crossover",
    "apply_mutation",
    "mutate",
    "smooth",
]

logger = logging.getLogger(__name__)

REMOVED = -1
"""Gene value of a removed via-point."""

StaticClearance = Callable[[FloatArray], FloatArray]
MoverClearance = Callable[[FloatArray, FloatArray], FloatArray]
#: ``static_segment(a (k, 2), b (k, 2)) -> (bound (k,), clearance (k,))``: a lower bound on
#: the static clearance along each segment a-b (>= 0: the segment is free) and an estimate
#: of its smallest clearance.
StaticSegment = Callable[[FloatArray, FloatArray], "tuple[FloatArray, FloatArray]"]

_EPS = 1e-12
# The smooth operator's new nodes lie at a random fraction of the corner's two segments,
# drawn from this range: small fractions give gentle cuts that pass near obstacles.
_SMOOTH_FRACTION = (0.2, 1.0)
# Above this many node pairs the static segment cache is not allocated.
_MAX_SEGMENT_CACHE = 1 << 22


# --------------------------------------------------------------------------- options


@dataclass(frozen=True)
class GAOptions:
    """Settings of the GA refinement; the defaults are the paper's values (section 5.3).

    Parameters
    ----------
    n_knots : int
        Chromosome length: knots at equal arc length along the input path (12).
    levels : int
        Integer levels per gene, odd so that level ``levels // 2`` is the knot itself (15).
    step : float or None
        Offset between two levels along a search line. None derives one step per knot from
        the free width of its search line (see ``docs/ga.md``).
    population : int
        Individuals per generation (50).
    generations : int
        Upper bound on generations (2000).
    pc : float
        Probability that a pair of parents is crossed (single point, 0.62).
    pm : float
        Probability that a gene mutates (0.1); the kind is drawn uniformly from
        :class:`Mutation`.
    p_smooth : float
        Probability that the smooth operator is tried on an individual (0.2).
    w_length, w_security, w_smooth : float
        Weights of the three fitness parts (1.0, 1.0, 0.5).
    patience : int or None
        Stop when the best cost has not improved for this many generations (200);
        None or 0 disables the early stop.
    safe_clearance : float or None
        Clearance at and beyond which the security part is zero; None: the robot radius.
    resolution : float or None
        Spacing of the clearance samples along each segment; None: robot radius / 2.
    time_resolution : float or None
        Spacing in time of extra mover-clearance samples that cover waits and slow stretches
        of the input timing; None: ``resolution`` divided by the input's mean speed.
    keep_speed : bool
        With input ``times``, a candidate is infeasible if any of its segments is longer than
        the stretch of the input whose time it takes, so the refined path is nowhere faster
        than the input and keeps the input's speed bound (True).

    Raises
    ------
    ValueError
        If a value is out of range.
    """

    n_knots: int = 12
    levels: int = 15
    step: float | None = None
    population: int = 50
    generations: int = 2000
    pc: float = 0.62
    pm: float = 0.1
    p_smooth: float = 0.2
    w_length: float = 1.0
    w_security: float = 1.0
    w_smooth: float = 0.5
    patience: int | None = 200
    safe_clearance: float | None = None
    resolution: float | None = None
    time_resolution: float | None = None
    keep_speed: bool = True

    def __post_init__(self):
        def need(ok: bool, what: str):
            if not ok:
                raise ValueError(f"GAOptions.{what}")

        need(
            _is_int(self.n_knots) and self.n_knots >= 1,
            f"n_knots must be an int >= 1, not {self.n_knots!r}",
        )
        need(
            _is_int(self.levels)
            and self.levels >= 3
            and self.levels % 2 == 1
            and self.levels <= 32767,
            f"levels must be an odd int in [3, 32767], not {self.levels!r}",
        )
        need(
            self.step is None or _pos(self.step),
            f"step must be None or a finite number > 0, not {self.step!r}",
        )
        need(
            _is_int(self.population) and self.population >= 2,
            f"population must be an int >= 2, not {self.population!r}",
        )
        need(
            _is_int(self.generations) and self.generations >= 0,
            f"generations must be an int >= 0, not {self.generations!r}",
        )
        for name in ("pc", "pm", "p_smooth"):
            v = getattr(self, name)
            need(
                _finite(v) and 0.0 <= v <= 1.0, f"{name} must be a probability in [0, 1], not {v!r}"
            )
        for name in ("w_length", "w_security", "w_smooth"):
            v = getattr(self, name)
            need(_finite(v) and v >= 0.0, f"{name} must be a finite weight >= 0, not {v!r}")
        need(
            self.patience is None or (_is_int(self.patience) and self.patience >= 0),
            f"patience must be None or an int >= 0, not {self.patience!r}",
        )
        for name in ("safe_clearance", "resolution", "time_resolution"):
            v = getattr(self, name)
            need(v is None or _pos(v), f"{name} must be None or a finite number > 0, not {v!r}")
        need(
            isinstance(self.keep_speed, bool), f"keep_speed must be a bool, not {self.keep_speed!r}"
        )


def _is_int(v) -> bool:
    return isinstance(v, (int, np.integer)) and not isinstance(v, bool)


def _finite(v) -> bool:
    return (
        isinstance(v, (int, float, np.integer, np.floating))
        and not isinstance(v, bool)
        and math.isfinite(v)
    )


def _pos(v) -> bool:
    return _finite(v) and v > 0


# --------------------------------------------------------------------------- coding


@dataclass(frozen=True, eq=False)
class PathCoding:
    """The paper's "reducing dimensions" coding of a path's via-points.

    Parameters
    ----------
    start, goal : (2,) float
        The fixed end points.
    knots : (K, 2) float
        Origins of the search lines, at equal arc length along the input path.
    normals : (K, 2) float
        Unit directions of the search lines, perpendicular to the path at each knot.
    steps : (K,) float
        Offset between two levels on each search line.
    levels : int
        Levels per gene; level ``levels // 2`` is the knot itself.
    """

    start: FloatArray
    goal: FloatArray
    knots: FloatArray
    normals: FloatArray
    steps: FloatArray
    levels: int

    @property
    def n_knots(self) -> int:
        return len(self.knots)

    @property
    def mid(self) -> int:
        """The level of zero offset."""
        return self.levels // 2

    @property
    def arc(self) -> FloatArray:
        """(K + 2,) float: the input's arc-length fraction of start, knots and goal.

        A via-point is reached when the input reached its knot (see
        :meth:`PathEvaluator.evaluate`).
        """
        return np.arange(self.n_knots + 2) / (self.n_knots + 1)

    @classmethod
    def from_path(
        cls, path_xy: ArrayLike, n_knots: int, levels: int, steps: ArrayLike | float
    ) -> PathCoding:
        """Place ``n_knots`` knots and their search lines along a polyline.

        Parameters
        ----------
        path_xy : (n, 2) float
            The input path, n >= 2, with positive length.
        n_knots, levels : int
        steps : float or (n_knots,) float

        Returns
        -------
        PathCoding

        Raises
        ------
        ValueError
            If the path has zero length.
        """
        pts = _dedupe(np.asarray(path_xy, dtype=float))
        if len(pts) < 2:
            raise ValueError("path has zero length: nothing to refine")
        s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
        total = s[-1]
        sk = total * np.arange(1, n_knots + 1) / (n_knots + 1)
        knots = _interp_polyline(pts, s, sk)
        # The central difference over one knot spacing gives the bisector direction at a
        # corner, so the search line there cuts the corner rather than sliding along a leg.
        half = 0.5 * total / (n_knots + 1)
        tangent = _interp_polyline(pts, s, sk + half) - _interp_polyline(pts, s, sk - half)
        tn = np.hypot(tangent[:, 0], tangent[:, 1])
        seg = np.clip(np.searchsorted(s, sk, side="right") - 1, 0, len(pts) - 2)
        seg_dir = pts[seg + 1] - pts[seg]
        bad = tn < 1e-9 * total
        tangent[bad] = seg_dir[bad]
        tangent /= np.hypot(tangent[:, 0], tangent[:, 1])[:, None]
        normals = np.stack([-tangent[:, 1], tangent[:, 0]], axis=1)
        steps = np.broadcast_to(np.asarray(steps, dtype=float), (n_knots,)).copy()
        arrays = [pts[0].copy(), pts[-1].copy(), knots, normals, steps]
        for a in arrays:
            a.setflags(write=False)
        return cls(*arrays, levels=int(levels))

    def offsets(self, chromosomes: ArrayLike) -> FloatArray:
        """Signed offsets along the search lines.

        Parameters
        ----------
        chromosomes : (P, K) int

        Returns
        -------
        (P, K) float
            NaN where the gene is :data:`REMOVED`.
        """
        g = np.asarray(chromosomes)
        off = (g - self.mid) * self.steps
        return np.where(g == REMOVED, np.nan, off)

    def decode(self, chromosomes: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Decode a population into padded paths.

        Parameters
        ----------
        chromosomes : (P, K) int

        Returns
        -------
        points : (P, K + 2, 2) float
            Start, the K via-points (removed ones sit at their knot), goal.
        mask : (P, K + 2) bool
            False where a via-point is removed.
        """
        g = np.asarray(chromosomes)
        P = g.shape[0]
        off = np.where(g == REMOVED, 0, g - self.mid) * self.steps
        pts = np.empty((P, self.n_knots + 2, 2))
        pts[:, 0] = self.start
        pts[:, -1] = self.goal
        pts[:, 1:-1] = self.knots + off[..., None] * self.normals
        mask = np.ones((P, self.n_knots + 2), dtype=bool)
        mask[:, 1:-1] = g != REMOVED
        return pts, mask

    def node_ids(self, chromosomes: ArrayLike) -> IntArray:
        """Lattice node number of every point of the decoded paths (for the segment cache).

        Returns
        -------
        (P, K + 2) int
            0 for the start, ``1 + k * levels + level`` for a via-point, the largest for the goal.
        """
        g = np.asarray(chromosomes, dtype=np.int64)
        P, K = g.shape
        ids = np.empty((P, K + 2), dtype=np.int64)
        ids[:, 0] = 0
        ids[:, -1] = 1 + K * self.levels
        ids[:, 1:-1] = 1 + np.arange(K) * self.levels + np.maximum(g, 0)
        return ids

    def polyline(self, chromosome: ArrayLike) -> FloatArray:
        """The path of one chromosome.

        Parameters
        ----------
        chromosome : (K,) int

        Returns
        -------
        (m, 2) float
            Start, kept via-points, goal.
        """
        pts, mask = self.decode(np.asarray(chromosome)[None])
        return pts[0][mask[0]]


def _dedupe(pts: FloatArray) -> FloatArray:
    keep = np.ones(len(pts), dtype=bool)
    keep[1:] = np.any(np.diff(pts, axis=0) != 0, axis=1)
    return pts[keep]


def _interp_polyline(pts: FloatArray, s: FloatArray, q: FloatArray) -> FloatArray:
    """Points at arc lengths ``q`` (clamped) on the polyline ``pts`` with arc lengths ``s``."""
    return np.stack([np.interp(q, s, pts[:, 0]), np.interp(q, s, pts[:, 1])], axis=1)


def _derive_steps(
    path: FloatArray,
    knots: FloatArray,
    normals: FloatArray,
    levels: int,
    robot_radius: float,
    resolution: float,
    static_clearance: StaticClearance,
) -> FloatArray:
    """One level step per knot from the free width of its search line.

    Each search line is probed on both sides up to ``reach_max`` = the larger of the input's
    largest distance from the start-goal chord (how far the zig-zag strays) and the knot
    spacing. The knot's reach is the farther free extent of the two sides, so the levels
    span the corridor around the knot; ``step = reach / (levels // 2)``.
    """
    start, goal = path[0], path[-1]
    dev = float(np.max(_point_segment_distance(path, start, goal)))
    spacing = float(np.sum(np.hypot(*np.diff(path, axis=0).T))) / (len(knots) + 1)
    reach_max = max(dev, spacing, 2.0 * robot_radius)
    n = int(math.ceil(reach_max / resolution))
    s = np.minimum(np.arange(1, n + 1) * resolution, reach_max)
    K = len(knots)
    probe = (
        knots[:, None, None, :]
        + np.array([1.0, -1.0])[None, :, None, None]
        * s[None, None, :, None]
        * normals[:, None, None, :]
    )
    c = _call_static(static_clearance, probe.reshape(-1, 2)).reshape(K, 2, n)
    blocked = c < 0
    first = np.where(blocked.any(axis=2), blocked.argmax(axis=2), n)  # index of first blocked probe
    extent = np.where(first > 0, s[np.maximum(first - 1, 0)], 0.0)
    extent = np.where(first == n, reach_max, extent)
    reach = np.clip(extent.max(axis=1), resolution, reach_max)
    # a knot inside an obstacle (the resampled input cuts a corner) gets the full reach
    reach = np.where(_call_static(static_clearance, knots) < 0, reach_max, reach)
    return reach / (levels // 2)


def _point_segment_distance(p: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    ab = b - a
    den = float(ab @ ab)
    t = np.zeros(len(p)) if den == 0 else np.clip((p - a) @ ab / den, 0.0, 1.0)
    return np.hypot(*(a + t[:, None] * ab - p).T)


# --------------------------------------------------------------------------- evaluation


@dataclass(frozen=True, eq=False)
class Evaluation:
    """Geometry and clearance of a batch of paths (see :meth:`PathEvaluator.evaluate`).

    Attributes
    ----------
    length : (P,) float
        Path length.
    smoothness : (P,) float
        Sum of absolute turning angles at the kept interior points, radians.
    min_clearance : (P,) float
        Smallest sampled clearance (static and movers).
    segment_clearance : (P, M - 1) float
        Clearance along the segment that ends at point j + 1 (``inf`` where that point is
        removed): the certified static bound, and the smallest mover sample on it.
    feasible : (P,) bool
        Every segment clearance >= 0, and with ``keep_speed`` no segment longer than the
        stretch of the input whose time it takes.
    """

    length: FloatArray
    smoothness: FloatArray
    min_clearance: FloatArray
    segment_clearance: FloatArray
    feasible: BoolArray


@dataclass(frozen=True, eq=False)
class FitnessParts:
    """The three fitness parts and the total cost of a batch of paths (lower is better).

    Attributes
    ----------
    length, smoothness, min_clearance : (P,) float
        Raw figures: metres, radians, metres.
    feasible : (P,) bool
    fit_length : (P,) float
        ``length / |goal - start|`` (>= 1; the raw length when start == goal).
    fit_security : (P,) float
        ``1 - min(min_clearance, safe) / safe`` in [0, 1] for feasible paths: 0 when every
        sample is at least ``safe_clearance`` away; 1 when touching. NaN when infeasible.
    fit_smooth : (P,) float
        ``smoothness / pi``: total turning in half turns.
    cost : (P,) float
        ``w_length * fit_length + w_security * fit_security + w_smooth * fit_smooth``;
        ``inf`` when infeasible.
    """

    length: FloatArray
    smoothness: FloatArray
    min_clearance: FloatArray
    feasible: BoolArray
    fit_length: FloatArray
    fit_security: FloatArray
    fit_smooth: FloatArray
    cost: FloatArray


class PathEvaluator:
    """Batch evaluation of padded paths: length, turning and sampled clearance.

    Parameters
    ----------
    robot_radius : float
        Sets the default sample spacing and safe clearance.
    static_clearance : callable
        ``static_clearance(xy (k, 2)) -> (k,)``: clearance of the robot centred at each point
        from static obstacles and bounds, >= 0 free. Assumed 1-Lipschitz (a signed distance
        minus the robot radius), which makes the segment bounds certified.
    mover_clearance : callable or None
        ``mover_clearance(xy (k, 2), t (k,)) -> (k,)``: clearance from the movers at times t.
    reference_path : (n, 2) float or None
        The input path, whose timing candidates reuse (see :meth:`evaluate`, ``arc``).
    reference_times : (n,) float or None
        Nondecreasing times of ``reference_path``; equal positions at increasing times are
        waits. None: candidates are timed at unit speed from t = 0 along themselves, and
        there is no speed rule.
    options : GAOptions or None

    Raises
    ------
    ValueError
        On inconsistent reference path and times.
    """

    def __init__(
        self,
        robot_radius: float,
        static_clearance: StaticClearance,
        mover_clearance: MoverClearance | None = None,
        reference_path: ArrayLike | None = None,
        reference_times: ArrayLike | None = None,
        options: GAOptions | None = None,
        static_segment: StaticSegment | None = None,
    ):
        if not _pos(robot_radius):
            raise ValueError(f"robot_radius must be a finite number > 0, not {robot_radius!r}")
        if not callable(static_clearance):
            raise ValueError("static_clearance must be callable")
        if mover_clearance is not None and not callable(mover_clearance):
            raise ValueError("mover_clearance must be callable or None")
        opts = options or GAOptions()
        self.options = opts
        self.static_clearance = static_clearance
        self.static_segment = static_segment
        self.mover_clearance = mover_clearance
        self.resolution = opts.resolution or 0.5 * robot_radius
        self.safe = opts.safe_clearance or robot_radius
        self.ref_length = 0.0
        self._check_speed = False
        self._grid_u = self._grid_t = self._grid_tiled = None
        self._cache = None
        if reference_times is not None:
            if reference_path is None:
                raise ValueError("reference_times needs reference_path")
            ref = np.asarray(reference_path, dtype=float)
            t = _check_times(reference_times, len(ref))
            s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(ref, axis=0).T))])
            total = s[-1]
            self.ref_length = total
            self._check_speed = opts.keep_speed and total > 0
            if mover_clearance is not None:
                # Movers are checked on one grid along the input's timing, at most `dt` apart
                # in time and `resolution` apart in the input's arc length (so at most
                # `resolution` apart on a candidate that is nowhere faster than the input).
                dt = opts.time_resolution
                if dt is None:
                    speed = total / (t[-1] - t[0]) if t[-1] > t[0] else 0.0
                    dt = self.resolution / speed if speed > 0 else max(t[-1] - t[0], 1.0) / 100
                u_ref = s / total if total > 0 else np.zeros_like(s)
                du = self.resolution / total if total > 0 else 1.0
                self._grid_u, self._grid_t = _time_grid(u_ref, t, dt, du)

    # -- segment cache (static clearance depends only on the segment's two lattice nodes)
    def _enable_segment_cache(self, n_nodes: int) -> None:
        """Remember the static bounds of segments between the lattice nodes of one coding."""
        if n_nodes * n_nodes <= _MAX_SEGMENT_CACHE:
            self._n_nodes = n_nodes
            self._cache = np.full((2, n_nodes * n_nodes), np.nan)

    def evaluate(
        self,
        points: FloatArray,
        mask: BoolArray,
        node_ids: IntArray | None = None,
        arc: FloatArray | None = None,
    ) -> Evaluation:
        """Evaluate padded paths.

        Parameters
        ----------
        points : (P, M, 2) float
            Paths padded to a common length; the first and last points are always kept.
        mask : (P, M) bool
            Which points belong to each path.
        node_ids : (P, M) int or None
            Lattice node numbers (:meth:`PathCoding.node_ids`) to use the segment cache.
        arc : (M,) or (P, M) float or None
            The fraction of the input's arc length each point stands for (nondecreasing, 0 at
            the start, 1 at the goal): a candidate is at point j when the input was at that
            fraction, and in between it moves as the input did over the same stretch (waits
            included). :attr:`PathCoding.arc` gives the knots' fractions. None: each path's
            own arc-length fraction (the whole path follows the input's timing).

        Returns
        -------
        Evaluation
        """
        points = np.asarray(points, dtype=float)
        mask = np.asarray(mask, dtype=bool)
        P, M, _ = points.shape
        idx = np.arange(M)
        last = np.maximum.accumulate(np.where(mask, idx, -1), axis=1)
        prev = last[:, :-1]  # slot j: the segment ending at point j + 1 starts here
        ri = np.arange(P)[:, None]
        # gathers go through flat indices and .take: several times faster than fancy indexing
        a_pts = points.reshape(-1, 2).take((ri * M + prev).ravel(), axis=0).reshape(P, M - 1, 2)
        active = mask[:, 1:]
        d = np.where(active[..., None], points[:, 1:] - a_pts, 0.0)
        seglen = np.hypot(d[..., 0], d[..., 1])
        length = seglen.sum(axis=1)

        # turning at kept interior point j (1..M-2): incoming slot j-1, outgoing slot
        # first[j+1]-1, where `first` skips points that repeat the one before (zero-length
        # segments), so a turn through a repeated point is still counted
        if M > 2:
            turn_mask = mask.copy()
            turn_mask[:, 1:-1] &= seglen[:, :-1] > _EPS
            first = np.minimum.accumulate(np.where(turn_mask, idx, M)[:, ::-1], axis=1)[:, ::-1]
            out = (ri * (M - 1) + first[:, 2:] - 1).ravel()
            din = d[:, :-1]
            dout = d.reshape(-1, 2).take(out, axis=0).reshape(P, M - 2, 2)
            cross = din[..., 0] * dout[..., 1] - din[..., 1] * dout[..., 0]
            dot = din[..., 0] * dout[..., 0] + din[..., 1] * dout[..., 1]
            ok = turn_mask[:, 1:-1] & (seglen.take(out).reshape(P, M - 2) > _EPS)
            smoothness = np.where(ok, np.abs(np.arctan2(cross, dot)), 0.0).sum(axis=1)
        else:
            smoothness = np.zeros(P)

        # samples along every kept segment, at most `resolution` apart, both ends included
        rows, slots = np.nonzero(active)
        fs = rows * (M - 1) + slots
        a = a_pts.reshape(-1, 2).take(fs, axis=0)
        e = d.reshape(-1, 2).take(fs, axis=0)
        L = seglen.take(fs)
        n = np.maximum(1, np.ceil(L / self.resolution - 1e-9)).astype(np.int64)
        seg_lb = np.full(len(rows), np.inf)
        seg_min = np.full(len(rows), np.inf)

        need = np.ones(len(rows), dtype=bool)
        keys = None
        if self._cache is not None and node_ids is not None:
            ids = np.asarray(node_ids)
            keys = ids.take(rows * M + prev.take(fs)) * self._n_nodes + ids.take(
                rows * M + slots + 1
            )
            cached_lb = self._cache[0, keys]
            need = np.isnan(cached_lb)
            seg_lb = np.where(need, np.inf, cached_lb)
            seg_min = np.where(need, np.inf, self._cache[1, keys])

        movers_on_segments = self.mover_clearance is not None and self._grid_u is None
        frac = rep = offs = xy = None
        if need.any() or movers_on_segments:
            counts = n + 1
            offs = np.zeros(len(rows), dtype=np.int64)
            np.cumsum(counts[:-1], out=offs[1:])
            rep = np.repeat(np.arange(len(rows)), counts)
            local = np.arange(len(rep)) - offs[rep]
            frac = local / n.take(rep)
            xy = a.take(rep, axis=0) + frac[:, None] * e.take(rep, axis=0)
            gap = (L / n).take(rep)
        if need.any():
            if need.all():
                sel, s_offs, s_xy, s_gap = None, offs, xy, gap
            else:
                sel = np.nonzero(need)[0]
                take = need[rep]
                s_xy, s_gap = xy[take], gap[take]
                cnt = (n + 1)[sel]
                s_offs = np.zeros(len(sel), dtype=np.int64)
                np.cumsum(cnt[:-1], out=s_offs[1:])
            if self.static_segment is not None:
                # the caller certifies whole segments (e.g. by sphere tracing)
                pick = slice(None) if sel is None else sel
                lb, mn = self.static_segment(a[pick], a[pick] + e[pick])
                lb, mn = np.asarray(lb, dtype=float), np.asarray(mn, dtype=float)
            else:
                c = _call_static(self.static_clearance, s_xy)
                lb = np.minimum.reduceat(_lipschitz_bound(c, s_gap, s_offs), s_offs)
                mn = np.minimum.reduceat(c, s_offs)
            if sel is None:
                seg_lb, seg_min = lb, mn
            else:
                seg_lb[sel], seg_min[sel] = lb, mn
            if keys is not None:
                kk = keys if sel is None else keys[sel]
                self._cache[0, kk] = lb
                self._cache[1, kk] = mn

        if movers_on_segments and len(rows):
            # no input timing: unit speed from t = 0, time = arc length
            sigma = (np.cumsum(seglen, axis=1) - seglen)[rows, slots][rep] + frac * L[rep]
            cm = _call_mover(self.mover_clearance, xy, sigma)
            seg_min = np.minimum(seg_min, np.minimum.reduceat(cm, offs))
            seg_lb = np.minimum(seg_lb, np.minimum.reduceat(cm, offs))

        seg_full = np.full((P, M - 1), np.inf)
        seg_full.reshape(-1)[fs] = seg_lb
        min_clear = np.full(P, np.inf)
        np.minimum.at(min_clear, rows, seg_min)
        feasible = seg_full.min(axis=1) >= 0
        timed = self.mover_clearance is not None and self._grid_u is not None
        if timed or self._check_speed:
            if arc is None:
                tot = np.where(length > 0, length, 1.0)[:, None]
                u_end = np.cumsum(seglen, axis=1) / tot
                u_start = u_end - seglen / tot
            else:
                arc = np.asarray(arc, dtype=float)
                if arc.ndim == 1:
                    u_end, u_start = arc.take(last[:, 1:]), arc.take(prev)
                else:
                    u_end, u_start = arc.take(ri * M + last[:, 1:]), arc.take(ri * M + prev)
            if self._check_speed:
                # nowhere faster than the input: each segment is at most as long as the
                # stretch of the input whose time it takes
                span = (u_end - u_start) * self.ref_length
                feasible &= ~np.any(active & (seglen > span * (1 + 1e-9) + 1e-12), axis=1)
            if timed:
                flat, cg = self._grid_clearance(a_pts, d, u_start, u_end)
                np.minimum.at(seg_full.reshape(-1), flat, cg)
                min_clear = np.minimum(min_clear, cg.reshape(P, -1).min(axis=1))
                feasible &= seg_full.min(axis=1) >= 0
        return Evaluation(length, smoothness, min_clear, seg_full, feasible)

    def _grid_clearance(self, a_pts, d, u_start, u_end) -> tuple[IntArray, FloatArray]:
        """Mover clearance on the timing grid.

        Slot j of a row covers the input fractions (u_start[j], u_end[j]]; the slots of a row
        partition [0, 1] in order, so each grid point falls in exactly one slot.

        Returns
        -------
        slot : (P * G,) int
            Flat slot index (row * S + j) of each grid point.
        clearance : (P * G,) float
        """
        P, S = u_end.shape
        gu, gt = self._grid_u, self._grid_t
        if self._grid_tiled is None or len(self._grid_tiled[0]) != P * len(gu):
            self._grid_tiled = (np.tile(gu, P), np.tile(gt, P))
        gu_all, gt_all = self._grid_tiled
        hi = np.searchsorted(gu, u_end.ravel(), side="right")
        hi[S - 1 :: S] = len(gu)
        lo = np.empty_like(hi)
        lo[1:] = hi[:-1]
        lo[::S] = 0
        slot = np.repeat(np.arange(P * S), hi - lo)
        u0 = u_start.ravel()
        width = u_end.ravel() - u0
        f = (gu_all - u0.take(slot)) / np.where(width > 0, width, 1.0).take(slot)
        np.clip(f, 0.0, 1.0, out=f)
        # .take: much faster than fancy indexing for row gathers
        xy = a_pts.reshape(-1, 2).take(slot, axis=0) + f[:, None] * d.reshape(-1, 2).take(
            slot, axis=0
        )
        return slot, _call_mover(self.mover_clearance, xy, gt_all)

    def fitness(self, ev: Evaluation, chord: FloatArray | float) -> FitnessParts:
        """Fitness parts of evaluated paths whose ends are ``chord`` apart.

        Parameters
        ----------
        ev : Evaluation
        chord : float or (P,) float
            ``|goal - start|`` of each path.

        Returns
        -------
        FitnessParts
        """
        o = self.options
        chord = np.broadcast_to(np.asarray(chord, dtype=float), ev.length.shape)
        fit_length = np.where(
            chord > _EPS, ev.length / np.where(chord > _EPS, chord, 1.0), ev.length
        )
        sec = np.clip(ev.min_clearance / self.safe, 0.0, 1.0)
        fit_security = np.where(ev.feasible, 1.0 - sec, np.nan)
        fit_smooth = ev.smoothness / math.pi
        cost = o.w_length * fit_length + o.w_smooth * fit_smooth
        cost = np.where(ev.feasible, cost + o.w_security * np.nan_to_num(fit_security), np.inf)
        return FitnessParts(
            ev.length,
            ev.smoothness,
            ev.min_clearance,
            ev.feasible,
            fit_length,
            fit_security,
            fit_smooth,
            cost,
        )


def _time_grid(u: FloatArray, t: FloatArray, dt: float, du: float) -> tuple[FloatArray, FloatArray]:
    """Samples (u, t) along the reference timing, at most ``dt`` apart in time and ``du`` in u."""
    dts = np.diff(t)
    n = np.maximum(1, np.ceil(np.maximum(dts / dt, np.diff(u) / du) - 1e-9)).astype(np.int64)
    idx = np.repeat(np.arange(len(dts)), n)
    local = np.arange(len(idx)) - np.repeat(np.cumsum(n) - n, n)
    f = local / n[idx]
    gu = np.append(u[idx] + f * (u[idx + 1] - u[idx]), u[-1])
    gt = np.append(t[idx] + f * dts[idx], t[-1])
    return gu, gt


def _lipschitz_bound(c: FloatArray, gap: FloatArray, offs: IntArray) -> FloatArray:
    """Per-sample lower bound of a 1-Lipschitz clearance on the gap to the next sample.

    Between samples ``gap`` apart with clearances c0, c1 the clearance is at least
    ``(c0 + c1 - gap) / 2``; the last sample of each segment has no gap after it.
    """
    lb = c.copy()
    if len(c) > 1:
        pair = 0.5 * (c[:-1] + c[1:] - gap[:-1])
        ends = offs[1:] - 1
        pair[ends] = np.inf
        np.minimum(lb[:-1], pair, out=lb[:-1])
    return lb


def _call_static(fn: StaticClearance, xy: FloatArray) -> FloatArray:
    c = np.asarray(fn(xy), dtype=float)
    if c.shape != (len(xy),):
        raise ValueError(f"static_clearance returned shape {c.shape} for {len(xy)} points")
    return np.where(np.isnan(c), -np.inf, c)


def _call_mover(fn: MoverClearance, xy: FloatArray, t: FloatArray) -> FloatArray:
    c = np.asarray(fn(xy, t), dtype=float)
    if c.shape != (len(xy),):
        raise ValueError(f"mover_clearance returned shape {c.shape} for {len(xy)} points")
    return np.where(np.isnan(c), -np.inf, c)


def _check_path(path_xy: ArrayLike) -> FloatArray:
    p = np.asarray(path_xy, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 2:
        raise ValueError(f"path_xy must have shape (n, 2) with n >= 2, not {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError("path_xy has non-finite values")
    return p


def _check_times(times: ArrayLike, n: int) -> FloatArray:
    t = np.asarray(times, dtype=float)
    if t.shape != (n,):
        raise ValueError(f"times must have shape ({n},), not {t.shape}")
    if not np.all(np.isfinite(t)):
        raise ValueError("times has non-finite values")
    if np.any(np.diff(t) < 0):
        raise ValueError("times must be nondecreasing")
    return t


def _pad(paths) -> tuple[FloatArray, BoolArray]:
    if isinstance(paths, np.ndarray) and paths.ndim == 3:
        pts = np.asarray(paths, dtype=float)
        return pts, np.ones(pts.shape[:2], dtype=bool)
    seq = [_check_path(p) for p in paths]
    M = max(len(p) for p in seq)
    pts = np.empty((len(seq), M, 2))
    mask = np.zeros((len(seq), M), dtype=bool)
    for i, p in enumerate(seq):
        # pad by repeating the start, masked out, so the goal stays last
        k = M - len(p)
        pts[i, :k] = p[0]
        pts[i, k:] = p
        mask[i, k:] = True
        mask[i, 0] = True
    return pts, mask


def fitness_parts(
    paths: FloatArray | Sequence[ArrayLike],
    robot_radius: float,
    static_clearance: StaticClearance,
    mover_clearance: MoverClearance | None = None,
    *,
    reference_path: ArrayLike | None = None,
    reference_times: ArrayLike | None = None,
    options: GAOptions | None = None,
) -> FitnessParts:
    """Fitness parts of whole paths, as the GA scores them (lower cost is better).

    ``fit_length = length / |goal - start|``, ``fit_security = 1 - min(c, safe) / safe``
    with ``c`` the smallest sampled clearance and ``safe`` = ``options.safe_clearance``
    (default: the robot radius), ``fit_smooth = sum |turning angle| / pi``, and
    ``cost = w_length * fit_length + w_security * fit_security + w_smooth * fit_smooth``.
    A path is infeasible (cost ``inf``) when the certified lower bound of its clearance falls
    below zero anywhere along it: samples at most ``resolution`` apart, and between two
    samples ``gap`` apart with clearances c0, c1 the bound ``(c0 + c1 - gap) / 2``.

    Parameters
    ----------
    paths : (P, m, 2) float or sequence of (m_i, 2) float
    robot_radius : float
    static_clearance, mover_clearance : callable
        See :func:`refine_path`.
    reference_path : (n, 2) float or None
    reference_times : (n,) float or None
        The input path and its times. Each path follows the input's timing by its own
        arc-length fraction: at fraction u of its length it is where the input was at
        fraction u of its length, at the same time (``arc=None`` in
        :meth:`PathEvaluator.evaluate`; :func:`refine_path` instead ties via-points to their
        knots). Without times, paths are timed at unit speed from 0 along themselves.
    options : GAOptions or None
        Weights and resolutions.

    Returns
    -------
    FitnessParts

    Raises
    ------
    ValueError
        On malformed paths, times or callables' outputs.
    """
    pts, mask = _pad(paths)
    ev = PathEvaluator(
        robot_radius, static_clearance, mover_clearance, reference_path, reference_times, options
    )
    e = ev.evaluate(pts, mask)
    chord = np.hypot(*(pts[:, -1] - pts[:, 0]).T)
    return ev.fitness(e, chord)


# --------------------------------------------------------------------------- operators


class Mutation(IntEnum):
    """The three mutation kinds (paper section 4.2).

    UP and DOWN shift a via-point one level along its search line (clamped at the ends);
    applied to a removed gene they re-insert the via-point at its knot (the middle level).
    REMOVE drops the via-point.
    """

    UP = 0
    DOWN = 1
    REMOVE = 2


def roulette_select(costs: FloatArray, rng: np.random.Generator, n: int) -> IntArray:
    """Roulette-wheel selection on costs (lower is better).

    The wheel uses windowed fitness: ``f = worst - cost + 0.1 * (worst - best)`` over the
    feasible individuals, 0 for infeasible ones (cost ``inf``); uniform when none is feasible
    or all are equal.

    Parameters
    ----------
    costs : (P,) float
    rng : numpy.random.Generator
    n : int
        How many to draw (with replacement).

    Returns
    -------
    (n,) int
        Indices into ``costs``.
    """
    costs = np.asarray(costs, dtype=float)
    ok = np.isfinite(costs)
    if not ok.any():
        return rng.integers(0, len(costs), n)
    best, worst = costs[ok].min(), costs[ok].max()
    span = worst - best
    if span <= _EPS * max(1.0, abs(best)):
        w = ok.astype(float)
    else:
        w = np.where(ok, worst - np.where(ok, costs, worst) + 0.1 * span, 0.0)
    cw = np.cumsum(w)
    return np.minimum(np.searchsorted(cw, rng.random(n) * cw[-1], side="right"), len(costs) - 1)


def crossover(chromosomes: IntArray, rng: np.random.Generator, pc: float) -> IntArray:
    """Single-point crossover of consecutive pairs (0, 1), (2, 3), ...

    Each pair is crossed with probability ``pc`` at a cut drawn uniformly in 1..K-1: the
    children swap their genes from the cut on. An odd last individual is copied.

    Parameters
    ----------
    chromosomes : (P, K) int
    rng : numpy.random.Generator
    pc : float

    Returns
    -------
    (P, K) int
        A new array; chromosome length is unchanged.
    """
    pop = np.array(chromosomes, copy=True)
    P, K = pop.shape
    npairs = P // 2
    if K < 2 or npairs == 0:
        return pop
    do = rng.random(npairs) < pc
    cut = rng.integers(1, K, npairs)
    swap = do[:, None] & (np.arange(K)[None, :] >= cut[:, None])
    a, b = pop[0 : 2 * npairs : 2].copy(), pop[1 : 2 * npairs : 2].copy()
    pop[0 : 2 * npairs : 2] = np.where(swap, b, a)
    pop[1 : 2 * npairs : 2] = np.where(swap, a, b)
    return pop


def apply_mutation(
    chromosomes: IntArray, rows: IntArray, genes: IntArray, kinds: IntArray, levels: int
) -> IntArray:
    """Apply given mutations (deterministic part of :func:`mutate`).

    Parameters
    ----------
    chromosomes : (P, K) int
    rows, genes, kinds : (q,) int
        Which individual, which gene, which :class:`Mutation`.
    levels : int

    Returns
    -------
    (P, K) int
        A new array.
    """
    pop = np.array(chromosomes, copy=True)
    rows = np.asarray(rows, dtype=np.int64)
    genes = np.asarray(genes, dtype=np.int64)
    kinds = np.asarray(kinds, dtype=np.int64)
    g = pop[rows, genes].astype(np.int64)
    mid = levels // 2
    up = np.where(g == REMOVED, mid, np.minimum(g + 1, levels - 1))
    down = np.where(g == REMOVED, mid, np.maximum(g - 1, 0))
    new = np.select([kinds == Mutation.UP, kinds == Mutation.DOWN], [up, down], REMOVED)
    pop[rows, genes] = new
    return pop


def mutate(chromosomes: IntArray, rng: np.random.Generator, pm: float, levels: int) -> IntArray:
    """Mutate each gene with probability ``pm``, the kind drawn uniformly from :class:`Mutation`.

    Parameters
    ----------
    chromosomes : (P, K) int
    rng : numpy.random.Generator
    pm : float
    levels : int

    Returns
    -------
    (P, K) int
        A new array.
    """
    pop = np.asarray(chromosomes)
    hit = rng.random(pop.shape) < pm
    rows, genes = np.nonzero(hit)
    kinds = rng.integers(0, 3, len(rows))
    return apply_mutation(pop, rows, genes, kinds, levels)


def smooth(
    chromosomes: IntArray,
    coding: PathCoding,
    evaluator: PathEvaluator,
    rng: np.random.Generator,
    p_smooth: float,
) -> tuple[IntArray, BoolArray]:
    """The smooth operator: replace a path's sharpest corner by three nodes, if free.

    For each individual, with probability ``p_smooth``: take the kept via-point V with the
    largest turning angle, and its kept neighbours U (before) and W (after). New nodes
    ``A = V + f (U - V)`` and ``B = V + f (W - V)``, with f drawn from [0.2, 1], and
    ``C = (A + 2 V + B) / 4`` (the midpoint of the quadratic Bezier arc A-V-B) replace V:
    the local path becomes U, A, C, B, W. The chromosome length is fixed, so the result is
    re-encoded: every knot strictly between U and W (V's own and any removed ones, which are
    re-inserted) takes the level nearest to where its search line crosses U-A-C-B-W, or is
    removed if its line misses that polyline within its levels. With one knot between U and
    W this cuts the corner towards C; with removed knots around V it realises all three nodes
    as closely as the levels allow. The change is accepted only when every new segment,
    from U to W, has a certified clearance bound >= 0 (static and movers).

    Parameters
    ----------
    chromosomes : (P, K) int
    coding : PathCoding
    evaluator : PathEvaluator
    rng : numpy.random.Generator
    p_smooth : float

    Returns
    -------
    new : (P, K) int
        A new array with the accepted changes.
    accepted : (P,) bool
        Which individuals changed.
    """
    pop = np.array(chromosomes, copy=True)
    accepted = np.zeros(len(pop), dtype=bool)
    rows, cand, new_slots = _propose_smooth(pop, coding, rng, p_smooth)
    if len(rows):
        pts, mask = coding.decode(cand)
        ev = evaluator.evaluate(pts, mask, coding.node_ids(cand), coding.arc)
        ok = _free(ev.segment_clearance, new_slots)
        pop[rows[ok]] = cand[ok]
        accepted[rows[ok]] = True
    return pop, accepted


def _free(segment_clearance: FloatArray, new_slots: BoolArray) -> BoolArray:
    return np.where(new_slots, segment_clearance, np.inf).min(axis=1) >= 0


def _propose_smooth(
    pop: IntArray, coding: PathCoding, rng: np.random.Generator, p_smooth: float
) -> tuple[IntArray, IntArray, BoolArray]:
    """Smooth-operator candidates (see :func:`smooth`) before the clearance check.

    Returns
    -------
    rows : (Q,) int
        Individuals whose candidate differs from them.
    cand : (Q, K) int
        The re-encoded candidates.
    new_slots : (Q, K + 1) bool
        Segment slots (slot j ends at point j + 1) between U and W: the new segments.
    """
    P, K = pop.shape
    tried = np.nonzero(rng.random(P) < p_smooth)[0]
    if len(tried) == 0:
        return tried, pop[:0], np.zeros((0, K + 1), dtype=bool)
    lam = rng.uniform(*_SMOOTH_FRACTION, len(tried))
    sub = pop[tried]
    pts, mask = coding.decode(sub)
    Q, M = mask.shape
    idx = np.arange(M)
    last = np.maximum.accumulate(np.where(mask, idx, -1), axis=1)
    first = np.minimum.accumulate(np.where(mask, idx, M)[:, ::-1], axis=1)[:, ::-1]
    prv, nxt = last[:, :-2], first[:, 2:]  # kept neighbours of points 1..M-2
    flat = pts.reshape(-1, 2)
    base = np.arange(Q)[:, None] * M
    inner = pts[:, 1:-1]
    din = inner - flat.take((base + prv).ravel(), axis=0).reshape(inner.shape)
    dout = flat.take((base + nxt).ravel(), axis=0).reshape(inner.shape) - inner
    cross = din[..., 0] * dout[..., 1] - din[..., 1] * dout[..., 0]
    dot = (din * dout).sum(-1)
    ang = np.where(mask[:, 1:-1], np.abs(np.arctan2(cross, dot)), 0.0)
    k = ang.argmax(axis=1)  # via index; point index k + 1
    valid = ang[np.arange(Q), k] > 1e-6
    r = np.arange(Q)
    iu, iw = prv[r, k], nxt[r, k]
    U, V, W = (
        flat.take(r * M + iu, axis=0),
        flat.take(r * M + k + 1, axis=0),
        flat.take(r * M + iw, axis=0),
    )
    A = V + lam[:, None] * (U - V)
    B = V + lam[:, None] * (W - V)
    C = 0.25 * A + 0.5 * V + 0.25 * B
    poly = np.stack([U, A, C, B, W], axis=1)  # (Q, 5, 2)
    p0, e = poly[:, :-1], np.diff(poly, axis=1)  # (Q, 4, 2)
    # intersect every knot line (p + s n) with every segment (p0 + tau e)
    rr = p0[:, None, :, :] - coding.knots[None, :, None, :]  # (Q, K, 4, 2)
    n = coding.normals[None, :, None, :]
    ee = e[:, None, :, :]
    den = n[..., 0] * ee[..., 1] - n[..., 1] * ee[..., 0]
    safe_den = np.where(np.abs(den) > _EPS, den, 1.0)
    s = (rr[..., 0] * ee[..., 1] - rr[..., 1] * ee[..., 0]) / safe_den
    tau = (rr[..., 0] * n[..., 1] - rr[..., 1] * n[..., 0]) / safe_den
    hits = (np.abs(den) > _EPS) & (tau >= -1e-9) & (tau <= 1 + 1e-9)
    cur = np.nan_to_num(coding.offsets(sub))  # removed genes: origin 0
    score = np.where(hits, np.abs(s - cur[..., None]), np.inf)
    j = score.reshape(-1, 4).argmin(axis=1) + 4 * np.arange(Q * K)
    s_best = s.take(j).reshape(Q, K)
    hit_any = np.isfinite(score.take(j)).reshape(Q, K)
    lvl = np.rint(s_best / coding.steps).astype(np.int64) + coding.mid
    in_range = hit_any & (lvl >= 0) & (lvl < coding.levels)
    new_genes = np.where(in_range, lvl, REMOVED)
    knot_pt = np.arange(K)[None, :] + 1
    region = (knot_pt > iu[:, None]) & (knot_pt < iw[:, None]) & valid[:, None]
    cand = np.where(region, new_genes, sub).astype(pop.dtype)
    changed = np.any(cand != sub, axis=1)
    slot_pt = np.arange(1, M)[None, :]
    new_slots = (slot_pt > iu[:, None]) & (slot_pt <= iw[:, None])
    return tried[changed], cand[changed], new_slots[changed]


# --------------------------------------------------------------------------- the GA


@dataclass(frozen=True, eq=False)
class GAResult:
    """Outcome of :func:`refine_path`.

    Attributes
    ----------
    path : (m, 2) float
        The refined path (start, kept via-points, goal), or the input path when
        ``improved`` is False.
    chromosome : (K,) int
        The best individual's genes (:data:`REMOVED` = -1 marks removed via-points).
    fitness_history : (g + 1,) float
        Best cost (lower is better) after each generation, generation 0 first; ``inf`` while
        no individual is feasible.
    generations : int
        Generations evolved (g).
    improved : bool
        True when the best individual is feasible and its cost is lower than the input's.
    fitness_before, fitness_after : float
        Cost of the input and of ``path``.
    length_before, length_after : float
        Path lengths.
    smoothness_before, smoothness_after : float
        Sums of absolute turning angles, radians.
    clearance_before, clearance_after : float
        Smallest sampled clearance (static and movers).
    trajectory : (q, 3) float or None
        With input ``times``: rows [t, x, y] of ``path`` timed as the mover checks assumed:
        each via-point at the time the input passed its knot, and in between as the input
        moved over the same stretch, waits included. Linear between rows.
    coding : PathCoding or None
        The knots, search lines and steps used (None if the path had zero length).
    """

    path: FloatArray
    chromosome: IntArray
    fitness_history: FloatArray
    generations: int
    improved: bool
    fitness_before: float
    fitness_after: float
    length_before: float
    length_after: float
    smoothness_before: float
    smoothness_after: float
    clearance_before: float
    clearance_after: float
    trajectory: FloatArray | None
    coding: PathCoding | None


def refine_path(
    path_xy: ArrayLike,
    times: ArrayLike | None,
    robot_radius: float,
    static_clearance: StaticClearance,
    mover_clearance: MoverClearance | None = None,
    options: GAOptions | None = None,
    seed: int | np.random.Generator | None = None,
    static_segment: StaticSegment | None = None,
) -> GAResult:
    """Straighten and smooth a path's via-points with a genetic algorithm.

    The algorithm (paper sections 3.1, 3.3, 4.2)::

        code the path: knots at equal arc length, a search line at each, genes = levels
        population = [all genes at the middle level (the input resampled),
                      all genes removed (the straight start-goal segment),
                      random perturbations of the middle level]
        repeat up to `generations` times, or until the best stalls for `patience`:
            cost of every individual (cached by chromosome)
            keep the best (elitism)
            roulette-wheel selection of the others' parents
            single-point crossover (pc), mutation per gene (pm), smooth operator (p_smooth)
        return the best path if it is feasible and cheaper than the input, else the input

    Timing (with ``times``): a via-point is reached when the input reached its knot (the
    knot sits at a known arc length of the input, whose time is interpolated from ``times``);
    along a segment between two via-points the robot moves as the input moved over the
    stretch between their knots, waits included. A gene thus only changes the timing of its
    own two segments, which keeps the mover constraints local.

    Parameters
    ----------
    path_xy : (n, 2) float
        The input path, n >= 2.
    times : (n,) float or None
        Nondecreasing times of the input's points (a repeated point at a later time is a
        wait); see Timing above. None: candidates are timed at unit speed from t = 0 along
        themselves (and ``keep_speed`` does not apply).
    robot_radius : float
        Sets the sample spacing (radius / 2) and the safe clearance (radius) by default.
    static_clearance : callable
        ``static_clearance(xy (k, 2)) -> (k,)``: signed clearance of the robot centred at each
        point from static obstacles and bounds (the robot radius already subtracted), >= 0
        free. A signed distance (1-Lipschitz) makes the segment checks certified.
    mover_clearance : callable or None
        ``mover_clearance(xy (k, 2), t (k,)) -> (k,)``: clearance from the movers at times t
        (the sums of radii already subtracted), >= 0 free.
    options : GAOptions or None
        Defaults are the paper's.
    seed : int, numpy.random.Generator or None
        See :func:`gfuzzy.rng.create_rng`.
    static_segment : callable or None
        ``static_segment(a (k, 2), b (k, 2)) -> (bound, clearance)``: certifies whole
        segments instead of sampling ``static_clearance`` along them (the planner passes
        an exact sphere-tracing check, which also works in passages narrower than the
        sample spacing allows).

    Returns
    -------
    GAResult
        Never worse than the input under the fitness: the input is returned, with
        ``improved`` False, when no individual is feasible or none beats it.

    Raises
    ------
    ValueError
        On malformed inputs, options or clearance outputs.
    TypeError
        On a bad ``seed``.

    Notes
    -----
    The clearance checks are sampled (certified for 1-Lipschitz static clearance, sampled in
    time for movers); the planner must still validate the final trajectory.
    """
    opts = options or GAOptions()
    if not isinstance(opts, GAOptions):
        raise ValueError(f"options must be a GAOptions, not {type(opts).__name__}")
    path = _check_path(path_xy)
    t_in = None if times is None else _check_times(times, len(path))
    if not _pos(robot_radius):
        raise ValueError(f"robot_radius must be a finite number > 0, not {robot_radius!r}")
    rng = create_rng(seed)

    evaluator = PathEvaluator(
        robot_radius, static_clearance, mover_clearance, path, t_in, opts, static_segment
    )
    chord = float(np.hypot(*(path[-1] - path[0])))
    before = evaluator.fitness(
        evaluator.evaluate(path[None], np.ones((1, len(path)), dtype=bool)), chord
    )
    b = _scalars(before)

    geo = _dedupe(path)
    if len(geo) < 2:
        logger.info("refine_path: zero-length path, returned unchanged")
        return _unchanged(path, t_in, b, np.array([b[0]]), 0, None, opts)

    if opts.step is None:
        proto = PathCoding.from_path(geo, opts.n_knots, opts.levels, 1.0)
        steps = _derive_steps(
            geo,
            proto.knots,
            proto.normals,
            opts.levels,
            robot_radius,
            evaluator.resolution,
            static_clearance,
        )
    else:
        steps = opts.step
    coding = PathCoding.from_path(geo, opts.n_knots, opts.levels, steps)
    evaluator._enable_segment_cache(opts.n_knots * opts.levels + 2)

    P, K = opts.population, opts.n_knots
    arc = coding.arc
    pop = _initial_population(rng, P, K, opts.levels)
    cache: dict[bytes, float] = {}

    def evaluate(batch: IntArray) -> Evaluation:
        pts, mask = coding.decode(batch)
        ev = evaluator.evaluate(pts, mask, coding.node_ids(batch), arc)
        cache.update(
            zip(
                (row.tobytes() for row in batch),
                evaluator.fitness(ev, chord).cost.tolist(),
                strict=True,
            )
        )
        return ev

    def missing(pop: IntArray) -> IntArray:
        seen: set[bytes] = set()
        rows = []
        for i, row in enumerate(pop):
            key = row.tobytes()
            if key not in cache and key not in seen:
                seen.add(key)
                rows.append(i)
        return np.asarray(rows, dtype=np.int64)

    evaluate(pop[missing(pop)])
    best_cost, best, stall = math.inf, pop[0].copy(), 0
    history = []
    patience = opts.patience or 0
    gen = 0
    while True:
        costs = np.fromiter((cache[row.tobytes()] for row in pop), dtype=float, count=P)
        i = int(np.argmin(costs))
        if costs[i] < best_cost - 1e-12 * max(
            1.0, abs(best_cost) if math.isfinite(best_cost) else 1.0
        ):
            best_cost, best, stall = float(costs[i]), pop[i].copy(), 0
        else:
            stall += 1
        history.append(best_cost)
        if gen >= opts.generations or (patience and stall >= patience):
            break
        parents = roulette_select(costs, rng, P - 1)
        kids = crossover(pop[parents], rng, opts.pc)
        kids = mutate(kids, rng, opts.pm, opts.levels)
        # One batch evaluation per generation: the new children and the smooth candidates.
        rows, cand, new_slots = _propose_smooth(kids, coding, rng, opts.p_smooth)
        todo = kids[missing(kids)]
        if len(todo) or len(rows):
            ev = evaluate(np.concatenate([todo, cand]))
            ok = _free(ev.segment_clearance[len(todo) :], new_slots)
            kids[rows[ok]] = cand[ok]
        pop = np.concatenate([best[None], kids])
        gen += 1
    history = np.asarray(history)
    logger.debug("refine_path: %d generations, %d distinct individuals evaluated", gen, len(cache))

    if not (math.isfinite(best_cost) and best_cost < b[0] - 1e-12 * max(1.0, abs(best_cost))):
        if not math.isfinite(best_cost):
            logger.info(
                "refine_path: no feasible individual in %d generations; input returned", gen
            )
        return _unchanged(path, t_in, b, history, gen, coding, opts, best)

    out = coding.polyline(best)
    pts, mask = coding.decode(best[None])
    after = _scalars(evaluator.fitness(evaluator.evaluate(pts, mask, None, arc), chord))
    traj = None if t_in is None else _timed(out, arc[mask[0]], path, t_in)
    logger.info(
        "refine_path: cost %.4g -> %.4g, length %.3f -> %.3f, turning %.3f -> %.3f rad, %d generations",
        b[0],
        after[0],
        b[1],
        after[1],
        b[2],
        after[2],
        gen,
    )
    return GAResult(
        path=out,
        chromosome=best.astype(np.int64),
        fitness_history=history,
        generations=gen,
        improved=True,
        fitness_before=b[0],
        fitness_after=after[0],
        length_before=b[1],
        length_after=after[1],
        smoothness_before=b[2],
        smoothness_after=after[2],
        clearance_before=b[3],
        clearance_after=after[3],
        trajectory=traj,
        coding=coding,
    )


def _scalars(fp: FitnessParts) -> tuple[float, float, float, float]:
    return (
        float(fp.cost[0]),
        float(fp.length[0]),
        float(fp.smoothness[0]),
        float(fp.min_clearance[0]),
    )


def _unchanged(path, t_in, b, history, gen, coding, opts, best=None) -> GAResult:
    chrom = (
        np.full(opts.n_knots, opts.levels // 2, dtype=np.int64)
        if best is None
        else best.astype(np.int64)
    )
    traj = None if t_in is None else np.column_stack([t_in, path])
    return GAResult(
        path=path.copy(),
        chromosome=chrom,
        fitness_history=np.asarray(history, dtype=float),
        generations=gen,
        improved=False,
        fitness_before=b[0],
        fitness_after=b[0],
        length_before=b[1],
        length_after=b[1],
        smoothness_before=b[2],
        smoothness_after=b[2],
        clearance_before=b[3],
        clearance_after=b[3],
        trajectory=traj,
        coding=coding,
    )


def _initial_population(rng: np.random.Generator, P: int, K: int, levels: int) -> IntArray:
    """The input resampled, the straight segment, and perturbations of growing spread."""
    mid = levels // 2
    pop = np.full((P, K), mid, dtype=np.int16)
    if P > 1:
        pop[1] = REMOVED
    if P > 2:
        spread = np.linspace(1.0, mid, P - 2)[:, None]
        g = np.clip(np.rint(mid + rng.normal(size=(P - 2, K)) * spread), 0, levels - 1).astype(
            np.int16
        )
        g[rng.random((P - 2, K)) < 0.1] = REMOVED
        pop[2:] = g
    return pop


def _timed(out: FloatArray, u_out: FloatArray, ref: FloatArray, t: FloatArray) -> FloatArray:
    """Rows [t, x, y] of the polyline ``out`` whose points stand for the input's arc-length
    fractions ``u_out``, timed as :meth:`PathEvaluator.evaluate` assumes: between two points
    the position is linear in the fraction, and the time is the input's at that fraction."""
    s_ref = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(ref, axis=0).T))])
    u_ref = s_ref / s_ref[-1]
    # the input's breakpoints keep its waits; the path's corners get their interpolated times
    u = np.concatenate([u_ref, u_out])
    tt = np.concatenate([t, np.interp(u_out, u_ref, t)])
    order = np.lexsort((u, tt))
    u, tt = u[order], tt[order]
    xy = np.column_stack([np.interp(u, u_out, out[:, 0]), np.interp(u, u_out, out[:, 1])])
    rows = np.column_stack([tt, xy])
    keep = np.ones(len(rows), dtype=bool)
    keep[1:] = np.any(np.abs(np.diff(rows, axis=0)) > 1e-12, axis=1)
    return rows[keep]
