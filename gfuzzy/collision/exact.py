"""Exact distances at contact, where FCL's are not to be trusted: a robot touching a static
obstacle by a rounding is measured with shapely (and discs in closed form), so that the
planner's "touching" is what ``gfuzzy check`` tolerates and never more.

FCL's collision test misses penetrations of up to ~3e-7 m and its distances overestimate
small gaps; :class:`gfuzzy.collision.geometry.StaticGeometry` asks these measures whenever
FCL puts the robot within ``_NEAR_CONTACT`` of an obstacle.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from ..scene.scene import Box, Disc, MapObstacle, Polygon, Robot, Scene

#: A robot this far into an obstacle or less (m) touches it: half the overlap ``gfuzzy
#: check`` tolerates as rounding (its ``tol``, 1e-9; the half leaves room for the two
#: measurements' own roundings). For a box or a footprint the overlap with the obstacles
#: (polygons) is also held to TOUCH_TOL square metres in all: the check measures such an
#: overlap by its area.
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
        self.robot: Robot = scene.robot
        from .shapes import shape_of

        shape = shape_of(scene.robot)
        self.pieces = getattr(shape, "pieces", None)
        if self.pieces is None:  # a box: one piece, its corners about the reference point
            hl, hw = 0.5 * scene.robot.size[0], 0.5 * scene.robot.size[1]
            self.pieces = [np.array([[hl, hw], [-hl, hw], [-hl, -hw], [hl, -hw]])]

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
        obstacles (negative: into one).

        Into a polygon, the overlap counts by its thickness (twice its area over its
        perimeter: the depth of a sliver along a face, less than a corner's) or, when that
        is more, by the overlaps' total area in square metres: what ``gfuzzy check``
        measures. Into a disc, by how far its centre is within its radius of the body.
        """
        body = self.swept(a, b)
        out = math.inf
        discs = self.obstacles.discs
        if len(discs):
            d = shapely.distance(body, shapely.points(discs[:, :2])) - discs[:, 2]
            out = float(np.min(d))
        area = 0.0
        for poly in self.obstacles.near(body, 1e-6):
            d = float(poly.distance(body))
            if d > 0.0:
                out = min(out, d)
                continue
            part = poly.intersection(body)
            a2 = float(part.area)
            area += a2
            if a2 > 0.0:
                out = min(out, -2.0 * a2 / max(float(part.length), 1e-300))
            else:
                out = min(out, 0.0)
        return min(out, -area) if area > 0.0 else out
