"""Collision geometry: FCL objects for the static scene and the robot, batched validity
and clearance, certified straight motions, and vectorised robot-vs-mover distances.

The world is planar (:mod:`gfuzzy.collision.fclmodel`: the FCL objects, for collision
tests and, measured exactly, for distances).

A *certified* motion is checked with a Lipschitz argument instead of sampling: along a
straight motion in the contract's metric (euclidean xy + |heading change| * circumradius),
no point of the robot moves farther than the metric length, so the clearance changes at
most that fast; an interval whose end clearances add up to at least its length is free.
"""

from __future__ import annotations

import math
import sys

import fcl
import numpy as np
import shapely

from ..poses import metric_distance, wrap_angle
from ..scene.scene import Box, Disc, MapObstacle, Polygon, Robot, Scene
from ..typed import FloatArray
from .exact import TOUCH_TOL, ExactBody, exact_measure
from .fclmodel import flat_mesh, manager_of, static_model
from .shapes import HEIGHT as _HEIGHT
from .shapes import QUAD_EXACT, body_pieces, convex_prism, point_convex_distance, shape_of

__all__ = [
    "StaticGeometry",
    "metric_distance",
    "wrap_angle",
    "mover_distance",
    "QUAD_EXACT",
]

_EPS_CERT_CLEARANCE = 1e-9  # clearance below which a motion is not certified (grazing)
_NEAR_CONTACT = 1e-4  # distances below this are decided by a collision test (0 or -1)
_DIST_MARGIN = 1e-4  # subtracted from FCL distances (see obstacle_clearance)
#: How far inside a box or footprint robot's outline its core lies (m): the core in an
#: obstacle is a collision FCL's test does not miss, the body then far into it.
_CORE_MARGIN = 1e-5
#: A map's distance-transform bound above this (m) certifies a motion's step without FCL.
_QUICK_CLEARANCE = 0.02
#: A box or footprint's swept body (a translation) this far from the obstacles or more, by
#: exact distance (FCL's, gfuzzy.collision.fclmodel), certifies the translation in one query
#: (ten times ``_DIST_MARGIN``).
_SWEPT_MARGIN = 1e-3
#: Steps of a box or footprint's translation traced before its swept body is asked (most
#: motions are certified in fewer: the swept body costs about as much as 8 steps).
_SWEPT_AFTER = 8


def _touching(d: float) -> float:
    """A distance to the bounds, with a rounding out (up to ``TOUCH_TOL``) taken as 0."""
    return 0.0 if -TOUCH_TOL <= d < 0 else d


def _inner_point(robot: Robot) -> tuple[float, float]:
    """A point inside the robot's body, in its frame: its reference point, or for a
    footprint that may not hold it, an interior point of the polygon."""
    footprint = getattr(robot, "footprint", None)
    if footprint is None or len(footprint) == 0:
        return (0.0, 0.0)
    poly = shapely.Polygon(np.asarray(footprint, dtype=float))
    if poly.contains(shapely.Point(0.0, 0.0)):
        return (0.0, 0.0)
    p = poly.representative_point()
    return (float(p.x), float(p.y))


def robot_geometry(robot: Robot):
    """The FCL geometry of the robot (about its reference point): its first piece (the
    only one of a disc, a box or a convex footprint; see :func:`robot_geometries`)."""
    return robot_geometries(robot)[0]


def robot_geometries(robot: Robot) -> list:
    """The FCL geometries of the robot about its reference point, one per convex piece
    (:meth:`gfuzzy.collision.shapes.Shape.fcl_geometries`)."""
    return shape_of(robot).fcl_geometries()


def _hull(points: FloatArray) -> FloatArray:
    """The convex hull of ``points`` (n, 2), counter-clockwise, no collinear vertex
    (Andrew's monotone chain)."""
    pts = sorted(map(tuple, points))

    def half(seq):
        out: list = []
        for p in seq:
            while len(out) >= 2 and (out[-1][0] - out[-2][0]) * (p[1] - out[-2][1]) - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0]) <= 0:
                out.pop()
            out.append(p)
        return out[:-1]

    return np.array(half(pts) + half(pts[::-1]), dtype=float)


def _core_geometries(robot: Robot) -> list:
    """FCL geometries of a box or footprint robot's body less ``_CORE_MARGIN`` all round
    (a footprint's convex pieces each shrunk: their union lies inside the body), or none
    for a disc. Half as tall as the body: caps in the obstacles' cap planes made FCL
    report a footprint's core 1.4e-4 m off a polygon's face in collision."""
    m = _CORE_MARGIN
    if robot.shape == "box":
        return [fcl.Box(robot.size[0] - 2 * m, robot.size[1] - 2 * m, _HEIGHT)]
    return [convex_prism(ring, 0.5 * _HEIGHT) for ring in body_pieces(robot, m)]


def _distance_callback(o1, o2, data):
    """python-fcl's ``defaultDistanceCallback`` in a Python function: a manager's ``distance``
    asks ``inspect.isroutine`` of its callback on every query, about 6 us for the Cython
    function (20,000 queries in a 200-vertex roadmap build), a fraction of that for this."""
    return fcl.defaultDistanceCallback(o1, o2, data)


def _collision_callback(o1, o2, data):
    """python-fcl's ``defaultCollisionCallback`` in a Python function (:func:`_distance_callback`)."""
    return fcl.defaultCollisionCallback(o1, o2, data)


class StaticGeometry:
    """FCL-backed collision queries against the static scene and the bounds.

    Parameters
    ----------
    scene : Scene
        Its ``robot.clearance`` c is kept from static obstacles: every clearance reported
        here is the distance to the nearest obstacle minus c (the bounds are measured
        without it), so "valid" means at least c from every obstacle, and certified
        motions keep that distance at every pose.

    Attributes
    ----------
    calls : int
        Number of FCL queries made so far (validity + distance), for benchmarks.
    checks : int
        Number of validity questions (:meth:`is_valid`), FCL or not.
    """

    def __init__(self, scene: Scene):
        self.scene = scene
        self.robot = scene.robot
        self.r = scene.robot.circumradius
        self.keep = float(scene.robot.clearance)  # distance kept from static obstacles
        # collision tests; distances (fclmodel): convex prisms meet prisms, a sphere a flat mesh
        # and spheres, the discs' spheres a box or footprint's flat mesh (one pass makes both)
        self._objects, model = static_model(scene)
        self._manager = manager_of(self._objects)
        self._prisms, self._flat, self._spheres = (manager_of(m) for m in (model.prisms, model.flat, model.spheres))
        self._has = (bool(model.prisms), bool(model.flat))
        self._discs = model.discs
        self._robot_objs = [fcl.CollisionObject(g, fcl.Transform()) for g in robot_geometries(scene.robot)]
        self._robot_obj = self._robot_objs[0]
        body = body_pieces(scene.robot)
        # the robot's distance queries, (object, manager, any obstacle there): its sphere
        # against the flat mesh, a footprint's prisms against the prisms, a box (an fcl.Box)
        # against the boxes and its prism against the other prisms; a box or footprint's body
        # as a flat mesh against the discs' spheres
        if scene.robot.shape == "disc":
            self._queries = [(self._robot_obj, self._flat, self._has[1])]
        elif scene.robot.shape == "footprint":
            self._queries = [(ob, self._prisms, self._has[0]) for ob in self._robot_objs]
        else:
            self._queries = [(self._robot_obj, manager_of(model.boxes), bool(model.boxes)),
                             (fcl.CollisionObject(convex_prism(body[0]), fcl.Transform()), manager_of(model.polygons), bool(model.polygons))]  # fmt: skip
        self._flat_body = fcl.CollisionObject(flat_mesh(body), fcl.Transform()) if body and model.spheres else None
        self._disc_obj = None  # the circumscribed disc (sweep_bound), made when first needed
        # a robot allowed to touch obstacles (robot.clearance 0): exact distances at contact
        self._exact = exact_measure(scene)
        # a box or footprint at contact: its core (the body less _CORE_MARGIN all round) in an
        # obstacle collides deep enough for FCL's test to decide, without the exact measure
        self._core_objs = [fcl.CollisionObject(g, fcl.Transform()) for g in _core_geometries(scene.robot)]
        self._shape = shape_of(scene.robot)
        self._grids = [ob for ob in scene.obstacles if isinstance(ob, MapObstacle) and len(ob.rects)]
        self._inner = _inner_point(scene.robot)
        # with maps only, a distance transform of their cells answers most validity questions
        self._map_only = bool(self._grids) and len(self._objects) == len(self._grids)
        self._edt: list | None = None
        # one request and one data object of each kind, reset before each query (_distance_data,
        # _collision_data), not made anew for every query
        self._creq = fcl.CollisionRequest()
        self._dreq = fcl.DistanceRequest()
        self._ddata = fcl.DistanceData(request=self._dreq)
        self._cdata = fcl.CollisionData(request=self._creq)
        self._trace_ends = (math.nan, math.nan)  # the last _trace's ends' clearances
        self._trace_ran_out = False  # whether the last _trace stopped at its steps' limit
        # a box or footprint's pieces and cores (translations' swept hulls, _swept_distance)
        self._pieces = (body_pieces(scene.robot), body_pieces(scene.robot, _CORE_MARGIN)) if self._objects else ([], [])
        self._kept_measure = None  # with a clearance kept: shapely's measure of translations
        if self._pieces[0] and self.keep > 0 and all(isinstance(ob, (Disc, Box, Polygon, MapObstacle)) for ob in scene.obstacles):
            self._kept_measure = ExactBody(scene)
        self._placed = fcl.Transform()  # the last pose's transform (_place)
        self.calls = 0
        self.checks = 0  # every validity question, answered by FCL or by the bounds alone

    # ---- bounds (analytic)
    def bounds_clearance(self, poses: FloatArray) -> FloatArray:
        """Distance from the robot body to the outside of the bounds (negative: outside).

        The bounds are measured in closed form, so a body meant to touch them is off only by
        a rounding: up to ``TOUCH_TOL`` out counts as touching (0), as the check, which
        tolerates 1e-9 m, says. A translation's distance to each side changes linearly, so
        its ends bound it; a turn is certified only with room (see :meth:`motion_free`).

        Parameters
        ----------
        poses : (n, d) float

        Returns
        -------
        (n,) float
        """
        poses = np.atleast_2d(np.asarray(poses, dtype=float))
        xmin, ymin, xmax, ymax = self.scene.bounds
        if self.robot.shape == "disc":
            x, y, r = poses[:, 0], poses[:, 1], self.robot.radius
            d = np.min(np.stack([x - r - xmin, xmax - x - r, y - r - ymin, ymax - y - r]), axis=0)
            return np.where((d < 0) & (d >= -TOUCH_TOL), 0.0, d)
        c = self.robot.corners(poses)
        d = np.minimum.reduce(
            [
                c[..., 0].min(-1) - xmin,
                xmax - c[..., 0].max(-1),
                c[..., 1].min(-1) - ymin,
                ymax - c[..., 1].max(-1),
            ]
        )
        return np.where((d < 0) & (d >= -TOUCH_TOL), 0.0, d)

    def _place(self, pose) -> None:
        if len(pose) == 3:
            yaw = float(pose[2])
            tf = fcl.Transform(
                np.array([math.cos(0.5 * yaw), 0.0, 0.0, math.sin(0.5 * yaw)]),
                np.array([pose[0], pose[1], 0.0]),
            )
            for ob in self._robot_objs:
                ob.setTransform(tf)
            if self.robot.shape == "box":
                self._queries[1][0].setTransform(tf)
            if self._flat_body is not None:
                self._flat_body.setTransform(tf)
            self._placed = tf
        else:
            self._robot_obj.setTranslation(np.array([pose[0], pose[1], 0.0]))

    def _bounds_clearance1(self, pose) -> float:
        """Scalar fast path of :meth:`bounds_clearance` for one pose."""
        xmin, ymin, xmax, ymax = self.scene.bounds
        x, y = pose[0], pose[1]
        if len(pose) == 2 or self.robot.shape == "disc":
            ex = ey = self.robot.radius
        elif self.robot.shape == "footprint":
            x0, y0, x1, y1 = self._shape.extents(float(pose[2]))
            return _touching(min(x + x0 - xmin, xmax - x - x1, y + y0 - ymin, ymax - y - y1))
        else:
            c, s = abs(math.cos(pose[2])), abs(math.sin(pose[2]))
            hl, hw = 0.5 * self.robot.size[0], 0.5 * self.robot.size[1]
            ex, ey = c * hl + s * hw, s * hl + c * hw
        return _touching(min(x - ex - xmin, xmax - x - ex, y - ey - ymin, ymax - y - ey))

    def _inside_bounds(self, pose) -> bool:
        return self._bounds_clearance1(pose) >= 0

    def clearance1(self, pose) -> float:
        """Clearance of one pose from static obstacles and bounds (see :meth:`clearance`)."""
        # the bounds at the circumradius bound the body's distance to them from below: when
        # the obstacles are nearer, the body's exact extents (costly for a footprint) are moot
        quick = self._bounds_at_circumradius(pose[0], pose[1])
        o = None
        if quick > 0:
            o = self.obstacle_clearance(pose) - self.keep
            if o <= quick:
                return o
        c = self._bounds_clearance1(pose)
        if c >= 0:  # touching the bounds exactly: the obstacles still count
            c = min(c, self.obstacle_clearance(pose) - self.keep if o is None else o)
        return c

    # ---- single pose (OMPL callback path)
    def is_valid(self, pose) -> bool:
        """True when the robot at ``pose`` is inside bounds and FCL's collision test finds it
        in no obstacle (the sampler's fast test: it misses penetrations of up to ~3e-7 m,
        which :meth:`clearance1` measures exactly; no motion is certified from
        such a pose, so it stays an isolated vertex)."""
        self.checks += 1
        if not self._inside_bounds(pose):
            return False
        if not self._objects:
            return True
        if self._map_only and self._map_bound(pose) > self.keep:
            return True
        if self.keep > 0:  # a distance, not a collision test, decides the clearance
            return self.obstacle_clearance(pose) >= self.keep
        if self._grids and self._inside_map(pose):
            return False
        self._place(pose)
        return not self._collides()

    def obstacle_clearance(self, pose) -> float:
        """Distance from the robot at ``pose`` to the nearest static obstacle (<= 0 when touching)."""
        if not self._objects:
            return math.inf
        if self._grids and self._inside_map(pose):
            return -1.0
        self._place(pose)
        # the distances are exact (fclmodel: measured to 1e-15 against shapely); the margin
        # keeps the clearance a lower bound all the same; at contact the distance is
        # unreliable, so the collision test decides (0 or -1)
        d = self._obstacle_distance(pose) - _DIST_MARGIN
        if d <= _NEAR_CONTACT:
            if self._exact is not None:
                # a robot allowed to touch is measured exactly at contact (gfuzzy.collision.
                # exact): a rounding into an obstacle (a pose meant to touch it) touches it,
                # as the check says, and a penetration FCL's collision test misses (up to
                # ~3e-7 m) is one
                if self._core_objs and self._core_collides():
                    return -1.0
                return 0.0 if self._exact.gap(pose, pose) >= -TOUCH_TOL else -1.0
            return -1.0 if self._collides() else 0.0
        return d

    def _obstacle_distance(self, pose) -> float:
        """The distance from the robot at ``pose`` (placed: :meth:`_place`) to the nearest
        static obstacle, exact away from contact (<= 0 in contact; see ``fclmodel``)."""
        dist = min(self._fcl_distance(*query) for query in self._queries)
        if self._flat_body is not None:  # a box or footprint among discs
            dist = min(dist, self._fcl_distance(self._flat_body, self._spheres))
        return dist

    def _fcl_distance(self, ob: fcl.CollisionObject, manager, has: bool = True) -> float:
        """FCL's distance from ``ob`` (placed) to the objects of ``manager`` (inf: ``has``
        false, none); <= 0 in contact."""
        if not has:
            return math.inf
        data = self._distance_data()
        manager.distance(ob, data, _distance_callback)
        self.calls += 1
        return data.result.min_distance

    def _distance_data(self) -> fcl.DistanceData:
        """The distance query's data as python-fcl's constructor makes it (no result yet, not
        done): the one object, reset (what ``defaultDistanceCallback`` reads and writes)."""
        data = self._ddata
        data.done = False
        result = data.result
        result.min_distance = sys.float_info.max
        result.nearest_points = [None, None]
        result.o1 = result.o2 = None
        result.b1 = result.b2 = -1
        return data

    def _collision_data(self) -> fcl.CollisionData:
        """The collision query's data as python-fcl's constructor makes it, reset
        (``defaultCollisionCallback`` stops at more contacts than the request's maximum)."""
        data = self._cdata
        data.done = False
        result = data.result
        result.is_collision = False
        result.contacts.clear()
        result.cost_sources.clear()
        return data

    def _map_bound(self, pose) -> float:
        """A lower bound of the robot's distance to the maps' blocked cells (-inf off a map).

        For the cell holding the reference point, e = the distance from its centre to the
        nearest blocked cell's centre; the blocked region is at least e - res sqrt(2) from
        the point (half a diagonal at each end) and the body at least that minus the
        circumradius from it.
        """
        if self._edt is None:
            from scipy import ndimage

            self._edt = [
                (ndimage.distance_transform_edt(~g.blocked) * g.resolution - g.resolution * math.sqrt(2.0))
                for g in self._grids
            ]
        x, y = float(pose[0]), float(pose[1])
        low = math.inf
        for grid, edt in zip(self._grids, self._edt, strict=True):
            h, w = edt.shape
            j = math.floor((x - grid.origin[0]) / grid.resolution)
            k = math.floor((y - grid.origin[1]) / grid.resolution)
            if not (0 <= j < w and 0 <= k < h):
                return -math.inf
            low = min(low, float(edt[h - 1 - k, j]))
        return low - self.r

    def _inside_map(self, pose) -> bool:
        """Whether a point inside the robot's body lies in a blocked map cell."""
        x, y = float(pose[0]), float(pose[1])
        if len(pose) > 2 and self._inner != (0.0, 0.0):
            c, s = math.cos(pose[2]), math.sin(pose[2])
            x, y = x + c * self._inner[0] - s * self._inner[1], y + s * self._inner[0] + c * self._inner[1]
        for grid in self._grids:
            h, w = grid.blocked.shape
            j = math.floor((x - grid.origin[0]) / grid.resolution)
            k = math.floor((y - grid.origin[1]) / grid.resolution)
            if 0 <= j < w and 0 <= k < h and grid.blocked[h - 1 - k, j]:
                return True
        return False

    def _core_collides(self) -> bool:
        """Whether FCL finds the robot's core (see ``_core_geometries``) at the pose last
        placed in an obstacle: the body then overlaps it by far more than a rounding."""
        return self._collides(self._core_objs, self._placed)

    def _collides(self, objs=None, tf=None) -> bool:
        """Whether FCL's collision test finds one of ``objs`` (default: the robot's pieces, as
        last placed; with ``tf``, placed there first) in an obstacle."""
        for ob in self._robot_objs if objs is None else objs:
            if tf is not None:
                ob.setTransform(tf)
            data = self._collision_data()
            self._manager.collide(ob, data, _collision_callback)
            self.calls += 1
            if data.result.is_collision:
                return True
        return False

    # ---- batches
    def valid(self, poses: FloatArray) -> np.ndarray:
        """Validity of many poses.

        Parameters
        ----------
        poses : (n, d) float

        Returns
        -------
        (n,) bool
        """
        poses = np.atleast_2d(np.asarray(poses, dtype=float))
        ok = self.bounds_clearance(poses) >= 0
        for i in np.nonzero(ok)[0]:
            ok[i] = self.is_valid(poses[i])
        return ok

    def clearance(self, poses: FloatArray) -> FloatArray:
        """Clearance of the robot body from static obstacles and the bounds.

        Parameters
        ----------
        poses : (n, d) float

        Returns
        -------
        (n,) float
            Positive: free by that margin; 0 touching; negative: colliding or outside.
            Obstacles count as grown by the robot's clearance (``robot.clearance``).
        """
        poses = np.atleast_2d(np.asarray(poses, dtype=float))
        return np.array([self.clearance1(p) for p in poses], dtype=float)

    def motion_free(self, a, b, max_steps: int = 100_000, ca=None, cb=None) -> bool:
        """True when the straight motion a -> b is certified free (see :meth:`motion_clearance`).

        The same certificate, but away from obstacles on a map it steps by the map's
        distance-transform bound (:meth:`_certifying_clearance`) instead of asking FCL.

        A motion that holds its heading (a translation: a disc's, a unicycle's lane) meets
        the bounds exactly at its ends (each side's distance changes linearly along it), so
        only the obstacles are traced: a pose touching the bounds (clearance 0, allowed)
        starts or ends a certified motion, which the tracing alone cannot prove.
        """
        if len(a) == 2 or float(b[2]) - float(a[2]) == 0.0:
            ends = (self._bounds_clearance1(a), self._bounds_clearance1(b))
            if not (ends[0] >= 0 and ends[1] >= 0):  # (NaN: not certified)
                return False
            # the callers' clearances count the bounds: a positive one still bounds the obstacles'
            ca = ca if ca is not None and ca > 0 else None
            cb = cb if cb is not None and cb > 0 else None
            if self._pieces[0] and len(a) == 3 and max_steps > _SWEPT_AFTER:
                # a box or footprint traced in more than a few steps: its swept body decides
                if self._trace(a, b, _SWEPT_AFTER, ca, cb, self._obstacle_certifying) >= 0:
                    return True
                if self._trace_ran_out:
                    swept = self._swept_verdict(a, b)
                    if swept is not None:
                        return swept
                else:
                    max_steps = 0  # refused: an end collides, or the motion grazes (below)
            if max_steps and self._trace(a, b, max_steps, ca, cb, self._obstacle_certifying) >= 0:
                return True
            # a robot touching an obstacle at an end starts or ends no traced motion (the
            # steps are its clearance): its translation is measured exactly instead
            return bool(self._exact is not None and min(self._trace_ends) == 0.0 and self._exact.gap(a, b) >= -TOUCH_TOL)
        return self._trace(a, b, max_steps, ca, cb, self._certifying_clearance) >= 0

    def _swept_verdict(self, a, b) -> bool | None:
        """A box or footprint's translation from pose ``a`` to ``b`` decided by its swept body
        alone, or None (a disc; or near contact: the tracing decides).

        The body translating sweeps, piece by piece, the convex hull of the piece at the two
        ends, exactly. FCL's distance from those hulls to the obstacles, when at least
        ``robot.clearance + _SWEPT_MARGIN``, certifies the whole translation in one query per
        piece (sphere tracing along a wall a centimetre away takes a hundred per metre); a
        distance below ``robot.clearance`` (exact, ``fclmodel``: the true one is below
        too), or with touching allowed the pieces' cores' hulls in an obstacle,
        refuses it (tracing towards a wall at a grazing angle takes thousands of steps).
        With touching allowed, a translation nearer than the margin is measured exactly
        (:meth:`gfuzzy.collision.exact.ExactBody.gap`, as ``gfuzzy check`` measures it)
        instead of traced: a lane 0.3 mm from a wall took 10,000 FCL queries.
        """
        pieces, cores = self._pieces
        if not pieces or len(a) != 3 or self._grids and self._inside_map(a):
            return None  # (wholly inside a map's cell, it meets none of the cells' faces)
        d = self._hull_distance(pieces, a, b)
        if d >= self.keep + _SWEPT_MARGIN:
            return True
        if self.keep > 0 and d < self.keep:
            return False
        if self.keep > 0:  # within the margin: shapely's distance, exact, decides
            return None if self._kept_measure is None else bool(self._kept_gap(a, b) >= self.keep + _EPS_CERT_CLEARANCE)
        if self._exact is None:
            return None
        if d <= 0 and cores and self._hull_distance(cores, a, b) <= -1.0:
            return False
        # touching allowed, within the margin: measured exactly (as at a touching end)
        return bool(self._exact.gap(a, b) >= -TOUCH_TOL)

    def _kept_gap(self, a, b) -> float:
        """Shapely's distance from the body translating from pose ``a`` to ``b`` to the
        obstacles within ``robot.clearance`` + ``_SWEPT_MARGIN`` of it (inf: none), for a
        robot that keeps a clearance (:meth:`_swept_verdict`)."""
        measure = self._kept_measure
        body = measure.swept(a, b)
        reach = self.keep + 2 * _SWEPT_MARGIN
        out = math.inf
        discs = measure.obstacles.discs
        if len(discs):
            out = float(np.min(shapely.distance(body, shapely.points(discs[:, :2])) - discs[:, 2]))
        for poly in measure.obstacles.near(body, reach):
            out = min(out, float(poly.distance(body)) if not poly.intersects(body) else -1.0)
        return out

    def _hull_distance(self, pieces: list, a, b) -> float:
        """FCL's distance from the pieces' hulls swept from pose ``a`` to ``b`` (heading
        ``a``'s) to the obstacles; -1 when one collides (FCL's collision test, asked only
        below ``robot.clearance + _SWEPT_MARGIN``: above, the distance is trusted, as
        :meth:`obstacle_clearance` trusts it)."""
        c, s = math.cos(float(a[2])), math.sin(float(a[2]))
        rot = np.array([[c, -s], [s, c]])
        shift = np.array([float(b[0]) - float(a[0]), float(b[1]) - float(a[1])])
        tf = fcl.Transform(np.array([float(a[0]), float(a[1]), 0.0]))
        out = math.inf
        for piece in pieces:
            w = piece @ rot.T
            hull = _hull(np.vstack([w, w + shift]))
            ob = fcl.CollisionObject(convex_prism(hull, 0.5 * _HEIGHT), tf)
            d = self._fcl_distance(ob, self._prisms, self._has[0])
            if len(self._discs):
                rel = self._discs[:, :2] - np.array([float(a[0]), float(a[1])])  # the hull's frame
                d = min(d, float(np.min(point_convex_distance(rel, hull) - self._discs[:, 2])))
            if d < self.keep + _SWEPT_MARGIN:
                data = self._collision_data()
                self._manager.collide(ob, data, _collision_callback)
                self.calls += 1
                if data.result.is_collision:
                    return -1.0
            out = min(out, d)
        return out

    def _obstacle_certifying(self, pose) -> float:
        """A lower bound of the clearance from the obstacles alone (not the bounds), less
        ``robot.clearance``: the map's distance transform where it leaves more than
        ``_QUICK_CLEARANCE``, else FCL's :meth:`obstacle_clearance`."""
        if not self._objects:
            return math.inf
        if self._map_only:
            c = self._map_bound(pose) - self.keep
            if c > _QUICK_CLEARANCE:
                return c
        return self.obstacle_clearance(pose) - self.keep

    def _bounds_at_circumradius(self, x: float, y: float) -> float:
        """A lower bound of the body's clearance from the bounds at (x, y), any heading: a
        disc of the circumradius (the exact clearance's expression order, less a hair, so
        never above it in floating point)."""
        xmin, ymin, xmax, ymax = self.scene.bounds
        r = self.r
        return min(x - r - xmin, xmax - x - r, y - r - ymin, ymax - y - r) - 1e-12

    def disc_bound(self, x: float, y: float) -> float:
        """A lower bound of the clearance of the robot's circumscribed disc at (x, y),
        whatever its heading (so of any turn in place there); -inf when no cheap bound
        exists (obstacles other than maps: FCL decides).

        The bounds at the circumradius, and the maps' distance transform
        (:meth:`_map_bound`), less ``robot.clearance``: a few microseconds, no FCL query.
        """
        c = self._bounds_at_circumradius(x, y)
        if not self._objects or not c > 0:  # (a NaN pose: NaN, as the clearance is)
            return c
        if not self._map_only:
            return -math.inf
        return min(c, self._map_bound((x, y)) - self.keep)

    def sweep_bound(self, x: float, y: float) -> float:
        """A lower bound of the clearance of every pose at (x, y), whatever its heading (so
        of any turn in place there): :meth:`disc_bound` when that is positive, else the FCL
        distance of the robot's circumscribed disc (one query) less ``robot.clearance``;
        -1 when the disc is not clear by more than FCL's margin.

        A turn in place sweeps at most that disc: where it is clear, every ring heading and
        every arc between them is free without a query per heading.
        """
        c = self.disc_bound(x, y)
        quick = self._bounds_at_circumradius(x, y)
        if c > 0 or not quick > 0:
            return c
        if self._grids and self._inside_map((x, y)):  # wholly inside a blocked cell: no wall met
            return -1.0
        if self._disc_obj is None:
            self._disc_obj = fcl.CollisionObject(fcl.Sphere(self.r), fcl.Transform())
        self._disc_obj.setTranslation(np.array([x, y, 0.0]))
        d = self._fcl_distance(self._disc_obj, self._flat, self._has[1]) - _DIST_MARGIN  # as obstacle_clearance's
        return min(quick, d - self.keep) if d > _NEAR_CONTACT else -1.0

    def sweep_free(self, a, b, ca=None, cb=None, max_steps: int = 100_000) -> bool:
        """True when the circumscribed disc's straight motion from ``a`` to ``b`` ((2,)
        positions) is certified free by :meth:`sweep_bound` (``ca``, ``cb``: the ends'
        bounds when known): so is the body's at any heading, held or turning."""
        return self._trace(a[:2], b[:2], max_steps, ca, cb, lambda p: self.sweep_bound(p[0], p[1])) >= 0

    def _certifying_clearance(self, pose) -> float:
        """A lower bound of :meth:`clearance1` good enough to step by: :meth:`disc_bound`
        where it leaves more than ``_QUICK_CLEARANCE`` (a lower bound certifies as the
        exact clearance does, in shorter steps), else FCL's :meth:`clearance1`."""
        c = self.disc_bound(float(pose[0]), float(pose[1]))
        return c if c > _QUICK_CLEARANCE else self.clearance1(pose)

    def motion_clearance(self, a, b, max_steps: int = 100_000, ca=None, cb=None) -> float:
        """Certify the straight motion a -> b (heading along the shorter arc) as free.

        Lipschitz argument: along the motion no point of the robot moves farther than the
        contract-metric length travelled, so a pose with clearance c proves every pose
        within metric distance c of it free. The check advances from both ends by the
        clearance found (sphere tracing) until the two certified stretches meet.

        ca, cb : float, optional
            The clearances of ``a`` and ``b`` when the caller knows them already (a
            roadmap's vertices are shared by many edges).

        Returns
        -------
        float
            -1 when the motion is not certified free (it collides, or grazes an obstacle
            with clearance below 1e-9 somewhere); otherwise the smallest clearance found
            at the poses examined (>= 0; an estimate of the motion's clearance, which is
            exact at the ends).
        """
        return self._trace(a, b, max_steps, ca, cb, self.clearance1)

    def _trace(self, a, b, max_steps: int, ca, cb, clear) -> float:
        """:meth:`motion_clearance` with the clearance (or a lower bound of it) ``clear``."""
        a = [float(v) for v in a]
        b = [float(v) for v in b]
        dx, dy = b[0] - a[0], b[1] - a[1]
        dh = 0.0
        if len(a) == 3:
            dh = (b[2] - a[2] + math.pi) % (2 * math.pi) - math.pi
        total = math.hypot(dx, dy) + abs(dh) * self.r
        self._trace_ran_out = False
        ca = clear(a) if ca is None else float(ca)
        self._trace_ends = (ca, math.nan)  # the ends' clearances, for motion_free's contact
        if ca < 0:
            return -1.0
        if total == 0.0:
            return ca
        cb = clear(b) if cb is None else float(cb)
        self._trace_ends = (ca, cb)
        if cb < 0:
            return -1.0
        lo = ca / total  # [0, lo] is certified
        hi = 1.0 - cb / total  # [hi, 1] is certified
        low = min(ca, cb)

        def pose(f: float):
            p = [a[0] + f * dx, a[1] + f * dy]
            if len(a) == 3:
                p.append((a[2] + f * dh + math.pi) % (2 * math.pi) - math.pi)
            return p

        for _ in range(max_steps):
            if lo >= hi:
                return low
            c = clear(pose(lo))
            if c < _EPS_CERT_CLEARANCE:
                return -1.0
            low = min(low, c)
            lo += c / total
            if lo >= hi:
                return low
            c = clear(pose(hi))
            if c < _EPS_CERT_CLEARANCE:
                return -1.0
            low = min(low, c)
            hi -= c / total
        if lo >= hi:
            return low
        self._trace_ran_out = True
        return -1.0


# --------------------------------------------------------------------------- movers


def mover_distance(
    robot: Robot, poses: FloatArray, shape: str, radius: float, size, xy: FloatArray, exact: bool = True
) -> FloatArray:
    """Distance between the robot at ``poses`` and a mover at ``xy`` (negative: overlap).

    Parameters
    ----------
    robot : Robot
        A disc, a box or a footprint (:meth:`gfuzzy.collision.shapes.Shape.mover_distance`).
    poses : (..., d) float
        Broadcastable against ``xy``.
    shape : {"disc", "box"}
        The mover's shape; ``radius`` (scalar or broadcastable array) for a disc,
        ``size`` ((2,) or (..., 2): w, h) for an axis-aligned box.
    xy : (..., 2) float
    exact : bool
        False allows a cheaper lower bound for a box or footprint robot against a box mover (the
        separating-axis gap); safety decisions stay sound, a little conservative.

    Returns
    -------
    (...,) float
        Exact for discs and boxes (see ``exact``); where shapes overlap the value is <= 0.
    """
    poses = np.asarray(poses, dtype=float)
    xy = np.asarray(xy, dtype=float)
    radius = np.asarray(radius, dtype=float)
    size = np.asarray(size, dtype=float)
    return shape_of(robot).mover_distance(poses, shape, radius, size, xy, exact)
