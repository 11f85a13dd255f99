"""Collision geometry: FCL objects for the static scene and the robot, batched validity
and clearance, certified straight motions, and vectorised robot-vs-mover distances.

The world is planar: every 2-D shape becomes a tall prism (FCL cylinder, box or convex
prism) so that a 3-D collision query answers the 2-D question.

A *certified* motion is checked with a Lipschitz argument instead of sampling: along a
straight motion in the contract's metric (euclidean xy + |heading change| * circumradius),
no point of the robot moves farther than the metric length, so the clearance changes at
most that fast; an interval whose end clearances add up to at least its length is free.
"""

from __future__ import annotations

import math

import fcl
import numpy as np

from .poses import metric_distance, wrap_angle
from .scene import Box, Disc, MapObstacle, Polygon, Robot, Scene
from .typing import FloatArray

__all__ = [
    "StaticGeometry",
    "metric_distance",
    "wrap_angle",
    "mover_distance",
]

_HEIGHT = 10.0  # prism height: any value > 0 works, all shapes share z = 0
_EPS_CERT_CLEARANCE = 1e-9  # clearance below which a motion is not certified (grazing)
_NEAR_CONTACT = 1e-4  # distances below this are decided by a collision test (0 or -1)
_DIST_MARGIN = 1e-4  # subtracted from FCL distances (GJK overestimates; see obstacle_clearance)
QUAD_EXACT = 2.0  # box-box distances are exact below this (see _quad_distance)


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
    import shapely

    shape = shapely.Polygon(poly.points, [h for h in poly.holes])
    tris = shapely.constrained_delaunay_triangles(shape)
    out = []
    for t in shapely.get_parts(tris):
        pts = np.asarray(t.exterior.coords)[:3]
        area2 = (pts[1, 0] - pts[0, 0]) * (pts[2, 1] - pts[0, 1]) - (pts[2, 0] - pts[0, 0]) * (
            pts[1, 1] - pts[0, 1]
        )
        if abs(area2) < 1e-14:
            continue
        out.append(pts if area2 > 0 else pts[::-1])
    return out


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
    """FCL collision objects for every static obstacle of ``scene``."""
    objs = []
    for ob in scene.obstacles:
        if isinstance(ob, Disc):
            # a sphere at z = 0, not a cylinder: against spheres and tall prisms its distance
            # is the planar one, and FCL computes sphere distances in closed form (its GJK
            # distance to a cylinder overestimates small gaps)
            objs.append(fcl.CollisionObject(fcl.Sphere(ob.radius), _yaw_transform(*ob.center)))
        elif isinstance(ob, Box):
            geom = fcl.Box(ob.size[0], ob.size[1], 2 * _HEIGHT)
            objs.append(fcl.CollisionObject(geom, _yaw_transform(ob.center[0], ob.center[1], ob.angle)))
        elif isinstance(ob, MapObstacle):
            if len(ob.rects):
                objs.append(fcl.CollisionObject(_walls(ob.rects), fcl.Transform()))
        else:
            for tri in _triangulate(ob):
                objs.append(fcl.CollisionObject(_prism(tri), fcl.Transform()))
    return objs


def _inner_point(robot: Robot) -> tuple[float, float]:
    """A point inside the robot's body, in its frame: its reference point, or for a
    footprint that may not hold it, an interior point of the polygon."""
    footprint = getattr(robot, "footprint", None)
    if footprint is None or len(footprint) == 0:
        return (0.0, 0.0)
    import shapely

    poly = shapely.Polygon(np.asarray(footprint, dtype=float))
    if poly.contains(shapely.Point(0.0, 0.0)):
        return (0.0, 0.0)
    p = poly.representative_point()
    return (float(p.x), float(p.y))


def robot_geometry(robot: Robot):
    """The FCL geometry of the robot (about its reference point)."""
    if robot.shape == "disc":
        return fcl.Sphere(robot.radius)  # see static_objects: exact planar distances
    return fcl.Box(robot.size[0], robot.size[1], 2 * _HEIGHT)


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
        self._objects = static_objects(scene)
        self._manager = fcl.DynamicAABBTreeCollisionManager()
        if self._objects:
            self._manager.registerObjects(self._objects)
        self._manager.setup()
        self._robot_obj = fcl.CollisionObject(robot_geometry(scene.robot), fcl.Transform())
        self._grids = [ob for ob in scene.obstacles if isinstance(ob, MapObstacle) and len(ob.rects)]
        self._inner = _inner_point(scene.robot)
        self._creq = fcl.CollisionRequest()
        self._dreq = fcl.DistanceRequest()
        self.calls = 0
        self.checks = 0  # every validity question, answered by FCL or by the bounds alone

    # ---- bounds (analytic)
    def bounds_clearance(self, poses: FloatArray) -> FloatArray:
        """Distance from the robot body to the outside of the bounds (negative: outside).

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
            return np.min(np.stack([x - r - xmin, xmax - x - r, y - r - ymin, ymax - y - r]), axis=0)
        c = self.robot.corners(poses)
        return np.minimum.reduce(
            [
                c[..., 0].min(-1) - xmin,
                xmax - c[..., 0].max(-1),
                c[..., 1].min(-1) - ymin,
                ymax - c[..., 1].max(-1),
            ]
        )

    def _place(self, pose) -> None:
        if len(pose) == 3:
            yaw = float(pose[2])
            self._robot_obj.setTransform(
                fcl.Transform(
                    np.array([math.cos(0.5 * yaw), 0.0, 0.0, math.sin(0.5 * yaw)]),
                    np.array([pose[0], pose[1], 0.0]),
                )
            )
        else:
            self._robot_obj.setTranslation(np.array([pose[0], pose[1], 0.0]))

    def _bounds_clearance1(self, pose) -> float:
        """Scalar fast path of :meth:`bounds_clearance` for one pose."""
        xmin, ymin, xmax, ymax = self.scene.bounds
        x, y = pose[0], pose[1]
        if len(pose) == 2 or self.robot.shape == "disc":
            ex = ey = self.robot.radius
        else:
            c, s = abs(math.cos(pose[2])), abs(math.sin(pose[2]))
            hl, hw = 0.5 * self.robot.size[0], 0.5 * self.robot.size[1]
            ex, ey = c * hl + s * hw, s * hl + c * hw
        return min(x - ex - xmin, xmax - x - ex, y - ey - ymin, ymax - y - ey)

    def _inside_bounds(self, pose) -> bool:
        return self._bounds_clearance1(pose) >= 0

    def clearance1(self, pose) -> float:
        """Clearance of one pose from static obstacles and bounds (see :meth:`clearance`)."""
        c = self._bounds_clearance1(pose)
        if c > 0:
            c = min(c, self.obstacle_clearance(pose) - self.keep)
        return c

    # ---- single pose (OMPL callback path)
    def is_valid(self, pose) -> bool:
        """True when the robot at ``pose`` is inside bounds and touches no obstacle's interior."""
        self.checks += 1
        if not self._inside_bounds(pose):
            return False
        if not self._objects:
            return True
        if self.keep > 0:  # a distance, not a collision test, decides the clearance
            return self.obstacle_clearance(pose) >= self.keep
        if self._grids and self._inside_map(pose):
            return False
        self._place(pose)
        data = fcl.CollisionData(request=self._creq)
        self._manager.collide(self._robot_obj, data, fcl.defaultCollisionCallback)
        self.calls += 1
        return not data.result.is_collision

    def obstacle_clearance(self, pose) -> float:
        """Distance from the robot at ``pose`` to the nearest static obstacle (<= 0 when touching)."""
        if not self._objects:
            return math.inf
        if self._grids and self._inside_map(pose):
            return -1.0
        self._place(pose)
        data = fcl.DistanceData(request=self._dreq)
        self._manager.distance(self._robot_obj, data, fcl.defaultDistanceCallback)
        self.calls += 1
        # FCL's GJK distances to convex prisms overestimate by up to ~3e-5 (measured):
        # subtract a margin so that the clearance stays a lower bound; at contact the
        # distance is unreliable altogether, so the collision test decides (0 or -1)
        d = data.result.min_distance - _DIST_MARGIN
        if d <= _NEAR_CONTACT:
            return -1.0 if self._collides() else 0.0
        return d

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

    def _collides(self) -> bool:
        data = fcl.CollisionData(request=self._creq)
        self._manager.collide(self._robot_obj, data, fcl.defaultCollisionCallback)
        self.calls += 1
        return data.result.is_collision

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
        """True when the straight motion a -> b is certified free (see :meth:`motion_clearance`)."""
        return self.motion_clearance(a, b, max_steps, ca, cb) >= 0

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
        a = [float(v) for v in a]
        b = [float(v) for v in b]
        dx, dy = b[0] - a[0], b[1] - a[1]
        dh = 0.0
        if len(a) == 3:
            dh = (b[2] - a[2] + math.pi) % (2 * math.pi) - math.pi
        total = math.hypot(dx, dy) + abs(dh) * self.r
        ca = self.clearance1(a) if ca is None else float(ca)
        if ca < 0:
            return -1.0
        if total == 0.0:
            return ca
        cb = self.clearance1(b) if cb is None else float(cb)
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
            c = self.clearance1(pose(lo))
            if c < _EPS_CERT_CLEARANCE:
                return -1.0
            low = min(low, c)
            lo += c / total
            if lo >= hi:
                return low
            c = self.clearance1(pose(hi))
            if c < _EPS_CERT_CLEARANCE:
                return -1.0
            low = min(low, c)
            hi -= c / total
        return -1.0


# --------------------------------------------------------------------------- movers


def _point_box_distance(p: FloatArray, half: FloatArray) -> FloatArray:
    """Signed distance from points to a centered axis-aligned box. p (..., 2), half (..., 2)."""
    q = np.abs(p) - half
    outside = np.hypot(np.maximum(q[..., 0], 0), np.maximum(q[..., 1], 0))
    inside = np.minimum(np.maximum(q[..., 0], q[..., 1]), 0)
    return outside + inside


def _vertex_edge_distance(P: FloatArray, Q: FloatArray) -> FloatArray:
    """Smallest distance from the vertices of quads P to the edges of quads Q.

    P, Q : (n, 4, 2) -> (n,)
    """
    a = Q[:, None, :, :]  # (n, 1, 4, 2) edge starts
    ab = np.roll(Q, -1, axis=1)[:, None, :, :] - a
    ap = P[:, :, None, :] - a  # (n, 4, 4, 2)
    t = np.clip(
        np.einsum("nijk,nijk->nij", ap, ab) / np.maximum(np.einsum("nijk,nijk->nij", ab, ab), 1e-300),
        0.0,
        1.0,
    )
    diff = ap - t[..., None] * ab
    return np.sqrt(np.einsum("nijk,nijk->nij", diff, diff).min(axis=(1, 2)))


def _quad_distance(A: FloatArray, B: FloatArray, exact: bool = True) -> FloatArray:
    """Distance between convex quads (<= 0 when they overlap). A, B (..., 4, 2), ccw.

    Exact below ``QUAD_EXACT`` metres; beyond it the (smaller) distance between the
    quads' circumscribed circles is returned, a lower bound that callers comparing with
    safety margins or saturating clearances never need refined. With ``exact=False`` the
    separating-axis gap is returned instead of the exact distance: a lower bound (exact
    when the closest features are parallel edges) at a fifth of the cost.
    """
    shape = np.broadcast_shapes(A.shape, B.shape)[:-2]
    A = np.broadcast_to(A, shape + (4, 2)).reshape(-1, 4, 2)
    B = np.broadcast_to(B, shape + (4, 2)).reshape(-1, 4, 2)
    ca, cb = A.mean(axis=1), B.mean(axis=1)
    ra = np.sqrt(((A - ca[:, None]) ** 2).sum(-1)).max(-1)
    rb = np.sqrt(((B - cb[:, None]) ** 2).sum(-1)).max(-1)
    out = np.hypot(*(ca - cb).T) - ra - rb
    near = np.nonzero(out < QUAD_EXACT)[0]
    if near.size:
        A, B = A[near], B[near]
        # separating-axis test on the edge normals of both quads (two per rectangle)
        gap = np.full(len(near), -np.inf)
        for P, Q in ((A, B), (B, A)):
            for k in range(2):
                e = P[:, k + 1] - P[:, k]
                nrm = np.stack([-e[:, 1], e[:, 0]], -1)
                nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
                pp = np.einsum("nkj,nj->nk", P, nrm)
                qq = np.einsum("nkj,nj->nk", Q, nrm)
                gap = np.maximum(gap, np.maximum(qq.min(-1) - pp.max(-1), pp.min(-1) - qq.max(-1)))
        if exact:
            d = np.minimum(_vertex_edge_distance(A, B), _vertex_edge_distance(B, A))
            out[near] = np.where(gap > 0, d, gap)
        else:
            out[near] = gap
    return out.reshape(shape)


def mover_distance(
    robot: Robot, poses: FloatArray, shape: str, radius: float, size, xy: FloatArray, exact: bool = True
) -> FloatArray:
    """Distance between the robot at ``poses`` and a mover at ``xy`` (negative: overlap).

    Parameters
    ----------
    robot : Robot
    poses : (..., d) float
        Broadcastable against ``xy``.
    shape : {"disc", "box"}
        The mover's shape; ``radius`` (scalar or broadcastable array) for a disc,
        ``size`` ((2,) or (..., 2): w, h) for an axis-aligned box.
    xy : (..., 2) float
    exact : bool
        False allows a cheaper lower bound for a box robot against a box mover (the
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
    if robot.shape == "disc":
        rel = xy - poses[..., :2]
        if shape == "disc":
            return np.hypot(rel[..., 0], rel[..., 1]) - robot.radius - radius
        return _point_box_distance(rel, 0.5 * size) - robot.radius
    # box robot
    c, s = np.cos(poses[..., 2]), np.sin(poses[..., 2])
    rel = xy - poses[..., :2]
    local = np.stack([c * rel[..., 0] + s * rel[..., 1], -s * rel[..., 0] + c * rel[..., 1]], -1)
    half_robot = 0.5 * np.asarray(robot.size)
    if shape == "disc":
        return _point_box_distance(local, half_robot) - radius
    shp = np.broadcast_shapes(poses.shape[:-1], xy.shape[:-1])
    A = robot.corners(np.broadcast_to(poses, shp + (3,)).reshape(-1, 3)).reshape(shp + (4, 2))
    half = np.broadcast_to(0.5 * size, shp + (2,))
    signs = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])
    B = np.broadcast_to(xy, shp + (2,))[..., None, :] + half[..., None, :] * signs
    return _quad_distance(A, B, exact)
