"""How deep two polygons overlap, for :mod:`gfuzzy.check.check` (sharing no code with the
planner's measure in ``gfuzzy.collision.exact``): the largest distance of a point of the
overlap from the outline of the shape it lies inside, or a piece's thickness.
"""

from __future__ import annotations

import numpy as np
import shapely

from ..typed import FloatArray

__all__ = ["Edges", "convex_outline", "overlap_depth"]


class Edges:
    """The boundary of a (large) region as its segments in a spatial index."""

    def __init__(self, region):
        rings = shapely.get_parts(shapely.boundary(region))
        xy, ring = shapely.get_coordinates(rings, return_index=True)
        same = ring[:-1] == ring[1:]
        self.a, self.b = xy[:-1][same], xy[1:][same]
        self.tree = shapely.STRtree(shapely.linestrings(np.stack([self.a, self.b], axis=1)))

    def near(self, parts, tol: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The segments within ``tol`` of each of ``parts``: (first, count, segments), the
        segments of part k being ``segments[first[k]:first[k] + count[k]]``."""
        i, j = self.tree.query(parts, predicate="dwithin", distance=tol)
        order = np.argsort(i, kind="stable")
        count = np.bincount(i, minlength=len(parts))
        return np.cumsum(count) - count, count, j[order]

    def along(self, p: FloatArray, q: FloatArray, part, near, tol: float) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """As :meth:`_Outlines.along` for p-q on ``part`` (of those given to :meth:`near`):
        against the segments within ``tol`` of that part (the bound needs one within
        ``tol`` of both ends); a point farther from all of them is measured against the
        whole boundary. The cut is where the segment within ``tol`` of p reaching farthest
        along p-q ends (past two boxes' seam at once), or 0.5."""
        k = len(p)
        first, count, segs = near
        n = count[part]
        i = np.repeat(np.arange(k), n)
        j = segs[np.repeat(first[part], n) + np.arange(len(i)) - np.repeat(np.cumsum(n) - n, n)]
        a, b = self.a[j], self.b[j]
        pdist, qdist = _point_segment_distance(p[i], a, b), _point_segment_distance(q[i], a, b)
        dp, dq, bound = np.full(k, np.inf), np.full(k, np.inf), np.full(k, np.inf)
        np.minimum.at(dp, i, pdist)
        np.minimum.at(dq, i, qdist)
        np.minimum.at(bound, i, np.maximum(pdist, qdist))
        for d, xy in ((dp, p), (dq, q)):
            far = ~(d <= tol)
            if far.any():
                d[far] = self.distance(xy[far])
        # the split: where the segment within tol of p reaching farthest along p-q ends
        pq = q - p
        norm = np.maximum(np.sum(pq * pq, -1), 1e-300)
        reach = np.fmax(np.sum((a - p[i]) * pq[i], -1), np.sum((b - p[i]) * pq[i], -1)) / norm[i]
        t = np.full(k, -np.inf)
        near_p = pdist <= tol
        np.maximum.at(t, i[near_p], reach[near_p])
        t = np.where((t > 1e-6) & (t < 1.0 - 1e-6), t, 0.5)
        return dp, dq, bound, t

    def distance(self, xy: FloatArray) -> FloatArray:
        """Each point's distance to the boundary."""
        (i, _), dist = self.tree.query_nearest(shapely.points(xy), return_distance=True, all_matches=False)
        out = np.full(len(xy), np.inf)
        out[i] = dist
        return out


class _Outlines:
    """Segments of outlines, one outline per shape (a body, a mover, a map's boundary
    near a body), padded to one array: each point is measured against its own shape's."""

    def __init__(self, a: FloatArray, b: FloatArray, owner, n: int):
        count = np.bincount(owner, minlength=n)
        width = max(int(count.max(initial=0)), 1)
        order = np.argsort(owner, kind="stable")
        owner = owner[order]
        slot = np.arange(len(owner)) - np.repeat(np.cumsum(count) - count, count)
        self.a = np.full((n, width, 2), np.nan)
        self.b = np.full((n, width, 2), np.nan)
        self.a[owner, slot], self.b[owner, slot] = a[order], b[order]

    @classmethod
    def of(cls, shapes) -> _Outlines:
        """The outlines of polygons ``shapes``."""
        rings, of = shapely.get_rings(np.asarray(shapes, dtype=object), return_index=True)
        xy, ring = shapely.get_coordinates(rings, return_index=True)
        same = ring[:-1] == ring[1:]
        return cls(xy[:-1][same], xy[1:][same], of[ring[:-1][same]], len(shapes))

    def along(self, p: FloatArray, q: FloatArray, owner) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """The outline's distance from points ``p`` and ``q`` (the i-th pair against outline
        ``owner[i]``), a bound of it over each segment p-q (the distance to one outline
        segment is convex along p-q: extreme at its ends; the outline is no farther than
        any one of its segments) and where to cut p-q if that bound is not enough (a
        fraction of it: where the segment within ``tol`` of p reaching farthest along
        p-q ends, or 0.5)."""
        a, b = self.a[owner], self.b[owner]
        dp = np.nan_to_num(_point_segment_distance(p[:, None], a, b), nan=np.inf)
        dq = np.nan_to_num(_point_segment_distance(q[:, None], a, b), nan=np.inf)
        bound = np.maximum(dp, dq).min(1, initial=np.inf)
        return dp.min(1, initial=np.inf), dq.min(1, initial=np.inf), bound, np.full(len(p), 0.5)


def _point_segment_distance(p: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """Distance from points ``p`` to segments ``a``-``b`` (broadcast, the last axis x, y)."""
    ab, ap = b - a, p - a
    t = np.clip(np.sum(ap * ab, -1) / np.maximum(np.sum(ab * ab, -1), 1e-300), 0.0, 1.0)
    return np.hypot(*np.moveaxis(ap - t[..., None] * ab, -1, 0))


#: Halvings of an overlap's edge whose depth is not yet bounded by ``tol`` (then its
#: bound counts: a violation is never missed, at worst one within 2**-40 of an edge's
#: length of tol is called one).
_DEPTH_HALVINGS = 40

#: A convex body's core: the body less a band this many ``tol`` wide along its outline.
_CORE_BAND = 0.3


def _within_tol(bodies, others, tol: float) -> np.ndarray:
    """Which convex ``bodies`` overlap ``others`` at most ``tol`` deep, proven without
    measuring the overlap: the body's core C (the body less a band ``0.3 tol`` wide along
    its outline) misses the obstacle, and every vertex of the body is within
    ``h = 0.45 tol`` of C (the Hausdorff distance, checked: a body too thin or too sharp
    for such a core is measured).

    Why: let B be the body and O the obstacle. A point y of B outside C is within h of B's
    outline (a line separates y from the convex C; B's vertex farthest beyond it is within h
    of C, and y is no deeper in B than that vertex is beyond y). So a point of O's outline
    inside B, not in C, is within h of B's outline; a point x of B's outline inside O more
    than tol from O's outline has a disc of radius tol about it inside O, holding a point of
    C (within h of x): C would meet O. A piece R of the overlap lies in the band of points
    within h of B's outline; each curve at distance t < h inside B's outline meets R in at
    most the length of R's outline (the projection onto the convex set of points t inside
    B, which shortens no curve, maps R's outline onto it), so R's area is at most h times
    its perimeter: its thickness, 2A/P, at most 2h < tol.
    """
    core = shapely.buffer(bodies, -_CORE_BAND * tol, join_style="mitre")
    near = shapely.hausdorff_distance(bodies, core) <= 0.45 * tol  # NaN (an empty core): False
    return near & ~shapely.intersects(core, others)


def convex_outline(points: FloatArray) -> bool:
    """Whether a simple polygon's outline (either way round) turns one way only at every
    vertex (a straight one, as at a point on a side, either way): a convex body, which
    :func:`_within_tol` may prove touching (the body is convex: the proof's premise; a
    concave body could hide a spike in the band it leaves unexamined)."""
    edges = np.roll(points, -1, axis=0) - points
    nxt = np.roll(edges, -1, axis=0)
    turns = edges[:, 0] * nxt[:, 1] - edges[:, 1] * nxt[:, 0]
    return bool(np.all(turns >= 0.0) or np.all(turns <= 0.0))


def overlap_depth(bodies, others, tol: float, other_edges: Edges | None = None, convex: bool = False,
                  relative: float | None = None) -> FloatArray:  # fmt: skip
    """How deep bodies and obstacles overlap (m; 0 where they only touch), pairwise
    (``others`` one geometry or one per body).

    An overlap's depth is the largest distance of a point of its outline from the outline
    of the shape it lies inside (a point of the body inside the obstacle from the
    obstacle's outline: a corner, a spike's tip, an edge across a thin wall; a point of the
    obstacle inside the body from the body's outline), or, when more, the thickness of one
    of its pieces (twice its area over its perimeter: an obstacle held inside the body, its
    outline near the body's). A rounding of two touching shapes is a sliver about its size
    deep however long it is. Along each edge of an overlap's outline the distance is
    bounded exactly (see :meth:`Edges.along`), the edge split until it is within
    ``tol`` or, by default, until a point deeper than ``tol`` is found (all a verdict
    needs: the depth of a deeper overlap is then a lower bound); with ``relative``, a
    deeper overlap is split on until within that fraction of the deepest point found (the
    depth returned is that point's: the vertices' exact, the true depth at most
    ``relative`` more; the number a report prints). Either way it is more than ``tol`` only
    where the overlap is. ``other_edges`` indexes the outline of a single large ``others``
    (a map).

    ``convex`` bodies (a box, its swept hull) whose overlap is proven at most ``tol`` deep
    by :func:`_within_tol` (a body sliding along a wall by a rounding) are not measured:
    their depth reads 0, touching.
    """
    bodies = np.asarray(bodies, dtype=object)
    others = np.broadcast_to(np.asarray(others, dtype=object), bodies.shape)
    if convex:
        measure = ~_within_tol(bodies, others, tol)
        depth = np.zeros(len(bodies))
        if measure.any():
            depth[measure] = overlap_depth(bodies[measure], others[measure], tol, other_edges, relative=relative)
        return depth
    parts, owner = shapely.get_parts(shapely.intersection(bodies, others), return_index=True)
    area = shapely.area(parts)
    solid = area > 0.0
    parts, owner, area = parts[solid], owner[solid], area[solid]
    depth = np.zeros(len(bodies))
    if len(parts) == 0:
        return depth
    np.maximum.at(depth, owner, 2.0 * area / np.maximum(shapely.length(parts), 1e-300))
    rings, ring_part = shapely.get_rings(parts, return_index=True)
    xy, ring = shapely.get_coordinates(rings, return_index=True)
    same = ring[:-1] == ring[1:]
    p, q, part = xy[:-1][same], xy[1:][same], ring_part[ring[:-1][same]]
    at = owner[part]
    body = _Outlines.of(bodies)
    other = _Outlines.of(others) if other_edges is None else None
    near = other_edges.near(parts, tol) if other_edges is not None else None
    for level in range(_DEPTH_HALVINGS + 1):
        if other is not None:
            ends = [body.along(p, q, at), other.along(p, q, at)]
        else:
            ends = [body.along(p, q, at), other_edges.along(p, q, part, near, tol)]
        np.maximum.at(depth, at, np.maximum(np.maximum(ends[0][0], ends[1][0]), np.maximum(ends[0][1], ends[1][1])))
        # each distance changes no faster than along p-q: a short edge is bounded at once
        half = 0.5 * np.hypot(*(q - p).T)
        bound = np.maximum(*(np.minimum(e[2], 0.5 * (e[0] + e[1]) + half) for e in ends))
        if level == _DEPTH_HALVINGS:
            np.maximum.at(depth, at, bound)
            break
        # open: not bounded by tol, nor (an overlap already too deep) by its depth so far
        if relative is None:
            open_ = (bound > tol) & (depth[at] <= tol)
        else:
            open_ = bound > np.maximum(tol, depth[at] * (1.0 + relative))
        if not open_.any():
            break
        # halved, and cut where a segment of the other's outline ends (past a seam at once)
        p, q, at, part, cut = p[open_], q[open_], at[open_], part[open_], ends[1][3][open_]
        lo, hi = np.minimum(cut, 0.5)[:, None], np.maximum(cut, 0.5)[:, None]
        u, v = p + lo * (q - p), p + hi * (q - p)
        mid = (hi > lo)[:, 0]
        p, q = np.concatenate([p, u[mid], v]), np.concatenate([u, v[mid], q])
        at, part = np.concatenate([at, at[mid], at]), np.concatenate([part, part[mid], part])
    return depth
