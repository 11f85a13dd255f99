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

__all__ = ["dijkstra", "shortest_paths"]


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


def warm() -> None:
    """Compile :func:`dijkstra` (the precompiled build calls it for its signature)."""
    indptr = np.array([0, 1, 2, 2], dtype=np.int64)
    dijkstra(indptr, np.array([1, 2], dtype=np.int64), np.array([1.0, 2.0]), np.array([0], dtype=np.int64))
