"""The Dijkstra of gfuzzy.timespace.graph_kernel and the CSR graphs of gfuzzy.timespace.roadgraph against scipy
(the oracle: scipy.sparse.csgraph.dijkstra and coo_matrix.tocsr share no code with them)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import coo_matrix, csr_matrix
from scipy.sparse.csgraph import dijkstra as scipy_dijkstra

from gfuzzy.timespace import jit
from gfuzzy.timespace.graph_kernel import dijkstra, shortest_paths
from gfuzzy.timespace.roadgraph import VertexGraph


def _random_graph(rng, n):
    m = int(rng.integers(0, 4 * n))
    edges = rng.integers(0, n, size=(m, 2))
    # weights on a coarse grid make equal-length paths (ties) common; some tiny ones too
    w = rng.choice([0.0, 0.25, 0.5, 1.0, 1.5, 0.1 + rng.random()], size=m)
    return edges, w


@pytest.mark.parametrize("seed", range(25))
def test_vertex_graph_is_scipys_csr(seed):
    """`VertexGraph.of` builds (in numpy) the CSR scipy's coo -> csr gives: sorted columns,
    repeated edges summed, zero weights raised to 1e-300."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 40))
    edges, w = _random_graph(rng, n)
    g = VertexGraph.of(n, edges, w)
    ww = np.maximum(w, 1e-300)
    ref = coo_matrix((np.r_[ww, ww], (np.r_[edges[:, 0], edges[:, 1]], np.r_[edges[:, 1], edges[:, 0]])), shape=(n, n))
    ref = ref.tocsr()
    ref.sort_indices()
    assert np.array_equal(g.indptr, ref.indptr)
    assert np.array_equal(g.indices, ref.indices)
    assert np.allclose(g.data, ref.data, rtol=1e-15, atol=0)


@pytest.mark.parametrize("seed", range(40))
def test_dijkstra_equals_scipy_to_the_bit(seed):
    """The compiled Dijkstra (the precompiled one when loaded, numba's otherwise) and
    `shortest_paths` give scipy's distances exactly, unreachable vertices included, on
    graphs with added edges (`with_edges`, as a query adds its connections)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 60))
    edges, w = _random_graph(rng, n)
    extra, wx = _random_graph(rng, n)
    g = VertexGraph.of(n, edges, w).with_edges(extra[:5], wx[:5])
    src = rng.integers(0, n, size=int(rng.integers(1, 4)))
    mat = csr_matrix((g.data, g.indices, g.indptr), shape=(n, n))
    ref = scipy_dijkstra(mat, directed=True, indices=src)
    got = dijkstra(g.indptr, g.indices, g.data, src.astype(np.int64))
    assert np.array_equal(got, ref)
    assert np.array_equal(shortest_paths(g.indptr, g.indices, g.data, src), ref)
    one = shortest_paths(g.indptr, g.indices, g.data, int(src[0]))
    assert one.shape == (n,) and np.array_equal(one, ref[0])
    assert np.array_equal(g.distances(src), ref)


def test_shortest_paths_uses_the_kernel_only_when_precompiled(monkeypatch):
    """Without precompiled kernels `shortest_paths` calls scipy (numba is not loaded for
    it); with them, the compiled Dijkstra."""
    import gfuzzy.timespace.graph_kernel as gk

    calls = []
    monkeypatch.setattr(gk, "dijkstra", lambda *a: calls.append(a) or np.zeros((1, 2)))
    g = VertexGraph.of(2, np.array([[0, 1]]), np.array([1.0]))
    out = shortest_paths(g.indptr, g.indices, g.data, [0])
    if jit.loaded() is None:
        assert calls == [] and np.array_equal(out, [[0.0, 1.0]])
    else:
        assert len(calls) == 1 and np.array_equal(out, [[0.0, 0.0]])


@pytest.mark.parametrize("seed", range(30))
def test_fewest_steps_equals_scipy_rounded(seed):
    """The bucket queue of whole-step weights (`bucket_steps`, the unicycle's safety windows'
    Dijkstra) and `fewest_steps` on either path give scipy's Dijkstra rounded, zero-step
    pieces (stored as 1e-300) and unreachable vertices included."""
    import gfuzzy.timespace.graph_kernel as gk

    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 80))
    m = int(rng.integers(0, 4 * n))
    a, b = rng.integers(0, n, size=(2, m))
    w = rng.choice([0, 0, 1, 1, 2, 3, 7, int(rng.integers(1, 120))], size=m)
    order = np.argsort(a, kind="stable")
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(a, minlength=n), out=indptr[1:])
    indices, steps = b[order].astype(np.int64), w[order].astype(np.int64)
    src = int(rng.integers(0, n))
    ref = scipy_dijkstra(csr_matrix((np.maximum(steps, 1e-300), indices, indptr), shape=(n, n)), directed=True, indices=src)
    ref = np.rint(np.where(ref < 1e-200, 0.0, ref))
    got = gk.bucket_steps(indptr, indices, steps, src, int(steps.max()) if m else 0)
    assert np.array_equal(got, ref)
    assert np.array_equal(gk.fewest_steps(indptr, indices, steps, src), ref)
