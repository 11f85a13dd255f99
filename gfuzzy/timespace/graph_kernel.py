"""Shortest distances on a CSR graph: scipy's Dijkstra, or the same compiled here when the
precompiled kernels are loaded.

``scipy.sparse.csgraph`` costs 0.1-0.2 s to import (it brings scipy.sparse.linalg,
scipy.linalg, unittest, Cython's shadow module...), which the first query of a process
paid for two Dijkstra runs of a few milliseconds. When :mod:`gfuzzy.timespace.jit` serves
precompiled kernels, :func:`shortest_paths` runs :func:`dijkstra` from them instead and
scipy's graph module is never imported; otherwise it calls scipy, as before (numba is
not loaded just for this).

Both give the same distances to the bit: each is the least fixed point of
``dist[v] = min over edges (u, v) of dist[u] + w``, the same floating-point sums, which
any Dijkstra finds whatever its order of ties (the weights are positive: at least 1e-300,
as :class:`gfuzzy.timespace.roadgraph.VertexGraph` stores them). ``tests/test_graph_kernel.py``
cross-checks them on random graphs.
"""

from __future__ import annotations

import numpy as np

from ..typed import FloatArray, IntArray
from .jit import loaded, njit

__all__ = ["dijkstra", "shortest_paths", "bucket_steps", "fewest_steps"]


@njit(lazy=True, cache=True)
def dijkstra(indptr, indices, data, sources):
    """Shortest distances from each source over a directed CSR graph (lazy binary heap).

    Parameters
    ----------
    indptr : (n + 1,) int ; indices : (nnz,) int ; data : (nnz,) float, positive
    sources : (s,) int

    Returns
    -------
    (s, n) float
        ``inf`` where a vertex is not reachable.
    """
    n = len(indptr) - 1
    out = np.full((len(sources), n), np.inf)
    cap = len(indices) + 1
    hd = np.empty(cap, np.float64)
    hv = np.empty(cap, np.int64)
    done = np.zeros(n, np.bool_)
    for r in range(len(sources)):
        dist = out[r]
        done[:] = False
        src = sources[r]
        dist[src] = 0.0
        hd[0] = 0.0
        hv[0] = src
        size = 1
        while size > 0:
            d = hd[0]
            u = hv[0]
            size -= 1
            if size > 0:  # the last entry sifts down from the root
                ld, lv = hd[size], hv[size]
                i = 0
                while True:
                    c = 2 * i + 1
                    if c >= size:
                        break
                    if c + 1 < size and hd[c + 1] < hd[c]:
                        c += 1
                    if hd[c] < ld:
                        hd[i], hv[i] = hd[c], hv[c]
                        i = c
                    else:
                        break
                hd[i], hv[i] = ld, lv
            if done[u] or d > dist[u]:
                continue
            done[u] = True
            for e in range(indptr[u], indptr[u + 1]):
                v = indices[e]
                nd = d + data[e]
                if nd < dist[v]:
                    dist[v] = nd
                    i = size  # push, sift up
                    size += 1
                    while i > 0:
                        p = (i - 1) >> 1
                        if hd[p] > nd:
                            hd[i], hv[i] = hd[p], hv[p]
                            i = p
                        else:
                            break
                    hd[i], hv[i] = nd, v
    return out


@njit(lazy=True, cache=True)
def bucket_steps(indptr, indices, steps, source, wmax):
    """Fewest steps from ``source`` over a directed CSR graph whose weights are whole
    numbers of steps (Dial's bucket queue: ``wmax + 1`` buckets used round, a linked list
    each; a weight of 0 joins the bucket being emptied).

    Parameters
    ----------
    indptr : (n + 1,) int ; indices : (nnz,) int ; steps : (nnz,) int, 0 <= steps <= wmax
    source : int ; wmax : int

    Returns
    -------
    (n,) float
        ``inf`` where a vertex is not reachable.
    """
    n = len(indptr) - 1
    big = np.iinfo(np.int64).max
    dist = np.full(n, big, np.int64)
    nb = wmax + 1
    head = np.full(nb, -1, np.int64)
    # a push per improvement: at most one per edge, and the source's
    nxt = np.empty(len(indices) + 1, np.int64)
    node = np.empty(len(indices) + 1, np.int64)
    dist[source] = 0
    head[0], nxt[0], node[0] = 0, -1, source
    used, live, d = 1, 1, 0
    while live > 0:
        b = d % nb
        while head[b] >= 0:
            e = head[b]
            head[b] = -1
            while e >= 0:
                live -= 1
                u = node[e]
                e = nxt[e]
                if dist[u] != d:  # improved since it was pushed
                    continue
                for q in range(indptr[u], indptr[u + 1]):
                    v = indices[q]
                    nd = d + steps[q]
                    if nd < dist[v]:
                        dist[v] = nd
                        c = nd % nb
                        node[used], nxt[used] = v, head[c]
                        head[c] = used
                        used += 1
                        live += 1
        d += 1
    out = np.empty(n)
    for i in range(n):
        out[i] = np.inf if dist[i] == big else float(dist[i])
    return out


def shortest_paths(indptr: IntArray, indices: IntArray, data: FloatArray, sources) -> FloatArray:
    """Distances from ``sources`` over the directed CSR graph, as
    ``scipy.sparse.csgraph.dijkstra(..., directed=True, indices=sources)`` gives them.

    Parameters
    ----------
    indptr : (n + 1,) int ; indices : (nnz,) int ; data : (nnz,) float, positive
    sources : int or (s,) int

    Returns
    -------
    (n,) float for one source, (s, n) float for a list.
    """
    one = np.ndim(sources) == 0
    src = np.atleast_1d(np.asarray(sources, dtype=np.int64))
    if loaded() is not None:
        out = dijkstra(
            np.ascontiguousarray(indptr, dtype=np.int64),
            np.ascontiguousarray(indices, dtype=np.int64),
            np.ascontiguousarray(data, dtype=np.float64),
            np.ascontiguousarray(src),
        )
    else:
        from scipy.sparse import csr_matrix
        from scipy.sparse.csgraph import dijkstra as scipy_dijkstra

        n = len(indptr) - 1
        out = scipy_dijkstra(csr_matrix((data, indices, indptr), shape=(n, n)), directed=True, indices=src)
    return out[0] if one else out


def fewest_steps(indptr: IntArray, indices: IntArray, steps: IntArray, source: int) -> FloatArray:
    """(n,) fewest steps from ``source`` over the directed CSR graph of whole-step weights
    (>= 0): :func:`bucket_steps` when the precompiled kernels are loaded, otherwise scipy's
    Dijkstra (zero weights as 1e-300) rounded: the same numbers (sums of whole numbers are
    exact), ``inf`` where unreachable."""
    steps = np.ascontiguousarray(steps, dtype=np.int64)
    if loaded() is not None:
        wmax = int(steps.max()) if len(steps) else 0
        return bucket_steps(np.ascontiguousarray(indptr, dtype=np.int64), np.ascontiguousarray(indices, dtype=np.int64),
                            steps, int(source), wmax)  # fmt: skip
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import dijkstra as scipy_dijkstra

    n = len(indptr) - 1
    d = scipy_dijkstra(csr_matrix((np.maximum(steps, 1e-300), indices, indptr), shape=(n, n)), directed=True,
                       indices=int(source))  # fmt: skip
    return np.rint(np.where(d < 1e-200, 0.0, d))


def warm() -> None:
    """Compile :func:`dijkstra` and :func:`bucket_steps` (the precompiled build calls it for
    their signatures)."""
    indptr = np.array([0, 1, 2, 2], dtype=np.int64)
    dijkstra(indptr, np.array([1, 2], dtype=np.int64), np.array([1.0, 2.0]), np.array([0], dtype=np.int64))
    bucket_steps(indptr, np.array([1, 2], dtype=np.int64), np.array([1, 0], dtype=np.int64), 0, 1)
