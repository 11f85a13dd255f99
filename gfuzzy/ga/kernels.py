"""Compiled (numba) inner loops of the GA's operators, bit for bit the numpy code they replace.

A generation of the GA works on a population of 50 short chromosomes: its numpy code spends
its time in the overhead of many small array calls, not in arithmetic. These kernels do the
same work in one call each. They perform the same floating-point operations, in the same
order, on the same operands as the numpy expressions they replace (no fast-math: IEEE
``+ - * /``, ``abs``, ``rint`` and comparisons are exact functions of their operands), so the
results are identical; what numba might compute differently from numpy (``arctan2``, and
numpy's pairwise sums) stays in numpy, between two kernels. ``tests/test_ga_kernels.py``
checks every kernel against the numpy expressions on random inputs.

The random draws stay in the callers (numpy's ``Generator``), in the same order: the kernels
only apply them. :func:`gfuzzy.ga.refine.warm` compiles (or loads from numba's on-disk cache) every
kernel; ``make warm`` calls it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..typed import BoolArray, IntArray
from .options import _EPS, REMOVED


@njit(cache=True)
def crossover_apply(pop: IntArray, do: BoolArray, cut: IntArray) -> None:
    """In place: pair i (rows 2i, 2i + 1) swaps its genes from ``cut[i]`` on when ``do[i]``."""
    K = pop.shape[1]
    for i in range(len(do)):
        if do[i]:
            a, b = 2 * i, 2 * i + 1
            for k in range(cut[i], K):
                t = pop[a, k]
                pop[a, k] = pop[b, k]
                pop[b, k] = t


@njit(cache=True)
def mutation_apply(pop: IntArray, hit: BoolArray, kinds: IntArray, levels: int) -> None:
    """In place: the ``q``-th hit gene in row-major order takes mutation ``kinds[q]`` (UP 0,
    DOWN 1, REMOVE 2; see :func:`gfuzzy.ga.operators.apply_mutation`)."""
    mid = levels // 2
    q = 0
    P, K = pop.shape
    for r in range(P):
        for k in range(K):
            if hit[r, k]:
                g = pop[r, k]
                kind = kinds[q]
                q += 1
                if kind == 0:
                    new = mid if g == REMOVED else min(g + 1, levels - 1)
                elif kind == 1:
                    new = mid if g == REMOVED else max(g - 1, 0)
                else:
                    new = REMOVED
                pop[r, k] = new


@njit(cache=True)
def _decode_row(g, start, goal, knots, normals, steps, mid, pts, mask) -> None:
    """:meth:`PathCoding.decode` of one chromosome into ``pts`` (K + 2, 2), ``mask`` (K + 2,)."""
    K = len(g)
    pts[0, 0], pts[0, 1] = start[0], start[1]
    pts[K + 1, 0], pts[K + 1, 1] = goal[0], goal[1]
    mask[0] = mask[K + 1] = True
    for k in range(K):
        off = (0.0 if g[k] == REMOVED else float(g[k] - mid)) * steps[k]
        pts[k + 1, 0] = knots[k, 0] + off * normals[k, 0]
        pts[k + 1, 1] = knots[k, 1] + off * normals[k, 1]
        mask[k + 1] = g[k] != REMOVED


@njit(cache=True)
def smooth_corners(sub, start, goal, knots, normals, steps, mid):
    """First half of the smooth operator (see :func:`gfuzzy.ga.operators._propose_smooth`):
    the decoded candidates, their kept neighbours, and the turning at every via-point as the
    ``(cross, dot)`` whose ``arctan2`` numpy takes.

    Returns
    -------
    pts : (Q, K + 2, 2) float
    mask : (Q, K + 2) bool
    prv, nxt : (Q, K) int
        The last kept point before, and the first after, each via-point (point k + 1).
    cross, dot : (Q, K) float
    """
    Q, K = sub.shape
    M = K + 2
    pts = np.empty((Q, M, 2))
    mask = np.empty((Q, M), dtype=np.bool_)
    prv = np.empty((Q, K), dtype=np.int64)
    nxt = np.empty((Q, K), dtype=np.int64)
    cross = np.empty((Q, K))
    dot = np.empty((Q, K))
    for q in range(Q):
        _decode_row(sub[q], start, goal, knots, normals, steps, mid, pts[q], mask[q])
        last = 0
        for i in range(1, M - 1):
            prv[q, i - 1] = last
            if mask[q, i]:
                last = i
        first = M - 1
        for i in range(M - 2, 0, -1):
            nxt[q, i - 1] = first
            if mask[q, i]:
                first = i
        for i in range(1, M - 1):
            a, b = prv[q, i - 1], nxt[q, i - 1]
            din0 = pts[q, i, 0] - pts[q, a, 0]
            din1 = pts[q, i, 1] - pts[q, a, 1]
            dout0 = pts[q, b, 0] - pts[q, i, 0]
            dout1 = pts[q, b, 1] - pts[q, i, 1]
            cross[q, i - 1] = din0 * dout1 - din1 * dout0
            # numpy's sum over the last axis of din * dout: 0.0 + the first, + the second
            dot[q, i - 1] = (0.0 + din0 * dout0) + din1 * dout1
    return pts, mask, prv, nxt, cross, dot


@njit(cache=True)
def smooth_reencode(sub, pts, mask, prv, nxt, ang, lam, knots, normals, steps, mid, levels):
    """Second half of the smooth operator: the sharpest corner's U, A, C, B, W polyline and
    the re-encoded genes of the knots between U and W.

    Parameters
    ----------
    sub : (Q, K) int
    pts, mask, prv, nxt
        From :func:`smooth_corners`.
    ang : (Q, K) float
        ``|arctan2(cross, dot)|``.
    lam : (Q,) float
        The corner fractions drawn.

    Returns
    -------
    cand : (Q, K) int64
    changed : (Q,) bool
    new_slots : (Q, K + 1) bool
    """
    Q, K = sub.shape
    M = K + 2
    cand = np.empty((Q, K), dtype=np.int64)
    changed = np.zeros(Q, dtype=np.bool_)
    new_slots = np.zeros((Q, M - 1), dtype=np.bool_)
    poly = np.empty((5, 2))
    for q in range(Q):
        k, best = 0, -1.0
        for i in range(K):
            a = ang[q, i] if mask[q, i + 1] else 0.0
            if a != a:  # argmax stops at the first NaN
                k, best = i, a
                break
            if a > best:  # the first largest, as argmax
                k, best = i, a
        valid = best > 1e-6
        iu, iw = prv[q, k], nxt[q, k]
        lq = lam[q]
        for c in range(2):
            U, V, W = pts[q, iu, c], pts[q, k + 1, c], pts[q, iw, c]
            A = V + lq * (U - V)
            B = V + lq * (W - V)
            poly[0, c], poly[1, c], poly[3, c], poly[4, c] = U, A, B, W
            poly[2, c] = 0.25 * A + 0.5 * V + 0.25 * B
        for kk in range(K):
            g = sub[q, kk]
            cand[q, kk] = g
            if not (valid and iu < kk + 1 < iw):
                continue
            cur = 0.0 if g == REMOVED else float(g - mid) * steps[kk]
            n0, n1 = normals[kk, 0], normals[kk, 1]
            best_score, best_s = np.inf, 0.0
            for j in range(4):
                e0 = poly[j + 1, 0] - poly[j, 0]
                e1 = poly[j + 1, 1] - poly[j, 1]
                r0 = poly[j, 0] - knots[kk, 0]
                r1 = poly[j, 1] - knots[kk, 1]
                den = n0 * e1 - n1 * e0
                ok = abs(den) > _EPS
                sd = den if ok else 1.0
                s = (r0 * e1 - r1 * e0) / sd
                tau = (r0 * n1 - r1 * n0) / sd
                score = abs(s - cur) if (ok and tau >= -1e-9 and tau <= 1 + 1e-9) else np.inf
                if j == 0 or score < best_score:  # the first smallest, as argmin
                    best_score, best_s = score, s
            new = REMOVED
            if np.isfinite(best_score):
                lvl = int(np.rint(best_s / steps[kk])) + mid
                if 0 <= lvl < levels:
                    new = lvl
            cand[q, kk] = new
            if new != g:
                changed[q] = True
        for j in range(M - 1):
            new_slots[q, j] = iu < j + 1 <= iw
    return cand, changed, new_slots


@njit(cache=True)
def lattice_geometry(genes, start, goal, knots, normals, steps, mid, levels, arc, n_nodes):
    """Decoding and segments of a population (:meth:`PathCoding.decode`, ``node_ids``,
    ``_Geometry`` and ``_arc_fractions`` of :mod:`gfuzzy.ga.fitness` with a 1-D ``arc``).

    Returns
    -------
    mask : (P, M) bool
    a_pts, d : (P, M - 1, 2) float
        Start and vector of every slot's segment (0 where the slot's end point is removed).
    active : (P, M - 1) bool
    u_start, u_end : (P, M - 1) float
    rows, slots, fs, keys : (S,) int
        The kept segments in row-major order (``np.nonzero(active)``), their flat slot and
        node-pair key.
    """
    P, K = genes.shape
    M = K + 2
    pts = np.empty((P, M, 2))
    mask = np.empty((P, M), dtype=np.bool_)
    a_pts = np.empty((P, M - 1, 2))
    d = np.empty((P, M - 1, 2))
    active = np.empty((P, M - 1), dtype=np.bool_)
    u_start = np.empty((P, M - 1))
    u_end = np.empty((P, M - 1))
    ids = np.empty(M, dtype=np.int64)
    S = 0
    for p in range(P):
        _decode_row(genes[p], start, goal, knots, normals, steps, mid, pts[p], mask[p])
        for j in range(M - 1):
            S += mask[p, j + 1]
    rows = np.empty(S, dtype=np.int64)
    slots = np.empty(S, dtype=np.int64)
    keys = np.empty(S, dtype=np.int64)
    i = 0
    for p in range(P):
        ids[0] = 0
        ids[M - 1] = 1 + K * levels
        for k in range(K):
            ids[k + 1] = 1 + k * levels + max(genes[p, k], 0)
        last = 0
        for j in range(M - 1):
            on = mask[p, j + 1]
            active[p, j] = on
            a_pts[p, j, 0], a_pts[p, j, 1] = pts[p, last, 0], pts[p, last, 1]
            u_start[p, j] = arc[last]
            if on:
                d[p, j, 0] = pts[p, j + 1, 0] - pts[p, last, 0]
                d[p, j, 1] = pts[p, j + 1, 1] - pts[p, last, 1]
                rows[i], slots[i], keys[i] = p, j, ids[last] * n_nodes + ids[j + 1]
                i += 1
                last = j + 1
            else:
                d[p, j, 0] = d[p, j, 1] = 0.0
            u_end[p, j] = arc[last]
    return mask, a_pts, d, active, u_start, u_end, rows, slots, rows * (M - 1) + slots, keys


@njit(cache=True)
def lattice_turning(mask, d, seglen):
    """``_turning`` of :mod:`gfuzzy.ga.fitness` up to its ``arctan2``: at each interior
    point, the ``(cross, dot)`` of its incoming and outgoing segments and whether it turns.

    Returns
    -------
    cross, dot : (P, M - 2) float
    ok : (P, M - 2) bool
    """
    P, M = mask.shape
    cross = np.empty((P, M - 2))
    dot = np.empty((P, M - 2))
    ok = np.empty((P, M - 2), dtype=np.bool_)
    turn = np.empty(M, dtype=np.bool_)
    first = np.empty(M, dtype=np.int64)
    for p in range(P):
        for j in range(M):
            turn[j] = mask[p, j]
            if 0 < j < M - 1:
                turn[j] = turn[j] and seglen[p, j - 1] > _EPS
        f = M
        for j in range(M - 1, -1, -1):
            if turn[j]:
                f = j
            first[j] = f
        for j in range(1, M - 1):
            out = first[j + 1] - 1
            i0, i1 = d[p, j - 1, 0], d[p, j - 1, 1]
            o0, o1 = d[p, out, 0], d[p, out, 1]
            cross[p, j - 1] = i0 * o1 - i1 * o0
            dot[p, j - 1] = i0 * o0 + i1 * o1
            ok[p, j - 1] = turn[j] and seglen[p, out] > _EPS
    return cross, dot, ok


@njit(cache=True)
def _minimum(a: float, b: float) -> float:
    """``np.minimum`` of two floats (NaN wins)."""
    if a != a or b != b:
        return a + b
    return b if b < a else a


@njit(cache=True)
def lattice_speed(active, seglen, u_start, u_end, ref_length):
    """(P,) bool: no kept segment longer than the stretch of the input whose time it takes."""
    P, S = active.shape
    feasible = np.ones(P, dtype=np.bool_)
    for p in range(P):
        for j in range(S):
            span = (u_end[p, j] - u_start[p, j]) * ref_length
            if active[p, j] and seglen[p, j] > span * (1 + 1e-9) + 1e-12:
                feasible[p] = False
    return feasible


@njit(cache=True)
def lattice_movers(P, S, rows, fs, cs, c0, feasible):
    """The cached mover clearances laid out per slot (``_timing_checks``), in place on
    ``feasible``. Returns seg_mover (P, S) and mover_min (P,)."""
    seg = np.full((P, S), np.inf)
    flat = seg.reshape(-1)
    for i in range(len(fs)):
        flat[fs[i]] = cs[i]
    mover_min = np.full(P, c0)
    for i in range(len(rows)):
        mover_min[rows[i]] = _minimum(mover_min[rows[i]], cs[i])
    for p in range(P):
        seg[p, 0] = _minimum(seg[p, 0], c0)
        lo = np.inf
        for j in range(S):
            lo = _minimum(lo, seg[p, j])
        if not lo >= 0:
            feasible[p] = False
    return seg, mover_min


@njit(cache=True)
def lattice_finish(rows, fs, seg_lb, seg_min, seg_mover, mover_min, feasible, length, smoothness, chord, safe,
                   w_length, w_security, w_smooth):  # fmt: skip
    """The end of ``PathEvaluator.evaluate`` and ``fitness``: per-slot clearance, smallest
    clearance, feasibility (in place) and cost.

    Returns
    -------
    seg_full : (P, S) float
    min_clear, cost : (P,) float
    """
    P, S = seg_mover.shape
    seg_full = np.full((P, S), np.inf)
    flat = seg_full.reshape(-1)
    for i in range(len(fs)):
        flat[fs[i]] = seg_lb[i]
    min_clear = np.full(P, np.inf)
    for i in range(len(rows)):
        min_clear[rows[i]] = _minimum(min_clear[rows[i]], seg_min[i])
    cost = np.empty(P)
    for p in range(P):
        lo = np.inf
        for j in range(S):
            seg_full[p, j] = _minimum(seg_full[p, j], seg_mover[p, j])
            lo = _minimum(lo, seg_full[p, j])
        min_clear[p] = _minimum(min_clear[p], mover_min[p])
        feasible[p] = feasible[p] and lo >= 0
        fit_length = length[p] / chord if chord > _EPS else length[p]
        sec = min_clear[p] / safe
        if sec < 0.0:
            sec = 0.0
        elif sec > 1.0:
            sec = 1.0
        fit_security = 1.0 - sec
        if fit_security != fit_security:  # np.nan_to_num
            fit_security = 0.0
        c = w_length * fit_length + w_smooth * (smoothness[p] / np.pi)
        cost[p] = c + w_security * fit_security if feasible[p] else np.inf
    return seg_full, min_clear, cost


@njit(cache=True)
def lattice_static_lookup(cache_lb, cache_min, keys, rows, feasible, exact, fs):
    """The static node-pair cache read for a batch (``PathEvaluator._cached_blocked`` and
    the lookup of ``_segment_clearance``).

    Parameters
    ----------
    cache_lb, cache_min : (N * N,) float
        The cache (NaN: not computed).
    keys, rows, fs : (S,) int
    feasible : (P,) bool
        Not ruled out by the speed rule or the movers.
    exact : (P * (M - 1),) bool
        Slots whose static check is wanted whatever the row.

    Returns
    -------
    seg_lb, seg_min : (S,) float
        Cached values, ``inf`` where not cached.
    sel : (q,) int
        The kept segments to compute: not cached, and in a row not ruled out (by the speed
        rule, the movers or a cached bound below zero) or on an exact slot.
    """
    S = len(keys)
    alive = feasible.copy()
    lb = np.empty(S)
    for i in range(S):
        lb[i] = cache_lb[keys[i]]
        if lb[i] < 0:
            alive[rows[i]] = False
    seg_lb = np.empty(S)
    seg_min = np.empty(S)
    sel = np.empty(S, dtype=np.int64)
    q = 0
    for i in range(S):
        if lb[i] != lb[i]:
            seg_lb[i] = seg_min[i] = np.inf
            if alive[rows[i]] or exact[fs[i]]:
                sel[q] = i
                q += 1
        else:
            seg_lb[i] = lb[i]
            seg_min[i] = cache_min[keys[i]]
    return seg_lb, seg_min, sel[:q]


@njit(cache=True)
def mover_grid_points(keys, todo, fs, slots, u_start, u_end, a_pts, d, gu, last_slot):
    """The timing-grid points of the new node pairs (``PathEvaluator._fill_mover_cache``):
    one kept segment per distinct key of ``keys[todo]`` (its first, keys in increasing
    order, as ``np.unique(..., return_index=True)``), and on it the grid points with ``u`` in
    its (u_start, u_end] (to the grid's end for the last slot).

    Parameters
    ----------
    keys, todo, fs, slots : int arrays
    u_start, u_end : (P * S,) float
    a_pts, d : (P * S, 2) float
    gu : (G,) float
    last_slot : int

    Returns
    -------
    uk : (U,) int
        The new keys.
    cnt : (U,) int
        Grid points per key.
    xy : (N, 2) float
    gi : (N,) int
        Grid index of each point.
    """
    kt = keys[todo]
    order = np.argsort(kt, kind="mergesort")
    uk = np.empty(len(kt), dtype=np.int64)
    j = np.empty(len(kt), dtype=np.int64)
    U = 0
    for i in range(len(order)):
        if i == 0 or kt[order[i]] != kt[order[i - 1]]:
            uk[U], j[U] = kt[order[i]], todo[order[i]]
            U += 1
    uk, j = uk[:U], j[:U]
    lo = np.empty(U, dtype=np.int64)
    cnt = np.empty(U, dtype=np.int64)
    for i in range(U):
        f = fs[j[i]]
        lo[i] = np.searchsorted(gu, u_start[f], side="right")
        hi = len(gu) if slots[j[i]] == last_slot else np.searchsorted(gu, u_end[f], side="right")
        cnt[i] = max(hi - lo[i], 0)
    xy = np.empty((cnt.sum(), 2))
    gi = np.empty(cnt.sum(), dtype=np.int64)
    q = 0
    for i in range(U):
        f = fs[j[i]]
        u0 = u_start[f]
        width = u_end[f] - u0
        w = width if width > 0 else 1.0
        for k in range(cnt[i]):
            g = lo[i] + k
            t = (gu[g] - u0) / w
            if t < 0.0:  # np.clip(f, 0, 1)
                t = 0.0
            elif t > 1.0:
                t = 1.0
            xy[q, 0] = a_pts[f, 0] + t * d[f, 0]
            xy[q, 1] = a_pts[f, 1] + t * d[f, 1]
            gi[q] = g
            q += 1
    return uk, cnt, xy, gi


@njit(cache=True)
def segment_minima(values, cnt):
    """(U,) the smallest of each run of ``cnt[i]`` consecutive ``values`` (``inf`` for an
    empty run), as ``np.minimum.reduceat``."""
    out = np.full(len(cnt), np.inf)
    q = 0
    for i in range(len(cnt)):
        if cnt[i] > 0:
            m = values[q]
            for k in range(1, cnt[i]):
                m = _minimum(m, values[q + k])
            out[i] = m
            q += cnt[i]
    return out
