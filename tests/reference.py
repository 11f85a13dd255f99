"""Independent references: a shapely model of the geometry (to cross-check FCL), the
movers' positions, a trajectory verdict, and a brute-force time-expanded search (to
cross-check the planner).

Everything here is built from the *scene document* (the plain dict written to YAML), never
from gfuzzy's parsed objects, so that a parsing or triangulation mistake in gfuzzy cannot
hide itself. Discs are handled analytically (the distance to the centre minus the radius),
never as buffered polygons, so the reference is exact up to floating point.

The classification is three-way with a tolerance ``eps``: a pose is *robustly free* when its
clearance exceeds ``eps``, *robustly colliding* when the robot shrunk by ``eps`` still
overlaps an obstacle (or the robot leaves the bounds by more than ``eps``), and otherwise
within ``eps`` of touching, where the two implementations may disagree.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from shapely import affinity

__all__ = [
    "Reference",
    "box_polygon",
    "robot_corners",
    "interpolate",
    "mover_reference_distance",
    "prism_mesh",
    "mover_position",
    "reference_violation",
    "contract_metric",
    "brute_force_steps",
]


def box_polygon(center, size, angle=0.0) -> shapely.Polygon:
    """A rectangle of ``size`` (along x, along y before rotation) rotated by ``angle`` rad."""
    hx, hy = 0.5 * size[0], 0.5 * size[1]
    poly = shapely.box(-hx, -hy, hx, hy)
    poly = affinity.rotate(poly, angle, origin=(0.0, 0.0), use_radians=True)
    return affinity.translate(poly, center[0], center[1])


def robot_corners(size, poses, shrink: float = 0.0) -> np.ndarray:
    """Corners (n, 4, 2) of a box robot of ``size`` (length, width) at ``poses`` (n, 3).

    ``shrink`` erodes the rectangle by that distance on every side.
    """
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    hl, hw = 0.5 * size[0] - shrink, 0.5 * size[1] - shrink
    local = np.array([[hl, hw], [-hl, hw], [-hl, -hw], [hl, -hw]])
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    x = poses[:, 0:1] + c * local[:, 0] - s * local[:, 1]
    y = poses[:, 1:2] + s * local[:, 0] + c * local[:, 1]
    return np.stack([x, y], axis=-1)


def footprint_bodies(points, poses, shrink: float = 0.0):
    """A footprint polygon (k, 2) placed at ``poses`` (n, 3), as shapely polygons, eroded by
    ``shrink`` (shapely's buffer)."""
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    local = np.asarray(points, dtype=float)
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    x = poses[:, 0:1] + c * local[:, 0] - s * local[:, 1]
    y = poses[:, 1:2] + s * local[:, 0] + c * local[:, 1]
    bodies = shapely.polygons(np.stack([x, y], axis=-1))
    return shapely.buffer(bodies, -shrink, join_style="mitre") if shrink > 0 else bodies


def interpolate(a, b, f) -> np.ndarray:
    """Poses at fractions ``f`` along a -> b; heading along the shorter arc (written afresh)."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    f = np.asarray(f, dtype=float)[:, None]
    d = b - a
    if a.size == 3:
        dh = math.remainder(float(d[2]), 2 * math.pi)  # in [-pi, pi]
        d = np.array([d[0], d[1], dh])
    return a + f * d


class Reference:
    """Shapely model of a scene's static part.

    Parameters
    ----------
    doc : dict
        The scene document (as written to YAML).
    mesh_footprints : dict, optional
        ``{file: shapely geometry}``: the xy footprint each mesh file was made from.
    """

    def __init__(self, doc: dict, mesh_footprints: dict | None = None):
        mesh_footprints = mesh_footprints or {}
        self.bounds = tuple(float(v) for v in doc["bounds"])
        robot = doc["robot"]
        if "disc" in robot:
            self.robot_kind, self.radius, self.size = "disc", float(robot["disc"]), None
        elif "footprint" in robot:
            self.robot_kind, self.radius, self.size = "footprint", 0.0, None
            self.points = np.asarray(robot["footprint"], dtype=float)
        else:
            self.robot_kind, self.radius, self.size = "box", 0.0, tuple(map(float, robot["box"]))
        polys, discs = [], []
        for item in doc.get("obstacles") or []:
            (kind, spec), = item.items()
            if kind == "disc":
                discs.append((tuple(spec["center"]), float(spec["radius"])))
            elif kind == "box":
                polys.append(box_polygon(spec["center"], spec["size"], spec.get("angle", 0.0)))
            elif kind == "polygon":
                polys.append(shapely.Polygon(spec))
            else:
                polys.append(mesh_footprints[spec["file"]])
        self.polys = shapely.union_all(polys) if polys else None
        if self.polys is not None:
            shapely.prepare(self.polys)
        self.discs = discs

    # ------------------------------------------------------------------ pieces
    def _bounds_margin(self, poses) -> np.ndarray:
        xmin, ymin, xmax, ymax = self.bounds
        if self.robot_kind == "disc":
            x, y, r = poses[:, 0], poses[:, 1], self.radius
            return np.min([x - r - xmin, xmax - x - r, y - r - ymin, ymax - y - r], axis=0)
        if self.robot_kind == "footprint":
            c = np.stack([shapely.get_coordinates(b)[:-1] for b in footprint_bodies(self.points, poses)])
        else:
            c = robot_corners(self.size, poses)
        return np.min(
            [
                c[..., 0].min(-1) - xmin,
                xmax - c[..., 0].max(-1),
                c[..., 1].min(-1) - ymin,
                ymax - c[..., 1].max(-1),
            ],
            axis=0,
        )

    def _bodies(self, poses, shrink=0.0):
        """Robot bodies as shapely geometry, plus the radius still to subtract."""
        if self.robot_kind == "disc":
            return shapely.points(poses[:, :2]), self.radius - shrink
        if self.robot_kind == "footprint":
            return footprint_bodies(self.points, poses, shrink), 0.0
        return shapely.polygons(robot_corners(self.size, poses, shrink)), 0.0

    def distances_by_kind(self, poses) -> tuple[np.ndarray, np.ndarray]:
        """Distances (n,) from the robot body to the polygonal obstacles and to the discs.

        Each is 0 where they meet and inf when there is no obstacle of that kind.
        """
        poses = np.atleast_2d(np.asarray(poses, dtype=float))
        body, r = self._bodies(poses)
        d_poly = np.full(len(poses), np.inf)
        d_disc = np.full(len(poses), np.inf)
        if self.polys is not None:
            d_poly = shapely.distance(body, self.polys) - r
        for center, dr in self.discs:
            d_disc = np.minimum(d_disc, shapely.distance(body, shapely.Point(center)) - r - dr)
        return np.maximum(d_poly, 0.0), np.maximum(d_disc, 0.0)

    def obstacle_distance(self, poses) -> np.ndarray:
        """Distance (n,) from the robot body to the nearest obstacle, 0 when they meet."""
        return np.minimum(*self.distances_by_kind(poses))

    def bounds_margin(self, poses) -> np.ndarray:
        """How far (n,) the robot body is inside the bounds (negative: outside)."""
        return self._bounds_margin(np.atleast_2d(np.asarray(poses, dtype=float)))

    def clearance(self, poses) -> np.ndarray:
        """min(bounds margin, obstacle distance): > 0 free by that much (n,)."""
        poses = np.atleast_2d(np.asarray(poses, dtype=float))
        return np.minimum(self._bounds_margin(poses), self.obstacle_distance(poses))

    def robustly_colliding(self, poses, eps=1e-6) -> np.ndarray:
        """True where the robot overlaps an obstacle or leaves the bounds by more than eps."""
        poses = np.atleast_2d(np.asarray(poses, dtype=float))
        out = self._bounds_margin(poses) < -eps
        body, r = self._bodies(poses, shrink=eps)
        if self.polys is not None:
            if self.robot_kind == "disc":
                out |= shapely.distance(body, self.polys) < r
            else:
                out |= shapely.intersects(body, self.polys)
        for center, dr in self.discs:
            out |= shapely.distance(body, shapely.Point(center)) < r + dr
        return out

    def robustly_free(self, poses, eps=1e-6) -> np.ndarray:
        return self.clearance(poses) > eps


def mover_reference_distance(robot: dict, pose, mover_shape: str, mover_param, xy) -> tuple[float, bool]:
    """Distance between one robot pose and one mover, and whether they overlap.

    ``robot`` is the scene's robot mapping; ``mover_param`` the radius or the (w, h) size.
    Returns ``(distance >= 0, overlap)``; ``overlap`` is the shapely verdict (interiors meet).
    """
    if "disc" in robot:
        body, r = shapely.Point(pose[0], pose[1]), float(robot["disc"])
    elif "footprint" in robot:
        body, r = footprint_bodies(robot["footprint"], [pose])[0], 0.0
    else:
        body, r = shapely.polygons(robot_corners(robot["box"], [pose]))[0], 0.0
    if mover_shape == "disc":
        other, r2 = shapely.Point(xy[0], xy[1]), float(mover_param)
    else:
        w, h = mover_param
        other, r2 = shapely.box(xy[0] - w / 2, xy[1] - h / 2, xy[0] + w / 2, xy[1] + h / 2), 0.0
    d = shapely.distance(body, other) - r - r2
    if r == 0 and r2 == 0:
        overlap = shapely.intersection(body, other).area > 0
    else:
        overlap = d < 0
    return max(d, 0.0), overlap


def prism_mesh(footprint: shapely.Polygon, height: float = 1.0):
    """A closed trimesh prism over a simple polygon (no triangulation engine needed)."""
    import trimesh

    footprint = shapely.geometry.polygon.orient(footprint, 1.0)
    tris = [
        np.asarray(t.exterior.coords)[:3]
        for t in shapely.get_parts(shapely.constrained_delaunay_triangles(footprint))
    ]
    verts, faces = [], []
    for tri in tris:
        area2 = (tri[1, 0] - tri[0, 0]) * (tri[2, 1] - tri[0, 1]) - (tri[2, 0] - tri[0, 0]) * (
            tri[1, 1] - tri[0, 1]
        )
        if area2 < 0:
            tri = tri[::-1]
        k = len(verts)
        verts += [[*p, height] for p in tri] + [[*p, 0.0] for p in tri[::-1]]
        faces += [[k, k + 1, k + 2], [k + 3, k + 4, k + 5]]
    ring = np.asarray(footprint.exterior.coords)
    for p, q in zip(ring[:-1], ring[1:], strict=True):
        k = len(verts)
        verts += [[*p, 0.0], [*q, 0.0], [*q, height], [*p, height]]
        faces += [[k, k + 1, k + 2], [k, k + 2, k + 3]]
    return trimesh.Trimesh(np.array(verts), np.array(faces), process=True)


def mover_position(mover: dict, t: float) -> tuple[np.ndarray, bool]:
    """Where a scene document's mover is at time ``t``, and whether it is there (written
    afresh from the format's definition, docs/formats.md: constant speed along the
    polyline, loop / bounce / once, ``offset`` metres at t = 0; or ``trajectory`` rows)."""
    if "trajectory" in mover:
        rows = np.asarray(mover["trajectory"], dtype=float)
        present = rows[0, 0] <= t <= rows[-1, 0]
        return np.array([np.interp(t, rows[:, 0], rows[:, 1]), np.interp(t, rows[:, 0], rows[:, 2])]), present
    pts = np.asarray(mover["path"], dtype=float)
    mode = mover.get("mode", "loop")
    if mode == "loop" and np.any(pts[0] != pts[-1]):
        pts = np.vstack([pts, pts[:1]])
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
    length = cum[-1]
    s = float(mover.get("offset", 0.0)) + float(mover.get("speed", 0.0)) * t
    if mode == "loop":
        s = s % length
    elif mode == "bounce":
        s = s % (2 * length)
        s = 2 * length - s if s > length else s
    else:
        s = min(max(s, 0.0), length)
    return np.array([np.interp(s, cum, pts[:, 0]), np.interp(s, cum, pts[:, 1])]), True


def reference_violation(doc: dict, waypoints, hold: float = 0.0, substeps: int = 8) -> str:
    """Why a trajectory breaks the contract, judged with this module only ("" if it does not).

    Checks the speed bound (the contract metric, written afresh), the static clearance
    (``robot.clearance``) and the distance to every mover (``robot.mover_clearance``) at
    ``substeps`` points inside every row-to-row motion and over the ``hold`` after the
    arrival. An oracle for answers that gfuzzy's own checker has already accepted.
    """
    robot = doc["robot"]
    wp = np.asarray(waypoints, dtype=float)
    ref = Reference(doc)
    keep, keep_movers = float(robot.get("clearance", 0.0)), float(robot.get("mover_clearance", 0.0))
    circum = float(robot["disc"]) if "disc" in robot else 0.5 * math.hypot(*robot["box"])
    vmax = float(robot["vmax"])
    times, poses = [wp[0, 0]], [wp[0, 1:]]
    for a, b in zip(wp[:-1], wp[1:], strict=True):
        d = b[1:] - a[1:]
        turn = abs(math.remainder(float(d[2]), 2 * math.pi)) if len(d) == 3 else 0.0
        if math.hypot(d[0], d[1]) + turn * circum > vmax * (b[0] - a[0]) * (1 + 1e-6) + 1e-9:
            return f"too fast between t={a[0]:g} and t={b[0]:g}"
        f = np.arange(1, substeps + 1) / substeps
        times.extend(a[0] + f * (b[0] - a[0]))
        poses.extend(interpolate(a[1:], b[1:], f))
    if hold > 0:
        extra = wp[-1, 0] + np.linspace(0.0, hold, 4 * substeps + 1)[1:]
        times.extend(extra)
        poses.extend([wp[-1, 1:]] * len(extra))
    poses = np.asarray(poses)
    bad = np.nonzero(ref.clearance(poses) < keep - 1e-6)[0]
    if bad.size:
        return f"static clearance below {keep:g} at t={times[bad[0]]:g}"
    for mover in doc.get("movers") or []:
        shape = "disc" if "disc" in mover else "box"
        param = mover["disc"] if shape == "disc" else mover["box"]
        for t, pose in zip(times, poses, strict=True):
            xy, present = mover_position(mover, float(t))
            if not present:
                continue
            dist, overlap = mover_reference_distance(robot, pose, shape, param, xy)
            if overlap or dist < keep_movers - 1e-6:
                return f"within {keep_movers:g} of mover {mover['name']!r} at t={t:g}"
    return ""


def contract_metric(a, b, circumradius: float) -> np.ndarray:
    """The contract's distance between poses (written afresh): the xy distance plus, for
    poses with a heading, the shorter turn times the robot's circumradius. Broadcasts."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    d = np.hypot(b[..., 0] - a[..., 0], b[..., 1] - a[..., 1])
    if a.shape[-1] == 3:
        turn = np.abs(np.remainder(b[..., 2] - a[..., 2] + math.pi, 2 * math.pi) - math.pi)
        d = d + turn * circumradius
    return d


def _robot_circumradius(robot: dict) -> float:
    return float(robot["disc"]) if "disc" in robot else 0.5 * math.hypot(*robot["box"])


def _segment_free(ref: Reference, a, b, keep: float, circumradius: float, spacing: float = 0.005) -> bool:
    """The straight motion a -> b keeps ``keep`` from the obstacles (the bounds are not held
    to it) and stays in bounds, judged at points ``spacing`` apart in the contract metric (an oracle, not a proof)."""
    n = max(2, int(math.ceil(float(contract_metric(a, b, circumradius)) / spacing)) + 1)
    poses = interpolate(a, b, np.linspace(0.0, 1.0, n))
    if ref.robustly_colliding(poses, eps=1e-9).any() or (ref.bounds_margin(poses) < 0.0).any():
        return False
    return bool(np.all(ref.obstacle_distance(poses) >= keep - 1e-9))


def _mover_distances(robot: dict, poses: np.ndarray, mover: dict, xy: np.ndarray) -> np.ndarray:
    """Distances (n,) from the robot at ``poses`` to a mover centred at ``xy`` (<= 0: they
    meet). Discs analytically, an axis-aligned box mover against a disc robot by the
    clamped offset, a box robot through shapely."""
    if "disc" in robot and "disc" in mover:
        return np.hypot(poses[:, 0] - xy[0], poses[:, 1] - xy[1]) - float(robot["disc"]) - float(mover["disc"])
    if "disc" in robot:
        w, h = mover["box"]
        dx = np.maximum(np.abs(poses[:, 0] - xy[0]) - 0.5 * w, 0.0)
        dy = np.maximum(np.abs(poses[:, 1] - xy[1]) - 0.5 * h, 0.0)
        return np.hypot(dx, dy) - float(robot["disc"])
    bodies = shapely.polygons(robot_corners(robot["box"], poses))
    if "disc" in mover:
        return shapely.distance(bodies, shapely.Point(xy[0], xy[1])) - float(mover["disc"])
    w, h = mover["box"]
    box = shapely.box(xy[0] - w / 2, xy[1] - h / 2, xy[0] + w / 2, xy[1] + h / 2)
    d = shapely.distance(bodies, box)
    return np.where(shapely.intersection(bodies, box).area > 0, -1.0, d)


def _mover_speed(mover: dict, t: float, half: float) -> float:
    """The mover's largest speed within [t - half, t + half] (docs/formats.md: ``speed``
    for a path; the fastest row-to-row segment of a ``trajectory`` overlapping the window)."""
    if "trajectory" not in mover:
        return float(mover.get("speed", 0.0))
    rows = np.asarray(mover["trajectory"], dtype=float)
    if len(rows) < 2:
        return 0.0
    best = 0.0
    for a, b in zip(rows[:-1], rows[1:], strict=True):
        if a[0] < t + half and b[0] > t - half:
            best = max(best, math.hypot(b[1] - a[1], b[2] - a[2]) / (b[0] - a[0]))
    return best


def _safe_table(doc: dict, poses: np.ndarray, t0: float, dt: float, steps: int) -> np.ndarray:
    """(len(poses), steps + 1) bool: the robot at each pose is safe at each step.

    The rule of docs/formats.md section 3, written afresh: at ``t_n = t0 + n dt`` every mover
    present at some time in ``[t_n - dt/2, t_n + dt/2]`` (a path mover always is; a
    ``trajectory`` mover between its first and last row), taken where it is at ``t_n``
    clamped to its rows, must be at least ``(vmax + v_mover) dt / 2 + mover_clearance`` away.
    """
    robot = doc["robot"]
    vmax = float(robot["vmax"])
    keep = float(robot.get("mover_clearance", 0.0))
    half = 0.5 * dt
    safe = np.ones((len(poses), steps + 1), dtype=bool)
    for mover in doc.get("movers") or []:
        rows = np.asarray(mover["trajectory"], dtype=float) if "trajectory" in mover else None
        for n in range(steps + 1):
            t = t0 + n * dt
            if rows is not None and not (t + half >= rows[0, 0] and t - half <= rows[-1, 0]):
                continue
            xy, _ = mover_position(mover, float(np.clip(t, rows[0, 0], rows[-1, 0])) if rows is not None else t)
            margin = (vmax + _mover_speed(mover, t, half)) * half + keep
            safe[:, n] &= _mover_distances(robot, poses, mover, xy) >= margin
    return safe


def brute_force_steps(
    doc: dict, vertices, edges, start, goal, t0: float, dt: float, horizon_steps: int,
    hold_steps: int = 0, connect_k: int = 10,
) -> int | None:
    """The fewest steps from ``start`` to ``goal`` on the roadmap in discretized time, by a
    breadth-first sweep of the whole time-expanded graph (no intervals, no heuristic);
    None when the goal is not reached within ``horizon_steps``.

    Built from the scene document and the roadmap's ``vertices`` (n, d) and ``edges`` (m, 2)
    only, sharing no code with the planner (docs/planner.md, docs/formats.md section 3):

    * start and goal join the free ones among their ``connect_k`` nearest vertices in the
      contract metric (the nearest free one among the ``4 connect_k`` nearest if none of
      those is free), and each other when the straight motion between them is free, judged
      with :class:`Reference` keeping ``robot.clearance``;
    * every edge is cut into ``k = ceil(length / (vmax dt (1 - 1e-9)))`` equal steps (a
      step moves at most vmax dt; the planner's guard against rounding up the speed);
    * one step moves to the next point of an edge or waits; a (point, step) pair must be
      safe by :func:`_safe_table`'s rule; the goal is accepted where it stays safe
      ``hold_steps`` more steps; the start must be safe at step 0 (the planner decides a
      first motion from a start the margin refuses exactly: it may then do better).
    """
    robot = doc["robot"]
    r = _robot_circumradius(robot)
    vmax = float(robot["vmax"])
    keep = float(robot.get("clearance", 0.0))
    ref = Reference(doc)
    V = np.asarray(vertices, dtype=float)
    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    nv = len(V)
    s_id, g_id = nv, nv + 1
    points = [*V, start, goal]
    links = [(int(a), int(b)) for a, b in np.asarray(edges, dtype=int).reshape(-1, 2)]
    for pose, node in ((start, s_id), (goal, g_id)):
        order = np.argsort(contract_metric(V, pose, r), kind="stable")
        joined = 0
        for tried, i in enumerate(order[: 4 * connect_k].tolist()):
            if tried >= connect_k and joined:
                break
            if _segment_free(ref, pose, V[i], keep, r):
                links.append((node, i))
                joined += 1
    if _segment_free(ref, start, goal, keep, r):
        links.append((s_id, g_id))
    step_len = vmax * dt * (1.0 - 1e-9)
    pairs = []
    for a, b in links:
        pa, pb = points[a], points[b]
        k = max(1, int(math.ceil(float(contract_metric(pa, pb, r)) / step_len)))
        chain = [a]
        for j in range(1, k):
            points.append(interpolate(pa, pb, [j / k])[0])
            chain.append(len(points) - 1)
        chain.append(b)
        pairs += list(zip(chain[:-1], chain[1:], strict=True))
    poses = np.asarray(points)
    from scipy.sparse import coo_matrix

    p = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    n = len(poses)
    adj = coo_matrix((np.ones(2 * len(p)), (np.r_[p[:, 0], p[:, 1]], np.r_[p[:, 1], p[:, 0]])), shape=(n, n)).tocsr()
    safe = _safe_table(doc, poses, t0, dt, horizon_steps + hold_steps)
    if not safe[s_id, 0]:
        return None
    here = np.zeros(n, dtype=bool)
    here[s_id] = True
    for step in range(horizon_steps + 1):
        if here[g_id] and safe[g_id, step : step + hold_steps + 1].all():
            return step
        if step == horizon_steps:
            break
        here = (here | (adj @ here.astype(float) > 0)) & safe[:, step + 1]
        if not here.any():
            return None
    return None
