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
from gfuzzy.check.depth import _within_tol
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
    rm = build_roadmap(scene, RoadmapOptions(vertices=40, seed=1))
    c = scene.robot.corners(np.array([[0.0, 0.0, 0.0]]))[0]
    corner = np.array([round(7.0 - c[:, 0].max(), 6), round(5.0 - c[:, 1].max(), 6), 0.0])  # top right
    assert StaticGeometry(scene).bounds_clearance(corner[None])[0] == 0.0
    for start, goal in ((corner, np.array([2.0, 2.5, 0.3])), (np.array([2.0, 2.5, 0.3]), corner)):
        res = Planner(scene, rm).plan(start, goal, 0.0, PlanOptions())
        assert res.solved, res.message
        rep = check_trajectory(scene, res.trajectory.waypoints)
        assert rep.valid, rep.reason


# ---- the overlap's depth (gfuzzy check and the planner's exact measure)

SPIKE_HALF = 0.45 * math.tan(math.radians(0.5))  # a 1-degree spike 0.45 long in front
SPIKE = [[0.6, 0.0], [0.15, SPIKE_HALF], [0.15, 0.2], [-0.2, 0.2], [-0.2, -0.2], [0.15, -0.2], [0.15, -SPIKE_HALF]]
BOX, LONG = {"box": [0.6, 0.4], "vmax": 0.5}, {"box": [2.5, 0.4], "vmax": 0.5}
REACH = 0.3 * math.cos(math.pi / 4) + 0.2 * math.sin(math.pi / 4)  # the 45-degree box's corner


def _walls(robot):
    """A long wall (top face y = 1) and a block (left face x = 10.5)."""
    return parse_scene({
        "version": 1, "name": "depth", "bounds": [0, 0, 12, 4], "robot": robot, "movers": [], "queries": [],
        "obstacles": [{"box": {"center": [6.0, 0.5], "size": [10.0, 1.0]}}, {"box": {"center": [11.0, 2.5], "size": [1.0, 3.0]}}],
    })  # fmt: skip


DEPTH_CASES = {  # name: (robot, rows [t, x, y, heading], valid)
    "corner 1e-6 m in": (BOX, [[0.0, 10.5 - REACH + 1e-6, 2.0, math.pi / 4]], False),
    "corner 3e-5 m in": (BOX, [[0.0, 10.5 - REACH + 3e-5, 2.0, math.pi / 4]], False),
    "spike's tip 1e-7 m in": ({"footprint": SPIKE, "vmax": 0.5}, [[0.0, 9.9 + 1e-7, 2.0, 0.0]], False),
    "spike's tip 5e-8 m in": ({"footprint": SPIKE, "vmax": 0.5}, [[0.0, 9.9 + 5e-8, 2.0, 0.0]], False),
    "2.5 m face 1e-17 m in": (LONG, [[0.0, 3.0, 1.2 - 1e-17, 0.0]], True),
    "2.5 m face 4.5e-10 m in": (LONG, [[0.0, 3.0, 1.2 - 4.5e-10, 0.0]], True),
    "2.5 m face 2e-9 m in": (LONG, [[0.0, 3.0, 1.2 - 2e-9, 0.0]], False),
    "5 m slide 1e-10 m in": (LONG, [[0.0, 2.0, 1.2 - 1e-10, 0.0], [10.0, 7.0, 1.2 - 1e-10, 0.0]], True),
    "5 m slide 4.5e-10 m in": (LONG, [[0.0, 2.0, 1.2 - 4.5e-10, 0.0], [10.0, 7.0, 1.2 - 4.5e-10, 0.0]], True),
}


@pytest.mark.parametrize("case", list(DEPTH_CASES))
def test_check_measures_an_overlap_by_its_depth(case):
    """``gfuzzy check`` measures a box's or footprint's overlap with a polygon by its depth:
    a corner or a spike's tip a micrometre in is a collision, a face a rounding in touches
    however long it is. Before: by its area (in m², against the 1e-9 m tolerance), so a
    corner 3e-5 m in and a spike's tip 1e-6 m in were valid, and a 2.5 m box flush 4.5e-10
    m in (area 1.1e-9) was not."""
    robot, rows, valid = DEPTH_CASES[case]
    rep = check_trajectory(_walls(robot), np.array(rows))
    assert rep.valid == valid, rep.reason


@pytest.mark.parametrize("case", list(DEPTH_CASES))
def test_the_planner_measures_an_overlap_by_its_depth(case):
    """The planner's exact measure is the check's: the same poses and slides are valid
    (``clearance1`` >= 0, ``motion_free``). Before: a slide 1e-10 m into a wall was
    refused beyond ~5 m (the overlaps' area summed over the sweep), a 2.5 m face 4.5e-10
    m in was refused, and a 1-degree spike's tip 5e-8 m in was accepted (its overlap's
    thickness, 2A/P, is not its depth)."""
    robot, rows, valid = DEPTH_CASES[case]
    geo = StaticGeometry(_walls(robot))
    poses = np.array(rows)[:, 1:]
    ok = all(geo.clearance1(p) >= 0 for p in poses)
    if len(poses) == 2:
        ok = ok and geo.motion_free(poses[0], poses[1])
    assert ok == valid


def test_a_thin_obstacle_across_the_body_is_a_collision():
    """A polygon 1.5e-9 m thick across the box: no corner of either lies inside the other
    and the overlap is 1.5e-9 m thick, but the wall runs 0.2 m deep through the body. Before:
    valid (its area, 9e-10 m², under the tolerance)."""
    robot = {"box": [0.6, 0.4], "vmax": 0.5}
    scene = parse_scene({
        "version": 1, "name": "thin", "bounds": [0, 0, 6, 2], "robot": robot, "movers": [], "queries": [],
        "obstacles": [{"polygon": [[2, 0.5], [4, 0.5], [4, 0.5 + 1.5e-9], [2, 0.5 + 1.5e-9]]}],
    })  # fmt: skip
    pose = np.array([3.0, 0.5, 0.3])
    rep = check_trajectory(scene, np.array([[0.0, *pose]]))
    assert not rep.valid and "penetration 0.2" in rep.reason, rep.reason
    assert StaticGeometry(scene).clearance1(pose) < 0


@pytest.mark.parametrize("thickness", [0.01, 0.3])
def test_an_overlap_deeper_than_the_tolerance_reports_its_depth_not_a_lower_bound(thickness):
    """A wall 1 cm (or 30 cm) thick across the box: the overlap's vertices are on both
    outlines (0 deep) and its thickness is about the wall's, but the wall's face runs
    0.2 m deep through the body; the check reports 0.2, as for a wall 1.5e-9 m thick.
    Before: the edges were split only until a point deeper than the tolerance was found,
    so the report read the piece's thickness (penetration 0.00984 for 1 cm)."""
    robot = {"box": [0.6, 0.4], "vmax": 0.5}
    scene = parse_scene({
        "version": 1, "name": "thick", "bounds": [0, 0, 6, 2], "robot": robot, "movers": [], "queries": [],
        "obstacles": [{"polygon": [[2, 0.5], [4, 0.5], [4, 0.5 + thickness], [2, 0.5 + thickness]]}],
    })  # fmt: skip
    rep = check_trajectory(scene, np.array([[0.0, 3.0, 0.5, 0.3]]))
    assert not rep.valid and "penetration 0.2)" in rep.reason, rep.reason


def _penetration(reason: str) -> float:
    """The penetration a collision's reason reports (the deepest, or at least that)."""
    return float(reason.split("(penetration ")[1].removeprefix("at least ").split(" ")[0].rstrip(";)"))


NEEDLE_X = 10.5 - 0.6 + 7e-4  # the spike's tip 7e-4 m into the block at heading 0


@pytest.mark.parametrize(
    "rows, certain",
    [
        ([[0.0, NEEDLE_X, 2.0, -0.5], [7.0, NEEDLE_X, 2.0, 0.2]], True),  # a turn: deepest at heading 0
        ([[0.0, NEEDLE_X, 2.0, -0.5], [7.0, NEEDLE_X, 2.0, 0.2], [8.0, NEEDLE_X - 0.3, 2.0, 0.2]], True),
        # sliding onto the long wall's top, the tip 7e-4 m into it the rest of the way (an even depth:
        # the search stops at its budget, "at least")
        ([[0.0, 0.5, 1.6 - 7e-4, -math.pi / 2], [18.0, 9.5, 1.6 - 7e-4, -math.pi / 2]], False),
    ],
    ids=["turn", "turn-and-back", "slide"],
)
def test_a_needle_7e_4_m_into_a_wall_reads_7e_4(rows, certain):
    """A spike's tip swept 7e-4 m into a wall: the first contact in time is found at its onset
    (1.1e-9 deep); the penetration reported is the deepest overlap over the trajectory, 7e-4,
    searched, not the onset's nor the deepest of the instants the bisection happened to
    sample. Before: "penetration 1.08e-09; 0.000595 deep ..., the deepest overlap sampled"."""
    rep = check_trajectory(_walls({"footprint": SPIKE, "vmax": 0.5}), np.array(rows))
    assert not rep.valid
    assert abs(_penetration(rep.reason) - 7e-4) < 1e-6, rep.reason
    assert ("at least" not in rep.reason) == certain, rep.reason
    assert check_trajectory(_walls({"footprint": SPIKE, "vmax": 0.5}), np.array(rows), deepest=False).valid is False


HEX = [[0.3, 0.0], [0.15, 0.2], [-0.15, 0.2], [-0.3, 0.0], [-0.15, -0.2], [0.15, -0.2]]  # flat top at 0.2


@pytest.mark.parametrize("robot", [BOX, {"footprint": HEX, "vmax": 0.5}], ids=["box", "convex-footprint"])
def test_a_box_proven_touching_is_not_measured_and_the_verdicts_are_the_same(robot):
    """A box or a convex footprint (or its swept hull) whose core, the body less a band 0.3e-9 m wide, misses the
    obstacles overlaps them at most 1e-9 deep: ``overlap_depth(convex=True)`` reads 0 for
    it without measuring (a slide along 100 abutting boxes 1e-12 m in: 10.4 s -> 0.7 s,
    tools/bench_check.py). Brute force near contact (poses and short slides 1e-12 to 1e-6
    m in or out, thin walls 0.5e-9 to 3e-9 m thick across the body, box movers): the same
    overlaps are deeper than the tolerance, measured the same, and most are proven."""
    import shapely

    from gfuzzy.check.check import _World
    from gfuzzy.check.depth import overlap_depth

    tol = 1e-9
    scene = _scene(robot)
    world = _World(scene, tol)
    rng = np.random.default_rng(7)
    poses = np.array([pose for pose, _ in _near_contact(scene, rng, 400)])
    bodies = world.robot_geoms(poses)
    step = rng.normal(size=(len(poses), 2)) * 1e-3
    corners = scene.robot.corners(poses)
    swept = shapely.convex_hull(shapely.multipoints(np.concatenate([corners, corners + step[:, None]], 1)))
    thin = []
    for w in (0.5e-9, 1.5e-9, 3e-9):
        for _ in range(5):
            y = 0.5 + rng.uniform(-0.1, 0.1)
            thin.append(shapely.box(2.0, y, 4.0, y + w))
    across = world.robot_geoms(np.array([[3.0, 0.5, rng.uniform(-1, 1)] for _ in thin]))
    mover = shapely.box(1.0, 0.4, 1.6, 0.8)  # a box mover above the box, its top 0.4 + d
    under = world.robot_geoms(np.array([[1.3 + rng.uniform(-0.5, 0.5), 0.2 + d, 0.0] for d in _depths(rng, 40)]))
    cases = [(bodies, world.static, world.static_edges), (swept, world.static, world.static_edges),
             (across, np.array(thin, dtype=object), None), (under, mover, None)]  # fmt: skip
    proven = deep = 0
    for geoms, others, edges in cases:
        zero = shapely.distance(geoms, others) <= 0
        them = others if edges is not None else np.broadcast_to(np.asarray(others, dtype=object), zero.shape)[zero]
        fast = overlap_depth(geoms[zero], them, tol, edges, convex=True)
        full = overlap_depth(geoms[zero], them, tol, edges)
        assert np.array_equal(fast > tol, full > tol)
        measured = fast > 0
        assert np.array_equal(fast[measured], full[measured])
        assert np.all(full[~measured] <= tol)
        # proven by the core: it must hold for many (read 0 whatever the full measure says)
        proven, deep = proven + int(np.sum(_within_tol(geoms[zero], them, tol))), deep + int(np.sum(full > tol))
    assert proven > 50 and deep > 50, (proven, deep)


def _abutting_slide(robot, into: float, boxes: int = 20):
    """A slide at 0.5 m/s along the top of ``boxes`` abutting 0.1 m boxes, ``into`` m into
    them, from 0.5 m before the first to 0.5 m past the last (20: the rows of
    tools/bench_check.py's slide, shorter)."""
    obstacles = [{"box": {"center": [2.05 + 0.1 * i, 4.0], "size": [0.1, 1.0]}} for i in range(boxes)]
    scene = parse_scene({"version": 1, "name": "abutting", "bounds": [0, 0, 6, 6], "robot": robot,
                         "movers": [], "queries": [], "obstacles": obstacles})  # fmt: skip
    end = 2.0 * (1.0 + 0.1 * boxes)
    t = np.append(np.arange(0.0, end, 0.07), end)
    rows = np.column_stack([t, 1.5 + t * 0.5, np.full(len(t), 4.7 - into), np.zeros(len(t))])
    return scene, rows


@pytest.mark.parametrize("into", [0.0, 1e-12])
def test_the_check_proves_a_convex_body_touching_and_measures_a_concave_footprint(into, monkeypatch):
    """``gfuzzy check`` takes the core's proof for a box and a convex footprint (their poses
    and swept hulls: convex, the proof's premise), never for a concave footprint (it could
    hide a spike in the band); every verdict is valid. Two boxes (one seam, 36 rows) prove it
    as 20 did: before, a footprint of the box's outline was measured too (its swept hulls
    took 9 s of the 20 boxes' 12 s of CPU; a box 0.7 s)."""
    import gfuzzy.check.depth as depth

    proofs = []

    def spy(bodies, others, tol):
        out = _within_tol(bodies, others, tol)
        proofs.append(int(np.sum(out)))
        return out

    monkeypatch.setattr(depth, "_within_tol", spy)
    outline = [[0.3, 0.2], [-0.3, 0.2], [-0.3, -0.2], [0.3, -0.2]]
    dented = [[0.3, 0.2], [0.0, 0.15], [-0.3, 0.2], [-0.3, -0.2], [0.3, -0.2]]  # its bottom on the boxes
    for robot, proven in (({"box": [0.6, 0.4], "vmax": 0.5}, True), ({"footprint": outline, "vmax": 0.5}, True),
                          ({"footprint": outline[::-1], "vmax": 0.5}, True), ({"footprint": dented, "vmax": 0.5}, False)):  # fmt: skip
        proofs.clear()
        scene, rows = _abutting_slide(robot, into, boxes=2)
        rep = check_trajectory(scene, rows)
        assert rep.valid, (robot, rep.reason)
        assert (sum(proofs) > 0) == proven, (robot, proofs)


def test_the_deepest_search_runs_only_when_asked(monkeypatch):
    """``check_trajectory(deepest=False)`` (the planner's stages) gives the same verdict and
    never searches for the deepest overlap; the default does, once, for an invalid answer."""
    from gfuzzy.check import check as check_module

    calls = []
    real = check_module._Checker.search_deepest
    monkeypatch.setattr(check_module._Checker, "search_deepest", lambda self, lip: calls.append(1) or real(self, lip))
    scene, rows = _abutting_slide({"box": [0.6, 0.4], "vmax": 0.5}, 0.01)
    quick = check_trajectory(scene, rows, deepest=False)
    assert not quick.valid and calls == []
    full = check_trajectory(scene, rows)
    assert not full.valid and calls == [1] and full.time == quick.time


def _depth_oracle(body, obstacle, obstacle_xy) -> float:
    """Independently: the deepest of the points sampled every 1e-4 m along each outline
    (and its vertices) inside the other shape, from that shape's outline. ``obstacle_xy``:
    the obstacle's outline so sampled (once for all bodies; only the points in the body's
    bounding box can be inside it)."""
    import shapely

    def inside(xy, b):
        xy = xy[shapely.contains_xy(b, xy[:, 0], xy[:, 1])]
        return float(np.max(shapely.distance(shapely.points(xy), b.boundary), initial=0.0))

    x0, y0, x1, y1 = body.bounds
    near = obstacle_xy[(obstacle_xy[:, 0] >= x0) & (obstacle_xy[:, 0] <= x1)
                       & (obstacle_xy[:, 1] >= y0) & (obstacle_xy[:, 1] <= y1)]  # fmt: skip
    return max(inside(shapely.get_coordinates(shapely.segmentize(body.boundary, 1e-4)), obstacle), inside(near, body))


@pytest.mark.parametrize(  # the box and the spike (4-9 s each): `make slow`; the L keeps a concave body
    "robot",
    [pytest.param(ROBOTS[0], id="box", marks=pytest.mark.slow), pytest.param(ROBOTS[1], id="L"),
     pytest.param({"footprint": SPIKE, "vmax": 0.5}, id="spike", marks=pytest.mark.slow)],
)  # fmt: skip
def test_check_and_the_planner_agree_with_a_depth_oracle_near_contact(robot):
    """Brute force, near-contact poses (a face, a corner, an obstacle's corner; 1e-12 to
    1e-6 m in or out): ``gfuzzy check`` calls a pose more than 2e-9 m deep (by an oracle
    sampling both outlines) a collision and one less than 0.3e-9 m deep valid; whatever the
    planner accepts the check accepts."""
    import shapely

    scene = _scene(robot)
    geo = StaticGeometry(scene)
    walls = shapely.union_all([shapely.Polygon(scene.obstacles[0].vertices()), shapely.Polygon(POLY)])
    shapely.prepare(walls)
    walls_xy = shapely.get_coordinates(shapely.segmentize(walls.boundary, 1e-4))
    rng = np.random.default_rng(5)
    deep = shallow = 0
    for pose, _ in _near_contact(scene, rng, 120):  # (the oracle: 15 ms a pose)
        if geo._bounds_clearance1(pose) < 0:
            continue
        body = shapely.Polygon(scene.robot.corners(pose[None])[0])
        if body.distance(shapely.Point(1.5, 3.5)) < 0.3 + 1e-6:
            continue  # the disc: measured by distance, as before
        truth = _depth_oracle(body, walls, walls_xy)
        rep = check_trajectory(scene, np.array([[0.0, *pose]]))
        if truth > 2e-9:
            deep += 1
            assert not rep.valid, (pose.tolist(), truth)
        elif truth < 0.3e-9:
            shallow += 1
            assert rep.valid, (pose.tolist(), truth, rep.reason)
        if geo.clearance1(pose) >= 0:
            assert rep.valid, (pose.tolist(), truth, rep.reason)
    assert deep > 30 and shallow > 30, (deep, shallow)


def test_a_spike_at_the_seam_of_two_map_rectangles_is_measured_in_their_union(tmp_path):
    """A map's blocked cells are rectangles to the planner; a 1-degree spike's tip 1e-7 m
    into the blocked region exactly on the line between two of them lies on each one's
    outline (0 deep in either). Measured against their union, it is 1e-7 m deep: refused,
    as the check refuses it. Before: accepted."""
    from PIL import Image

    from gfuzzy.scene.scene import load_scene

    px = np.full((2, 3), 254, np.uint8)
    px[0, :] = 0  # the top row blocked across, the bottom one in its first two cells
    px[1, :2] = 0
    Image.fromarray(px).save(tmp_path / "m.png")
    (tmp_path / "m.yaml").write_text("image: m.png\nresolution: 0.5\norigin: [2.0, 1.0, 0.0]\nnegate: 0\n"
                                     "occupied_thresh: 0.65\nfree_thresh: 0.196\n")  # fmt: skip
    import yaml

    doc = {"version": 1, "name": "seam", "bounds": [0, 0, 6, 3], "robot": {"footprint": SPIKE, "vmax": 0.5},
           "movers": [], "queries": [], "obstacles": [{"map": {"file": "m.yaml"}}]}  # fmt: skip
    (tmp_path / "seam.yaml").write_text(yaml.safe_dump(doc))
    scene = load_scene(tmp_path / "seam.yaml")
    assert len(scene.obstacles[0].rects) == 2
    geo = StaticGeometry(scene)
    for depth, valid in ((1e-7, False), (1e-17, True)):
        pose = np.array([2.0 - 0.6 + depth, 1.5, 0.0])  # the tip at y = 1.5, between the rows
        assert (geo.clearance1(pose) >= 0) == valid, depth
        assert check_trajectory(scene, np.array([[0.0, *pose]])).valid == valid, depth


def test_a_deep_pose_is_decided_by_the_core_without_the_exact_measure(monkeypatch):
    """A box 0.1 m into the wall is refused by FCL's test of its core at that pose, before
    any exact measure (made to fail here): the core is placed at the pose asked (after a
    pose elsewhere), not left where it was."""
    geo = StaticGeometry(_walls(BOX))
    assert geo.clearance1(np.array([5.0, 2.5, 0.3])) > 0
    assert geo.clearance1(np.array([5.0, 1.2 + 1e-5, 0.0])) >= 0  # near contact: measured exactly

    def refuse(a, b):
        raise AssertionError("the exact measure was asked")

    monkeypatch.setattr(geo._exact, "gap", refuse)
    assert geo.clearance1(np.array([5.0, 1.1, 0.0])) < 0
    assert geo.clearance1(np.array([10.5 - REACH + 0.05, 2.0, math.pi / 4])) < 0
