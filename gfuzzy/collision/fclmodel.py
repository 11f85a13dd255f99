"""The FCL model of the static scene: the obstacles as FCL objects, for collision tests and,
measured exactly, for distances.

The world is planar: every 2-D shape becomes a tall prism (FCL convex or box), a sphere at
z = 0, or a mesh, so that a 3-D query answers the 2-D question. Collision tests use
:func:`static_objects`. Distances, which the planner uses as lower bounds (sphere tracing,
certified edges, turning sweeps), use :func:`distance_model`: only pairs whose FCL distance
is exact, as measured against shapely (``tools/fcl_accuracy.py``, docs/planner.md):

* FCL's GJK (libccd; python-fcl 0.7 offers no other solver: its ``gjk_solver_type`` reaches
  the C++ request as ``rel_err``) between a sphere and a convex prism overestimates, either
  argument order, by up to 1.5e-3 m (0.1 % of 30,000 random cases beyond 1e-4; the smaller
  of the two orders still 1.2e-4), and between an ``fcl.Box`` and a convex by up to 1.5e-3
  in both orders (a footprint 0.6 m from a box: 2 % of the poses within a centimetre).
* Between convex prisms, and from a convex or a sphere to a mesh, it was exact (to 1e-15 in
  15,000 random cases), between two ``fcl.Box`` to 5e-7 (21,000 cases, near-parallel ones
  among them), and from a sphere to a box or a sphere FCL has closed forms.

(Likely why: in a planar query GJK's directions have z = 0, where a sphere's and a box's
support points lie at z = 0 and a convex prism's at its first ring's z = -H; two prisms'
differences, and two boxes', stay in one plane, the mixed pairs' do not.) So for distances
a box is a convex prism (against a box robot's ``fcl.Box``, an ``fcl.Box``), a sphere (a
disc robot, the circumscribed disc) meets the polygons and boxes as one flat mesh of their
triangles at z = 0 and the discs as spheres (closed forms), and the discs' spheres meet a
box or footprint robot as a flat mesh of its body (:func:`flat_mesh`), never its prisms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import fcl
import numpy as np
import shapely

from ..scene.scene import Box, Disc, MapObstacle, Polygon, Scene
from ..typed import FloatArray
from .shapes import HEIGHT as _HEIGHT
from .shapes import convex_prism

__all__ = ["static_objects", "DistanceModel", "distance_model", "static_model", "flat_mesh", "manager_of"]


def _yaw_transform(x: float, y: float, yaw: float = 0.0) -> fcl.Transform:
    q = np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])
    return fcl.Transform(q, np.array([x, y, 0.0]))


def _prism(tri: FloatArray) -> fcl.Convex:
    """A solid triangular prism (FCL convex) over a counter-clockwise triangle."""
    h = _HEIGHT
    verts = np.vstack([np.c_[tri, np.full(3, -h)], np.c_[tri, np.full(3, h)]])
    faces = np.array([3, 0, 2, 1, 3, 3, 4, 5, 4, 0, 1, 4, 3, 4, 1, 2, 5, 4, 4, 2, 0, 3, 5])
    return fcl.Convex(verts, 5, faces)


def _triangulate(poly: Polygon) -> list[FloatArray]:
    shape = shapely.Polygon(poly.points, [h for h in poly.holes])
    tris = shapely.constrained_delaunay_triangles(shape)
    out = []
    for t in shapely.get_parts(tris):
        pts = np.asarray(t.exterior.coords)[:3]
        area2 = (pts[1, 0] - pts[0, 0]) * (pts[2, 1] - pts[0, 1]) - (pts[2, 0] - pts[0, 0]) * (
            pts[1, 1] - pts[0, 1]
        )
        if abs(area2) < 1e-14:
            out.extend(_sliver(pts))
            continue
        out.append(pts if area2 > 0 else pts[::-1])
    return out


#: Half the width (m) of the thin wall put where a polygon is a line (a flat triangle of its
#: triangulation): the checker's closed polygon blocks there, so the planner must too.
_SLIVER = 1e-6


def _sliver(pts: FloatArray) -> list[FloatArray]:
    """A flat triangle (its corners on a line, as where a polygon goes out along a line and
    back: the closed polygon holds that segment) as two counter-clockwise triangles of a
    rectangle ``_SLIVER`` about its longest side; none when it is a point."""
    pairs = [(0, 1), (1, 2), (0, 2)]
    i, j = max(pairs, key=lambda ij: float(np.hypot(*(pts[ij[1]] - pts[ij[0]]))))
    p, q = pts[i], pts[j]
    length = float(np.hypot(*(q - p)))
    if length < 1e-9:
        return []
    n = _SLIVER * np.array([p[1] - q[1], q[0] - p[0]]) / length  # to the left of p -> q
    a, b, c, d = p - n, q - n, q + n, p + n
    return [np.array([a, b, c]), np.array([a, c, d])]


def _walls(rects: FloatArray) -> fcl.BVHModel:
    """One FCL mesh of the side faces of the map's blocked rectangles, twice as tall as
    the robot (so its top and bottom are never reached).

    A single mesh keeps a query in FCL's C++ traversal (thousands of separate objects cost
    a Python callback each). A mesh is only a surface: a robot wholly inside one
    rectangle touches none of it, which :meth:`StaticGeometry._inside_map` catches.

    Parameters
    ----------
    rects : (k, 4) float
        ``[xmin, ymin, xmax, ymax]`` rows.
    """
    k = len(rects)
    x0, y0, x1, y1 = (rects[:, i] for i in range(4))
    corners = np.stack([np.stack([x0, y0], -1), np.stack([x1, y0], -1), np.stack([x1, y1], -1), np.stack([x0, y1], -1)], 1)
    h = 2 * _HEIGHT
    verts = np.concatenate([np.c_[corners.reshape(-1, 2), np.full(4 * k, -h)], np.c_[corners.reshape(-1, 2), np.full(4 * k, h)]])
    base = (np.arange(k) * 4)[:, None]
    lo, hi = base + np.arange(4), 4 * k + base + np.arange(4)
    lo2, hi2 = base + (np.arange(4) + 1) % 4, 4 * k + base + (np.arange(4) + 1) % 4
    tris = np.concatenate([np.stack([lo, lo2, hi2], -1), np.stack([lo, hi2, hi], -1)], 1).reshape(-1, 3)
    model = fcl.BVHModel()
    model.beginModel(len(tris), len(verts))
    model.addSubModel(verts, tris.astype(np.int32))
    model.endModel()
    return model


def static_objects(scene: Scene) -> list[fcl.CollisionObject]:
    """FCL collision objects for every static obstacle of ``scene`` (:func:`static_model`'s)."""
    return static_model(scene)[0]


def _convex_ring(poly: Polygon) -> FloatArray | None:
    """The polygon's ring, counter-clockwise, when it is strictly convex (no hole, no dent,
    no corner on a straight side): one FCL prism instead of its n - 2 triangles' (a 16-gon's
    distance costs a fifth: a footprint drive's rings and lanes among round obstacles ask
    tens of thousands); None otherwise (triangulated)."""
    if poly.holes or len(poly.points) < 3:
        return None
    shape = shapely.Polygon(np.asarray(poly.points, dtype=float))
    if not shape.is_valid or shape.area <= 0.0:
        return None
    hull = shape.convex_hull
    if len(hull.exterior.coords) - 1 != len(poly.points) or hull.area - shape.area > 1e-12 * max(1.0, hull.area):
        return None
    return np.asarray(shapely.geometry.polygon.orient(hull, 1.0).exterior.coords, dtype=float)[:-1]


def flat_mesh(rings: list[FloatArray]) -> fcl.BVHModel:
    """One FCL mesh of convex counter-clockwise rings (each (m, 2)) fanned into triangles at
    z = 0: a sphere at z = 0 meets it at the rings' planar distance, in closed form."""
    verts, tris = [], []
    for ring in rings:
        base = len(verts)
        verts.extend((float(x), float(y), 0.0) for x, y in ring)
        tris.extend((base, base + i, base + i + 1) for i in range(1, len(ring) - 1))
    model = fcl.BVHModel()
    model.beginModel(len(tris), len(verts))
    model.addSubModel(np.array(verts, dtype=float), np.array(tris, dtype=np.int32))
    model.endModel()
    return model


@dataclass(frozen=True)
class DistanceModel:
    """The static obstacles as FCL measures their distance exactly (see the module).

    Attributes
    ----------
    prisms : list of fcl.CollisionObject
        For a convex prism (a box or footprint robot's pieces, their swept hulls): the
        polygons as in :func:`static_objects`, boxes as convex prisms, maps' walls.
    flat : list of fcl.CollisionObject
        For a sphere (a disc robot, a circumscribed disc): the polygons' and boxes' convex
        parts as one flat mesh, the discs' spheres, maps' walls.
    spheres : list of fcl.CollisionObject
        The discs' spheres, for a box or footprint robot's flat mesh.
    boxes : list of fcl.CollisionObject
        The boxes as ``fcl.Box``, for a box robot's ``fcl.Box`` (the cost of main's).
    polygons : list of fcl.CollisionObject
        ``prisms`` but the boxes, for a box robot's prism.
    discs : (k, 3) float
        The disc obstacles, ``x, y, radius`` (a swept hull's distance, in closed form).
    """

    prisms: list
    flat: list
    spheres: list
    boxes: list
    polygons: list
    discs: FloatArray


def distance_model(scene: Scene) -> DistanceModel:
    """The :class:`DistanceModel` of ``scene``'s static obstacles (:func:`static_model`'s)."""
    return static_model(scene)[1]


def static_model(scene: Scene) -> tuple[list[fcl.CollisionObject], DistanceModel]:
    """The FCL collision objects of every static obstacle of ``scene`` (for collision tests)
    and its :class:`DistanceModel`, made in one pass: each polygon triangulated once, each
    map's walls meshed once, each geometry shared by the objects that hold it.

    For collision tests a disc is a sphere at z = 0, not a cylinder (against spheres and
    tall prisms its distance is the planar one, and FCL computes sphere distances in closed
    form: its GJK distance to a cylinder overestimates small gaps); a box an ``fcl.Box``; a
    polygon its convex prism, or its triangles' prisms; a map its walls.
    """
    objects, prisms, rings, flat, spheres, boxes, polygons, discs = [], [], [], [], [], [], [], []
    for ob in scene.obstacles:
        if isinstance(ob, Disc):
            discs.append((ob.center[0], ob.center[1], ob.radius))
            sphere = fcl.Sphere(ob.radius)
            for objs in (objects, spheres, flat):
                objs.append(fcl.CollisionObject(sphere, _yaw_transform(*ob.center)))
        elif isinstance(ob, Box):
            rings.append(np.asarray(ob.vertices(), dtype=float))
            prisms.append(fcl.CollisionObject(convex_prism(rings[-1], _HEIGHT), fcl.Transform()))
            geom = fcl.Box(ob.size[0], ob.size[1], 2 * _HEIGHT)
            for objs in (objects, boxes):
                objs.append(fcl.CollisionObject(geom, _yaw_transform(ob.center[0], ob.center[1], ob.angle)))
        elif isinstance(ob, MapObstacle):
            if len(ob.rects):
                walls = _walls(ob.rects)
                for objs in (objects, prisms, polygons, flat):
                    objs.append(fcl.CollisionObject(walls, fcl.Transform()))
        else:
            ring = _convex_ring(ob)
            parts = [ring] if ring is not None else _triangulate(ob)
            for part in parts:
                geom = convex_prism(part, _HEIGHT) if ring is not None else _prism(part)  # one geometry, three objects
                for objs in (objects, prisms, polygons):
                    objs.append(fcl.CollisionObject(geom, fcl.Transform()))
            rings.extend(parts)
    if rings:
        flat.append(fcl.CollisionObject(flat_mesh(rings), fcl.Transform()))
    model = DistanceModel(prisms, flat, spheres, boxes, polygons, np.array(discs, dtype=float).reshape(-1, 3))
    return objects, model


def manager_of(objects: list) -> fcl.DynamicAABBTreeCollisionManager:
    """FCL's broad phase over ``objects`` (none: an empty manager)."""
    manager = fcl.DynamicAABBTreeCollisionManager()
    if objects:
        manager.registerObjects(objects)
    manager.setup()
    return manager
