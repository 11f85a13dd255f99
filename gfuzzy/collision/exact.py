"""Exact distances at contact, where FCL's are not to be trusted: a robot touching a static
obstacle by a rounding is measured with shapely (and discs in closed form), so that the
planner's "touching" is what ``gfuzzy check`` tolerates and never more.

FCL's collision test misses penetrations of up to ~3e-7 m and at contact its distances
are roundings (elsewhere they are exact: :mod:`gfuzzy.collision.fclmodel`);
:class:`gfuzzy.collision.geometry.StaticGeometry` asks these measures when FCL's distance
puts the robot within ``_NEAR_CONTACT + _DIST_MARGIN`` of an obstacle and FCL's collision
test of the body's core (deep collisions) finds it in none.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from ..scene.scene import Box, Disc, MapObstacle, Polygon, Scene

#: A robot this far into an obstacle or less (m) touches it: half the overlap ``gfuzzy
#: check`` tolerates as rounding (its ``tol``, 1e-9; the half leaves room for the two
#: measurements' own roundings). A box's or a footprint's overlap with polygons is
#: measured by its depth (:func:`overlap_depth`), as the check measures it.
TOUCH_TOL = 0.5e-9


def exact_measure(scene: Scene):
    """The exact measure for ``scene``'s robot (:class:`ExactDisc` or :class:`ExactBody`),
    or None when none applies (a robot that keeps a clearance from obstacles: touching is
    not allowed, so FCL's distances, less a margin, decide)."""
    if scene.robot.clearance != 0:
        return None
    if not all(isinstance(ob, (Disc, Box, Polygon, MapObstacle)) for ob in scene.obstacles):
        return None
    return ExactDisc(scene) if scene.robot.shape == "disc" else ExactBody(scene)


class _Obstacles:
    """The static obstacles as shapely polygons in a spatial index and discs as rows."""

    def __init__(self, scene: Scene):
        self.discs = np.array([[*ob.center, ob.radius] for ob in scene.obstacles if isinstance(ob, Disc)]).reshape(-1, 3)
        polys = [shapely.Polygon(ob.vertices()) for ob in scene.obstacles if isinstance(ob, Box)]
        polys += [shapely.Polygon(ob.points, list(ob.holes)) for ob in scene.obstacles if isinstance(ob, Polygon)]
        for ob in scene.obstacles:
            if isinstance(ob, MapObstacle) and len(ob.rects):
                polys += list(shapely.box(*np.asarray(ob.rects, dtype=float).T))
        self.polys = shapely.STRtree(polys) if polys else None
        self._geoms = polys

    def near(self, geom, distance: float) -> list:
        """The polygons within ``distance`` of ``geom``."""
        if self.polys is None:
            return []
        return [self._geoms[i] for i in self.polys.query(geom, predicate="dwithin", distance=distance).tolist()]


class _Measure:
    """The obstacles, indexed when first needed (most geometries never meet contact, and a
    large map's cells take a while to index)."""

    def __init__(self, scene: Scene):
        self._scene = scene
        self._obstacles: _Obstacles | None = None

    @property
    def obstacles(self) -> _Obstacles:
        if self._obstacles is None:
            self._obstacles = _Obstacles(self._scene)
        return self._obstacles


class ExactDisc(_Measure):
    """Exact distances of a disc robot's straight motions to the static obstacles (discs in
    closed form, boxes, polygons and maps' blocked rectangles with shapely), for poses at
    contact (see :meth:`gfuzzy.collision.geometry.StaticGeometry.motion_free`)."""

    def __init__(self, scene: Scene):
        super().__init__(scene)
        self.r = float(scene.robot.radius)

    def gap(self, a, b) -> float:
        """The least distance of the disc moving straight from ``a`` to ``b`` ((2,) or more:
        the position first) to the obstacles, less its radius (negative: into one)."""
        p, q = np.asarray(a[:2], dtype=float), np.asarray(b[:2], dtype=float)
        out = math.inf
        discs = self.obstacles.discs
        if len(discs):
            d = q - p
            c = discs[:, :2]
            t = np.clip(((c - p) @ d) / max(float(d @ d), 1e-300), 0.0, 1.0)
            out = float(np.min(np.hypot(*(p + t[:, None] * d - c).T) - discs[:, 2]))
        seg = shapely.LineString([p, q]) if np.any(p != q) else shapely.Point(p)
        # not a buffer's box: the buffer's polygon lies inside the round ends and missed
        # obstacles the disc reaches
        for poly in self.obstacles.near(seg, self.r + 1e-6):
            out = min(out, float(poly.distance(seg)))
        return out - self.r


class ExactBody(_Measure):
    """Exact overlaps of a box or footprint robot's translations (and poses) with the static
    obstacles, measured with shapely as ``gfuzzy check`` measures them: the body swept
    along a translation is the union of its convex pieces' hulls at the two ends."""

    def __init__(self, scene: Scene):
        super().__init__(scene)
        from .shapes import body_pieces

        self.pieces = body_pieces(scene.robot)  # a box: one piece, its corners about the reference point

    def swept(self, a, b):
        """The region the body covers moving straight from pose ``a`` to pose ``b`` (the
        heading of ``a`` held: a translation, or ``a`` alone when ``b`` is ``a``)."""
        c, s = math.cos(float(a[2])), math.sin(float(a[2]))
        rot = np.array([[c, -s], [s, c]])
        p, q = np.asarray(a[:2], dtype=float), np.asarray(b[:2], dtype=float)
        hulls = []
        for piece in self.pieces:
            w = piece @ rot.T
            hulls.append(shapely.convex_hull(shapely.MultiPoint(np.concatenate([w + p, w + q]))))
        return hulls[0] if len(hulls) == 1 else shapely.union_all(hulls)

    def gap(self, a, b) -> float:
        """The least distance of the body translating from pose ``a`` to ``b`` to the
        obstacles (negative: into one, by the overlap's depth: :func:`overlap_depth`).

        Into a disc, by how far its centre is within its radius of the body.
        """
        body = self.swept(a, b)
        out = math.inf
        discs = self.obstacles.discs
        if len(discs):
            d = shapely.distance(body, shapely.points(discs[:, :2])) - discs[:, 2]
            out = float(np.min(d))
        touching = []
        for poly in self.obstacles.near(body, 1e-6):
            d = float(poly.distance(body))
            if d > 0.0:
                out = min(out, d)
            else:
                touching.append(poly)
        if touching:
            # measured against their union: a body at the seam of two map cells is as deep
            # in the blocked region as the check measures it (every polygon that meets the
            # body is here, so the overlap is the whole of it)
            out = min(out, -overlap_depth(body, shapely.union_all(touching)))
        return out


def overlap_depth(body, obstacle, within: float = TOUCH_TOL) -> float:
    """How deep ``body`` and ``obstacle`` (shapely polygons) overlap (m; 0 when they only
    touch).

    The largest distance of a point of the overlap's outline from the outline of the shape
    it lies inside (the body's corners, a spike's tip, its edge across a thin wall, in the
    obstacle, from the obstacle's outline; the obstacle's inside the body, from the body's),
    or, when more, a piece's thickness (twice its area over its perimeter: an obstacle held
    inside the body). A rounding of touching shapes is a sliver about its size deep however
    long; a corner a micrometre in is a micrometre deep. Each edge of the overlap's outline
    is bounded by the larger of its ends' distances to one segment of the outline measured
    (a point's distance to a segment is convex along an edge), and halved while that bound
    is more than ``within`` and no point is found deeper: the deepest point found (the
    vertices' exact), more than ``within`` only where one is. ``gfuzzy check`` measures an overlap so, with its own code.
    """
    inter = shapely.intersection(body, obstacle)
    pieces = [g for g in shapely.get_parts(inter) if g.area > 0.0]
    if not pieces:
        return 0.0
    depth = max(2.0 * g.area / max(g.length, 1e-300) for g in pieces)
    outlines = [(seg[:, 0], seg[:, 1]) for seg in (_segments(body), _segments(obstacle))]
    edges = np.concatenate([_segments(g) for g in pieces])
    p, q = edges[:, 0], edges[:, 1]
    for level in range(_HALVINGS + 1):
        far = np.zeros(len(p))
        bound = np.zeros(len(p))
        for a, b in outlines:
            dp, dq = _to_segments(p, a, b), _to_segments(q, a, b)
            far = np.maximum(far, np.maximum(dp.min(1), dq.min(1)))
            bound = np.maximum(bound, np.maximum(dp, dq).min(1))
        depth = max(depth, float(far.max()))
        if level == _HALVINGS:
            return max(depth, float(bound.max()))
        done = bound <= within
        if depth > within or done.all():
            return depth
        p, q = p[~done], q[~done]
        m = 0.5 * (p + q)
        p, q = np.concatenate([p, m]), np.concatenate([m, q])
    return depth


#: Halvings of an overlap's edge not yet bounded (then its bound counts).
_HALVINGS = 40


def _segments(geom) -> np.ndarray:
    """The segments of a polygon's (or several polygons') rings, (n, 2, 2)."""
    out = []
    for ring in shapely.get_rings(shapely.get_parts(geom)):
        xy = shapely.get_coordinates(ring)
        out.append(np.stack([xy[:-1], xy[1:]], axis=1))
    return np.concatenate(out) if out else np.zeros((0, 2, 2))


def _to_segments(points, a, b) -> np.ndarray:
    """Distances (k, n) of points (k, 2) to segments a-b ((n, 2) each)."""
    d = b - a
    rel = points[:, None, :] - a[None]
    t = np.clip(np.einsum("knj,nj->kn", rel, d) / np.maximum(np.einsum("nj,nj->n", d, d), 1e-300), 0.0, 1.0)
    return np.hypot(*np.moveaxis(rel - t[..., None] * d[None], -1, 0))
