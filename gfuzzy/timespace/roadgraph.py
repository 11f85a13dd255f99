"""The query-independent part of a query's space-time graph, kept on the roadmap.

A query's graph (the one builder: :func:`gfuzzy.planner.prepared.prepare_goal`, then
:meth:`gfuzzy.planner.prepared.PreparedGoal.splice`) is the roadmap's spanner plus the goal's
and the start's connections, every edge cut into one-step points
(:func:`gfuzzy.timespace.spacetime.split_edges`). Numbered as the planner numbers it (the
roadmap's vertices, the start, the goal, then the interior points edge by edge: the
spanner's edges, the goal's connections, the start's), the spanner's part never depends on
the query: the same ids, the same poses, the same one-step moves. This module keeps that
part, cut once per (step length, stretch), on the :class:`~gfuzzy.roadmap.roadmap.Roadmap`, and
splices a goal's connections into it (:meth:`SplitSpanner.splice`: the arrays a build from
scratch of the spanner and those connections gives, adjacency order included).

It also keeps the roadmap vertices' static clearances, which every certified connection
to a vertex needs (:meth:`gfuzzy.collision.geometry.StaticGeometry.motion_clearance`): computed
once per vertex, lazily, keyed by the scene's static hash and ``robot.clearance``.

The caches live in ``Roadmap._derived`` (derived data: never saved, never pickled, never
compared); a roadmap does not change after building, so they never go stale. Two threads
sharing a roadmap at worst compute an entry twice (each value is a pure function of its
key), never read a half-made one: an entry enters the dict only once complete.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..collision.geometry import StaticGeometry, metric_distance
from ..errors import TimeStepError
from ..poses import split_counts
from ..settings import MAX_POINTS
from ..typed import FloatArray, IntArray
from .spacetime import split_edges

__all__ = [
    "SplitSpanner",
    "Spliced",
    "VertexGraph",
    "spanner_split",
    "roadmap_metres",
    "vertex_clearances",
    "connect",
    "check_points",
    "split_points",
    "MAX_SPLITS",
]

#: Split spanners kept per roadmap (one per (step length, stretch) in use); the oldest
#: goes first. A planner uses one; a few cover a caller alternating dt or stretch.
MAX_SPLITS = 4


def check_points(total: int) -> None:
    """Refuse a query graph of ``total`` points past ``settings.MAX_POINTS`` (before it is cut).

    Raises
    ------
    TimeStepError
        When ``total`` exceeds ``MAX_POINTS``.
    """
    if total > MAX_POINTS:
        raise TimeStepError(
            f"the time step is too fine for this roadmap: its edges would be cut into "
            f"{total:,} points (at most {MAX_POINTS:,}); use a larger dt"
        )


def vertex_clearances(roadmap, geometry: StaticGeometry) -> FloatArray:
    """The roadmap vertices' static clearances, shared by every query: (V,) float, NaN
    where not computed yet (:func:`connect` fills them as it needs them).

    Keyed by the scene's static hash and ``robot.clearance`` (a clearance is measured
    from obstacles grown by it), so a geometry with another clearance gets its own table.
    """
    key = ("clearance", geometry.scene.static_hash, float(geometry.keep))
    table = roadmap._derived.get(key)
    if table is None:
        table = roadmap._derived[key] = np.full(len(roadmap.vertices), np.nan)
    return table


def connect(geometry: StaticGeometry, roadmap, pose: FloatArray, k: int, clearance: float | None = None):
    """Certified straight connections from ``pose`` to its nearest roadmap vertices.

    The nearest vertices in the contract metric are tried in order until ``k`` connect
    (at most ``4 k`` tries; past ``k`` tries only while none has connected).

    Parameters
    ----------
    pose : (d,) float
    k : int
    clearance : float, optional
        ``geometry.clearance1(pose)`` when the caller has it.

    Returns
    -------
    list of (vertex, metric length)
    """
    V = roadmap.vertices
    if len(V) == 0:
        return []
    d = metric_distance(V, pose[None, :], geometry.r)
    order = np.argsort(d, kind="stable")
    ca = geometry.clearance1(pose) if clearance is None else clearance
    table = vertex_clearances(roadmap, geometry)
    out = []
    tried = 0
    k = max(k, 1)
    for i in order[: 4 * k].tolist():
        if tried >= k and out:
            break
        tried += 1
        cb = table[i]
        if cb != cb:  # NaN: not computed yet
            cb = table[i] = geometry.clearance1(V[i])
        if geometry.motion_free(pose, V[i], ca=ca, cb=cb):
            out.append((int(i), float(d[i])))
    return out


@dataclass
class VertexGraph:
    """A symmetric weighted graph on the roadmap's vertices plus the start and the goal
    (ids ``nv``, ``nv + 1``, no edges), as CSR arrays, for Dijkstra per query.

    Attributes
    ----------
    n : int
    indptr : (n + 1,) int
    indices : (nnz,) int
    data : (nnz,) float
        Both directions of every edge; weights at least 1e-300 (csgraph drops zeros).
    """

    n: int
    indptr: IntArray
    indices: IntArray
    data: FloatArray

    @classmethod
    def of(cls, n: int, edges: IntArray, weights: FloatArray) -> VertexGraph:
        """Both directions of ``edges`` in CSR form, columns sorted within a row and
        repeated entries summed (what scipy's ``coo_matrix(...).tocsr()`` gives), in numpy:
        no scipy import for a query."""
        w = np.maximum(np.asarray(weights, dtype=float), 1e-300)
        edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
        rows = np.r_[edges[:, 0], edges[:, 1]]
        cols = np.r_[edges[:, 1], edges[:, 0]]
        order = np.lexsort((cols, rows))
        rows, cols, w = rows[order], cols[order], np.r_[w, w][order]
        first = np.r_[True, (rows[1:] != rows[:-1]) | (cols[1:] != cols[:-1])] if len(rows) else np.zeros(0, bool)
        at = np.flatnonzero(first)
        data = np.add.reduceat(w, at) if len(at) else w
        indptr = np.zeros(n + 1, dtype=np.int64)
        np.cumsum(np.bincount(rows[at], minlength=n), out=indptr[1:])
        return cls(n, indptr, cols[at], data)

    def with_edges(self, edges: IntArray, weights: FloatArray) -> VertexGraph:
        """This graph plus ``edges`` (both directions), each new entry at the end of its
        row: one pass over the arrays, no sort."""
        w = np.maximum(np.asarray(weights, dtype=float), 1e-300)
        rows = np.r_[edges[:, 0], edges[:, 1]]
        order = np.argsort(rows, kind="stable")  # by row: empty rows share an insertion place
        rows, cols, w = rows[order], np.r_[edges[:, 1], edges[:, 0]][order], np.r_[w, w][order]
        at = self.indptr[rows + 1]
        indptr = self.indptr.copy()
        indptr[1:] += np.cumsum(np.bincount(rows, minlength=self.n))
        return VertexGraph(self.n, indptr, np.insert(self.indices, at, cols), np.insert(self.data, at, w))

    def distances(self, sources) -> FloatArray:
        """Shortest distances from ``sources`` (:func:`gfuzzy.timespace.graph_kernel.shortest_paths`:
        (n,) for one source, (s, n) for a list)."""
        from .graph_kernel import shortest_paths

        return shortest_paths(self.indptr, self.indices, self.data, sources)


def roadmap_metres(roadmap) -> VertexGraph:
    """The whole roadmap weighted in metres (the contract's roadmap distance), cached."""
    hit = roadmap._derived.get(("metres",))
    if hit is None:
        n = len(roadmap.vertices) + 2
        hit = roadmap._derived[("metres",)] = VertexGraph.of(n, roadmap.edges, roadmap.lengths)
    return hit


@dataclass
class SplitSpanner:
    """A roadmap's spanner cut into one-step points, numbered as a query's graph numbers them.

    Ids: vertices ``0 .. nv-1``, the start ``nv``, the goal ``nv + 1`` (rows left to fill),
    then the spanner edges' interior points from ``n = nv + 2``; ``N0`` ids in all.

    Attributes
    ----------
    nv, n, N0 : int
    step_len : float
    edges : (E, 2) int
    lengths : (E,) float
        The spanner's edges (``roadmap.spanner(stretch)``).
    k, offs, a, b, j : as :func:`gfuzzy.timespace.spacetime.split_edges` returns them
    rest : (N0 - n,) int
        Each interior point's steps to its edge's end ``b`` (``k - j``).
    poses : (N0, d) float
    indptr : (N0 + 1,) int
    neighbors : (M0,) int
        One-step moves, in the order a build from scratch lists them.
    cut : (nv,) int
        Where, in a vertex's list, a connection's last interior point goes: before the
        moves along the vertex's single-step spanner edges that end at it (the order of
        :func:`split_edges`' moves, see :meth:`splice`).
    steps : VertexGraph
        The spanner on the vertices, weighted in steps (``k``).
    """

    nv: int
    n: int
    N0: int
    step_len: float
    edges: IntArray
    lengths: FloatArray
    k: IntArray
    offs: IntArray
    a: IntArray
    b: IntArray
    j: IntArray
    rest: IntArray
    poses: FloatArray
    indptr: IntArray
    neighbors: IntArray
    cut: IntArray
    steps: VertexGraph

    def splice(self, edges: IntArray, lengths: FloatArray, ends: FloatArray, lead: IntArray | None = None) -> Spliced:
        """The spanner with ``edges`` (each from the start or the goal) added after its own.

        Parameters
        ----------
        edges : (x, 2) int
            ``edges[:, 0]`` is the start or the goal (id ``nv`` or ``nv + 1``).
        lengths : (x,) float
        ends : (2, d) float
            The poses of the start and the goal.
        lead : (x,) int, optional
            Where each edge's pieces are whole steps (:func:`split_edges`); equal pieces
            by default.

        Returns
        -------
        Spliced
            Exactly the arrays :func:`split_edges` and a stable sort by source give on the
            spanner's edges followed by ``edges``.

        Raises
        ------
        LimitError
            When the cut would exceed ``MAX_POINTS`` points.
        """
        kx = split_counts(lengths, self.step_len)
        total = self.N0 + int((kx - 1).sum())
        check_points(total)
        verts = self.poses[: self.n].copy()
        verts[self.nv :] = ends
        cut = split_edges(verts, edges, lengths, self.step_len, self.N0, lead)
        kx, offx, inner, ax, bx, jx, srcx, dstx = cut.k, cut.offs, cut.inner, cut.a, cut.b, cut.j, cut.src, cut.dst
        poses = np.concatenate([self.poses, inner])
        poses[self.nv : self.n] = ends
        # A build from scratch sorts the moves of all edges by source, stably, over
        # [src, dst] of split_edges: per edge list, the chains' first moves, their last
        # moves, the single-step edges, then the same reversed. A connection's edge is
        # (start or goal, vertex v), so v gains only reversed moves: the last interior
        # point's (after v's own reversed last moves: at `cut[v]`), and a single-step
        # edge's (at the end of v's list). The start, the goal and the new interior
        # points have no spanner moves: their lists are the connections' alone.
        s2 = np.concatenate([srcx, dstx])
        d2 = np.concatenate([dstx, srcx])
        order = np.argsort(s2, kind="stable")
        single_rev = np.zeros(len(s2), dtype=bool)  # reversed single-step moves
        single_rev[len(s2) - int((kx == 1).sum()) :] = True
        rows, vals, tail = s2[order], d2[order], single_rev[order]
        at = np.full(len(rows), len(self.neighbors), dtype=np.int64)  # new points: appended
        old = rows < self.N0
        r_old = rows[old]
        at_old = self.indptr[r_old + 1]  # the start's and the goal's lists are empty
        vtx = r_old < self.nv
        at_old[vtx & ~tail[old]] = self.indptr[r_old[vtx & ~tail[old]]] + self.cut[r_old[vtx & ~tail[old]]]
        at[old] = at_old
        neighbors = np.insert(self.neighbors, at, vals)  # stable: equal places keep this order
        added = np.bincount(s2, minlength=total)
        indptr = np.concatenate([self.indptr, np.full(total - self.N0, self.indptr[-1])])
        indptr[1:] += np.cumsum(added)
        return Spliced(kx, offx, ax, bx, jx, poses, indptr, neighbors)


@dataclass
class Spliced:
    """A query's graph arrays (:meth:`SplitSpanner.splice`): the connections' cut
    (``k``, ``offs``, ``a``, ``b``, ``j`` of :func:`split_edges`, their interior ids from
    ``N0``) and the whole graph's poses and adjacency."""

    k: IntArray
    offs: IntArray
    a: IntArray
    b: IntArray
    j: IntArray
    poses: FloatArray
    indptr: IntArray
    neighbors: IntArray


def split_points(roadmap, step_len: float, stretch: float) -> int:
    """The points of the roadmap's ``stretch`` spanner cut into steps of at most ``step_len``
    (its vertices, a query's two ends, its edges' inner points), counted without cutting:
    every holonomic query's graph holds them, so :func:`check_points` refusing them refuses
    the time step for every query alike."""
    keep = roadmap.spanner(stretch)
    return len(roadmap.vertices) + 2 + int((split_counts(roadmap.lengths[keep], step_len) - 1).sum())


def spanner_split(roadmap, step_len: float, stretch: float) -> SplitSpanner:
    """The roadmap's ``stretch`` spanner cut into steps of at most ``step_len``, cached.

    Raises
    ------
    LimitError
        When the cut would exceed ``MAX_POINTS`` points (checked before cutting).
    """
    key = ("split", float(step_len), float(stretch))
    cache = roadmap._derived
    hit = cache.pop(key, None)  # pop and put back: most recently used last
    if hit is not None:
        cache[key] = hit
        return hit
    nv = len(roadmap.vertices)
    n = nv + 2
    keep = roadmap.spanner(stretch)
    edges, lengths = roadmap.edges[keep], roadmap.lengths[keep]
    check_points(split_points(roadmap, step_len, stretch))
    verts = np.vstack([roadmap.vertices, np.zeros((2, roadmap.vertices.shape[1]))])
    cut = split_edges(verts, edges, lengths, step_len, n)
    k, offs, inner, a, b, j, src, dst = cut.k, cut.offs, cut.inner, cut.a, cut.b, cut.j, cut.src, cut.dst
    N0 = n + int(offs[-1])
    s2 = np.concatenate([src, dst])
    d2 = np.concatenate([dst, src])
    order = np.argsort(s2, kind="stable")
    counts = np.bincount(s2, minlength=N0)
    indptr = np.zeros(N0 + 1, dtype=np.int64)
    np.cumsum(counts, out=indptr[1:])
    single_ends = np.bincount(edges[k == 1, 1], minlength=nv)[:nv]
    split = SplitSpanner(
        nv=nv, n=n, N0=N0, step_len=float(step_len), edges=edges, lengths=lengths, k=k, offs=offs,
        a=a, b=b, j=j, rest=np.repeat(k, k - 1) - j, poses=np.vstack([verts, inner]), indptr=indptr,
        neighbors=d2[order], cut=counts[:nv] - single_ends, steps=VertexGraph.of(n, edges, k.astype(float)),
    )  # fmt: skip
    splits = [key_ for key_ in list(cache) if key_[0] == "split"]
    for old in splits[: max(0, len(splits) - MAX_SPLITS + 1)]:
        cache.pop(old, None)  # (another thread may have dropped it: no KeyError)
    cache[key] = split
    return split
