"""Shortest steps and metres on a unicycle's graph at node level (:mod:`gfuzzy.timespace.unicycle`):
scipy CSR matrices of its pieces, Dijkstra, and the start's new nodes by Bellman-Ford."""

from __future__ import annotations

import numpy as np

from ..typed import FloatArray, IntArray

__all__ = ["matrix", "dijkstra", "with_rows", "new_to_goal", "steps_from_start"]


def matrix(A, B, w, n):
    """Node-level graph (parallel pieces: the shortest), scipy CSR (n, n)."""
    from scipy.sparse import csr_matrix

    key = A * n + B
    o = np.lexsort((w, key))
    keep = np.ones(len(o), dtype=bool)
    keep[1:] = key[o][1:] != key[o][:-1]
    o = o[keep]
    return csr_matrix((np.maximum(w[o], 1e-300), (A[o], B[o])), shape=(n, n))


def dijkstra(mat, index: int) -> FloatArray:
    from scipy.sparse.csgraph import dijkstra

    d = dijkstra(mat, directed=True, indices=index)
    return np.where(d < 1e-200, 0.0, d)


def new_to_goal(A, B, k, L, N: int, x: int, hop: FloatArray, metres: FloatArray):
    """Steps and metres to the goal (x,) of a start's x new nodes (ids from N), by
    Bellman-Ford over its pieces A -> B (k steps, L metres; every piece leaves a new node),
    the kept nodes' ``hop`` / ``metres`` fixed (a start's pieces never lead out and back)."""
    nn = len(hop)
    old = B < N  # into the kept graph (beyond its nodes, an interior point: no way on)
    hk = np.where(old & (B < nn), hop[np.minimum(B, nn - 1)], np.inf)
    mk = np.where(old & (B < nn), metres[np.minimum(B, nn - 1)], np.inf)
    hop_x, met_x = np.full(x, np.inf), np.full(x, np.inf)
    bx = np.where(old, 0, B - N)
    for _ in range(x + 1):
        h0, m0 = hop_x.copy(), met_x.copy()
        np.minimum.at(hop_x, A - N, k + np.where(old, hk, hop_x[bx]))
        np.minimum.at(met_x, A - N, L + np.where(old, mk, met_x[bx]))
        if np.array_equal(h0, hop_x) and np.array_equal(m0, met_x):
            break
    return hop_x, met_x


def with_rows(mat, A, B, w, n: int):
    """CSR ``mat`` (its rows first) grown to (n, n) with entries (A, B, w) inserted at their
    rows' ends (parallel ones: the shortest, :func:`_matrix`)."""
    from scipy.sparse import csr_matrix

    extra = matrix(A, B, w, n)
    rows = np.repeat(np.arange(n), np.diff(extra.indptr))
    m_indptr = np.concatenate([mat.indptr, np.full(n - mat.shape[0], mat.indptr[-1])])
    at = m_indptr[rows + 1]
    indptr = m_indptr + np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=n))])
    return csr_matrix((np.insert(mat.data, at, extra.data), np.insert(mat.indices, at, extra.indices), indptr),
                      shape=(n, n))  # fmt: skip


def steps_from_start(kept, A, B, k, p_of, j, x: int, total: int) -> FloatArray:
    """(total,) steps from a spliced start to every point of its graph, by Dijkstra over the
    nodes (the kept goal graph's ``kept``, a :class:`gfuzzy.timespace.unicycle.UnicycleGoal`,
    and the start's x new nodes, renumbered after the kept ones): the exact lower bound of
    the safety windows (:class:`gfuzzy.timespace.spacetime.IntervalStore`). The start's pieces
    ``A -> B`` (k steps; ``p_of``, ``j``: its interior points' pieces and indices)."""
    from .graph_kernel import fewest_steps

    nn, N = kept.nn, len(kept.poses)
    a_c, b_c = A - N + nn, np.where(B >= N, B - N + nn, B)
    o = np.lexsort((k, b_c, a_c))  # by row; parallel pieces: the shortest first
    first = np.ones(len(o), dtype=bool)
    first[1:] = (a_c[o][1:] != a_c[o][:-1]) | (b_c[o][1:] != b_c[o][:-1])
    o = o[first]
    m = kept.steps
    whole, piece_of = _kept_steps(kept)
    rows = np.cumsum(np.bincount(a_c[o] - nn, minlength=x))
    # whole steps (a zero-step piece is stored as 1e-300): a bucket queue, or scipy's Dijkstra rounded
    hop_s = fewest_steps(np.concatenate([m.indptr, m.indptr[-1] + rows]), np.concatenate([m.indices, b_c[o]]),
                         np.concatenate([whole, k[o].astype(np.int64)]), nn)  # fmt: skip
    from_start = np.empty(total)
    from_start[:nn] = hop_s[:nn]
    from_start[N : N + x] = hop_s[nn:]
    from_start[nn:N] = hop_s[piece_of] + kept.j
    hs = np.concatenate([hop_s[:nn], np.zeros(N - nn), hop_s[nn:]])
    from_start[N + x :] = hs[A[p_of]] + j
    return from_start


def _kept_steps(kept) -> tuple[IntArray, IntArray]:
    """(the kept graph's node-level steps as whole numbers, each kept interior point's piece's
    first node), computed once per kept graph (a navigator's every call asks for them)."""
    hit = getattr(kept, "_whole_steps", None)
    if hit is not None and hit[0] is kept.steps:
        return hit[1], hit[2]
    whole, piece_of = np.rint(kept.steps.data).astype(np.int64), kept.A[kept.p_of]
    kept._whole_steps = (kept.steps, whole, piece_of)
    return whole, piece_of
