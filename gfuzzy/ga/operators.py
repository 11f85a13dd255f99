"""The genetic operators (paper section 4.2): roulette-wheel selection, single-point
crossover, the three mutations and the smooth operator."""

from __future__ import annotations

from enum import IntEnum

import numpy as np

from ..typed import BoolArray, FloatArray, IntArray
from . import kernels
from .coding import PathCoding
from .fitness import PathEvaluator
from .options import _EPS, REMOVED

# The smooth operator's new nodes lie at a random fraction of the corner's two segments,
# drawn from this range: small fractions give gentle cuts that pass near obstacles.
_SMOOTH_FRACTION = (0.2, 1.0)


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
    kernels.crossover_apply(pop, do, cut)
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
    pop = np.array(chromosomes, copy=True)
    hit = rng.random(pop.shape) < pm
    kinds = rng.integers(0, 3, np.count_nonzero(hit))
    # apply_mutation on the hits in row-major order (np.nonzero's), compiled
    kernels.mutation_apply(pop, hit, kinds, levels)
    return pop


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
    sub = pop[tried].astype(np.int64)
    c = coding
    pts, mask, prv, nxt, cross, dot = kernels.smooth_corners(sub, c.start, c.goal, c.knots, c.normals, c.steps, c.mid)
    ang = np.abs(np.arctan2(cross, dot))  # numpy's arctan2, as the numpy operator took
    cand, changed, new_slots = kernels.smooth_reencode(
        sub, pts, mask, prv, nxt, ang, lam, c.knots, c.normals, c.steps, c.mid, c.levels
    )
    return tried[changed], cand[changed].astype(pop.dtype), new_slots[changed]
