"""A box or footprint robot touching a static obstacle: a pose or a translation a rounding
into one is touching (``gfuzzy check`` tolerates 1e-9), a penetration FCL's collision test
misses (up to ~3e-7 m) is not, and whatever the planner accepts passes the check.

Brute force: poses near contact at faces and corners of a rotated box, a concave polygon,
a disc and a map's blocked cells, depths from -1e-6 to +1e-6 m (exactly 0 and a rounding
included), a box and an L footprint at aligned and random headings.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gfuzzy.check.check import check_trajectory
from gfuzzy.collision.geometry import StaticGeometry
from gfuzzy.planner.planner import Planner, PlanOptions, query_problem
from gfuzzy.roadmap.roadmap import Roadmap
from gfuzzy.scene.scene import parse_scene

LFOOT = [[0.3, -0.2], [0.3, 0.35], [0.05, 0.35], [0.05, 0.2], [-0.3, 0.2], [-0.3, -0.2]]
POLY = [[4.5, 2.5], [5.6, 2.5], [5.6, 3.6], [5.2, 3.6], [5.2, 2.9], [4.5, 2.9]]
WALL = {"center": [3.0, 1.0], "size": [0.4, 1.0], "angle": 0.5}


def _scene(robot):
    doc = {
        "version": 1, "name": "touch", "bounds": [0, 0, 7, 5], "robot": robot, "movers": [], "queries": [],
        "obstacles": [{"box": WALL}, {"polygon": POLY}, {"disc": {"center": [1.5, 3.5], "radius": 0.3}}],
    }  # fmt: skip
    return parse_scene(doc)


def _edges(scene):
    """(point, inward unit normal, unit direction, length) of every polygon edge."""
    out = []
    for ob in scene.obstacles[:2]:
        pts = np.asarray(ob.vertices() if hasattr(ob, "vertices") else ob.points, dtype=float)
        area2 = np.sum(pts[:, 0] * np.roll(pts[:, 1], -1) - np.roll(pts[:, 0], -1) * pts[:, 1])
        for p, q in zip(pts, np.roll(pts, -1, axis=0), strict=True):
            u = (q - p) / np.hypot(*(q - p))
            n = np.array([-u[1], u[0]]) if area2 > 0 else np.array([u[1], -u[0]])  # inward
            out.append((p, n, u, float(np.hypot(*(q - p)))))
    return out


def _depths(rng, k):
    tiny = [0.0, 1e-17, -1e-17, 4e-17]
    d = [tiny[i % 4] for i in range(k // 4)]
    d += list(rng.choice([-1.0, 1.0], k - len(d)) * 10.0 ** rng.uniform(-12, -6, k - len(d)))
    return d


def _near_contact(scene, rng, k):
    """Poses whose deepest point lies ``depth`` into an obstacle (negative: clear of it),
    with the depth: a body vertex into a face, a body face flush with it, an obstacle's
    corner into a body face, the body at a disc."""
    robot = scene.robot
    edges = _edges(scene)
    out = []
    for depth in _depths(rng, k):
        kind = rng.integers(4)
        if kind == 3:  # the disc obstacle: the nearest body point at depth
            head = rng.uniform(-math.pi, math.pi)
            phi = rng.uniform(-math.pi, math.pi)
            n = np.array([math.cos(phi), math.sin(phi)])  # from the disc's centre outwards
            c = robot.corners(np.array([[0.0, 0.0, head]]))[0]
            far = float(np.max(c @ -n))  # the body's extent towards the disc
            xy = np.array([1.5, 3.5]) + n * (0.3 - depth + far)
            out.append((np.array([*xy, head]), depth))
            continue
        p, n, u, length = edges[rng.integers(len(edges))]
        base = p + u * rng.uniform(0.0, length) * (kind != 2)
        if kind == 0:  # a face flush with the obstacle's face: aligned headings
            head = math.atan2(u[1], u[0]) + rng.integers(4) * 0.5 * math.pi
        else:
            head = rng.uniform(-math.pi, math.pi)
        c = robot.corners(np.array([[0.0, 0.0, head]]))[0]
        if kind == 2:  # the obstacle's corner p pushed into the body's face facing it
            m = -n if rng.integers(2) else np.array([math.cos(a := rng.uniform(0, 6.3)), math.sin(a)])
            ref = float(np.max(c @ m))  # the body's extent along -m: its face towards p
            xy = p - m * (ref - depth)
            out.append((np.array([*xy, head]), depth))
            continue
        deep = float(np.max(c @ n))  # the body's farthest reach along the inward normal
        xy = base - n * (deep - depth)
        out.append((np.array([*xy, head]), depth))
    return out


def _overlap(scene, pose) -> float:
    """The body's overlap with the obstacles, independently: its area with the polygons,
    its depth into the disc."""
    import shapely

    body = shapely.Polygon(scene.robot.corners(pose[None])[0])
    polys = [shapely.Polygon(scene.obstacles[0].vertices()), shapely.Polygon(POLY)]
    area = sum(body.intersection(p).area for p in polys)
    return max(area, 0.3 - body.distance(shapely.Point(1.5, 3.5)))


ROBOTS = [{"box": [0.6, 0.4], "vmax": 0.5}, {"footprint": LFOOT, "vmax": 0.5}]


@pytest.mark.parametrize("robot", ROBOTS, ids=["box", "footprint"])
def test_near_contact_poses_and_translations_pass_the_check(robot):
    """Every near-contact pose the planner takes for valid, and every translation from it
    it certifies, passes ``gfuzzy check``; a pose whose deepest point is 0 m or a rounding
    into an obstacle (on paper: touching) is valid. Before: a box flush with a rotated wall
    by a rounding was ``invalid_query`` while the check accepted it."""
    scene = _scene(robot)
    geo = StaticGeometry(scene)
    rng = np.random.default_rng(11)
    accepted = moved = 0
    for pose, depth in _near_contact(scene, rng, 400):
        if geo._bounds_clearance1(pose) < 0:
            continue
        ok = query_problem(geo, pose, pose) == ""
        alone = check_trajectory(scene, np.array([[0.0, *pose]]))
        if abs(depth) <= 1e-16 and _overlap(scene, pose) <= 1e-15:  # touching, elsewhere clear
            assert ok, (pose.tolist(), depth)
        if not ok:
            continue
        accepted += 1
        assert alone.valid, (pose.tolist(), depth, alone.reason)
        phi = rng.uniform(-math.pi, math.pi)
        to = pose + np.array([math.cos(phi), math.sin(phi), 0.0]) * rng.uniform(0.01, 0.5)
        if geo._bounds_clearance1(to) >= 0 and geo.motion_free(pose, to):
            moved += 1
            t = float(np.hypot(*(to - pose)[:2])) / 0.4
            rep = check_trajectory(scene, np.array([[0.0, *pose], [t, *to]]))
            assert rep.valid, (pose.tolist(), to.tolist(), depth, rep.reason)
    assert accepted > 100 and moved > 30, (accepted, moved)


@pytest.mark.parametrize("kinematics", ["holonomic", "unicycle"])
@pytest.mark.parametrize("robot", ROBOTS, ids=["box", "footprint"])
def test_a_start_flush_with_a_rotated_wall_by_a_rounding_is_planned_from(robot, kinematics):
    """A box (or footprint) whose back face lies on a rotated wall's face, a rounding into
    it, drives away, the answer passing the check; 1e-6 m into it is ``invalid_query``.
    Before: ``invalid_query`` ("collides with a static obstacle") at most offsets."""
    robot = {**robot, "kinematics": kinematics, **({"wmax": 1.0} if kinematics == "unicycle" else {})}
    scene = _scene(robot)
    ang = WALL["angle"]
    c, s = math.cos(ang), math.sin(ang)
    back = -float(np.min(np.asarray(LFOOT)[:, 0])) if "footprint" in robot else 0.3
    # a vertex 1 m out from the wall at the start's heading: a holonomic body at contact
    # leaves by a translation (a turn from there is not certified)
    verts = np.array([[3.0 - c - 0.3 * s, 1.0 - s + 0.3 * c, math.atan2(-s, -c)], [1.2, 1.9, 0.0], [3.5, 4.5, 0.0]])
    lengths = np.hypot(*(verts[1:, :2] - verts[:-1, :2]).T) + np.abs(np.diff(verts[:, 2])) * scene.robot.circumradius
    rm = Roadmap(verts, np.array([[0, 1], [1, 2]]), lengths, scene.name,
                 scene.static_hash, scene.robot.circumradius)  # fmt: skip
    solved = 0
    for off in np.linspace(-0.3, 0.3, 7):
        # the body's heading points away from the wall (-x of the wall), its back on the face
        start = [3.0 + c * (-0.2 - back) + s * off, 1.0 + s * (-0.2 - back) - c * off, math.atan2(-s, -c)]
        res = Planner(scene, rm).plan(start, [3.5, 4.5, 0.0], 0.0, PlanOptions())
        assert res.status.value != "invalid_query", (off, res.message)
        if res.solved:
            solved += 1
            rep = check_trajectory(scene, res.trajectory.waypoints)
            assert rep.valid, (off, rep.reason)
        start[0] += c * 1e-6
        start[1] += s * 1e-6
        assert Planner(scene, rm).plan(start, [3.5, 4.5, 0.0]).status.value == "invalid_query"
    assert solved >= 5, solved


def test_a_footprint_touching_a_polygons_face_at_a_vertex_is_valid():
    """The L footprint's vertex on the polygon's face x = 5.6 (4e-17 m into it): valid, as
    the check says. Its core (1e-5 m inside the body) was a prism as tall as the obstacles',
    their caps in one plane, and FCL's collision test found it 1.4e-5 m off the face in
    collision (so "collides with a static obstacle"; 2 of 12000 poses of a brute force)."""
    scene = _scene(ROBOTS[1])
    pose = np.array([5.959954863428175, 2.503238010925636, -0.6457138723069202])
    assert _overlap(scene, pose) == 0.0
    assert query_problem(StaticGeometry(scene), pose, pose) == ""
    assert check_trajectory(scene, np.array([[0.0, *pose]])).valid




@pytest.mark.parametrize("robot", [{"box": [0.4, 0.2], "vmax": 1.0}, {"footprint": LFOOT, "vmax": 1.0}], ids=["box", "footprint"])
def test_a_body_touching_the_bounds_by_a_rounding_is_inside_them(robot):
    """The bounds' distance is closed-form: a body placed at decimal coordinates to touch a
    side (a box 0.4 long at x = 4.8 in bounds 5 wide) is out of it by a rounding (up to
    4e-16 m here), which counts as touching, as the check says; 1e-6 m out is still out,
    and the query says by how much."""
    scene = _scene(robot)
    geometry = StaticGeometry(scene)
    goal = np.array([3.5, 4.5, 0.0])
    rounded = 0
    for heading in (0.0, math.pi / 2, math.pi, -math.pi / 2):
        c = scene.robot.corners(np.array([[0.0, 0.0, heading]]))[0]
        for k in range(20):
            y = round(1.0 + 0.13 * k, 2)
            for pose in (
                np.array([round(7.0 - c[:, 0].max(), 6), y, heading]),
                np.array([round(-c[:, 0].min(), 6), y, heading]),
                np.array([y + 3.0, round(5.0 - c[:, 1].max(), 6), heading]),  # clear of the wall
                np.array([y + 3.0, round(-c[:, 1].min(), 6), heading]),
            ):
                body = scene.robot.corners(pose[None])[0]
                raw = min(body[:, 0].min(), 7.0 - body[:, 0].max(), body[:, 1].min(), 5.0 - body[:, 1].max())
                rounded += raw < 0  # out of the bounds by a rounding
                assert float(geometry.bounds_clearance(pose[None])[0]) >= 0.0, pose
                assert geometry._bounds_clearance1(pose) >= 0.0, pose
                assert query_problem(geometry, pose, goal) == "", pose
    assert rounded > 0  # the case is met
    out = np.array([7.0 - c[:, 0].max() + 1e-6, 2.5, -math.pi / 2])
    assert float(geometry.bounds_clearance(out[None])[0]) < 0
    assert "out of bounds (by 1e-06 m)" in query_problem(geometry, out, goal)


@pytest.mark.parametrize("robot", [{"box": [0.4, 0.2], "vmax": 1.0}, {"footprint": LFOOT, "vmax": 1.0}], ids=["box", "footprint"])
def test_a_holonomic_end_touching_the_bounds_in_a_corner_is_bridged_to_the_roadmap(robot):
    """A body in a corner of the bounds, touching two sides by a rounding (the user's decimal
    pose), turns nowhere and meets no roadmap vertex at its own heading: the bridge's rays
    start with a step certified from contact (they advanced by the clearance, 0 there, and
    so never left), and the answer passes the check (before: ``no_path``)."""
    from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap

    scene = _scene(robot)
    rm = build_roadmap(scene, RoadmapOptions(vertices=100, seed=1))
    c = scene.robot.corners(np.array([[0.0, 0.0, 0.0]]))[0]
    corner = np.array([round(7.0 - c[:, 0].max(), 6), round(5.0 - c[:, 1].max(), 6), 0.0])  # top right
    assert StaticGeometry(scene).bounds_clearance(corner[None])[0] == 0.0
    for start, goal in ((corner, np.array([2.0, 2.5, 0.3])), (np.array([2.0, 2.5, 0.3]), corner)):
        res = Planner(scene, rm).plan(start, goal, 0.0, PlanOptions())
        assert res.solved, res.message
        rep = check_trajectory(scene, res.trajectory.waypoints)
        assert rep.valid, rep.reason
