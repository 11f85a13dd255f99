"""Footprint robots (gfuzzy.collision.shapes): parsing, distances against independent oracles, the
compiled kernel against the numpy reference, planning a concave robot where only its exact
shape fits, a footprint equal to a box, the navigator and render.

The oracles here share no code with the planner: a segment-crossing test written below for
"is this polygon simple", shapely on the whole (unsplit) polygon for distances.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import shapely
from helpers import main_completed, run_main
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gfuzzy
from gfuzzy.check.check import check_trajectory
from gfuzzy.collision.geometry import StaticGeometry, mover_distance
from gfuzzy.collision.shapes import FootprintShape, convex_pieces, shape_of
from gfuzzy.errors import SceneError
from gfuzzy.planner.planner import Planner, PlanOptions, Status
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap
from gfuzzy.scene.scene import parse_scene

ROOT = __import__("pathlib").Path(__file__).resolve().parent.parent

# a U opening forward (a cart's two arms round a notch 0.5 wide, 0.5 deep)
U = [[0.4, -0.45], [0.4, -0.25], [-0.1, -0.25], [-0.1, 0.25], [0.4, 0.25], [0.4, 0.45], [-0.4, 0.45], [-0.4, -0.45]]
L = [[0.6, -0.3], [0.6, 0.3], [0.2, 0.3], [0.2, -0.1], [-0.4, -0.1], [-0.4, -0.3]]
AHEAD = [[0.2, -0.2], [0.8, -0.2], [0.8, 0.2], [0.2, 0.2]]  # the reference point outside, behind it


def _scene(robot: dict, obstacles=(), movers=(), queries=(), bounds=(0, 0, 6, 4)) -> gfuzzy.Scene:
    doc = {"version": 1, "name": "fp", "bounds": list(bounds), "robot": {"vmax": 1.0, **robot}}
    doc["obstacles"] = list(obstacles)
    if movers:
        doc["movers"] = list(movers)
    if queries:
        doc["queries"] = list(queries)
    return parse_scene(doc)


# --------------------------------------------------------------------------- oracles


def _crosses(p, q, r, s) -> bool:
    """Closed segments pq and rs share a point (orientation tests, collinear overlaps)."""

    def orient(a, b, c):
        v = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        return 0 if v == 0 else (1 if v > 0 else -1)

    def on(a, b, c):
        return min(a[0], b[0]) <= c[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= c[1] <= max(a[1], b[1])

    o1, o2, o3, o4 = orient(p, q, r), orient(p, q, s), orient(r, s, p), orient(r, s, q)
    if o1 != o2 and o3 != o4:
        return True
    return (o1 == 0 and on(p, q, r)) or (o2 == 0 and on(p, q, s)) or (o3 == 0 and on(r, s, p)) or (o4 == 0 and on(r, s, q))


def _simple(pts) -> bool:
    """Oracle: no two non-adjacent edges meet, adjacent ones only at their shared vertex,
    and the area is not zero."""
    n = len(pts)
    edges = [(pts[i], pts[(i + 1) % n]) for i in range(n)]
    for i in range(n):
        for j in range(i + 1, n):
            adjacent = j == i + 1 or (i == 0 and j == n - 1)
            a, b = edges[i]
            c, d = edges[j]
            if not adjacent and _crosses(a, b, c, d):
                return False
            if adjacent:  # they share one vertex: only a fold-back (collinear overlap) is bad
                shared = b if j == i + 1 else a
                other_i = a if j == i + 1 else b
                other_j = d if j == i + 1 else c
                u = (other_i[0] - shared[0], other_i[1] - shared[1])
                v = (other_j[0] - shared[0], other_j[1] - shared[1])
                if u[0] * v[1] - u[1] * v[0] == 0 and u[0] * v[0] + u[1] * v[1] > 0:
                    return False
    area = sum(pts[i][0] * pts[(i + 1) % n][1] - pts[(i + 1) % n][0] * pts[i][1] for i in range(n))
    return abs(area) > 1e-9


def _body(points, pose) -> shapely.Polygon:
    """The footprint at ``pose`` as one shapely polygon (never split into pieces)."""
    P = np.asarray(points, float)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return shapely.Polygon(np.c_[pose[0] + c * P[:, 0] - s * P[:, 1], pose[1] + s * P[:, 0] + c * P[:, 1]])


@st.composite
def star_polygons(draw, min_n=3, max_n=12):
    """A simple polygon: vertices at increasing angles about a point (star-shaped), in
    either winding, the point (the robot's reference) anywhere near it."""
    n = draw(st.integers(min_n, max_n))
    cuts = draw(st.lists(st.floats(0.05, 0.95), min_size=n, max_size=n))
    angles = [2 * math.pi * (c + i) / n for i, c in enumerate(cuts)]  # one per sector: strictly increasing
    radii = draw(st.lists(st.floats(0.1, 1.0), min_size=n, max_size=n))
    cx, cy = draw(st.floats(-0.8, 0.8)), draw(st.floats(-0.8, 0.8))
    pts = [[round(cx + r * math.cos(a), 6), round(cy + r * math.sin(a), 6)] for a, r in zip(angles, radii, strict=True)]
    return pts[::-1] if draw(st.booleans()) else pts


# --------------------------------------------------------------------------- parsing


@settings(max_examples=60, deadline=None)
@given(star_polygons())
def test_random_simple_polygons_are_accepted(pts):
    if not _simple(pts):  # rounding can make a thin spike degenerate: the oracle decides
        with pytest.raises(SceneError):
            _scene({"footprint": pts})
        return
    robot = _scene({"footprint": pts}).robot
    assert robot.shape == "footprint" and robot.dof == 3
    assert robot.circumradius == pytest.approx(max(math.hypot(*p) for p in pts), abs=0)
    # stored counter-clockwise, the same polygon
    stored = shapely.Polygon(robot.footprint)
    assert shapely.Polygon(pts).symmetric_difference(stored).area < 1e-12
    assert shapely.LinearRing(robot.footprint).is_ccw


@settings(max_examples=80, deadline=None)
@given(star_polygons(min_n=4), st.data())
def test_shuffled_polygons_rejected_exactly_when_self_intersecting(pts, data):
    i = data.draw(st.integers(0, len(pts) - 1))
    j = data.draw(st.integers(0, len(pts) - 1))
    pts = [list(p) for p in pts]
    pts[i], pts[j] = pts[j], pts[i]
    if _simple(pts):
        assert _scene({"footprint": pts}).robot.shape == "footprint"
    else:
        with pytest.raises(SceneError, match=r"robot\.footprint"):
            _scene({"footprint": pts})


def test_bowties_are_rejected_and_counted():
    """Swapping two vertices of a convex quad always makes a bow-tie."""
    rng = np.random.default_rng(3)
    for _ in range(50):
        a = np.sort(rng.uniform(0, 2 * math.pi, 4))
        quad = np.c_[np.cos(a), np.sin(a)] * rng.uniform(0.2, 1.0)
        bow = quad[[0, 2, 1, 3]].tolist()
        assert not _simple(bow)
        with pytest.raises(SceneError, match="self-intersecting"):
            _scene({"footprint": bow})


@pytest.mark.parametrize(
    "robot, message",
    [
        ({"footprint": [[0, 0], [1, 0]]}, "at least 3"),
        ({"footprint": [[0, 0], [1, 0], [2, 0]]}, "robot.footprint: polygon is"),
        ({"footprint": U, "disc": 0.3}, "exactly one of disc, box or footprint, not disc and footprint"),
        ({"footprint": "U"}, "robot.footprint: expected a list of points"),
        ({"footprint": [[0, 0], [1, 0], [0, float("inf")]]}, r"robot.footprint\[2\]\[1\]"),
    ],
)
def test_bad_footprints_name_the_place(robot, message):
    with pytest.raises(SceneError, match=message):
        _scene(robot)


def test_bad_footprint_on_the_command_line_is_one_line(tmp_path, capsys, caplog):
    f = tmp_path / "bad.yaml"
    f.write_text("version: 1\nname: bad\nbounds: [0, 0, 4, 3]\nrobot: {footprint: [[0, 0], [1, 1], [1, 0], [0, 1]], vmax: 1}\n")
    p = main_completed(capsys, "roadmap", f, "-o", tmp_path / "rm.json")
    assert p.returncode == 2
    assert p.stderr.strip().count("\n") == 0 and "robot.footprint" in p.stderr and "Traceback" not in p.stderr
    assert not (tmp_path / "rm.json").exists()
    assert [r.getMessage() for r in caplog.records if r.levelno >= 30] == []  # a real process's stderr: one line


# --------------------------------------------------------------------------- pieces and distances


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(star_polygons())
def test_convex_pieces_tile_the_polygon(pts):
    if not _simple(pts):
        return
    pieces = convex_pieces(np.array(pts, float))
    poly = shapely.Polygon(pts)
    union = shapely.union_all([shapely.Polygon(p) for p in pieces])
    assert union.symmetric_difference(poly).area < 1e-9 * max(poly.area, 1.0)
    assert sum(shapely.Polygon(p).area for p in pieces) == pytest.approx(poly.area, rel=1e-9)  # no overlaps
    for p in pieces:
        assert shapely.Polygon(p).equals(shapely.convex_hull(shapely.Polygon(p)))


def test_concave_pieces_are_few():
    assert len(convex_pieces(np.array(L, float))) == 2
    assert len(convex_pieces(np.array(U, float))) == 3
    assert len(convex_pieces(np.array(AHEAD, float))) == 1


@pytest.mark.parametrize("fp", [U, L, AHEAD], ids=["U", "L", "origin-outside"])
def test_mover_distances_against_shapely(fp):
    robot = _scene({"footprint": fp}).robot
    rng = np.random.default_rng(11)
    n = 1500
    poses = np.column_stack([rng.uniform(-1.5, 1.5, (n, 2)), rng.uniform(-math.pi, math.pi, n)])
    xy, rad, size = rng.uniform(-1.5, 1.5, (n, 2)), rng.uniform(0.02, 0.5, n), rng.uniform(0.05, 1.0, (n, 2))
    d_disc = mover_distance(robot, poses, "disc", rad, (0, 0), xy)
    d_box = mover_distance(robot, poses, "box", 0, size, xy)
    d_gap = mover_distance(robot, poses, "box", 0, size, xy, exact=False)
    counts = {"apart": 0, "overlap": 0}
    for i in range(n):
        body = _body(fp, poses[i])
        box = shapely.box(*(xy[i] - size[i] / 2), *(xy[i] + size[i] / 2))
        # the disc: the body's distance from its centre less its radius (exact: no polygon)
        disc_gap = body.distance(shapely.Point(xy[i])) - rad[i]
        for d, oracle, overlap in ((d_disc[i], disc_gap, disc_gap < -1e-6), (d_box[i], body.distance(box), None)):
            if oracle > 1e-6:
                counts["apart"] += 1
                assert d > 0
                assert d == pytest.approx(oracle, abs=1e-12)
            elif overlap if overlap is not None else body.intersection(box).area > 1e-9:
                counts["overlap"] += 1
                assert d <= 0
        assert d_gap[i] <= d_box[i] + 1e-12 and (d_gap[i] > 0) == (d_box[i] > 0)  # a lower bound, same sign
    assert counts["apart"] > 500 and counts["overlap"] > 200


@pytest.mark.parametrize("fp", [U, AHEAD], ids=["U", "origin-outside"])
def test_static_clearance_against_shapely(fp):
    obstacles = [
        {"box": {"center": [2, 2], "size": [0.5, 1.0], "angle": 0.3}},
        {"polygon": [[3.5, 0.5], [4.5, 0.5], [4.0, 1.4]]},
        {"disc": {"center": [1.2, 3.0], "radius": 0.3}},
    ]
    scene = _scene({"footprint": fp}, obstacles, bounds=(0, 0, 5, 4))
    geo = StaticGeometry(scene)
    world = shapely.union_all(
        [shapely.Polygon(scene.obstacles[0].vertices()), shapely.Polygon(scene.obstacles[1].points)]
    )
    rng = np.random.default_rng(2)
    seen = {"free": 0, "hit": 0}
    for _ in range(600):
        pose = rng.uniform([0.9, 0.9, -math.pi], [4.1, 3.1, math.pi])
        body = _body(fp, pose)
        oracle = min(body.distance(world), body.distance(shapely.Point(1.2, 3.0)) - 0.3)
        c = geo.obstacle_clearance(pose)
        if oracle > 1e-3:
            seen["free"] += 1
            assert oracle - 3e-4 <= c <= oracle + 1e-9  # a lower bound within FCL's margin
        elif body.intersection(world).area > 1e-8:
            seen["hit"] += 1
            assert c < 0 and not geo.is_valid(pose)
        # the bounds, from the outline's vertices
        xs, ys = np.asarray(body.exterior.coords).T
        bounds = min(xs.min(), ys.min(), 5 - xs.max(), 4 - ys.max())
        assert geo.bounds_clearance(pose[None])[0] == pytest.approx(bounds, abs=1e-12)
    assert seen["free"] > 100 and seen["hit"] > 50


def test_inradius_and_circumradius():
    u = _scene({"footprint": U}).robot
    assert u.circumradius == pytest.approx(math.hypot(0.4, 0.45))
    assert u.inradius == 0.0  # the reference point is in the notch: outside the body
    t = _scene({"footprint": [[0.3, -0.1], [0.3, 0.1], [0.1, 0.1], [0.1, 0.3], [-0.3, 0.3], [-0.3, -0.3], [0.1, -0.3], [0.1, -0.1]]}).robot
    assert t.inradius == pytest.approx(math.hypot(0.1, 0.1))  # the nearest outline point: a concave corner
    ahead = _scene({"footprint": AHEAD}).robot
    assert ahead.inradius == 0.0 and ahead.circumradius == pytest.approx(math.hypot(0.8, 0.2))


# --------------------------------------------------------------------------- compiled kernel


def test_compiled_footprint_distance_is_the_reference_bit_for_bit():
    """The kernel's footprint-mover distance equals mover_distance(exact=False) exactly, on
    thousands of random cases: random concave footprints, disc and box movers."""
    from gfuzzy.timespace.movers_kernel import footprint_distance

    rng = np.random.default_rng(7)
    total = {"neg": 0, "pos": 0}
    for fp in (U, L, AHEAD, [[0.3, 0.0], [-0.2, 0.25], [-0.05, 0.0], [-0.2, -0.25]]):
        robot = _scene({"footprint": fp}).robot
        pieces, counts = shape_of(robot).padded()
        n = 1500
        poses = np.column_stack([rng.uniform(0, 3, (n, 2)), rng.uniform(-math.pi, math.pi, n)])
        xy, rad, size = rng.uniform(0, 3, (n, 2)), rng.uniform(0.02, 0.5, n), rng.uniform(0.05, 1.2, (n, 2))
        c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
        for kind in ("disc", "box"):
            ref = mover_distance(robot, poses, kind, rad, size, xy, exact=False)
            got = np.array([
                footprint_distance(xy[i, 0] - poses[i, 0], xy[i, 1] - poses[i, 1], c[i], s[i], kind == "disc", rad[i],
                                   0.5 * size[i, 0], 0.5 * size[i, 1], pieces, counts)
                for i in range(n)
            ])  # fmt: skip
            np.testing.assert_array_equal(got, ref)
            total["neg"] += int((ref < 0).sum())
            total["pos"] += int((ref > 0).sum())
    assert total["neg"] > 500 and total["pos"] > 5000


@pytest.mark.parametrize("fp", [U, AHEAD], ids=["U", "origin-outside"])
@pytest.mark.parametrize("broad", ["dense", "grid"])
def test_compiled_safety_same_pairs_for_a_footprint(fp, broad, monkeypatch):
    """MoverField.unsafe_pairs: the compiled kernel against numpy for a footprint robot."""
    from gfuzzy.timespace import movers
    from gfuzzy.timespace.movers import MoverField

    if broad == "grid":
        monkeypatch.setattr(movers, "DENSE_BROAD_PHASE", 0)
    rng = np.random.default_rng(5)
    mvs = []
    for k in range(6):
        path = rng.uniform(0.3, 5.7, (3, 2)).tolist()
        shape = {"disc": 0.3} if k % 2 else {"box": [0.6, 0.4]}
        mvs.append({"name": f"m{k}", **shape, "path": path, "speed": 0.7, "mode": "loop"})
    scene = _scene({"footprint": fp}, movers=mvs)
    a, b = rng.uniform(0.3, 5.7, (2, 40, 2))
    groups = [a[i] + np.linspace(0, 1, 6)[:, None] * (b[i] - a[i]) for i in range(40)]
    xy = np.vstack(groups)
    poses = np.column_stack([xy, rng.uniform(-math.pi, math.pi, len(xy))])
    ptr = np.arange(0, len(xy) + 1, 6)
    lo = rng.integers(0, 20, len(ptr) - 1)
    hi = lo + rng.integers(0, 60, len(ptr) - 1)
    pairs = []
    for compiled in (False, True):
        field = MoverField(scene, 0.5, 0.1, 70, 1.0, clearance=0.1)
        field.compiled = compiled
        node, step = field.unsafe_pairs(poses, ptr, lo, hi)
        pairs.append(set(zip(node.tolist(), step.tolist(), strict=True)))
    assert pairs[0] == pairs[1]
    assert len(pairs[0]) > 50


# --------------------------------------------------------------------------- planning


DOCK = {
    "obstacles": [
        {"box": {"center": [3, 1.0], "size": [0.2, 2.0]}},
        {"box": {"center": [3, 3.5], "size": [0.2, 1.0]}},
        {"box": {"center": [5.0, 2.0], "size": [0.2, 0.2]}},  # the post to dock round
    ],
    "movers": [{"name": "p1", "disc": 0.25, "path": [[1, 0.5], [1, 3.5]], "speed": 0.4, "mode": "bounce"}],
    "queries": [{"name": "dock", "start": [1, 2, 0], "goal": [4.85, 2.0, 0]}],
}


@pytest.fixture(scope="module")
def dock():
    scene = _scene({"footprint": U}, DOCK["obstacles"], DOCK["movers"], DOCK["queries"])
    return scene, build_roadmap(scene, RoadmapOptions(vertices=120, seed=1))


def test_u_docks_round_a_post_only_with_its_exact_shape(dock):
    """The goal has the post inside the U's notch: free for the exact concave footprint,
    not for its convex hull nor for the U turned round; the plan reaches it and the
    independent checker accepts it."""
    scene, rm = dock
    goal = np.array(scene.queries[0].goal)
    assert StaticGeometry(scene).is_valid(goal)
    hull = np.asarray(shapely.convex_hull(shapely.Polygon(U)).exterior.coords)[:-1].tolist()
    assert not StaticGeometry(_scene({"footprint": hull}, DOCK["obstacles"])).is_valid(goal)
    assert not StaticGeometry(scene).is_valid(goal + [0, 0, math.pi])
    assert not StaticGeometry(scene).is_valid(goal + [0, 0, 1.2])
    assert _body(U, goal + [0, 0, 1.2]).intersects(shapely.box(4.9, 1.9, 5.1, 2.1))  # the oracle agrees
    q = scene.queries[0]
    res = Planner(scene, rm).plan(q.start, q.goal, q.t0)
    assert res.status == Status.SOLVED
    report = check_trajectory(scene, res.trajectory.waypoints, q)
    assert report.valid, report.reason
    wp = res.trajectory.waypoints
    assert wp.shape[1] == 4 and np.allclose(wp[-1, 1:], goal)


def test_check_sweeps_the_concave_footprint_exactly(dock):
    """Driving straight onto the post (it slides into the notch) is valid for the checker,
    whose swept set is the union of the triangles' swept hulls, not the hull's sweep; the
    same drive with the U turned round hits the post."""
    scene, _ = dock
    ok = np.array([[0.0, 4.2, 2.0, 0.0], [1.0, 4.85, 2.0, 0.0]])
    report = check_trajectory(scene, ok)
    assert report.valid, report.reason
    assert report.min_clearance == pytest.approx(0.15, abs=1e-9)  # the post: 0.15 from each arm and the notch's end
    bad = ok.copy()
    bad[:, 3] = math.pi
    bad[:, 1] = [4.2, 5.1]
    report = check_trajectory(scene, bad)
    assert not report.valid and "static obstacle" in report.reason


def test_reference_point_outside_the_footprint():
    """A footprint ahead of its reference point (a towed cart's hitch): planned among a
    mover, checked, and its turning sweeps what the circumradius bounds."""
    scene = _scene(
        {"footprint": AHEAD},
        [{"box": {"center": [3, 1.2], "size": [0.3, 2.4]}}],
        [{"name": "m", "box": [0.5, 0.5], "path": [[4.5, 0.5], [4.5, 3.5]], "speed": 0.5, "mode": "bounce"}],
        [{"name": "q", "start": [0.5, 0.5, 0.0], "goal": [5.0, 2.0, 1.5708]}],
    )
    rm = build_roadmap(scene, RoadmapOptions(vertices=200, seed=2))
    q = scene.queries[0]
    for backend in ("compiled", "reference"):
        res = Planner(scene, rm).plan(q.start, q.goal, q.t0, PlanOptions(backend=backend))
        assert res.status == Status.SOLVED
        report = check_trajectory(scene, res.trajectory.waypoints, q)
        assert report.valid, report.reason


def test_footprint_equal_to_a_box_gives_the_box_answers():
    """A footprint that is the box's rectangle: the same distances, clearances, roadmap
    and plan as the box robot."""
    common = dict(
        obstacles=[{"box": {"center": [3, 1.2], "size": [0.3, 2.4]}}, {"disc": {"center": [1.5, 3.0], "radius": 0.3}}],
        movers=[{"name": "m", "disc": 0.3, "path": [[4.5, 0.5], [4.5, 3.5]], "speed": 0.5, "mode": "bounce"}],
        queries=[{"name": "q", "start": [0.5, 0.5, 0.0], "goal": [5.2, 3.0, 1.0]}],
    )
    box = _scene({"box": [0.6, 0.3]}, **common)
    fp = _scene({"footprint": [[0.3, 0.15], [-0.3, 0.15], [-0.3, -0.15], [0.3, -0.15]]}, **common)
    assert fp.robot.circumradius == box.robot.circumradius and fp.robot.inradius == box.robot.inradius
    rng = np.random.default_rng(4)
    n = 2000
    poses = np.column_stack([rng.uniform(0, 6, (n, 2)), rng.uniform(-math.pi, math.pi, n)])
    xy, size = rng.uniform(0, 6, (n, 2)), rng.uniform(0.1, 1.0, (n, 2))
    for kind in ("disc", "box"):
        a = mover_distance(box.robot, poses, kind, 0.3, size, xy)
        b = mover_distance(fp.robot, poses, kind, 0.3, size, xy)
        near = a < 2.0  # the box's quads answer with circumscribed circles beyond QUAD_EXACT
        np.testing.assert_allclose(b[near], a[near], atol=1e-12)
        assert np.all(b[~near] >= a[~near] - 1e-12)
    gb, gf = StaticGeometry(box), StaticGeometry(fp)
    np.testing.assert_allclose(gf.bounds_clearance(poses), gb.bounds_clearance(poses), atol=1e-12)
    cb, cf = gb.clearance(poses[:300]), gf.clearance(poses[:300])
    np.testing.assert_array_equal(cb < 0, cf < 0)
    np.testing.assert_allclose(cf, cb, atol=2e-4)  # FCL's box against its convex prism
    q = box.queries[0]
    rb = Planner(box, build_roadmap(box, RoadmapOptions(vertices=50, seed=3))).plan(q.start, q.goal)
    rf = Planner(fp, build_roadmap(fp, RoadmapOptions(vertices=50, seed=3))).plan(q.start, q.goal)
    assert rb.status == rf.status == Status.SOLVED
    assert rf.duration == pytest.approx(rb.duration, abs=1e-9)


@pytest.mark.parametrize(
    "flags", [[], pytest.param(["--refine", "--speed-layer"], marks=pytest.mark.slow)], ids=["search", "stages"]
)
def test_bundled_footprint_scene_meets_its_expectations(flags, capsys, monkeypatch):
    monkeypatch.chdir(ROOT)
    p = main_completed(capsys, "regress", ROOT / "scenes" / "footprint-office.yaml", *flags)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "3 of 3 queries met their expectations" in p.stdout


def test_navigator_drives_a_footprint_robot_among_people():
    from gfuzzy.navigation.navsim import simulate

    scene = gfuzzy.load_scene(ROOT / "scenes" / "footprint-office.yaml")
    rm = gfuzzy.load_roadmap(ROOT / "roadmaps" / "footprint-office.json", scene)
    q = scene.queries[0]
    res = simulate(scene, rm, q.start, q.goal, q.t0, 0.25, max_time=80.0)
    assert res.reached
    report = check_trajectory(scene, res.trajectory.waypoints, q)
    assert report.valid, report.reason


def test_navigate_cli_with_a_footprint_robot(tmp_path, capsys):
    # in process: navigate's and check's own processes are tested in test_navigator
    out = tmp_path / "nav.json"
    scene = ROOT / "scenes" / "footprint-office.yaml"
    rc, stdout, stderr = run_main(capsys, "navigate", scene, "--query", "late-to-ne", "-o", out)
    assert rc == 0, stdout + stderr
    doc = json.loads(out.read_text())
    assert doc["status"] == "solved" and len(doc["waypoints"][0]) == 4
    assert run_main(capsys, "check", scene, out)[0] == 0


def test_render_draws_the_footprint_and_its_heading(tmp_path):
    """The drawn robot is the footprint at the pose (its vertices, turned), with a heading
    tick to its front; the PNG is written."""
    from matplotlib.patches import Polygon as PolygonPatch

    from gfuzzy.render import draw
    from gfuzzy.render.render import render_scene

    scene = _scene({"footprint": U}, DOCK["obstacles"], queries=DOCK["queries"])
    pose = np.array([2.0, 1.5, 0.7])
    patch = draw._footprint(scene, pose)
    assert isinstance(patch, PolygonPatch)
    want = np.asarray(_body(U, pose).exterior.coords)[:-1]
    np.testing.assert_allclose(patch.get_xy()[: len(U)], want, atol=1e-12)
    tick = draw._heading_tick(scene, pose)
    np.testing.assert_allclose(tick[1], [2.0 + 0.4 * math.cos(0.7), 1.5 + 0.4 * math.sin(0.7)])
    out = tmp_path / "u.png"
    render_scene(scene, out)
    assert out.stat().st_size > 10_000
    gif = tmp_path / "u.gif"
    wp = np.array([[0.0, 1.0, 2.0, 0.0], [2.0, 2.5, 2.0, 0.5], [4.0, 4.85, 2.0, 0.0]])
    gfuzzy.render.render.render(scene, gif, wp)
    assert gif.stat().st_size > 10_000


def test_shape_interface_is_one_per_kind():
    assert type(shape_of(_scene({"disc": 0.3}).robot)).__name__ == "DiscShape"
    assert type(shape_of(_scene({"box": [0.6, 0.3]}).robot)).__name__ == "BoxShape"
    fp = shape_of(_scene({"footprint": U}).robot)
    assert isinstance(fp, FootprintShape) and len(fp.fcl_geometries()) == 3
    x0, y0, x1, y1 = fp.extents(math.pi / 2)
    assert (x0, y0, x1, y1) == pytest.approx((-0.45, -0.4, 0.45, 0.4))


@settings(max_examples=80, deadline=None)
@given(star_polygons())
def test_inradius_against_shapely(pts):
    if not _simple(pts):
        return
    robot = _scene({"footprint": pts}).robot
    poly = shapely.Polygon(pts)
    origin = shapely.Point(0.0, 0.0)
    want = poly.exterior.distance(origin) if poly.contains(origin) else 0.0
    assert robot.inradius == pytest.approx(want, abs=1e-12)
    assert shape_of(robot).origin_inside == (want > 0)


@pytest.mark.slow  # the unicycle kernels' first compilation dominates
def test_unicycle_footprint_docks_and_its_rows_are_unicycle_moves(dock):
    """kinematics: unicycle with a footprint (CONTRACT section 6): the same roadmap, an
    answer of waits, turns in place and straight moves, accepted by the checker (whose turn
    bound uses the footprint's circumradius)."""
    import dataclasses

    scene, rm = dock
    uni = dataclasses.replace(scene, robot=dataclasses.replace(scene.robot, kinematics="unicycle"))
    q = uni.queries[0]
    res = Planner(uni, rm).plan(q.start, q.goal, q.t0)
    assert res.status == Status.SOLVED
    report = check_trajectory(uni, res.trajectory.waypoints, q)
    assert report.valid, report.reason
    wp = res.trajectory.waypoints
    d = np.diff(wp[:, 1:], axis=0)
    moved = np.hypot(d[:, 0], d[:, 1]) > 1e-9
    lateral = np.abs(-np.sin(wp[:-1, 3]) * d[:, 0] + np.cos(wp[:-1, 3]) * d[:, 1])
    assert np.all(lateral[moved] <= 1e-6)
    turned = np.abs((d[:, 2] + np.pi) % (2 * np.pi) - np.pi) > 1e-9
    assert not np.any(moved & turned) and turned.any()


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(star_polygons(min_n=4), st.integers(0, 2**31 - 1))
def test_random_footprints_validity_and_mover_distance_against_shapely(pts, seed):
    """Random (often concave) footprints: FCL validity and clearance, and the distance to a
    disc mover, against shapely on the whole polygon."""
    if not _simple(pts):
        return
    obstacles = [{"box": {"center": [2, 2], "size": [0.4, 1.2], "angle": 0.4}}, {"polygon": [[3.2, 0.4], [3.9, 0.6], [3.4, 1.3]]}]
    scene = _scene({"footprint": pts}, obstacles, bounds=(-2, -2, 6, 6))
    geo = StaticGeometry(scene)
    world = shapely.union_all([shapely.Polygon(scene.obstacles[0].vertices()), shapely.Polygon(scene.obstacles[1].points)])
    rng = np.random.default_rng(seed)
    for pose in rng.uniform([1.0, 0.0, -math.pi], [4.0, 3.0, math.pi], (40, 3)):
        body = _body(pts, pose)
        oracle = body.distance(world)
        if oracle > 1e-3:
            assert geo.is_valid(pose) and oracle - 3e-4 <= geo.obstacle_clearance(pose) <= oracle + 1e-9
        elif body.intersection(world).area > 1e-8:
            assert not geo.is_valid(pose)
        q = pose[:2] + rng.uniform(-1.2, 1.2, 2)
        d = float(mover_distance(scene.robot, pose, "disc", 0.2, (0, 0), q))
        ref = body.distance(shapely.Point(q)) - 0.2
        if body.distance(shapely.Point(q)) > 1e-9:
            assert d == pytest.approx(ref, abs=1e-12)
        else:
            assert d <= -0.2 + 1e-12


def test_half_turn_symmetric_robots():
    """The same body turned by pi (the passage sampler's one-way chains, the lanes' one
    check for both directions): a disc, a box, a centred rectangle; not an off-centre cart
    or an L."""
    rect = [[0.3, 0.15], [-0.3, 0.15], [-0.3, -0.15], [0.3, -0.15]]
    cart = [[0.5, 0.15], [-0.1, 0.15], [-0.1, -0.15], [0.5, -0.15]]
    ell = [[0.3, -0.2], [0.3, 0.0], [0.0, 0.0], [0.0, 0.2], [-0.3, 0.2], [-0.3, -0.2]]
    robots = ({"disc": 0.3}, {"box": [0.6, 0.3]}, {"footprint": rect})
    got = [_scene(r).robot.half_turn_symmetric for r in robots]
    assert got == [True, True, True]
    assert not _scene({"footprint": cart}).robot.half_turn_symmetric
    assert not _scene({"footprint": ell}).robot.half_turn_symmetric
    # the same vertices negated, in another order: another polygon (a reviewer's lane was
    # certified one way and copied to the other, where it collides)
    star = [[0.4, 0.0], [0.1, 0.06], [0.0, 0.2], [-0.4, 0.0], [0.0, -0.2], [-0.1, -0.06]]
    bow = [[-0.3081, -0.2855], [0.043, -0.3164], [0.0972, 0.1204], [0.3362, -0.3498],
           [0.3081, 0.2855], [-0.3362, 0.3498], [-0.043, 0.3164], [-0.0972, -0.1204]]  # fmt: skip
    for fp in (star, bow):
        robot = _scene({"footprint": fp}).robot
        body = shapely.Polygon(robot.footprint)
        assert shapely.affinity.rotate(body, 180, origin=(0, 0)).symmetric_difference(body).area > 1e-3
        assert not robot.half_turn_symmetric
