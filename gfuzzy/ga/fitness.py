"""Fitness of candidate paths (paper section 3.3): length, turning and certified clearance
from static obstacles and movers, evaluated for a whole population at once."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..typed import ArrayLike, BoolArray, FloatArray, IntArray
from . import kernels
from .options import (
    _EPS,
    GAOptions,
    MoverClearance,
    StaticClearance,
    StaticSegment,
    _call_mover,
    _call_static,
    _check_path,
    _check_times,
    _pos,
)

# Above this many node pairs the static segment cache is not allocated.
_MAX_SEGMENT_CACHE = 1 << 22


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
        self._cache = self._mover_cache = None
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
            # the mover clearance on the timing grid, too, depends only on the two nodes
            # (their positions and their knots' arc fractions): its minimum per node pair
            self._mover_cache = np.full(n_nodes * n_nodes, np.nan)
            self._start_clearance: dict[bytes, float] = {}

    def evaluate(
        self,
        points: FloatArray,
        mask: BoolArray,
        node_ids: IntArray | None = None,
        arc: FloatArray | None = None,
        exact: BoolArray | None = None,
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
        exact : (P, M - 1) bool or None
            None: everything is evaluated. Otherwise the static check of a row already ruled
            out by the speed rule, the movers or a cached static bound below zero (one of its
            segments is known to be blocked) is skipped, except on the slots marked here:
            such a row stays infeasible (cost ``inf``), but its ``min_clearance`` and its
            ``segment_clearance`` outside the marked slots may be too high.

        Returns
        -------
        Evaluation
        """
        g = _Geometry(np.asarray(points, dtype=float), np.asarray(mask, dtype=bool))
        smoothness = _turning(g)
        keys = None
        if self._cache is not None and node_ids is not None:
            ids = np.asarray(node_ids)
            keys = ids.take(g.rows * g.M + g.prev.take(g.fs)) * self._n_nodes + ids.take(
                g.rows * g.M + g.slots + 1
            )
        P, M = g.P, g.M
        # the speed rule and the movers first: a row they rule out needs no static check
        # (the caller's, e.g. FCL sphere tracing, is the dearest part) unless `exact` asks
        feasible, seg_mover, mover_min = self._timing_checks(g, keys, arc)
        skip = None
        if exact is not None:
            alive = feasible & ~self._cached_blocked(g.rows, keys, P)
            need = alive[g.rows] | np.asarray(exact, dtype=bool).reshape(-1).take(g.fs)
            skip = ~need
        seg_lb, seg_min = self._segment_clearance(g, keys, skip)
        seg_full = np.full((P, M - 1), np.inf)
        seg_full.reshape(-1)[g.fs] = seg_lb
        min_clear = np.full(P, np.inf)
        np.minimum.at(min_clear, g.rows, seg_min)
        if seg_mover is not None:
            np.minimum(seg_full, seg_mover, out=seg_full)
            min_clear = np.minimum(min_clear, mover_min)
        feasible &= seg_full.min(axis=1) >= 0
        return Evaluation(g.length, smoothness, min_clear, seg_full, feasible)

    def _cached_blocked(self, rows: IntArray, keys: IntArray | None, P: int) -> BoolArray:
        """(P,) bool: rows with a kept segment whose cached static bound is below zero (so
        infeasible whatever their other segments hold)."""
        blocked = np.zeros(P, dtype=bool)
        if keys is not None and self._cache is not None:
            blocked[rows[self._cache[0].take(keys) < 0]] = True
        return blocked

    def _timing_checks(self, g: _Geometry, keys: IntArray | None, arc: FloatArray | None):
        """The speed rule and the movers on the timing grid.

        Returns
        -------
        feasible : (P,) bool
            Not ruled out by the speed rule or the movers.
        seg_mover : (P, M - 1) float or None
            Smallest mover clearance on each slot's grid points (None: no timed movers).
        mover_min : (P,) float or None
            Smallest mover clearance of each row.
        """
        P, M = g.P, g.M
        feasible = np.ones(P, dtype=bool)
        seg_mover = mover_min = None
        timed = self.mover_clearance is not None and self._grid_u is not None
        if not (timed or self._check_speed):
            return feasible, seg_mover, mover_min
        u_start, u_end = _arc_fractions(g, arc)
        if self._check_speed:
            # nowhere faster than the input: each segment is at most as long as the
            # stretch of the input whose time it takes
            span = (u_end - u_start) * self.ref_length
            feasible &= ~np.any(g.active & (g.seglen > span * (1 + 1e-9) + 1e-12), axis=1)
        if not timed:
            return feasible, seg_mover, mover_min
        seg_mover = np.full((P, M - 1), np.inf)
        if keys is not None and arc is not None and np.ndim(arc) == 1:
            cs, c0 = self._grid_clearance_cached(g, keys, u_start, u_end)
            seg_mover.reshape(-1)[g.fs] = cs
            # the grid points at the input's start (u = 0) belong to slot 0
            seg_mover[:, 0] = np.minimum(seg_mover[:, 0], c0)
            mover_min = np.full(P, c0)
            np.minimum.at(mover_min, g.rows, cs)
        else:
            flat, cg = self._grid_clearance(g.a_pts, g.d, u_start, u_end)
            np.minimum.at(seg_mover.reshape(-1), flat, cg)
            mover_min = cg.reshape(P, -1).min(axis=1)
        feasible &= seg_mover.min(axis=1) >= 0
        return feasible, seg_mover, mover_min

    def _segment_clearance(
        self, g: _Geometry, keys: IntArray | None, skip: BoolArray | None = None
    ) -> tuple[FloatArray, FloatArray]:
        """Static bound and smallest clearance of every kept segment (and, without input
        timing, the movers sampled along it at unit speed).

        Parameters
        ----------
        g : _Geometry
        keys : (S,) int or None
            Node-pair keys of the kept segments, to use the segment cache.
        skip : (S,) bool or None
            Kept segments whose static check is not needed (left ``inf`` when not cached).

        Returns
        -------
        seg_lb, seg_min : (S,) float
            Per kept segment, in the order of ``g.rows``.
        """
        rows, slots, fs = g.rows, g.slots, g.fs
        a = g.a_pts.reshape(-1, 2).take(fs, axis=0)
        e = g.d.reshape(-1, 2).take(fs, axis=0)
        L = g.seglen.take(fs)
        # samples along every kept segment, at most `resolution` apart, both ends included
        n = np.maximum(1, np.ceil(L / self.resolution - 1e-9)).astype(np.int64)
        seg_lb = np.full(len(rows), np.inf)
        seg_min = np.full(len(rows), np.inf)

        need = np.ones(len(rows), dtype=bool)
        if keys is not None:
            cached_lb = self._cache[0, keys]
            need = np.isnan(cached_lb)
            seg_lb = np.where(need, np.inf, cached_lb)
            seg_min = np.where(need, np.inf, self._cache[1, keys])
        if skip is not None:
            need &= ~skip

        if need.any():
            sel = None if need.all() else np.nonzero(need)[0]
            pick = slice(None) if sel is None else sel
            lb, mn = self._static_bounds(a[pick], e[pick], L[pick], n[pick])
            if sel is None:
                seg_lb, seg_min = lb, mn
            else:
                seg_lb[sel], seg_min[sel] = lb, mn
            if keys is not None:
                kk = keys if sel is None else keys[sel]
                self._cache[0, kk] = lb
                self._cache[1, kk] = mn

        if self.mover_clearance is not None and self._grid_u is None and len(rows):
            # no input timing: unit speed from t = 0, time = arc length
            offs, rep, frac, xy, _ = _samples(a, e, L, n)
            sigma = (np.cumsum(g.seglen, axis=1) - g.seglen)[rows, slots][rep] + frac * L[rep]
            cm = _call_mover(self.mover_clearance, xy, sigma)
            seg_min = np.minimum(seg_min, np.minimum.reduceat(cm, offs))
            seg_lb = np.minimum(seg_lb, np.minimum.reduceat(cm, offs))
        return seg_lb, seg_min

    def _static_bounds(self, a: FloatArray, e: FloatArray, L: FloatArray, n: IntArray):
        """Static bound and smallest clearance of the segments ``a`` to ``a + e`` (lengths
        ``L``, ``n`` sample gaps): the caller's segment check, or samples of the static
        clearance. Returns (lb, mn), (S,) float each."""
        if self.static_segment is not None:
            # the caller certifies whole segments (e.g. by sphere tracing)
            lb, mn = self.static_segment(a, a + e)
            return np.asarray(lb, dtype=float), np.asarray(mn, dtype=float)
        s_offs, _, _, s_xy, s_gap = _samples(a, e, L, n)
        c = _call_static(self.static_clearance, s_xy)
        lb = np.minimum.reduceat(_lipschitz_bound(c, s_gap, s_offs), s_offs)
        return lb, np.minimum.reduceat(c, s_offs)

    def _grid_clearance_cached(
        self, g: _Geometry, keys: IntArray, u_start: FloatArray, u_end: FloatArray
    ) -> tuple[FloatArray, float]:
        """:meth:`_grid_clearance` through the node-pair cache: the same grid points, the same
        positions (computed by the same formula from the same operands), so the same values.

        A kept segment from node a to node b covers the grid points with ``u`` in
        (u_a, u_b] (to the end of the grid for the goal); the points at ``u <= 0`` (the input
        waiting at its start) are at the start, and belong to slot 0 whatever it holds.

        Returns
        -------
        seg : (S,) float
            Smallest mover clearance on each kept segment's grid points (``inf`` if none).
        start : float
            Smallest mover clearance at the start's grid points.
        """
        vals = self._mover_cache[keys]
        todo = np.nonzero(np.isnan(vals))[0]
        if len(todo):
            self._fill_mover_cache(g, keys, todo, u_start, u_end)
            vals = self._mover_cache[keys]
        return vals, self._start_mover_clearance(g.a_pts[0, 0])

    def _fill_mover_cache(self, g, keys: IntArray, todo: IntArray, u_start: FloatArray, u_end: FloatArray):
        """The node-pair mover cache for the kept segments ``todo`` (not cached yet); ``g``
        has the :class:`_Geometry` attributes ``M, fs, slots, a_pts, d``."""
        S = g.M - 1
        uk, cnt, xy, gi = kernels.mover_grid_points(
            keys, todo, g.fs, g.slots, u_start.reshape(-1), u_end.reshape(-1), g.a_pts.reshape(-1, 2),
            g.d.reshape(-1, 2), self._grid_u, S - 1,
        )  # fmt: skip
        out = np.full(len(uk), np.inf)
        if len(gi):
            out = kernels.segment_minima(_call_mover(self.mover_clearance, xy, self._grid_t.take(gi)), cnt)
        self._mover_cache[uk] = out

    def _start_mover_clearance(self, start: FloatArray) -> float:
        """Smallest mover clearance at the grid points at u <= 0 (the input waiting at its
        start), at ``start``."""
        gu, gt = self._grid_u, self._grid_t
        key = start.tobytes()
        c0 = self._start_clearance.get(key)
        if c0 is None:
            n0 = int(np.searchsorted(gu, 0.0, side="right"))
            xy0 = np.broadcast_to(start, (n0, 2)).copy()
            c0 = self._start_clearance[key] = float(
                _call_mover(self.mover_clearance, xy0, gt[:n0]).min(initial=np.inf)
            )
        return c0

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


class _Geometry:
    """Segments of a batch of padded paths (slot j: the segment that ends at point j + 1).

    Attributes: ``P, M``; ``last`` (P, M) the last kept point at or before each point;
    ``prev`` (P, M - 1) where each slot's segment starts; ``a_pts``, ``d`` (P, M - 1, 2) its
    start and vector (0 where the end point is removed); ``active`` (P, M - 1); ``seglen``
    (P, M - 1); ``length`` (P,); ``rows``, ``slots``, ``fs`` (S,) the kept segments' row,
    slot and flat slot.
    """

    def __init__(self, points: FloatArray, mask: BoolArray):
        P, M, _ = points.shape
        self.P, self.M, self.mask = P, M, mask
        idx = np.arange(M)
        self.last = np.maximum.accumulate(np.where(mask, idx, -1), axis=1)
        self.prev = self.last[:, :-1]  # slot j: the segment ending at point j + 1 starts here
        self.ri = ri = np.arange(P)[:, None]
        # gathers go through flat indices and .take: several times faster than fancy indexing
        flat = (ri * M + self.prev).ravel()
        self.a_pts = points.reshape(-1, 2).take(flat, axis=0).reshape(P, M - 1, 2)
        self.active = active = mask[:, 1:]
        self.d = np.where(active[..., None], points[:, 1:] - self.a_pts, 0.0)
        self.seglen = np.hypot(self.d[..., 0], self.d[..., 1])
        self.length = self.seglen.sum(axis=1)
        self.rows, self.slots = np.nonzero(active)
        self.fs = self.rows * (M - 1) + self.slots


def _turning(g: _Geometry) -> FloatArray:
    """(P,) sum of absolute turning angles at the kept interior points.

    Turning at kept interior point j (1..M-2): incoming slot j-1, outgoing slot first[j+1]-1,
    where ``first`` skips points that repeat the one before (zero-length segments), so a turn
    through a repeated point is still counted.
    """
    P, M, d, seglen = g.P, g.M, g.d, g.seglen
    if M <= 2:
        return np.zeros(P)
    turn_mask = g.mask.copy()
    turn_mask[:, 1:-1] &= seglen[:, :-1] > _EPS
    idx = np.arange(M)
    first = np.minimum.accumulate(np.where(turn_mask, idx, M)[:, ::-1], axis=1)[:, ::-1]
    out = (g.ri * (M - 1) + first[:, 2:] - 1).ravel()
    din = d[:, :-1]
    dout = d.reshape(-1, 2).take(out, axis=0).reshape(P, M - 2, 2)
    cross = din[..., 0] * dout[..., 1] - din[..., 1] * dout[..., 0]
    dot = din[..., 0] * dout[..., 0] + din[..., 1] * dout[..., 1]
    ok = turn_mask[:, 1:-1] & (seglen.take(out).reshape(P, M - 2) > _EPS)
    return np.where(ok, np.abs(np.arctan2(cross, dot)), 0.0).sum(axis=1)


def _arc_fractions(g: _Geometry, arc: FloatArray | None) -> tuple[FloatArray, FloatArray]:
    """(P, M - 1) input arc fractions at the start and end of every slot (see ``evaluate``)."""
    if arc is None:
        tot = np.where(g.length > 0, g.length, 1.0)[:, None]
        u_end = np.cumsum(g.seglen, axis=1) / tot
        return u_end - g.seglen / tot, u_end
    arc = np.asarray(arc, dtype=float)
    M, last, prev = g.M, g.last, g.prev
    if arc.ndim == 1:
        return arc.take(prev), arc.take(last[:, 1:])
    return arc.take(g.ri * M + prev), arc.take(g.ri * M + last[:, 1:])


def _samples(a: FloatArray, e: FloatArray, L: FloatArray, n: IntArray):
    """Samples along segments a + f e (lengths L, n + 1 samples each, both ends included).

    Returns
    -------
    offs : (S,) int
        Index of each segment's first sample.
    rep : (N,) int
        Segment of each sample.
    frac : (N,) float
        Fraction f of each sample.
    xy : (N, 2) float
    gap : (N,) float
        Spacing of the samples of each sample's segment.
    """
    counts = n + 1
    offs = np.zeros(len(n), dtype=np.int64)
    np.cumsum(counts[:-1], out=offs[1:])
    rep = np.repeat(np.arange(len(n)), counts)
    local = np.arange(len(rep)) - offs[rep]
    frac = local / n.take(rep)
    xy = a.take(rep, axis=0) + frac[:, None] * e.take(rep, axis=0)
    gap = (L / n).take(rep)
    return offs, rep, frac, xy, gap


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
