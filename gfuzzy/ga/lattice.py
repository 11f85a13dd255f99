"""The GA's own evaluation of a population of chromosomes, compiled: the same figures as
:meth:`PathEvaluator.evaluate` and :meth:`PathEvaluator.fitness` on the decoded paths.

:meth:`PathEvaluator.evaluate` takes any padded paths; the GA only ever evaluates
chromosomes of one :class:`PathCoding` with its node-pair caches on, where a generation's few
dozen short rows make numpy's per-call overhead the whole cost. :func:`evaluate_genes`
does that case with the kernels of :mod:`.kernels` (same operations on the same operands),
keeping in numpy what numba might compute differently (``hypot``, ``arctan2``, the row
sums) and calling the clearance callables exactly as the reference does (same segments, same
order). ``tests/test_ga_kernels.py`` checks it against the reference on random populations.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..typed import BoolArray, FloatArray, IntArray
from . import kernels
from .coding import PathCoding
from .fitness import Evaluation, PathEvaluator


def supported(evaluator: PathEvaluator) -> bool:
    """The evaluator's set-up is one :func:`evaluate_genes` reproduces: node-pair caches on,
    and movers (if any) checked on the input's timing grid."""
    if evaluator._cache is None:
        return False
    return evaluator.mover_clearance is None or evaluator._grid_u is not None


def evaluate_genes(
    evaluator: PathEvaluator,
    coding: PathCoding,
    batch: IntArray,
    exact: BoolArray | None,
    chord: float,
) -> tuple[Evaluation, FloatArray]:
    """:meth:`PathEvaluator.evaluate` of the decoded ``batch`` (with its node ids and
    ``coding.arc``) and the cost :meth:`PathEvaluator.fitness` gives it.

    Parameters
    ----------
    evaluator : PathEvaluator
        :func:`supported`.
    coding : PathCoding
    batch : (P, K) int
        P >= 1.
    exact : (P, K + 1) bool or None
        As in :meth:`PathEvaluator.evaluate`; None: no slot.
    chord : float

    Returns
    -------
    Evaluation
    cost : (P,) float
    """
    ev, c = evaluator, coding
    genes = np.ascontiguousarray(batch, dtype=np.int64)
    P, M = len(genes), c.n_knots + 2
    mask, a_pts, d, active, u_start, u_end, rows, slots, fs, keys = kernels.lattice_geometry(
        genes, c.start, c.goal, c.knots, c.normals, c.steps, c.mid, c.levels, c.arc, ev._n_nodes
    )
    seglen = np.hypot(d[..., 0], d[..., 1])
    length = seglen.sum(axis=1)
    cross, dot, ok = kernels.lattice_turning(mask, d, seglen)
    smoothness = np.where(ok, np.abs(np.arctan2(cross, dot)), 0.0).sum(axis=1)
    # the speed rule and the movers first (see PathEvaluator.evaluate)
    if ev._check_speed:
        feasible = kernels.lattice_speed(active, seglen, u_start, u_end, float(ev.ref_length))
    else:
        feasible = np.ones(P, dtype=bool)
    if ev.mover_clearance is not None:
        cs = ev._mover_cache[keys]
        todo = np.flatnonzero(np.isnan(cs))
        if len(todo):
            g = SimpleNamespace(M=M, fs=fs, slots=slots, a_pts=a_pts, d=d)
            ev._fill_mover_cache(g, keys, todo, u_start, u_end)
            cs = ev._mover_cache[keys]
        c0 = float(ev._start_mover_clearance(a_pts[0, 0]))
        seg_mover, mover_min = kernels.lattice_movers(P, M - 1, rows, fs, cs, c0, feasible)
    else:
        seg_mover, mover_min = np.full((P, M - 1), np.inf), np.full(P, np.inf)
    seg_lb, seg_min = _static(ev, keys, rows, fs, a_pts, d, seglen, feasible, exact)
    o = ev.options
    seg_full, min_clear, cost = kernels.lattice_finish(
        rows, fs, seg_lb, seg_min, seg_mover, mover_min, feasible, length, smoothness, float(chord),
        float(ev.safe), float(o.w_length), float(o.w_security), float(o.w_smooth),
    )  # fmt: skip
    return Evaluation(length, smoothness, min_clear, seg_full, feasible), cost


def _static(ev: PathEvaluator, keys, rows, fs, a_pts, d, seglen, feasible, exact) -> tuple[FloatArray, FloatArray]:
    """``PathEvaluator._segment_clearance`` through the node-pair cache: the cached bounds,
    and the caller's check for the kept segments not cached yet in rows not ruled out
    (see ``exact`` in :meth:`PathEvaluator.evaluate`) or on ``exact`` slots."""
    P, S = seglen.shape
    marks = np.zeros(P * S, dtype=bool) if exact is None else np.ascontiguousarray(exact, dtype=bool).reshape(-1)
    seg_lb, seg_min, sel = kernels.lattice_static_lookup(ev._cache[0], ev._cache[1], keys, rows, feasible, marks, fs)
    if len(sel):
        fsel = fs.take(sel)
        L = seglen.reshape(-1).take(fsel)
        n = np.maximum(1, np.ceil(L / ev.resolution - 1e-9)).astype(np.int64)
        a = a_pts.reshape(-1, 2).take(fsel, axis=0)
        e = d.reshape(-1, 2).take(fsel, axis=0)
        lb, mn = ev._static_bounds(a, e, L, n)
        seg_lb[sel], seg_min[sel] = lb, mn
        kk = keys.take(sel)
        ev._cache[0, kk] = lb
        ev._cache[1, kk] = mn
    return seg_lb, seg_min
