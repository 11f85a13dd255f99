"""The free space of a disc robot, computed exactly, and paths through it.

A disc robot of radius r that keeps a clearance c fits at a centre point exactly when the
point lies inside the bounds shrunk by r and outside every static obstacle grown by
r + c. That set (the *free space*) is a union of polygons with holes: shapely computes
it, and its connected parts (the *regions*) say which places the robot can travel
between. :mod:`gfuzzy.roadmap.roadmap` compares them with the roadmap's components and joins
roadmap components that share a region (:func:`repair`); :mod:`gfuzzy.planner.planner` joins a
start or a goal that sees no roadmap vertex, and explains a ``no_path`` by the regions
(:func:`gfuzzy.roadmap.narrowest.separation`).

Shapely grows shapes with arcs cut into chords, which lie *inside* the true arcs: the
obstacles are grown by an extra ``tolerance`` that covers the chords' sagitta, so the
free space computed here is a subset of the true one. Paths run through it at a margin
(``delta``) from its boundary, and every motion added to a roadmap is certified by
:meth:`gfuzzy.collision.geometry.StaticGeometry.motion_free` (FCL, exact): shapely proposes, the
certification decides.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np

from ..collision.geometry import StaticGeometry, metric_distance
from ..scene.scene import Box, Disc, Scene
from ..typed import FloatArray, IntArray

__all__ = [
    "FreeSpace",
    "Repair",
    "free_space",
    "inscribed_disc",
    "inscribed_free_space",
    "disc_centres",
    "blocked_points",
    "repair",
    "link_pose",
]

log = logging.getLogger(__name__)

#: Segments per quarter circle where shapely grows a shape (a chord's sagitta is then
#: 7.5e-5 of the radius; it is covered by :attr:`FreeSpace.tolerance`).
QUAD_SEGS = 64
#: Margins from the free space's boundary tried, largest first, for the paths a repair
#: adds (metres); a passage narrower than twice a margin is closed at that margin.
DELTAS = (0.02, 0.005, 0.001, 0.0002)
#: Blocked rectangles of a map per tile of the free space's computation (:func:`_free_of`).
TILE_RECTS = 100
#: At most this many repair paths per build (a guard against pathological scenes).
MAX_LINKS = 2000
#: Vertices with less clearance than this touch an obstacle: no certified motion leaves
#: them (see :meth:`gfuzzy.collision.geometry.StaticGeometry.motion_clearance`), so they are not joined.
TOUCHING = 1e-9


@dataclass
class FreeSpace:
    """The free space of a disc robot's centre, split into its connected regions.

    Attributes
    ----------
    regions : list of shapely.Polygon
        The connected parts, largest area first.
    tolerance : float
        Extra growth of every obstacle covering shapely's chords (metres).
    grown : float
        The obstacles' growth: robot radius + clearance (without ``tolerance``).
    """

    regions: list
    tolerance: float
    grown: float
    _eroded: dict = field(default_factory=dict, repr=False)
    _tri: dict = field(default_factory=dict, repr=False)

    def region_of(self, xy: FloatArray, slack: float = 1e-3) -> IntArray:
        """The region holding each point.

        Parameters
        ----------
        xy : (n, 2) float
        slack : float
            A point outside every region but within ``slack`` of one counts as in it
            (the regions are a slightly conservative subset of the free space).

        Returns
        -------
        (n,) int
            Region index, -1 for none.
        """
        import shapely

        xy = np.atleast_2d(np.asarray(xy, dtype=float))[:, :2]
        out = np.full(len(xy), -1, dtype=np.int64)
        for k, reg in enumerate(self.regions):
            todo = out < 0
            if not todo.any():
                break
            inside = shapely.contains_xy(reg, xy[todo, 0], xy[todo, 1])
            out[np.nonzero(todo)[0][inside]] = k
        left = np.nonzero(out < 0)[0]
        for i in left.tolist():
            p = shapely.Point(xy[i])
            d = [reg.distance(p) for reg in self.regions]
            if d and min(d) <= slack:
                out[i] = int(np.argmin(d))
        return out

    def eroded(self, region: int, delta: float) -> list:
        """The parts of ``regions[region]`` at least about ``delta`` (never less than
        ``delta / 2``) from its boundary."""
        key = (region, delta)
        got = self._eroded.get(key)
        if got is None:
            import shapely

            # arcs of 8 chords and a simplification by delta / 2 keep every point at least
            # delta / 2 inside the region, with few vertices to triangulate (a map's blocked
            # cells grown by the robot have thousands of rounded corners)
            shrunk = self.regions[region].buffer(-delta, quad_segs=8).simplify(0.5 * delta)
            got = [g for g in getattr(shrunk, "geoms", [shrunk]) if not g.is_empty and g.area > 0]
            for g in got:
                shapely.prepare(g)
            self._eroded[key] = got
        return got


def obstacle_shape(ob, grow: float = 0.0):
    """One static obstacle grown by ``grow`` as a shapely geometry (None: not supported).

    The one place an obstacle of any kind (disc, box, polygon, mesh footprint, map) becomes
    shapely: the free space here, the sensor's occlusion and ``populate``'s walls use it."""
    import shapely

    if isinstance(ob, Disc):
        return shapely.Point(ob.center).buffer(ob.radius + grow, quad_segs=QUAD_SEGS)
    if isinstance(ob, Box):
        base = shapely.Polygon(ob.vertices())
    elif hasattr(ob, "rects"):  # a map: rectangles whose union is exactly its blocked cells
        r = np.asarray(ob.rects, dtype=float).reshape(-1, 4)
        if not len(r):
            return shapely.Polygon()
        return _grown_cells(r, grow)
    elif hasattr(ob, "points"):
        base = shapely.Polygon(ob.points, [list(h) for h in getattr(ob, "holes", ())])
    elif hasattr(ob, "shapely"):  # an obstacle that knows its own exact shape
        base = ob.shapely()
    else:
        return None
    return base.buffer(grow, quad_segs=QUAD_SEGS) if grow > 0 else base


def free_space(scene: Scene, grown: float | None = None) -> FreeSpace | None:
    """The free space of ``scene``'s disc robot.

    Parameters
    ----------
    scene : Scene
    grown : float, optional
        Grow the obstacles by this instead of the robot's radius + clearance (the
        bounds still shrink by the radius).

    Returns
    -------
    FreeSpace or None
        None for a robot that is not a disc, or a scene with an obstacle kind whose exact
        shape is unknown here.
    """
    import shapely

    robot = scene.robot
    if robot.shape != "disc":
        return None
    grown = robot.radius + robot.clearance if grown is None else float(grown)
    xmin, ymin, xmax, ymax = scene.bounds
    extent = max(xmax - xmin, ymax - ymin)
    # a chord of a circle of radius R with QUAD_SEGS per quarter lies R (1 - cos(pi / (4 q)))
    # inside it: cover that for the largest radius grown (an obstacle disc's included)
    biggest = grown + max([ob.radius for ob in scene.obstacles if isinstance(ob, Disc)], default=0.0)
    tolerance = 2.0 * (biggest + 1e-3) * (1.0 - math.cos(math.pi / (4 * QUAD_SEGS))) + 1e-7 * (1 + extent)
    shapes, rects = [], []
    for ob in scene.obstacles:
        if hasattr(ob, "rects"):  # a map: grown tile by tile below
            rects.append(np.asarray(ob.rects, dtype=float).reshape(-1, 4))
            continue
        s = obstacle_shape(ob, grown + tolerance)
        if s is None:
            log.info("free space not computed: obstacle %r has no known exact shape", type(ob).__name__)
            return None
        shapes.append(s)
    r = robot.radius
    inner = shapely.box(xmin + r, ymin + r, xmax - r, ymax - r) if xmax - xmin > 2 * r and ymax - ymin > 2 * r else None
    if inner is None:
        return FreeSpace([], tolerance, grown)
    rect = np.concatenate(rects) if rects else np.zeros((0, 4))
    free = _free_of(inner, shapes, rect, grown + tolerance, 1e-9 * (1 + extent))
    parts = [g for g in getattr(free, "geoms", [free]) if isinstance(g, shapely.Polygon) and g.area > 1e-12]
    parts.sort(key=lambda g: -g.area)
    for g in parts:
        shapely.prepare(g)
    return FreeSpace(parts, tolerance, grown)


#: Metres the robot's inscribed disc is shrunk by before its free space proves anything
#: (pieces apart, no room at all): more than shapely's chord tolerance, so the computed free
#: space holds the true one.
SEPARATION_MARGIN = 2e-3


def inscribed_disc(robot) -> tuple[FloatArray, float]:
    """A disc inside the robot's body: its centre in the robot's frame and its radius (a
    box's inscribed disc; a footprint's largest, found by ``polylabel`` to 0.1 mm)."""
    if robot.shape != "footprint":
        return np.zeros(2), robot.inradius
    import shapely
    from shapely.ops import polylabel

    body = shapely.Polygon(robot.footprint)
    c = polylabel(body, 1e-4)
    return np.array([c.x, c.y]), float(body.exterior.distance(c))


def inscribed_free_space(scene: Scene, margin: float | None = None) -> tuple[FloatArray, FreeSpace] | None:
    """The free space of the robot's inscribed disc (:func:`inscribed_disc`, shrunk by
    ``margin``; default :data:`SEPARATION_MARGIN` or 1e-3 of the radius, the larger: past
    shapely's chords, 7.5e-5 of the radius grown) and the disc's centre in the robot's frame;
    None where it proves nothing (a disc smaller than the margin, obstacles without an exact
    shape, shapely's chords deeper than the margin).

    The disc lies inside the body, so wherever the robot is free its disc is free too, in
    this free space: it holds the true free space of the disc (the margin covers shapely's
    chords and FCL's missed penetrations of ~3e-7 m). None of it (no region) proves that the
    robot fits nowhere; two places in different regions, that no motion joins them.
    """
    from types import SimpleNamespace

    robot = scene.robot
    centre, radius = inscribed_disc(robot)
    if margin is None:
        margin = max(SEPARATION_MARGIN, 1e-3 * radius)
    r = radius - margin
    if r <= 0:
        return None
    disc = SimpleNamespace(shape="disc", radius=r, clearance=robot.clearance)
    fs = free_space(SimpleNamespace(robot=disc, bounds=scene.bounds, obstacles=scene.obstacles))
    if fs is None or fs.tolerance >= margin:
        return None
    return centre, fs


def disc_centres(centre: FloatArray, poses) -> FloatArray:
    """(n, 2): where a point ``centre`` of the robot's frame (its inscribed disc's, from
    :func:`inscribed_free_space`) lies at each pose ``[x, y, heading]``."""
    v = np.atleast_2d(np.asarray(poses, dtype=float))
    cos, sin = np.cos(v[:, 2]), np.sin(v[:, 2])
    return v[:, :2] + np.column_stack([cos * centre[0] - sin * centre[1], sin * centre[0] + cos * centre[1]])


def _free_of(inner, shapes: list, rects: FloatArray, grow: float, overlap: float):
    """``inner`` less ``shapes`` (grown already) and ``rects`` (a map's blocked cells) grown by ``grow``.

    A map's blocked cells have thousands of corners, and GEOS grows them all at once in
    time and memory that rise faster than their number (a 90 x 60 m map at 5 cm: 18 s of
    CPU and 800 MB): so the free space is cut into tiles of about :data:`TILE_RECTS`
    rectangles each, every tile keeps what is free of the cells within ``grow`` of it, and
    the tiles, overlapping by ``overlap`` so that neighbours always join, are united
    (the same set: a point of a tile is within ``grow`` of a cell only if that cell is
    within ``grow`` of the tile). ``tools/bench_map.py`` measures both ways.
    """
    import shapely

    if len(rects) <= TILE_RECTS:
        blocked = shapes + ([_grown_cells(rects, grow)] if len(rects) else [])
        return inner.difference(shapely.union_all(blocked)) if blocked else inner
    x0, y0, x1, y1 = inner.bounds
    side = max(math.sqrt((x1 - x0) * (y1 - y0) * TILE_RECTS / len(rects)), 8.0 * grow)
    xs = np.linspace(x0, x1, max(1, math.ceil((x1 - x0) / side)) + 1)
    ys = np.linspace(y0, y1, max(1, math.ceil((y1 - y0) / side)) + 1)
    others = shapely.union_all(shapes) if shapes else None
    pieces = []
    for i in range(len(xs) - 1):
        for j in range(len(ys) - 1):
            a, b = xs[i] - overlap, ys[j] - overlap
            c, d = xs[i + 1] + overlap, ys[j + 1] + overlap
            near = (rects[:, 2] >= a - grow) & (rects[:, 0] <= c + grow) & (rects[:, 3] >= b - grow) & (rects[:, 1] <= d + grow)
            core = shapely.box(a, b, c, d).intersection(inner)
            blocked = [_grown_cells(rects[near], grow)] if near.any() else []
            if others is not None:
                blocked.append(others.intersection(shapely.box(a, b, c, d)))
            pieces.append(core.difference(shapely.union_all(blocked)) if blocked else core)
    return shapely.union_all(pieces)


def _grown_cells(rects: FloatArray, grow: float):
    """The union of ``rects`` ``[xmin, ymin, xmax, ymax]`` grown by ``grow`` (not grown at 0)."""
    import shapely

    base = shapely.union_all(shapely.box(rects[:, 0], rects[:, 1], rects[:, 2], rects[:, 3]))
    return base.buffer(grow, quad_segs=QUAD_SEGS) if grow > 0 else base


def blocked_points(scene: Scene):
    """A vectorised test: which xy points lie inside a static obstacle or outside bounds
    (the passage sampler's bridge test, :mod:`gfuzzy.roadmap.roadmap`)."""
    import shapely

    from ..scene.scene import MapObstacle

    shapes = []
    grids = [ob_ for ob_ in scene.obstacles if isinstance(ob_, MapObstacle)]
    for ob_ in scene.obstacles:
        if isinstance(ob_, MapObstacle):
            continue
        if isinstance(ob_, Disc):
            shapes.append(shapely.Point(ob_.center).buffer(ob_.radius, 32))
        elif isinstance(ob_, Box):
            shapes.append(shapely.Polygon(ob_.vertices()))
        else:
            shapes.append(shapely.Polygon(ob_.points, list(ob_.holes)))
    union = shapely.union_all(shapes) if shapes else shapely.Polygon()
    shapely.prepare(union)
    xmin, ymin, xmax, ymax = scene.bounds

    def blocked(xy: FloatArray) -> np.ndarray:
        x, y = xy[:, 0], xy[:, 1]
        out = (x <= xmin) | (x >= xmax) | (y <= ymin) | (y >= ymax)
        if shapes:
            out |= shapely.contains_xy(union, x, y)
        for grid in grids:
            rows, cols, inside = grid.cells_of(xy)
            out |= inside & grid.blocked[rows, cols]
        return out

    return blocked


# --------------------------------------------------------------------------- paths


class _Corridors:
    """A triangulation of one eroded region and the graph through its inner edges'
    midpoints: a path from triangle to triangle through those midpoints stays inside."""

    def __init__(self, poly):
        import shapely
        from scipy.sparse import coo_matrix

        self.poly = poly
        tris = np.asarray(shapely.get_parts(shapely.constrained_delaunay_triangles(poly)))
        tris = tris[shapely.area(tris) > 0]
        self.tris = tris
        self.tree = shapely.STRtree(tris)
        corners = shapely.get_coordinates(shapely.get_exterior_ring(tris)).reshape(-1, 4, 2)[:, :3]
        p = corners.reshape(-1, 2)  # (3T, 2): the corners, each triangle's in a row of three
        q = np.roll(corners, -1, axis=1).reshape(-1, 2)
        swap = (p[:, 0] > q[:, 0]) | ((p[:, 0] == q[:, 0]) & (p[:, 1] > q[:, 1]))
        lo, hi = np.where(swap[:, None], q, p), np.where(swap[:, None], p, q)
        _, first, inverse = np.unique(np.hstack([lo, hi]), axis=0, return_index=True, return_inverse=True)
        self.mids = 0.5 * (lo[first] + hi[first])
        te = inverse.reshape(-1, 3).astype(np.int64)
        self.tri_edges = te
        a = np.concatenate([te[:, 0], te[:, 1], te[:, 2]])
        b = np.concatenate([te[:, 1], te[:, 2], te[:, 0]])
        w = np.linalg.norm(self.mids[a] - self.mids[b], axis=1) + 1e-12
        n = len(self.mids)
        self.graph = coo_matrix((np.r_[w, w], (np.r_[a, b], np.r_[b, a])), shape=(n, n)).tocsr()

    def triangle(self, p: FloatArray) -> int:
        import shapely

        hits = self.tree.query(shapely.Point(p), predicate="intersects")
        return int(hits[0]) if len(hits) else -1

    def path(self, a: FloatArray, b: FloatArray) -> FloatArray | None:
        """A polyline a -> b inside the region (None when a or b is outside it)."""
        from scipy.sparse.csgraph import dijkstra

        ta, tb = self.triangle(a), self.triangle(b)
        if ta < 0 or tb < 0:
            return None
        if ta == tb:
            return np.array([a, b], dtype=float)
        ea, eb = self.tri_edges[ta], self.tri_edges[tb]
        dist, pred = dijkstra(self.graph, indices=ea, return_predecessors=True, min_only=False)
        start_cost = np.linalg.norm(self.mids[ea] - a, axis=1)
        end_cost = np.linalg.norm(self.mids[eb] - b, axis=1)
        total = start_cost[:, None] + dist[:, eb] + end_cost[None, :]
        i, j = np.unravel_index(int(np.argmin(total)), total.shape)
        if not math.isfinite(total[i, j]):
            return None
        chain = [int(eb[j])]
        while chain[-1] != ea[i]:
            chain.append(int(pred[i, chain[-1]]))
        return np.vstack([a, self.mids[chain[::-1]], b])

    def shortcut(self, pts: FloatArray) -> FloatArray:
        """Greedy visibility shortcut of a polyline inside the region: from each kept point
        the farthest point seen, found by galloping then bisection (O(log n) tests a step;
        only segments tested inside are kept)."""
        import shapely

        def sees(i: int, j: int) -> bool:
            return j == i + 1 or bool(self.poly.covers(shapely.LineString([pts[i], pts[j]])))

        out = [0]
        i, n = 0, len(pts)
        while i < n - 1:
            if sees(i, n - 1):
                j = n - 1
            else:
                lo, step = i + 1, 1  # lo is seen
                while lo + step < n - 1 and sees(i, lo + step):
                    lo, step = lo + step, 2 * step
                hi = min(lo + step, n - 1)  # not seen
                while hi - lo > 1:
                    mid = (lo + hi) // 2
                    if sees(i, mid):
                        lo = mid
                    else:
                        hi = mid
                j = lo
            out.append(j)
            i = j
        return pts[out]


def _corridors(fs: FreeSpace, region: int, delta: float) -> list:
    key = (region, delta)
    got = fs._tri.get(key)
    if got is None:
        got = fs._tri[key] = [_Corridors(p) for p in fs.eroded(region, delta)]
    return got


def _certified_chain(geometry: StaticGeometry, pts: FloatArray, fine: FloatArray) -> list | None:
    """Certify a shortcut polyline; a failed shortcut falls back to the finer polyline's
    points between its ends. Returns the points of a certified chain, or None."""
    idx = {tuple(p): k for k, p in enumerate(fine.tolist())}
    out = [fine[0]]
    for p, q in zip(pts[:-1], pts[1:], strict=True):
        if geometry.motion_free(p, q):
            out.append(q)
            continue
        i, j = idx[tuple(p.tolist())], idx[tuple(q.tolist())]
        for k in range(i, j):
            if not geometry.motion_free(fine[k], fine[k + 1]):
                return None
            out.append(fine[k + 1])
    return out


def _region_path(geometry, fs: FreeSpace, region: int, a: FloatArray, b: FloatArray) -> list | None:
    """A certified polyline a -> b through ``region``, at the largest margin that works."""
    import shapely

    for delta in DELTAS:
        for cor in _corridors(fs, region, delta):
            ins = shapely.contains_xy(cor.poly, [a[0], b[0]], [a[1], b[1]])
            pa, pb = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
            ends = []
            for p, ok in ((pa, ins[0]), (pb, ins[1])):
                if not ok:  # step onto the eroded part first (the certification decides)
                    q = np.asarray(shapely.shortest_line(shapely.Point(p), cor.poly).coords[1])
                    if np.linalg.norm(q - p) > 2 * delta + fs.tolerance:
                        break
                    ends.append((p, q))
                else:
                    ends.append((p, p))
            if len(ends) < 2:
                continue
            fine = cor.path(ends[0][1], ends[1][1])
            if fine is None:
                continue
            fine = _dedupe(np.vstack([pa[None, :2], fine, pb[None, :2]]))
            chain = _certified_chain(geometry, cor.shortcut(fine), fine)
            if chain is not None:
                return chain
    return None


def _dedupe(pts: FloatArray) -> FloatArray:
    keep = np.r_[True, np.any(np.abs(np.diff(pts, axis=0)) > 0, axis=1)]
    return pts[keep]


# --------------------------------------------------------------------------- repair


@dataclass(frozen=True)
class Repair:
    """What :func:`repair` added to a roadmap.

    Attributes
    ----------
    vertices : (V', 2) float
        All vertices: the roadmap's, then the added ones.
    edges : (E', 2) int
        All edges, smaller index first: the roadmap's, then the added ones.
    added_vertices, added_edges : int
    regions : int
        Free-space regions.
    joined : int
        Roadmap components joined to another through the free space.
    unjoined : int
        Roadmap components left apart although a region holds them with others (a path
        the certification refused; 0 in every scene tried).
    touching : int
        Vertices left out because they touch an obstacle (clearance 0: no motion from
        them can be certified; PRM keeps them, edgeless).
    """

    vertices: FloatArray
    edges: IntArray
    added_vertices: int
    added_edges: int
    regions: int
    joined: int
    unjoined: int
    touching: int = 0

    def to_dict(self) -> dict:
        return {
            "added_vertices": self.added_vertices,
            "added_edges": self.added_edges,
            "free_space_regions": self.regions,
            "components_joined": self.joined,
            "components_unjoined": self.unjoined,
            "touching_vertices": self.touching,
        }


class _Union:
    def __init__(self, n: int):
        self.parent = list(range(n))

    def add(self) -> int:
        self.parent.append(len(self.parent))
        return len(self.parent) - 1

    def find(self, i: int) -> int:
        p = self.parent
        while p[i] != i:
            p[i] = p[p[i]]
            i = p[i]
        return i

    def join(self, a: int, b: int) -> None:
        ra, rb = self.find(a), self.find(b)
        if ra != rb:
            self.parent[max(ra, rb)] = min(ra, rb)


def _wire(geometry: StaticGeometry, verts: FloatArray, n0: int, k: int, have: set) -> list:
    """Certified edges from each added vertex (index >= n0) to its k nearest vertices, as
    PRM connects its own: a repair path's corners then serve routes in every direction, not
    only along the path."""
    from scipy.spatial import cKDTree

    tree = cKDTree(verts)
    out = []
    _, near = tree.query(verts[n0:], k=min(k + 1, len(verts)))
    for i, row in enumerate(np.atleast_2d(near).tolist(), start=n0):
        for j in row:
            e = (min(i, j), max(i, j))
            if j == i or j >= len(verts) or e in have:
                continue
            have.add(e)
            if geometry.motion_free(verts[i], verts[j]):
                out.append(e)
    return out


def _join(geometry, fs: FreeSpace, region: int, verts: list, main: list, other: list):
    """(chain, other's vertex, main's vertex) joining two roadmap components through
    ``region``: from the 3 vertices of ``other`` nearest to ``main``; None if none certifies."""
    from scipy.spatial import cKDTree  # only when there is something to join

    dist, near = cKDTree(np.asarray([verts[i] for i in main])).query(np.asarray([verts[i] for i in other]))
    for t in np.argsort(dist, kind="stable")[:3].tolist():
        ia, ib = other[t], main[int(near[t])]
        chain = _region_path(geometry, fs, region, np.asarray(verts[ia]), np.asarray(verts[ib]))
        if chain is not None:
            return chain, ia, ib
    return None


def repair(
    geometry: StaticGeometry, fs: FreeSpace, vertices: FloatArray, edges: IntArray, neighbors: int = 10
) -> Repair:
    """Join the roadmap components that share a free-space region.

    For every region holding vertices of several roadmap components, the component with
    the most vertices there is joined to each other one by a path through the region (a
    triangulation of the region eroded by a margin, Dijkstra through its inner edges'
    midpoints, a greedy shortcut), its corners added as vertices and every motion
    certified; each added vertex is then connected to its nearest vertices too. A region
    without any vertex gets one (a point inside it), so that a query there has a vertex to
    reach. Deterministic: no randomness.

    Parameters
    ----------
    geometry : StaticGeometry
        Of the disc robot's scene.
    fs : FreeSpace
    vertices : (V, 2) float
    edges : (E, 2) int
    neighbors : int
        Each added vertex is also joined to its ``neighbors`` nearest vertices where the
        motion is certified (as PRM's k nearest; 0: only along the repair paths).

    Returns
    -------
    Repair
    """
    verts = [tuple(v) for v in np.asarray(vertices, dtype=float).tolist()]
    new_edges: list = []
    uf = _Union(len(verts))
    for a, b in np.asarray(edges, dtype=np.int64).tolist():
        uf.join(a, b)
    region = fs.region_of(np.asarray(vertices, dtype=float).reshape(-1, 2)).tolist()
    joined = unjoined = stuck = 0

    def add_chain(chain, ia: int, ib: int) -> None:
        ids = [ia]
        for p in chain[1:-1]:
            verts.append((float(p[0]), float(p[1])))
            region.append(-2)  # on a repair path: never an end of another one
            ids.append(uf.add())
        ids.append(ib)
        for u, w in zip(ids[:-1], ids[1:], strict=True):
            new_edges.append((min(u, w), max(u, w)))
            uf.join(u, w)

    for k in range(len(fs.regions)):
        members = [i for i, r in enumerate(region) if r == k]
        if not members:
            c = np.asarray(fs.regions[k].representative_point().coords[0])
            if geometry.is_valid(c):
                verts.append((float(c[0]), float(c[1])))
                region.append(k)
                uf.add()
            continue
        if len({uf.find(i) for i in members}) > 1:
            # a vertex touching an obstacle (clearance 0, e.g. a bridge sample at contact)
            # starts no certifiable motion: it is left out, not counted as a missed passage
            touching = [i for i in members if geometry.clearance1(verts[i]) < TOUCHING]
            members = [i for i in members if i not in set(touching)]
            stuck += len(touching)
        for _ in range(MAX_LINKS):
            groups: dict = {}
            for i in members:
                groups.setdefault(uf.find(i), []).append(i)
            if len(groups) < 2:
                break
            order = sorted(groups, key=lambda g: (-len(groups[g]), g))
            other = order[1]
            found = _join(geometry, fs, k, verts, groups[order[0]], groups[other])
            done = found is not None
            if done:
                add_chain(*found)
                joined += 1
            if not done:  # give up on this component: keep it out of later rounds
                unjoined += 1
                log.warning("free-space repair: could not certify a path into roadmap component %d", other)
                members = [i for i in members if uf.find(i) != other]
    n0 = len(vertices)
    if len(verts) > n0 and neighbors > 0:
        new_edges += _wire(geometry, np.asarray(verts, dtype=float), n0, neighbors, set(new_edges))
    old = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    all_edges = np.vstack([old, np.asarray(sorted(set(new_edges)), dtype=np.int64).reshape(-1, 2)])
    return Repair(
        np.asarray(verts, dtype=float).reshape(-1, 2),
        all_edges,
        len(verts) - n0,
        len(all_edges) - len(edges),
        len(fs.regions),
        joined,
        unjoined,
        stuck,
    )


def link_pose(geometry: StaticGeometry, fs: FreeSpace, pose: FloatArray, vertices: FloatArray) -> list | None:
    """A certified polyline from ``pose`` to the nearest vertex of its region.

    Returns
    -------
    list of (2,) float or None
        The polyline's points, the pose first and the vertex last; None when the pose's
        region holds no vertex or no path was certified.
    """
    pose = np.asarray(pose, dtype=float)[:2]
    reg = int(fs.region_of(pose[None, :])[0])
    if reg < 0 or len(vertices) == 0:
        return None
    vr = fs.region_of(vertices)
    cand = np.nonzero(vr == reg)[0]
    if not cand.size:
        return None
    d = metric_distance(vertices[cand], pose[None, :], 0.0)
    for i in cand[np.argsort(d, kind="stable")[:3]].tolist():
        chain = _region_path(geometry, fs, reg, pose, np.asarray(vertices[i], dtype=float))
        if chain is not None:
            return chain
    return None
