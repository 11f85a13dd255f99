"""The differential drive's plane roadmap: lanes and turning rings (:mod:`gfuzzy.timespace.unicycle`).

A unicycle's lanes are straight roadmap edges driven at their own heading, certified for the
body held at it (a disc's also split at *turn points* where they leave a passage, each with
lanes to its nearest vertices: :func:`_turn_points`); its turning rings are the headings,
one turning step apart, at which it turns in place at a vertex, certified while they
sweep. Both are the query-independent part of its search graph, cached on the roadmap by :func:`gfuzzy.timespace.unicycle._base`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..typed import FloatArray, IntArray
from .drive import turn_free
from .roadgraph import vertex_clearances

__all__ = ["Lanes", "lanes", "LANE_NEIGHBOURS", "DISC_TRACE_STEPS", "OutOfTime", "on_time"]

#: For an SE(2) roadmap (box robots): how many nearest vertices in the plane each vertex
#: tries as extra lanes, besides the roadmap's own edges.
LANE_NEIGHBOURS = 10
#: Steps of the circumscribed disc's sphere tracing along a lane at most (beyond: the body
#: at the lane's heading is traced instead, as near walls).
DISC_TRACE_STEPS = 64


class OutOfTime(Exception):
    """The planning budget ran out while the graph was being built (nothing is cached)."""


def on_time(deadline: float) -> None:
    """Raise :class:`OutOfTime` past ``deadline`` (``time.perf_counter()`` seconds)."""
    if time.perf_counter() > deadline:
        raise OutOfTime


@dataclass
class Lanes:
    """The plane roadmap of a unicycle: positions and certified lanes.

    Attributes
    ----------
    xy : (V, 2) float
        The roadmap's vertices' positions, then a disc's turn points (:func:`_turn_points`).
    edges : (E, 2) int
    ok : (E, 2) bool
        Whether edge ``(u, v)`` is free at the heading of u -> v (column 0) and of v -> u
        (column 1), the body held at that heading along the whole segment.
    """

    xy: FloatArray
    edges: IntArray
    ok: np.ndarray


def lanes(roadmap, geometry, stretch: float = 1.0, deadline: float = math.inf) -> Lanes:
    """The unicycle's plane roadmap of ``roadmap`` (see the module docstring), cached;
    :class:`OutOfTime` past ``deadline`` (``time.perf_counter()`` seconds)."""
    robot = geometry.robot
    key = ("unicycle-lanes", geometry.scene.static_hash, float(geometry.keep), float(stretch), robot.shape, robot.size)
    hit = roadmap._derived.get(key)
    if hit is not None:
        return hit
    xy = np.ascontiguousarray(roadmap.vertices[:, :2], dtype=float)
    if robot.shape == "disc":
        keep = roadmap.spanner(stretch)
        edges = roadmap.edges[keep].astype(np.int64).reshape(-1, 2)
        clear = vertex_clearances(roadmap, geometry)  # shared with every query's connections
        todo = np.nonzero(np.isnan(clear))[0]
        clear[todo] = [geometry.clearance1(xy[i]) for i in todo.tolist()]
        xy, edges = _turn_points(geometry, xy, edges, clear, deadline)
        out = Lanes(xy, edges, np.ones((len(edges), 2), dtype=bool))
    else:
        out = _box_lanes(roadmap, geometry, xy, deadline)
        if stretch > 1.0 and len(out.edges):  # as the disc's: a spanner of the lanes
            from ..roadmap.roadmap import Roadmap

            lens = np.hypot(*(xy[out.edges[:, 1]] - xy[out.edges[:, 0]]).T)
            plane = Roadmap(xy, out.edges, lens, roadmap.scene_name, roadmap.scene_hash, roadmap.circumradius)
            keep = plane.spanner(stretch)
            out = Lanes(xy, out.edges[keep], out.ok[keep])
    roadmap._derived[key] = out
    return out


#: Nearest roadmap vertices a disc's turn point (:func:`_turn_points`) tries lanes to.
TURN_LINKS = 10
#: A disc's vertex is in a passage (:func:`_turn_points`) below this clearance, in radii.
PASSAGE_CLEARANCE = 0.5
#: Below this gradient of the clearance a vertex is on a ridge between walls (:func:`_in_passage`).
PASSAGE_RIDGE = 0.5
#: Where :func:`_in_passage` looks for a radius of clearance: these times as far from the
#: vertex as one wall alone would give it one.
PASSAGE_REACH = (1.5, 2.0)


def _turn_points(geometry, xy: FloatArray, edges: IntArray, clear: FloatArray,
                 deadline: float = math.inf) -> tuple[FloatArray, IntArray]:  # fmt: skip
    """A disc drive's lanes with turn points where they leave a passage: (xy, edges), the
    points after the roadmap's vertices (``clear``: the vertices' static clearances).

    A drive turns only at vertices; a lane through a door from a vertex in it runs on to
    the next vertex, which may lie far beyond the door, on a mover's line through it (the
    unseen rooms, seed 2 case 88: 1.6 m and 1.1 m on, a box bouncing along the line, missed
    where a witness turns off just beyond the door). From each vertex in a passage (less
    clearance than ``PASSAGE_CLEARANCE`` radii, pinched from two opposite sides:
    :func:`_in_passage`; beside one wall it has a radius of clearance a radius off), each
    lane gets a point where the disc first has a radius of clearance (sphere tracing: the
    clearance grows by at most the distance moved), unless the point lies within a radius
    of the vertex, within two of the lane's far end, or within one of a point already added; the point gets lanes to both ends of its lane (which is kept whole too) and to its ``TURN_LINKS`` nearest
    vertices that the disc sweeps free (:meth:`StaticGeometry.sweep_free`).
    """
    r = float(geometry.robot.radius)
    n = len(xy)
    if not n or not len(edges):
        return xy, edges
    points: list = []
    added: list = []
    for v in np.nonzero(clear < PASSAGE_CLEARANCE * r)[0].tolist():
        on_time(deadline)
        if not _in_passage(geometry, xy[v], clear[v], r):
            continue
        for w in np.concatenate([edges[edges[:, 0] == v, 1], edges[edges[:, 1] == v, 0]]).tolist():
            p = _passage_end(geometry, xy[v], xy[w], r)
            if p is None or any(math.hypot(*(p - q)) < r for q in points):
                continue
            points.append(p)
            i = n + len(points) - 1
            added += [(v, i), (i, w)]
    for i, p in enumerate(points, start=n):
        on_time(deadline)
        near = np.argsort(np.hypot(*(xy - p).T), kind="stable")[:TURN_LINKS]
        added += [(int(j), i) for j in near.tolist() if geometry.sweep_free(p, xy[j])]
    if not points:
        return xy, edges
    out = np.unique(np.sort(np.vstack([edges, np.array(added, dtype=np.int64)]), axis=1), axis=0)
    return np.vstack([xy, np.array(points)]), out


def _in_passage(geometry, p: FloatArray, c: float, r: float) -> bool:
    """Whether the disc at ``p`` (clearance ``c`` below a radius) is pinched from two
    opposite sides (a door, a corridor up to about 4.5 radii wide): moving straight away
    from its nearest wall (up the clearance's gradient, central differences a twentieth of
    a radius wide), it has less than a radius of clearance ``PASSAGE_REACH`` times as far on
    as one wall alone would give it one (half as far again and twice), or the gradient is
    below ``PASSAGE_RIDGE`` (a ridge of the clearance between two walls: a door's middle)."""
    e = 0.05 * r
    g = np.array([geometry.clearance1(p + d) - geometry.clearance1(p - d) for d in ((e, 0.0), (0.0, e))]) / (2 * e)
    n = math.hypot(*g)
    if n < PASSAGE_RIDGE:
        return True
    return all(geometry.clearance1(p + (k * (r - c) / n) * g) < r for k in PASSAGE_REACH)


def _passage_end(geometry, a: FloatArray, b: FloatArray, r: float) -> FloatArray | None:
    """The first point from ``a`` towards ``b`` at which the disc has ``r`` of clearance (to
    within 5% of ``r`` past it), or None when that lies within ``r`` of ``a``, within ``2 r``
    of ``b``, or nowhere before it."""
    length = math.hypot(*(b - a))
    t = 0.0
    while t < length - 2.0 * r:
        p = a + (t / length) * (b - a)
        c = geometry.clearance1(p)
        if c >= r:
            return p if t >= r else None
        t += max(r - c, 0.05 * r)
    return None


def _box_lanes(roadmap, geometry, xy: FloatArray, deadline: float = math.inf) -> Lanes:
    cand = [np.sort(roadmap.edges.astype(np.int64).reshape(-1, 2), axis=1)]
    if len(xy) > 1:
        k = min(LANE_NEIGHBOURS, len(xy) - 1)
        u = np.repeat(np.arange(len(xy)), k)
        cand.append(np.sort(np.stack([u, _nearest(xy, k).reshape(-1)], axis=1), axis=1))
    edges = np.unique(np.vstack(cand), axis=0)
    d = np.hypot(*(xy[edges[:, 1]] - xy[edges[:, 0]]).T)
    edges = edges[(edges[:, 0] != edges[:, 1]) & (d > 1e-9)]
    ok = np.zeros((len(edges), 2), dtype=bool)
    symmetric = geometry.robot.half_turn_symmetric  # the same body turned by pi
    # the circumscribed disc's clearance at each position bounds every heading's there: a
    # lane the disc drives clear is free at both headings (one trace for the two, its ends
    # shared by every lane of a vertex); else the body at the lane's heading decides
    swept = np.array([geometry.sweep_bound(float(x), float(y)) for x, y in xy])
    for i, (u, v) in enumerate(edges.tolist()):
        if i % 64 == 0:
            on_time(deadline)
        (ux, uy), (vx, vy) = xy[u], xy[v]
        if swept[u] > 0 and swept[v] > 0 and geometry.sweep_free([ux, uy], [vx, vy], swept[u], swept[v], DISC_TRACE_STEPS):
            ok[i] = True
            continue
        h = math.atan2(vy - uy, vx - ux)
        ok[i, 0] = geometry.motion_free([ux, uy, h], [vx, vy, h])
        ok[i, 1] = ok[i, 0] if symmetric else geometry.motion_free([vx, vy, h + math.pi], [ux, uy, h + math.pi])
    keep = ok.any(axis=1)
    return Lanes(xy, edges[keep], ok[keep])


#: From this many points :func:`_nearest` asks a k-d tree (its blocks take time that grows
#: with the square of the points: 1 s at 5,000, 15 s at 20,000).
KDTREE_FROM = 3000


def _nearest(xy: FloatArray, k: int, rows: int = 512) -> IntArray:
    """The ``k`` nearest other points of each point of ``xy`` (V, 2), (V, k) int in no
    particular order: squared distances in blocks of ``rows`` (no k-d tree for fewer than
    ``KDTREE_FROM`` points: importing scipy.spatial cost a first query 0.25-1 s, more than
    the search)."""
    if len(xy) >= KDTREE_FROM:
        from scipy.spatial import cKDTree

        idx = cKDTree(xy).query(xy, k=k + 1)[1]  # itself among them (first, but for duplicates)
        own = idx == np.arange(len(xy))[:, None]
        own[~own.any(axis=1), -1] = True  # itself not among them (duplicates): drop the farthest
        return idx[~own].reshape(len(xy), k).astype(np.int64)
    out = np.empty((len(xy), k), dtype=np.int64)
    for lo in range(0, len(xy), rows):
        d = ((xy[lo : lo + rows, None, :] - xy[None, :, :]) ** 2).sum(-1)
        d[np.arange(len(d)), lo + np.arange(len(d))] = np.inf  # not itself
        out[lo : lo + rows] = np.argpartition(d, k - 1, axis=1)[:, :k]
    return out


def _brackets(h: float, r0: int, n_ring: int, step_h: float) -> list:
    """The two ring points around heading ``h`` (ring of ``n_ring`` headings from -pi, its
    first point ``r0``): [(point, signed turn to it)], the one below first."""
    u = (h + math.pi) / step_h
    i = int(math.floor(u)) % n_ring
    below = -((h + math.pi - i * step_h) % (2 * math.pi))
    above = ((i + 1) * step_h - math.pi - h) % (2 * math.pi)
    return [(r0 + i, below), (r0 + (i + 1) % n_ring, above)]


def _rings(geometry, xy: FloatArray, cv: IntArray, ch: FloatArray, n_ring: int, deadline: float = math.inf,
           ringless_from: int | None = None, memo: dict | None = None):  # fmt: skip
    """The turning rings of the vertices with copies (see :class:`_Base`) and the turns
    joining them and the copies (ring points as ``-(1 + i)``); :class:`OutOfTime` past
    ``deadline``. Points from ``ringless_from`` on get none (a repair's chain points,
    :mod:`gfuzzy.timespace.unirepair`, which bring their own turns); ``memo``: each
    vertex's free ring points and arcs by position, kept for the next call.

    Returns
    -------
    ring_ptr : (V,) int ; ring_v : (R,) int ; ring_h : (R,) float ; ring_ok : (R,) bool
    ta, tb : list of int ; tdh : list of float
        The turns: from, to, signed heading change.
    """
    robot = geometry.robot
    step_h = 2 * math.pi / n_ring
    bounds = np.searchsorted(cv, np.arange(len(xy) + 1))
    has = np.diff(bounds) > 0
    if ringless_from is not None:
        has[ringless_from:] = False
    ring_ptr = np.full(len(xy), -1, dtype=np.int64)
    ring_ptr[has] = np.arange(int(has.sum())) * n_ring
    grid = -math.pi + step_h * np.arange(n_ring)
    ring_v = np.repeat(np.nonzero(has)[0], n_ring)
    ring_h = np.tile(grid, int(has.sum()))
    ring_ok = np.ones(len(ring_v), dtype=bool)
    ta, tb, tdh = [], [], []
    disc = robot.shape == "disc"
    for v in np.nonzero(has)[0].tolist():
        on_time(deadline)
        x, y = (float(c) for c in xy[v])
        r0 = int(ring_ptr[v])
        # the circumscribed disc clear: every heading and arc is (one query, not two per point)
        swept = disc or geometry.sweep_bound(x, y) > 0
        arcs = np.ones(n_ring, dtype=bool)  # arc i -> i + 1 free
        if not swept:
            got = memo.get((x, y)) if memo is not None else None
            if got is None:
                got = _ring_free(geometry, x, y, grid, step_h)
                if memo is not None:
                    memo[(x, y)] = got
            ring_ok[r0 : r0 + n_ring], arcs = got[0], got[1].copy()
        for i in range(n_ring):
            j = (i + 1) % n_ring
            if arcs[i]:
                ta += [-(1 + r0 + i), -(1 + r0 + j)]
                tb += [-(1 + r0 + j), -(1 + r0 + i)]
                tdh += [step_h, -step_h]
        for c in range(int(bounds[v]), int(bounds[v + 1])):
            for r, arc in _brackets(ch[c], r0, n_ring, step_h):
                if ring_ok[r] and (swept or turn_free(geometry, x, y, ch[c], arc, swept=False)):
                    ta += [c, -(1 + r)]
                    tb += [-(1 + r), c]
                    tdh += [arc, -arc]
        for c, d, arc in _same_interval(ch, int(bounds[v]), int(bounds[v + 1]), step_h):
            if swept or turn_free(geometry, x, y, ch[c], arc, swept=False):
                ta += [c, d]
                tb += [d, c]
                tdh += [arc, -arc]
    return ring_ptr, ring_v, ring_h, ring_ok, ta, tb, tdh


def chain_turns(turns: FloatArray, copy_id, ch: FloatArray, ta: list, tb: list, tdh: list) -> None:
    """Append a repair's certified turns (rows: point, heading from, signed change;
    :mod:`gfuzzy.timespace.unirepair`) to ``ta``, ``tb``, ``tdh`` both ways, between the
    copies ``copy_id(point, heading)`` (headings ``ch``), the change fitted to the copies'
    own headings."""
    for p, h, dh in turns.tolist():
        c, d = copy_id(int(p), h), copy_id(int(p), h + dh)
        dh += float(((ch[d] - ch[c] - dh) + math.pi) % (2 * math.pi) - math.pi)
        ta += [c, d]
        tb += [d, c]
        tdh += [dh, -dh]


def _ring_free(geometry, x: float, y: float, grid: FloatArray, step_h: float):
    """Which headings of a ring at (x, y) are free, and which arcs ``i -> i + 1`` are.

    Sphere tracing round the ring (the argument of
    :meth:`gfuzzy.collision.geometry.StaticGeometry.motion_clearance`): a heading with
    clearance c proves every heading within ``c / r`` free, so one query covers the ring
    points that far on, and the arc between two queried points is free when their
    clearances add up to more than its metric length (else it is traced).

    Returns
    -------
    ok, arcs : (n,) bool
    """
    n, r = len(grid), geometry.r

    def arc(i: int, c_i: float, j: int, c_j: float) -> bool:
        if c_i + c_j > (j - i) * step_h * r:
            return True
        return turn_free(geometry, x, y, grid[j - 1], step_h, swept=False)

    ok, arcs = np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
    anchor, c_anchor, c_first = 0, -1.0, -1.0  # the last queried point and its clearance
    i = 0
    while i < n:
        c = geometry.clearance1([x, y, grid[i]])
        ok[i] = c >= 0
        if i == 0:
            c_first = c
        elif ok[i] and ok[i - 1]:  # i - 1 is the anchor or a point it covers
            arcs[i - 1] = arc(anchor, c_anchor, i, c)
        anchor, c_anchor = i, c
        # the points proven free beyond i (none when it only touches: c = 0)
        m = max(0, min(n - 1 - i, math.floor(c / (step_h * r) - 1e-12))) if ok[i] else 0
        ok[i + 1 : i + m + 1] = True
        arcs[i : i + m] = True
        i += m + 1
    if n > 1 and ok[n - 1] and ok[0]:  # the arc closing the ring
        arcs[n - 1] = arc(anchor, c_anchor, n, c_first)
    return ok, arcs


def _same_interval(ch: FloatArray, lo: int, hi: int, step_h: float) -> list:
    """The copies ``lo .. hi - 1`` of one vertex (headings ``ch``, sorted) that follow one
    another counter-clockwise with no ring point between them: [(c, d, arc)], ``arc`` > 0
    the turn from c to d.

    The ring joins such copies only through a ring point outside the arc between them, up
    to a turning step away: in a corridor with a few centimetres to spare that heading may
    collide where the small turn itself is free, so these copies also join directly.
    """
    out = []
    for c in range(lo, hi if hi - lo > 1 else lo):
        d = c + 1 if c + 1 < hi else lo
        arc = float((ch[d] - ch[c]) % (2 * math.pi))
        to_ring = ((math.floor((ch[c] + math.pi) / step_h) + 1) * step_h - math.pi - ch[c]) % (2 * math.pi)
        if 0.0 < arc < to_ring:
            out.append((c, d, arc))
    return out
