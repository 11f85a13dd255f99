"""The genetic operators (paper section 4.2): roulette-wheel selection, single-point
crossover, the three mutations and the smooth operator."""

from __future__ import annotations

from enum import IntEnum

import numpy as np

from ..typing import BoolArray, FloatArray, IntArray
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
