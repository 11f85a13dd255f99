"""Robot shapes behind one interface: a disc, a box, a footprint polygon.

A :class:`Shape` answers what the planner asks of the robot's body: its circumscribed and
inscribed radii about the reference point, its FCL geometry (convex prisms, see
:mod:`gfuzzy.collision.geometry`), its outline at poses, its extent along the world axes (the
bounds), and its distance to a mover (a disc or an axis-aligned box). :func:`shape_of`
gives a robot's shape.

A footprint is any simple polygon, concave included: it is cut into convex pieces (a
constrained Delaunay triangulation whose triangles are merged while the union stays
convex, Hertel-Mehlhorn), and every answer is the union of the pieces' answers: a
collision is a piece's collision, a distance the smallest piece distance. Nothing is
replaced by a convex hull. The disc's and the box's answers are the code they always had
(moved here from :mod:`gfuzzy.collision.geometry`, same operations, same bits).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Protocol

import fcl
import numpy as np

from ..scene.scene import Robot, footprint_inradius
from ..typed import FloatArray

__all__ = ["Shape", "DiscShape", "BoxShape", "FootprintShape", "shape_of", "body_pieces", "convex_pieces", "HEIGHT", "QUAD_EXACT"]

HEIGHT = 10.0  # prism half height: any value > 0 works, all shapes share z = 0
QUAD_EXACT = 2.0  # box-box distances are exact below this (see _quad_distance)
_BOX_SIGNS = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])


class Shape(Protocol):
    """What the planner asks of a robot's body (see the module's docstring)."""

    circumradius: float
    inradius: float

    def fcl_geometries(self) -> list:
        """FCL geometries about the reference point (their union is the body)."""

    def outline(self, poses: FloatArray) -> FloatArray:
        """(n, k, 2) outline vertices at (n, 3) poses, counter-clockwise."""

    def extents(self, heading: float) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of the body about the reference point at ``heading``."""

    def mover_distance(self, poses, shape: str, radius, size, xy, exact: bool = True) -> FloatArray:
        """Distance to a mover (negative or 0 where they overlap); see
        :func:`gfuzzy.collision.geometry.mover_distance`."""


# --------------------------------------------------------------------------- distances


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


def _to_local(poses: FloatArray, xy: FloatArray) -> FloatArray:
    """Points ``xy`` (..., 2) in the frames of ``poses`` (..., 3)."""
    c, s = np.cos(poses[..., 2]), np.sin(poses[..., 2])
    rel = xy - poses[..., :2]
    return np.stack([c * rel[..., 0] + s * rel[..., 1], -s * rel[..., 0] + c * rel[..., 1]], -1)


def _segments_distance(p: FloatArray, ring: FloatArray) -> FloatArray:
    """Distance from points p (n, 2) to the closed ring's edges (V, 2) -> (n,)."""
    a = ring[None]  # (1, V, 2)
    ab = np.roll(ring, -1, axis=0)[None] - a
    ap = p[:, None, :] - a  # (n, V, 2)
    den = ab[..., 0] * ab[..., 0] + ab[..., 1] * ab[..., 1]
    t = np.clip((ap[..., 0] * ab[..., 0] + ap[..., 1] * ab[..., 1]) / np.maximum(den, 1e-300), 0.0, 1.0)
    dx, dy = ap[..., 0] - t * ab[..., 0], ap[..., 1] - t * ab[..., 1]
    return np.sqrt(dx * dx + dy * dy).min(axis=1)


def _edge_normals(ring: FloatArray) -> FloatArray:
    """Outward unit normals (V, 2) of a counter-clockwise ring (V, 2)."""
    e = np.roll(ring, -1, axis=0) - ring
    n = np.stack([e[:, 1], -e[:, 0]], -1)
    return n / np.sqrt(n[:, 0] * n[:, 0] + n[:, 1] * n[:, 1])[:, None]


def point_convex_distance(p: FloatArray, ring: FloatArray) -> FloatArray:
    """Signed distance from points p (n, 2) to a convex counter-clockwise ring (V, 2):
    exact outside, minus the depth inside.

    Returns
    -------
    (n,) float
    """
    nrm = _edge_normals(ring)
    s = ((p[:, None, 0] - ring[None, :, 0]) * nrm[None, :, 0] + (p[:, None, 1] - ring[None, :, 1]) * nrm[None, :, 1]).max(1)
    out = s > 0
    if out.any():
        s[out] = _segments_distance(p[out], ring)
    return s


def convex_convex_distance(P: FloatArray, ring: FloatArray, exact: bool = True) -> FloatArray:
    """Distance between convex polygons P (n, m, 2) (counter-clockwise) and one convex
    counter-clockwise ``ring`` (V, 2): the separating-axis gap (<= 0 when
    they overlap); where it is positive and ``exact``, the exact distance (the nearest
    vertex-edge pair either way).

    Returns
    -------
    (n,) float
    """
    n = len(P)
    gap = np.full(n, -np.inf)
    rn = _edge_normals(ring)  # the ring's normals
    for k in range(len(ring)):
        pp = P[..., 0] * rn[k, 0] + P[..., 1] * rn[k, 1]  # (n, m)
        rr = ring[:, 0] * rn[k, 0] + ring[:, 1] * rn[k, 1]  # (V,)
        gap = np.maximum(gap, np.maximum(pp.min(-1) - rr.max(), rr.min() - pp.max(-1)))
    m = P.shape[1]
    for k in range(m):
        e = P[:, (k + 1) % m] - P[:, k]
        nx, ny = e[:, 1], -e[:, 0]
        nn = np.sqrt(nx * nx + ny * ny)
        nx, ny = nx / nn, ny / nn
        pp = P[..., 0] * nx[:, None] + P[..., 1] * ny[:, None]
        rr = ring[None, :, 0] * nx[:, None] + ring[None, :, 1] * ny[:, None]
        gap = np.maximum(gap, np.maximum(pp.min(-1) - rr.max(-1), rr.min(-1) - pp.max(-1)))
    if exact:
        sep = np.nonzero(gap > 0)[0]
        if sep.size:
            Ps = P[sep]
            d = _segments_distance(Ps.reshape(-1, 2), ring).reshape(len(sep), m).min(1)
            for k in range(m):  # the ring's vertices against P's edges
                a = Ps[:, k]
                ab = Ps[:, (k + 1) % m] - a
                ap = ring[None] - a[:, None]
                den = np.maximum(ab[:, 0] * ab[:, 0] + ab[:, 1] * ab[:, 1], 1e-300)
                t = np.clip((ap[..., 0] * ab[:, None, 0] + ap[..., 1] * ab[:, None, 1]) / den[:, None], 0.0, 1.0)
                dx, dy = ap[..., 0] - t * ab[:, None, 0], ap[..., 1] - t * ab[:, None, 1]
                d = np.minimum(d, np.sqrt(dx * dx + dy * dy).min(1))
            gap[sep] = d
    return gap


# --------------------------------------------------------------------------- pieces


def _cross(o, a, b) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _is_convex(ring: FloatArray, tol: float) -> bool:
    k = len(ring)
    return all(_cross(ring[i - 1], ring[i], ring[(i + 1) % k]) >= -tol for i in range(k))


def _drop_collinear(ring: FloatArray, tol: float) -> FloatArray:
    keep = [i for i in range(len(ring)) if abs(_cross(ring[i - 1], ring[i], ring[(i + 1) % len(ring)])) > tol]
    return ring[keep]


def convex_pieces(points: FloatArray) -> list[FloatArray]:
    """Convex pieces whose union is the simple polygon ``points`` (k, 2).

    A constrained Delaunay triangulation (shapely), then Hertel-Mehlhorn: neighbouring
    pieces are merged while their union stays convex (at most four times the fewest
    pieces; one piece for a convex polygon, two for an L).

    Returns
    -------
    list of (m, 2) float
        Counter-clockwise, no collinear vertices.
    """
    import shapely

    pts = np.asarray(points, dtype=float)
    scale = float(np.abs(pts).max()) or 1.0
    tol = 1e-12 * scale * scale
    if _is_convex(_ccw(pts), tol):
        return [_drop_collinear(_ccw(pts), tol)]
    index = {(float(x), float(y)): i for i, (x, y) in enumerate(pts)}
    tris = []
    for t in shapely.get_parts(shapely.constrained_delaunay_triangles(shapely.Polygon(pts))):
        c = np.asarray(t.exterior.coords)[:3]
        ids = []
        for x, y in c:
            i = index.get((float(x), float(y)))
            if i is None:  # not expected: the nearest input vertex
                i = int(np.argmin(np.hypot(pts[:, 0] - x, pts[:, 1] - y)))
            ids.append(i)
        if abs(_cross(pts[ids[0]], pts[ids[1]], pts[ids[2]])) <= tol:
            continue
        tris.append(ids if _cross(pts[ids[0]], pts[ids[1]], pts[ids[2]]) > 0 else ids[::-1])
    pieces = [list(t) for t in tris]
    merged = True
    while merged:
        merged = False
        for a in range(len(pieces)):
            for b in range(a + 1, len(pieces)):
                ring = _merge(pieces[a], pieces[b])
                if ring is not None and _is_convex(pts[ring], tol):
                    pieces[a] = ring
                    del pieces[b]
                    merged = True
                    break
            if merged:
                break
    return [_drop_collinear(pts[p], tol) for p in pieces]


def _merge(A: list, B: list) -> list | None:
    """The ring of two counter-clockwise index rings sharing an edge, or None."""
    for i in range(len(A)):
        u, v = A[i], A[(i + 1) % len(A)]
        for j in range(len(B)):
            if B[j] == v and B[(j + 1) % len(B)] == u:
                a = A[i + 1 :] + A[: i + 1]  # starts at v, ends at u
                b = B[j + 1 :] + B[: j + 1]  # starts at u, ends at v
                return a + b[1:-1]
    return None


def _ccw(pts: FloatArray) -> FloatArray:
    x, y = pts[:, 0], pts[:, 1]
    signed = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    return pts if signed > 0 else pts[::-1].copy()


def convex_prism(ring: FloatArray, height: float = HEIGHT) -> fcl.Convex:
    """A solid prism (FCL convex) over a convex counter-clockwise polygon (m, 2), from
    -``height`` to ``height``."""
    m = len(ring)
    verts = np.vstack([np.c_[ring, np.full(m, -height)], np.c_[ring, np.full(m, height)]])
    faces = [m, *range(m - 1, -1, -1), m, *range(m, 2 * m)]  # bottom (facing down), top
    for i in range(m):
        j = (i + 1) % m
        faces += [4, i, j, m + j, m + i]
    return fcl.Convex(verts, 2 + m, np.array(faces, dtype=np.int64))


# --------------------------------------------------------------------------- shapes


@dataclass(frozen=True)
class DiscShape:
    """A disc of ``radius`` about the reference point (poses ``[x, y]``)."""

    radius: float

    @property
    def circumradius(self) -> float:
        return self.radius

    @property
    def inradius(self) -> float:
        return self.radius

    def fcl_geometries(self) -> list:
        # a sphere at z = 0, not a cylinder: against spheres and tall prisms its distance
        # is the planar one, in closed form (see gfuzzy.collision.fclmodel.static_model)
        return [fcl.Sphere(self.radius)]

    def outline(self, poses: FloatArray, n: int = 48) -> FloatArray:
        poses = np.asarray(poses, dtype=float).reshape(len(poses), -1)
        a = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
        ring = self.radius * np.stack([np.cos(a), np.sin(a)], -1)
        return poses[:, None, :2] + ring[None]

    def extents(self, heading: float = 0.0) -> tuple[float, float, float, float]:
        r = self.radius
        return (-r, -r, r, r)

    def mover_distance(self, poses, shape, radius, size, xy, exact=True) -> FloatArray:
        rel = xy - poses[..., :2]
        if shape == "disc":
            return np.hypot(rel[..., 0], rel[..., 1]) - self.radius - radius
        return _point_box_distance(rel, 0.5 * size) - self.radius


@dataclass(frozen=True)
class BoxShape:
    """A ``length`` x ``width`` box centred on the reference point, length along the heading."""

    robot: Robot

    @property
    def circumradius(self) -> float:
        return 0.5 * math.hypot(*self.robot.size)

    @property
    def inradius(self) -> float:
        return 0.5 * min(self.robot.size)

    def fcl_geometries(self) -> list:
        return [fcl.Box(self.robot.size[0], self.robot.size[1], 2 * HEIGHT)]

    def outline(self, poses: FloatArray) -> FloatArray:
        return self.robot.corners(poses)

    def extents(self, heading: float) -> tuple[float, float, float, float]:
        c, s = abs(math.cos(heading)), abs(math.sin(heading))
        hl, hw = 0.5 * self.robot.size[0], 0.5 * self.robot.size[1]
        ex, ey = c * hl + s * hw, s * hl + c * hw
        return (-ex, -ey, ex, ey)

    def mover_distance(self, poses, shape, radius, size, xy, exact=True) -> FloatArray:
        robot = self.robot
        c, s = np.cos(poses[..., 2]), np.sin(poses[..., 2])
        rel = xy - poses[..., :2]
        local = np.stack([c * rel[..., 0] + s * rel[..., 1], -s * rel[..., 0] + c * rel[..., 1]], -1)
        half_robot = 0.5 * np.asarray(robot.size)
        if shape == "disc":
            return _point_box_distance(local, half_robot) - radius
        shp = np.broadcast_shapes(poses.shape[:-1], xy.shape[:-1])
        A = robot.corners(np.broadcast_to(poses, shp + (3,)).reshape(-1, 3)).reshape(shp + (4, 2))
        half = np.broadcast_to(0.5 * size, shp + (2,))
        B = np.broadcast_to(xy, shp + (2,))[..., None, :] + half[..., None, :] * _BOX_SIGNS
        return _quad_distance(A, B, exact)


@dataclass(frozen=True, eq=False)
class FootprintShape:
    """A simple polygon (concave allowed) in the robot's frame, cut into convex pieces.

    Attributes
    ----------
    points : (k, 2) float
        The polygon, counter-clockwise.
    pieces : list of (m_i, 2) float
        Convex, counter-clockwise; their union is the polygon.
    """

    points: FloatArray
    pieces: list = field(compare=False)

    @classmethod
    def of(cls, footprint) -> FootprintShape:
        pts = _ccw(np.asarray(footprint, dtype=float))
        return cls(pts, convex_pieces(pts))

    @property
    def circumradius(self) -> float:
        return float(max(math.hypot(x, y) for x, y in self.points))

    @property
    def origin_inside(self) -> bool:
        """Whether the reference point is inside the body (strictly)."""
        return self.inradius > 0

    @property
    def inradius(self) -> float:
        """Distance from the reference point to the outline when it is inside, else 0."""
        return footprint_inradius(self.points)

    def padded(self) -> tuple[FloatArray, np.ndarray]:
        """The pieces as one array (P, V, 2) (rows past a piece's count repeat its first
        vertex) and their vertex counts (P,): what the compiled kernel takes."""
        V = max(len(p) for p in self.pieces)
        out = np.empty((len(self.pieces), V, 2))
        for i, p in enumerate(self.pieces):
            out[i, : len(p)] = p
            out[i, len(p) :] = p[0]
        return out, np.array([len(p) for p in self.pieces], dtype=np.int64)

    def fcl_geometries(self) -> list:
        return [convex_prism(p) for p in self.pieces]

    def outline(self, poses: FloatArray) -> FloatArray:
        poses = np.asarray(poses, dtype=float).reshape(-1, 3)
        c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
        x, y = self.points[:, 0], self.points[:, 1]
        return np.stack(
            [poses[:, None, 0] + c[:, None] * x - s[:, None] * y, poses[:, None, 1] + s[:, None] * x + c[:, None] * y], -1
        )

    def extents(self, heading: float) -> tuple[float, float, float, float]:
        c, s = math.cos(heading), math.sin(heading)
        x, y = self.points[:, 0], self.points[:, 1]
        wx, wy = c * x - s * y, s * x + c * y
        return (float(wx.min()), float(wy.min()), float(wx.max()), float(wy.max()))

    def mover_distance(self, poses, shape, radius, size, xy, exact=True) -> FloatArray:
        """Exact distance to a disc or an axis-aligned box mover (``exact=False``: the
        separating-axis gap against a box, a lower bound, as the compiled kernel uses)."""
        shp = np.broadcast_shapes(poses.shape[:-1], xy.shape[:-1])
        poses = np.broadcast_to(poses, shp + (3,)).reshape(-1, 3)
        xy = np.broadcast_to(xy, shp + (2,)).reshape(-1, 2)
        local = _to_local(poses, xy)
        if shape == "disc":
            d = np.min([point_convex_distance(local, p) for p in self.pieces], axis=0)
            return (d - np.broadcast_to(radius, shp).reshape(-1)).reshape(shp)
        # the box mover in the robot's frame: its centre, its axes turned by -heading
        half = np.broadcast_to(0.5 * size, shp + (2,)).reshape(-1, 2)
        c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
        ax = np.stack([c, -s], -1)  # world x in the robot's frame
        ay = np.stack([s, c], -1)  # world y
        B = (
            local[:, None, :]
            + (half[:, 0, None] * _BOX_SIGNS[None, :, 0])[..., None] * ax[:, None, :]
            + (half[:, 1, None] * _BOX_SIGNS[None, :, 1])[..., None] * ay[:, None, :]
        )
        d = np.min([convex_convex_distance(B, p, exact) for p in self.pieces], axis=0)
        return d.reshape(shp)


@lru_cache(maxsize=64)
def shape_of(robot: Robot) -> Shape:
    """The shape of ``robot`` (cached per robot)."""
    if robot.shape == "disc":
        return DiscShape(robot.radius)
    if robot.shape == "box":
        return BoxShape(robot)
    return FootprintShape.of(robot.footprint)


def body_pieces(robot: Robot, margin: float = 0.0) -> list[FloatArray]:
    """A box or footprint robot's convex pieces about its reference point (a box: one),
    counter-clockwise, each shrunk by ``margin`` (their union then lies inside the body);
    none for a disc."""
    if robot.shape == "box":
        hl, hw = 0.5 * robot.size[0] - margin, 0.5 * robot.size[1] - margin
        return [np.array([[hl, -hw], [hl, hw], [-hl, hw], [-hl, -hw]])]
    if robot.shape != "footprint":
        return []
    pieces = [np.asarray(p, dtype=float) for p in shape_of(robot).pieces]
    if margin == 0.0:
        return [_ccw(p) for p in pieces]
    import shapely

    out = []
    for piece in pieces:
        core = shapely.Polygon(piece).buffer(-margin, join_style="mitre")
        if not core.is_empty and core.geom_type == "Polygon":
            out.append(_ccw(np.asarray(core.exterior.coords)[:-1]))
    return out
