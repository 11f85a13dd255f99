"""FCL geometry against an independent shapely reference (tests/reference.py).

Poses are drawn uniformly and, to exercise the hard cases, close to touching. Agreement is
required everywhere except within ``EPS`` of touching.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from reference import Reference, interpolate, mover_reference_distance, prism_mesh

from gfuzzy.collision.geometry import (
    StaticGeometry,
    metric_distance,
    mover_distance,
    wrap_angle,
)
from gfuzzy.poses import interpolate_segment as interpolate_poses
from gfuzzy.scene.scene import parse_scene

EPS = 1e-6

U_SHAPE = [[3.0, 0.5], [4.5, 0.5], [4.5, 2.0], [4.1, 2.0], [4.1, 0.9], [3.4, 0.9], [3.4, 2.0], [3.0, 2.0]]
L_SHAPE = shapely.Polygon([(0.5, 2.5), (2.0, 2.5), (2.0, 2.9), (0.9, 2.9), (0.9, 3.6), (0.5, 3.6)])
ROBOTS = {"disc": {"disc": 0.3, "vmax": 1.0}, "box": {"box": [0.8, 0.4], "vmax": 1.0}}


@pytest.fixture(scope="module")
def mesh_folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("geometry")
    prism_mesh(L_SHAPE, 1.0).export(folder / "ell.stl")
    return folder


class World:
    """A scene with every obstacle kind, its FCL geometry and its shapely reference."""

    def __init__(self, kind: str, folder):
        self.kind = kind
        self.doc = {
            "version": 1,
            "name": f"geometry-{kind}",
            "bounds": [0.0, 0.0, 6.0, 4.0],
            "robot": ROBOTS[kind],
            "obstacles": [
                {"box": {"center": [1.5, 1.2], "size": [0.8, 0.5], "angle": 0.6}},
                {"disc": {"center": [5.0, 3.0], "radius": 0.5}},
                {"polygon": U_SHAPE},  # concave
                {"mesh": {"file": "ell.stl"}},  # concave too
            ],
        }
        self.scene = parse_scene(self.doc, file="geometry.yaml", folder=folder)
        self.geometry = StaticGeometry(self.scene)
        self.ref = Reference(self.doc, {"ell.stl": L_SHAPE})
        self.dof = 2 if kind == "disc" else 3

    def uniform(self, rng, n):
        poses = np.c_[rng.uniform(-0.5, 6.5, n), rng.uniform(-0.5, 4.5, n)]
        if self.dof == 3:
            poses = np.c_[poses, rng.uniform(-math.pi, math.pi, n)]
        return poses

    def near_contact(self, rng, n, band=0.02):
        """Poses within ``band`` of touching an obstacle or the bounds, on either side."""
        pool = self.uniform(rng, 40 * n)
        gap = self.ref.clearance(pool)
        shallow = ~self.ref.robustly_colliding(pool, band)
        keep = (gap < band) & shallow
        return pool[keep][:n]


@pytest.fixture(scope="module", params=["disc", "box"])
def world(request, mesh_folder):
    return World(request.param, mesh_folder)


# --------------------------------------------------------------------------- validity


def test_validity_agrees_with_shapely(world):
    rng = np.random.default_rng(11)
    poses = np.vstack([world.uniform(rng, 2500), world.near_contact(rng, 1500)])
    valid = world.geometry.valid(poses)
    free = world.ref.robustly_free(poses, EPS)
    colliding = world.ref.robustly_colliding(poses, EPS)
    assert free.sum() > 500 and colliding.sum() > 500  # both sides well represented
    bad_free = poses[free & ~valid]
    bad_coll = poses[colliding & valid]
    assert len(bad_free) == 0, f"free poses called invalid: {bad_free[:5]}"
    assert len(bad_coll) == 0, f"colliding poses called valid: {bad_coll[:5]}"
    single = np.array([world.geometry.is_valid(p) for p in poses[:300]])
    np.testing.assert_array_equal(single, valid[:300])


def test_clearance_agrees_with_shapely(world):
    """Within 1e-4 where only flat shapes meet and the gap exceeds 2e-4; never above the
    true clearance."""
    rng = np.random.default_rng(12)
    poses = np.vstack([world.uniform(rng, 2000), world.near_contact(rng, 1000)])
    got = world.geometry.clearance(poses)
    want = world.ref.clearance(poses)
    free = world.ref.robustly_free(poses, EPS)
    colliding = world.ref.robustly_colliding(poses, EPS)
    d_poly, d_disc = world.ref.distances_by_kind(poses)
    margin = world.ref.bounds_margin(poses)
    flat = (world.kind == "box") & (np.minimum(d_poly, margin) < d_disc - 1e-3)
    err = np.abs(got - want)
    # FCL distances lose a 1e-4 margin, and below 2e-4 the clearance is decided by a
    # collision test and reported as 0 (touching): a lower bound, which is what the
    # certified motions need
    far = want > 2e-4 + 1e-6
    assert np.all(err[free & flat & far] <= 1e-4 + 1e-6), np.max(err[free & flat & far])
    assert np.all(err[free] <= 2e-3), np.max(err[free])
    assert np.all(got[free] <= want[free] + 1e-6), np.max(got[free] - want[free])
    assert np.all(got[colliding & ~world.ref.robustly_colliding(poses, 1e-3)] <= 1e-4)
    deep = world.ref.robustly_colliding(poses, 1e-3)
    assert np.all(got[deep] < 0)
    # bounds are analytic
    np.testing.assert_allclose(world.geometry.bounds_clearance(poses), margin, atol=1e-12)


def test_no_obstacles_means_bounds_only():
    doc = {"version": 1, "name": "empty", "bounds": [0, 0, 2, 0.7], "robot": ROBOTS["box"]}
    geo = StaticGeometry(parse_scene(doc))
    assert geo.is_valid([1.0, 0.35, 0.0])
    assert not geo.is_valid([1.0, 0.35, math.pi / 2])  # 0.8 long in a 0.7 high room
    assert geo.clearance([[1.0, 0.35, 0.0]])[0] == pytest.approx(0.15)
    assert geo.clearance([[1.0, 0.35, math.pi / 2]])[0] == pytest.approx(-0.05)
    assert geo.motion_free([0.5, 0.35, 0.0], [1.5, 0.35, 0.0])
    assert not geo.motion_free([0.5, 0.35, 0.0], [1.5, 0.35, math.pi / 2])


def _ring(center, distance, n, phase=0.0):
    a = phase + np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    return np.c_[center[0] + distance * np.cos(a), center[1] + distance * np.sin(a)]


def _disc_world():
    doc = {
        "version": 1,
        "name": "ring",
        "bounds": [0, 0, 10, 6],
        "robot": ROBOTS["disc"],
        "obstacles": [{"disc": {"center": [5.0, 3.0], "radius": 0.5}}],
    }
    return StaticGeometry(parse_scene(doc))


def test_touching_discs_are_valid_and_overlapping_ones_are_not():
    geo = _disc_world()
    for gap, ok in ((1e-3, True), (1e-4, True), (-1e-4, False), (-1e-3, False)):
        poses = _ring((5.0, 3.0), 0.8 + gap, 64, phase=0.1)
        assert np.all(geo.valid(poses) == ok), gap


@pytest.mark.parametrize("base", [1e-15, 4e-15])
def test_a_polygons_zero_width_spike_blocks_as_in_the_check(base):
    """A polygon going up a line and back (a spike ``base`` wide: its triangle is flat) holds
    that segment, and the check blocks there; the FCL geometry dropped the flat triangle and
    let a disc through it (an unseen drive's answer the check refused,
    tools/bench_unseen_drives.py). Both sides of the spike and the spike itself."""
    from gfuzzy.check.check import check_trajectory

    spike = [[0, 0], [2, 0], [2, 1], [1 + base, 1], [1, 3], [1, 1], [0, 1]]
    scene = parse_scene({"version": 1, "name": "spike", "bounds": [-1, -1, 3, 4],
                         "robot": {"disc": 0.2, "vmax": 1.0}, "obstacles": [{"polygon": spike}]})  # fmt: skip
    geo = StaticGeometry(scene)
    for x, ok in ((0.75, True), (0.85, False), (1.0, False), (1.15, False), (1.25, True)):
        pose = np.array([x, 2.0])
        assert check_trajectory(scene, np.array([[0.0, *pose], [1e-3, *pose]]), deepest=False).valid == ok, x
        assert geo.is_valid(pose) == ok, x
        assert (geo.clearance1(pose) >= 0) == ok, x


def test_clearance_never_overestimates_near_a_disc():
    geo = _disc_world()
    for gap in (1e-1, 1e-2, 1e-3, 1e-4):
        got = geo.clearance(_ring((5.0, 3.0), 0.8 + gap, 400, phase=0.3))
        assert np.all(got <= gap + 1e-6), (gap, float(np.max(got - gap)))


def test_clearance_is_negative_wherever_is_valid_is_false():
    geo = _disc_world()
    for gap in (-1e-5, -3e-5, -1e-4):
        poses = _ring((5.0, 3.0), 0.8 + gap, 400, phase=0.7)
        assert not geo.valid(poses).any()
        got = geo.clearance(poses)
        assert np.all(got < 0), (gap, int(np.sum(got >= 0)), float(np.max(got)))


# --------------------------------------------------------------------------- certified motions


def _random_motions(world, rng, n):
    starts = world.uniform(rng, 20 * n)
    starts = starts[world.geometry.valid(starts)][:n]
    step = rng.normal(size=(len(starts), 2))
    step *= (rng.uniform(0.05, 1.5, len(starts)) / np.hypot(*step.T))[:, None]
    ends = starts.copy()
    ends[:, :2] += step
    if world.dof == 3:
        ends[:, 2] = wrap_angle(starts[:, 2] + rng.uniform(-math.pi, math.pi, len(starts)))
    return starts, ends


def _grazing_motions(world):
    """Straight motions that pass an obstacle at gaps from -1e-3 to +1e-3."""
    motions = []
    for gap in (-1e-3, -1e-4, -2e-5, 2e-5, 1e-4, 1e-3):
        if world.kind == "disc":
            d = 0.8 + gap  # past the disc at (5, 3), radius 0.5, robot 0.3
            motions.append(([4.9, 3.0 - d], [5.6, 3.0 - d]))
            # along the U's left outer wall x = 3.0
            motions.append(([3.0 - 0.3 - gap, 0.6], [3.0 - 0.3 - gap, 1.9]))
        else:
            # box robot level under the rotated-free U floor y = 0.5, half width 0.2
            motions.append(([3.2, 0.5 - 0.2 - gap, 0.0], [4.3, 0.5 - 0.2 - gap, 0.0]))
            # past the disc, half width 0.2 below the disc's lowest point
            motions.append(([4.4, 2.5 - 0.2 - gap, 0.0], [5.5, 2.5 - 0.2 - gap, 0.0]))
    return [(np.array(a), np.array(b)) for a, b in motions]


def test_motion_free_never_certifies_a_colliding_motion(world):
    rng = np.random.default_rng(13)
    starts, ends = _random_motions(world, rng, 100)
    motions = list(zip(starts, ends, strict=True)) + _grazing_motions(world)
    fractions = np.linspace(0.0, 1.0, 2000)
    certified = rejected = live = 0
    for a, b in motions:
        samples = interpolate(a, b, fractions)
        colliding = world.ref.robustly_colliding(samples, EPS)
        if world.geometry.motion_free(a, b):
            certified += 1
            assert not colliding.any(), f"certified {a} -> {b} collides at {samples[colliding][0]}"
        else:
            rejected += 1
            if world.ref.clearance(samples).min() > 0.02:
                live += 1
    assert certified > 20 and rejected > 20
    assert live == 0, f"{live} motions with clearance > 0.02 everywhere were not certified"


def test_motion_free_rejects_invalid_ends(world):
    bad = np.array([-1.0, -1.0, 0.0])[: world.dof]
    good = world.uniform(np.random.default_rng(3), 200)
    good = good[world.geometry.valid(good)][0]
    assert not world.geometry.motion_free(bad, good)
    assert not world.geometry.motion_free(good, bad)
    assert world.geometry.motion_free(good, good)


# --------------------------------------------------------------------------- a SLAM map


@pytest.fixture(scope="module")
def house():
    """The bundled small house (a SLAM map, the only obstacle) with its footprint robot."""
    from helpers import ROOT

    from gfuzzy.scene.scene import load_scene

    return StaticGeometry(load_scene(ROOT / "scenes" / "small-house.yaml"))


def _house_points(geo, rng, n):
    xmin, ymin, xmax, ymax = geo.scene.bounds
    return np.c_[rng.uniform(xmin, xmax, n), rng.uniform(ymin, ymax, n)]


def _bound_and_clearance(geo, bound_at, xy):
    """(n,) a heading-free bound ``bound_at(x, y)`` at each point of ``xy`` (n, 2), and the
    footprint's least clearance over 16 headings there."""
    heads = np.linspace(-math.pi, math.pi, 16, endpoint=False)
    bound = np.array([bound_at(x, y) for x, y in xy])
    return bound, np.array([[geo.clearance1([x, y, h]) for h in heads] for x, y in xy]).min(axis=1)


def test_a_maps_disc_bound_never_exceeds_the_clearance_at_any_heading(house, world):
    """:meth:`StaticGeometry.disc_bound` (the map's distance transform at the circumradius)
    is a lower bound of the footprint's clearance at every heading: a turn in place there
    is free. Without maps it has no cheap bound (-inf)."""
    rng = np.random.default_rng(5)
    bound, exact = _bound_and_clearance(house, house.disc_bound, _house_points(house, rng, 500))
    useful = bound > 0
    assert useful.sum() > 50 and (exact > 0).sum() > useful.sum()  # neither vacuous nor exact
    assert np.all(bound[useful] <= exact[useful] + 2e-4), np.max(bound[useful] - exact[useful])
    assert world.geometry.disc_bound(3.0, 2.0) == -math.inf  # polygons, discs and a mesh


def test_the_sweep_bound_never_exceeds_the_clearance_at_any_heading(house, world):
    """:meth:`StaticGeometry.sweep_bound` (the circumscribed disc's FCL distance where the
    cheap bound says nothing) is a lower bound of the clearance at every heading, among
    boxes, discs, a concave polygon, a mesh and a map; :meth:`StaticGeometry.sweep_free`
    certifies only straight moves that are free at every heading (checked at 16)."""
    rng = np.random.default_rng(7)
    heads = np.linspace(-math.pi, math.pi, 16, endpoint=False)
    for geo, xy in ((house, _house_points(house, rng, 300)), (world.geometry, world.uniform(rng, 400)[:, :2])):
        bound = np.array([geo.sweep_bound(x, y) for x, y in xy])
        pose = (lambda x, y, h: [x, y]) if geo.robot.shape == "disc" else (lambda x, y, h: [x, y, h])
        exact = np.array([[geo.clearance1(pose(x, y, h)) for h in heads] for x, y in xy]).min(axis=1)
        useful = bound > 0
        assert useful.sum() > 30 and (exact > 0).sum() >= useful.sum()  # not vacuous (a disc: exact)
        assert np.all(bound[useful] <= exact[useful] + 1e-9), np.max(bound[useful] - exact[useful])
        for (ax, ay), (bx, by) in zip(xy[:60], xy[60:120], strict=True):
            if geo.sweep_free([ax, ay], [bx, by], max_steps=500):
                for h in heads[::4]:
                    assert geo.motion_free(pose(ax, ay, h), pose(bx, by, h)), (ax, ay, bx, by, h)


def test_clearance1_is_the_bounds_and_obstacles_composition(house, world):
    """The circumradius shortcut of :meth:`StaticGeometry.clearance1` changes no value: it
    equals min(bounds, obstacles - keep) as computed in full."""
    rng = np.random.default_rng(6)
    for geo, poses in ((house, np.c_[_house_points(house, rng, 300), rng.uniform(-3, 3, 300)]),
                       (world.geometry, world.uniform(rng, 300))):  # fmt: skip
        for p in poses:
            full = geo._bounds_clearance1(p)
            if full >= 0:
                full = min(full, geo.obstacle_clearance(p) - geo.keep)
            assert geo.clearance1(p) == full, p


def test_a_pose_touching_the_bounds_still_meets_the_obstacles():
    """A disc exactly touching the bounds (x - r = xmin in floating point) that overlaps a
    box: its clearance is negative, as ``is_valid`` says (it used to be 0: the obstacles
    were only asked when the bounds left more than 0)."""
    doc = {"version": 1, "name": "edge", "bounds": [-5, -5, 5, 5], "robot": {"disc": 0.105, "vmax": 1.0},
           "obstacles": [{"box": {"center": [-4.8, 0.0], "size": [0.2, 0.4]}}]}  # fmt: skip
    geo = StaticGeometry(parse_scene(doc))
    pose = [-4.895, 0.0]
    assert geo._bounds_clearance1(pose) == 0.0  # touching, to the last bit
    assert not geo.is_valid(pose)
    assert geo.clearance1(pose) < 0


def test_a_pose_that_is_not_a_number_is_not_certified(house):
    """A NaN or infinite pose is refused (the distance transform is not asked)."""
    for bad in ([math.nan, 0.0, 0.0], [math.inf, 0.0, 0.0]):
        assert not house.motion_free(bad, [0.0, 0.0, 0.0])
        assert not house.motion_free([0.0, 0.0, 0.0], bad)
        assert not (house.disc_bound(bad[0], bad[1]) > 0)


def test_a_maps_motions_are_certified_as_before_with_fewer_fcl_queries(house):
    """On a map, :meth:`motion_free` steps by the distance transform where it leaves room
    and by FCL near the walls: the same decisions as ``motion_clearance >= 0`` (which
    always asks FCL), every certified motion free at 200 poses along it, and fewer FCL
    queries."""
    rng = np.random.default_rng(7)
    xy = _house_points(house, rng, 3000)
    starts = np.c_[xy, rng.uniform(-math.pi, math.pi, len(xy))]
    starts = starts[house.valid(starts)][:150]
    step = rng.normal(size=(len(starts), 2))
    step *= (rng.uniform(0.2, 3.0, len(starts)) / np.hypot(*step.T))[:, None]
    ends = np.c_[starts[:, :2] + step, wrap_angle(starts[:, 2] + rng.uniform(-1.0, 1.0, len(starts)))]
    quick = full = 0
    certified = 0
    for a, b in zip(starts, ends, strict=True):
        c0 = house.calls
        free = house.motion_free(a, b)
        c1 = house.calls
        assert free == (house.motion_clearance(a, b) >= 0), (a, b)
        quick, full = quick + c1 - c0, full + house.calls - c1
        if free:
            certified += 1
            on = interpolate_poses(a, b, np.linspace(0.0, 1.0, 200))
            assert np.all(house.clearance(on) >= 0), (a, b)
    assert 20 < certified < len(starts)
    assert quick < 0.8 * full, (quick, full)


# --------------------------------------------------------------------------- movers

PAIRS = [("disc", "disc"), ("disc", "box"), ("box", "disc"), ("box", "box")]


@pytest.mark.parametrize("robot_kind,mover_shape", PAIRS)
def test_mover_distance_agrees_with_shapely(robot_kind, mover_shape):
    rng = np.random.default_rng(hash((robot_kind, mover_shape)) % 2**32)
    scene = parse_scene(
        {"version": 1, "name": "m", "bounds": [-10, -10, 10, 10], "robot": ROBOTS[robot_kind]}
    )
    robot_doc = ROBOTS[robot_kind]
    n = 600
    poses = rng.uniform(-3, 3, (n, 2))
    if robot_kind == "box":
        poses = np.c_[poses, rng.uniform(-math.pi, math.pi, n)]
    xy = poses[:, :2] + rng.uniform(-1.5, 1.5, (n, 2))
    overlaps = 0
    for k in range(n):
        if mover_shape == "disc":
            param = float(rng.uniform(0.05, 0.8))
            got = mover_distance(scene.robot, poses[k], "disc", param, (0.0, 0.0), xy[k])
        else:
            param = tuple(rng.uniform(0.05, 1.2, 2))
            got = mover_distance(scene.robot, poses[k], "box", 0.0, param, xy[k])
        want, overlap = mover_reference_distance(robot_doc, poses[k], mover_shape, param, xy[k])
        if overlap:
            overlaps += 1
            assert got <= 1e-12, (poses[k], xy[k], param, got)
        elif want > 1e-9:
            assert got == pytest.approx(want, abs=1e-9), (poses[k], xy[k], param)
    assert 50 < overlaps < n - 50


@pytest.mark.parametrize("robot_kind,mover_shape", PAIRS)
def test_mover_distance_broadcasts(robot_kind, mover_shape):
    rng = np.random.default_rng(5)
    robot = parse_scene(
        {"version": 1, "name": "m", "bounds": [-10, -10, 10, 10], "robot": ROBOTS[robot_kind]}
    ).robot
    dof = 2 if robot_kind == "disc" else 3
    poses = rng.uniform(-2, 2, (7, dof))
    xy = rng.uniform(-2, 2, (5, 2))
    args = ("disc", 0.3, (0.0, 0.0)) if mover_shape == "disc" else ("box", 0.0, (0.6, 0.4))
    grid = mover_distance(robot, poses[:, None, :], *args[:1], args[1], args[2], xy[None, :, :])
    assert grid.shape == (7, 5)
    for i in range(7):
        for j in range(5):
            assert grid[i, j] == pytest.approx(
                float(mover_distance(robot, poses[i], args[0], args[1], args[2], xy[j])), abs=1e-12
            )


def test_mover_distance_hand_values():
    disc = parse_scene({"version": 1, "name": "d", "bounds": [-9, -9, 9, 9], "robot": {"disc": 0.5, "vmax": 1}}).robot
    box = parse_scene({"version": 1, "name": "b", "bounds": [-9, -9, 9, 9], "robot": {"box": [2.0, 1.0], "vmax": 1}}).robot
    assert mover_distance(disc, [0, 0], "disc", 0.25, (0, 0), [2, 0]) == pytest.approx(1.25)
    assert mover_distance(disc, [0, 0], "box", 0.0, (1, 1), [2, 2]) == pytest.approx(math.hypot(1.5, 1.5) - 0.5)
    assert mover_distance(box, [0, 0, 0], "disc", 0.5, (0, 0), [3, 0]) == pytest.approx(1.5)
    assert mover_distance(box, [0, 0, math.pi / 2], "box", 0.0, (1, 1), [0, 2]) == pytest.approx(0.5)
    assert mover_distance(box, [0, 0, math.pi / 4], "box", 0.0, (1, 1), [3, 0]) == pytest.approx(
        3 - 0.5 - 1.5 / math.sqrt(2)
    )
    assert mover_distance(box, [0, 0, 0], "box", 0.0, (1, 1), [0, 0]) < 0


# --------------------------------------------------------------------------- metric and interpolation


def test_metric_distance_hand_values():
    assert metric_distance([0, 0], [3, 4], 7.0) == pytest.approx(5.0)
    assert metric_distance([0, 0, 3.0], [3, 4, -3.0], 2.0) == pytest.approx(5 + 2 * (2 * math.pi - 6))
    assert metric_distance([1, 1, 0.5], [1, 1, 0.5 + math.pi / 2], 0.5) == pytest.approx(math.pi / 4)
    many = metric_distance(np.zeros((4, 3)), np.c_[np.ones(4), np.zeros(4), np.full(4, 0.1)], 1.0)
    np.testing.assert_allclose(many, 1.1)


def test_interpolate_poses_takes_the_shorter_arc():
    a, b = np.array([0.0, 0.0, 3.0]), np.array([2.0, -2.0, -3.0])
    f = np.linspace(0, 1, 101)
    got = interpolate_poses(a, b, f)
    want = interpolate(a, b, f)
    np.testing.assert_allclose(got[:, :2], want[:, :2], atol=1e-12)
    np.testing.assert_allclose(np.cos(got[:, 2] - want[:, 2]), 1.0, atol=1e-12)
    assert np.all((got[:, 2] >= -math.pi) & (got[:, 2] < math.pi))
    np.testing.assert_allclose(got[0], a, atol=1e-12)
    assert math.cos(got[-1, 2] - b[2]) == pytest.approx(1.0)
    # the heading moves by 2*pi - 6 in total, never through 0
    assert np.all(np.abs(got[:, 2]) >= 3.0 - 1e-12)
    two = interpolate_poses([0.0, 0.0], [1.0, 2.0], np.array([0.25]))
    np.testing.assert_allclose(two, [[0.25, 0.5]])


def test_the_sweep_bound_keeps_the_robots_clearance():
    """With ``robot.clearance`` (the distance kept from walls) the sweep bound is still a
    lower bound of the clearance at every heading, which counts that distance (a bound that
    forgot it over-estimated by up to 6 mm with a clearance of 5 cm)."""
    from dataclasses import replace

    from helpers import ROOT

    from gfuzzy.scene.scene import load_scene

    base = load_scene(ROOT / "scenes" / "small-house.yaml")
    geo = StaticGeometry(replace(base, robot=replace(base.robot, clearance=0.05)))
    assert geo.keep == 0.05
    bound, exact = _bound_and_clearance(geo, geo.sweep_bound, _house_points(geo, np.random.default_rng(8), 300))
    useful = bound > 0
    assert useful.sum() > 30
    assert np.all(bound[useful] <= exact[useful] + 1e-9), np.max(bound[useful] - exact[useful])


def _beside_wall(clearance: float, robot: dict):
    wall = {"polygon": [[0.0, 1.0], [6.0, 1.0], [6.0, 1.2], [0.0, 1.2]]}
    return parse_scene({"version": 1, "name": "w", "bounds": [0, 0, 6, 4], "robot": {**robot, "clearance": clearance},
                        "obstacles": [wall], "movers": [], "queries": []})  # fmt: skip


@pytest.mark.parametrize("keep", [0.0, 0.05])
def test_a_translation_along_a_wall_is_certified_by_its_swept_body(keep):
    """A box translating 3 m beside a wall 0.3 mm (beyond its clearance) away is certified
    in a few FCL queries, not traced in steps of 0.3 mm (10,000 queries for a unicycle's
    lane in the unseen bent corridor); one grazing into the wall is refused as cheaply."""
    sc = _beside_wall(keep, {"box": [0.6, 0.4], "vmax": 1.0})
    geo = StaticGeometry(sc)
    y = 1.0 - 0.2 - keep - 3e-4
    assert geo.motion_free([0.5, y, 0.0], [3.5, y, 0.0])
    assert geo.calls < 50, geo.calls
    geo.calls = 0
    assert not geo.motion_free([0.5, y - 0.05, 0.0], [5.5, y + 0.002, 0.0])
    assert geo.calls < 50, geo.calls


@pytest.mark.parametrize("keep", [0.0, 0.02])
def test_swept_certificates_are_sound_near_walls(keep):
    """Every translation of a footprint that :meth:`StaticGeometry.motion_free` certifies
    near a wall keeps the clearance by shapely's exact measure of its swept body (the
    convex hulls of its pieces at the two ends), touching allowed only by a rounding."""
    from gfuzzy.collision.exact import TOUCH_TOL, ExactBody

    sc = _beside_wall(keep, {"footprint": [[-0.2, -0.2], [0.4, -0.2], [0.4, 0.0], [0.0, 0.0], [0.0, 0.3], [-0.2, 0.3]],
                             "vmax": 1.0})  # fmt: skip
    geo, body = StaticGeometry(sc), ExactBody(_beside_wall(0.0, {"box": [0.1, 0.1], "vmax": 1.0}))
    body.pieces = [np.asarray(p) for p in geo._pieces[0]]
    wall = shapely.box(0.0, 1.0, 6.0, 1.2)
    rng = np.random.default_rng(3)
    certified = 0
    for _ in range(300):
        h = rng.uniform(-math.pi, math.pi)
        a = [rng.uniform(0.6, 5.4), rng.uniform(0.4, 0.8), h]
        b = [a[0] + rng.uniform(-1.5, 1.5), a[1] + rng.uniform(-0.01, 0.01), h]
        if geo.motion_free(a, b):
            certified += 1
            d = wall.distance(body.swept(a, b)) if not wall.intersects(body.swept(a, b)) else -body.swept(a, b).intersection(wall).area
            assert d >= keep - TOUCH_TOL, (a, b, d)
    assert certified > 50


@pytest.mark.parametrize("keep", [0.0, 0.02])
@pytest.mark.parametrize("delta", [-5e-3, -5e-4, 5e-4, 2e-3])
def test_a_lane_passing_an_obstacle_beside_its_middle_is_judged_by_its_swept_body(keep, delta):
    """A unicycle box's 3 m lane passing a disc beside its middle, the disc's edge ``keep +
    delta`` from the box's side: certified exactly when delta > 0. Beside a straight wall
    the swept body's nearest point is at a lane's end, which the trace decides first; here
    only the swept body (or the exact measure within its margin) can (a certificate 1 cm
    inside the clearance passed every test before)."""
    from gfuzzy.collision.geometry import StaticGeometry
    from gfuzzy.scene.scene import parse_scene

    disc = {"disc": {"center": [2.0, 1.0 + 0.2 + keep + 0.1 + delta], "radius": 0.1}}
    robot = {"box": [0.6, 0.4], "vmax": 1.0, "kinematics": "unicycle", "clearance": keep}
    sc = parse_scene({"version": 1, "name": "k", "bounds": [0, 0, 6, 4], "robot": robot, "obstacles": [disc]})
    assert StaticGeometry(sc).motion_free([0.5, 1.0, 0.0], [3.5, 1.0, 0.0]) == (delta > 0)


def test_a_convex_polygon_is_one_prism_and_measures_as_its_triangles():
    """A strictly convex polygon is one FCL prism (its triangles' n - 2 cost a footprint
    drive's thousands of distances five times as much); a dented one, or one with a corner on
    a straight side, is still triangulated. Distances against shapely's either way."""
    from gfuzzy.collision.fclmodel import static_objects

    a = np.linspace(0.0, 2 * math.pi, 16, endpoint=False)
    gon = np.c_[2.0 + 0.4 * np.cos(a), 2.0 + 0.4 * np.sin(a)].round(6).tolist()
    side = [[0.5, 0.5], [1.0, 0.5], [1.5, 0.5], [1.5, 1.2], [0.5, 1.2]]  # (1.0, 0.5) on a side
    doc = {"version": 1, "name": "gons", "bounds": [0, 0, 6, 4],
           "robot": {"footprint": [[0.3, 0.0], [-0.2, 0.2], [-0.1, 0.0], [-0.2, -0.2]], "vmax": 1.0},
           "obstacles": [{"polygon": gon}, {"polygon": side}, {"polygon": U_SHAPE}]}  # fmt: skip
    scene = parse_scene(doc)
    assert len(static_objects(scene)) == 1 + 3 + 6  # the 16-gon one (14 on main), the others triangulated
    geo = StaticGeometry(scene)
    world = shapely.union_all([shapely.Polygon(p) for p in (gon, side, U_SHAPE)])
    robot = shapely.Polygon(doc["robot"]["footprint"])
    rng = np.random.default_rng(3)
    for pose in rng.uniform([0.5, 0.5, -math.pi], [5.5, 3.5, math.pi], (60, 3)):
        body = shapely.affinity.translate(shapely.affinity.rotate(robot, pose[2], origin=(0, 0), use_radians=True), *pose[:2])
        exact = body.distance(world)
        if exact > 1e-3:
            assert exact - 3e-4 <= geo.obstacle_clearance(pose) <= exact
        elif body.intersection(world).area > 1e-8:
            assert not geo.is_valid(pose)


# --------------------------------------------------------------------------- FCL's distances exact

#: Hypothesis's footprint and pose (test_shapes.py's validity test), 0.617 m from a box, where
#: FCL's GJK from an ``fcl.Box`` put the box 1.18e-4 m farther than it is: more than the
#: clearance's 1e-4 margin, so the clearance was above the exact distance.
GJK_FOOTPRINT = [[0.23097, 0.095671], [0.268794, 0.421604], [-0.401701, 0.627942], [-0.46194, 0.191342],
                 [-0.92388, -0.382683], [-0.382683, -0.92388], [0.382683, -0.92388], [0.92388, -0.382683]]  # fmt: skip
GJK_POSE = (3.10898464, 2.71349682, 2.26967394)
MARGIN = 1e-4  # geometry._DIST_MARGIN: subtracted from an exact distance, the clearance keeps it


def _footprint_body(pts, pose):
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return shapely.Polygon(np.asarray(pts) @ np.array([[c, s], [-s, c]]) + np.asarray(pose[:2]))


def test_the_clearance_keeps_its_margin_where_gjk_overshot_a_box():
    """The reproducer and 300 poses within about a centimetre and 0.01 rad of it, where GJK
    from an ``fcl.Box`` to the footprint's convex pieces erred by up to 1.5e-3 m in both
    argument orders (tools/fcl_accuracy.py): boxes are convex prisms for distances now, and
    the clearance is the exact distance less the margin. The same with the box the robot
    and the footprint's whole body an obstacle."""
    obstacles = [{"box": {"center": [2, 2], "size": [0.4, 1.2], "angle": 0.4}}, {"polygon": [[3.2, 0.4], [3.9, 0.6], [3.4, 1.3]]}]
    scene = parse_scene({"version": 1, "name": "gjk", "bounds": [-2, -2, 6, 6], "robot": {"footprint": GJK_FOOTPRINT, "vmax": 1.0},
                         "obstacles": obstacles})  # fmt: skip
    world = shapely.union_all([shapely.Polygon(scene.obstacles[0].vertices()), shapely.Polygon(scene.obstacles[1].points)])
    geo = StaticGeometry(scene)
    exact = _footprint_body(GJK_FOOTPRINT, GJK_POSE).distance(world)
    assert geo.obstacle_clearance(GJK_POSE) == pytest.approx(exact - MARGIN, abs=1e-9)  # main: exact + 1.8e-5
    poses = np.asarray(GJK_POSE) + np.random.default_rng(5).normal(0.0, 0.01, (300, 3))
    over = [(p, geo.obstacle_clearance(p) - (_footprint_body(GJK_FOOTPRINT, p).distance(world) - MARGIN)) for p in poses]
    assert max(e for _, e in over) <= 1e-9, max(over, key=lambda pe: pe[1])
    # the same pair the other way round: the box the robot, the footprint's piece an obstacle
    piece = np.asarray(shapely.geometry.polygon.orient(_footprint_body(GJK_FOOTPRINT, GJK_POSE)).exterior.coords)[:-1]
    piece = [list(p) for p in np.round(piece, 9)]
    scene = parse_scene({"version": 1, "name": "gjk", "bounds": [-2, -2, 6, 6], "robot": {"box": [0.4, 1.2], "vmax": 1.0},
                         "obstacles": [{"polygon": piece}]})  # fmt: skip
    geo = StaticGeometry(scene)
    for p in np.array([2.0, 2.0, 0.4]) + np.random.default_rng(6).normal(0.0, 0.01, (300, 3)):
        box = shapely.affinity.rotate(shapely.box(-0.2, -0.6, 0.2, 0.6), p[2], origin=(0, 0), use_radians=True)
        exact = shapely.affinity.translate(box, *p[:2]).distance(shapely.Polygon(piece))
        assert geo.obstacle_clearance(p) <= exact - MARGIN + 1e-9, (p, geo.obstacle_clearance(p) - exact + MARGIN)


def test_a_sphere_and_a_convex_keep_the_margin_among_polygons_boxes_and_discs():
    """FCL's GJK between a sphere and a convex prism erred by up to 1.5e-3 m, either argument
    order: a disc robot near a convex polygon, a box and a disc obstacle, a footprint near
    them (and its circumscribed disc's sweep bound), 150 poses each at gaps from 1e-4 to
    0.3 m, all keep the margin below shapely's exact distance (main: 2.1e-4 above it), or
    within 2e-4 of contact are 0 (touching: the collision test decides there)."""
    gon = [[1.0, 0.0], [0.6, 0.8], [-0.3, 0.95], [-0.9, 0.4], [-0.85, -0.5], [0.0, -1.0], [0.7, -0.7]]
    box = {"box": {"center": [2.5, -2.0], "size": [0.8, 0.5], "angle": 0.3}}
    obstacles = [{"polygon": gon}, box, {"disc": {"center": [-2.5, 2.0], "radius": 0.4}}]
    gaps = np.geomspace(1e-4, 0.3, 8)
    rng = np.random.default_rng(0)
    boxed = shapely.Polygon(parse_scene({"version": 1, "name": "b", "bounds": [-9, -9, 9, 9], "robot": {"disc": 0.1, "vmax": 1.0},
                                         "obstacles": [box]}).obstacles[0].vertices())  # fmt: skip
    world, centre = shapely.union_all([shapely.Polygon(gon), boxed]), shapely.Point(-2.5, 2.0)

    def exact_disc(xy, r):  # the exact distance of a disc of radius r at xy
        return min(world.distance(shapely.Point(xy)), centre.distance(shapely.Point(xy)) - 0.4) - r

    for robot in ({"disc": 0.3}, {"footprint": GJK_FOOTPRINT}):
        scene = parse_scene({"version": 1, "name": "s", "bounds": [-9, -9, 9, 9], "robot": {**robot, "vmax": 1.0}, "obstacles": obstacles})
        geo = StaticGeometry(scene)
        rings = [shape.buffer(geo.r + g, 16).exterior for shape in (shapely.Polygon(gon), boxed) for g in gaps]
        over = []
        for _ in range(150):
            if rng.random() < 0.3:  # near the disc obstacle
                a = rng.uniform(0, 2 * math.pi)
                xy = np.array([-2.5, 2.0]) + (0.4 + geo.r + gaps[int(rng.integers(0, 8))]) * np.array([math.cos(a), math.sin(a)])
            else:
                ring = rings[int(rng.integers(0, len(rings)))]
                xy = np.asarray(ring.interpolate(rng.uniform(0.0, ring.length)).coords[0])
            if "disc" in robot:
                over.append(geo.obstacle_clearance(xy) - max(exact_disc(xy, 0.3) - MARGIN, 0.0))
                continue
            pose = (*xy, rng.uniform(-math.pi, math.pi))
            body = _footprint_body(GJK_FOOTPRINT, pose)
            over.append(geo.obstacle_clearance(pose) - max(min(world.distance(body), body.distance(centre) - 0.4) - MARGIN, 0.0))
            bound = geo.sweep_bound(*xy)  # the circumscribed disc
            if bound > 0:
                over.append(bound - (exact_disc(xy, geo.r) - MARGIN))
        assert max(over) <= 1e-9, (robot, max(over))


def test_each_polygon_and_map_is_made_once_for_the_collision_and_the_distance_model(monkeypatch):
    """``StaticGeometry`` triangulated every polygon and meshed every map's walls twice, once
    for its collision objects and once for its distance model (``fclmodel.static_model``
    makes both in one pass)."""
    from conftest import ROOT

    from gfuzzy.collision import fclmodel
    from gfuzzy.scene.scene import load_scene

    made = {"_triangulate": 0, "_walls": 0}

    def counting(name):
        f = getattr(fclmodel, name)

        def counted(*args):
            made[name] += 1
            return f(*args)

        return counted

    for name in made:
        monkeypatch.setattr(fclmodel, name, counting(name))
    doc = {"version": 1, "name": "once", "bounds": [0, 0, 6, 4], "robot": ROBOTS["box"],
           "obstacles": [{"polygon": U_SHAPE}, {"polygon": [list(p) for p in L_SHAPE.exterior.coords[:-1]]}]}  # fmt: skip
    geo = StaticGeometry(parse_scene(doc))
    assert made == {"_triangulate": 2, "_walls": 0}
    assert not geo.is_valid([3.75, 0.7, 0.0]) and geo.is_valid([1.5, 1.5, 0.0])
    StaticGeometry(load_scene(ROOT / "scenes" / "tb3-arena.yaml"))  # one map
    assert made == {"_triangulate": 2, "_walls": 1}


def test_a_free_query_after_a_colliding_one_is_free():
    """The FCL data objects are made once and reset before each query: a collision or a
    contact left in them would make every later pose collide, a distance found would bound
    every later one."""
    scene = parse_scene({"version": 1, "name": "reuse", "bounds": [0, 0, 6, 4], "robot": ROBOTS["box"],
                         "obstacles": [{"polygon": U_SHAPE}, {"box": {"center": [1.0, 3.0], "size": [0.5, 0.5]}}]})  # fmt: skip
    geo = StaticGeometry(scene)
    for _ in range(2):
        assert not geo.is_valid([3.2, 1.2, 0.0])  # in the U's left arm
        assert geo.is_valid([1.5, 1.0, 0.0])
        near, far = geo.obstacle_clearance([2.3, 1.0, 0.0]), geo.obstacle_clearance([1.0, 1.0, 0.5])
        assert near == pytest.approx(3.0 - 2.3 - 0.4, abs=1e-3) and far > near + 0.2


def test_the_managers_callbacks_are_python_functions(monkeypatch):
    """python-fcl's managers ask ``inspect.isroutine`` of their callback on every query: of
    its Cython ``defaultDistanceCallback`` about 6 us (as long as the rest of a 20-object
    query's Python), of a Python function a fraction. The geometry hands them Python
    functions calling the defaults (the answers are the defaults')."""
    import inspect

    import fcl.fcl

    asked = []
    real = inspect.isroutine
    monkeypatch.setattr(fcl.fcl.inspect, "isroutine", lambda f: asked.append(f) or real(f))
    scene = parse_scene({"version": 1, "name": "cb", "bounds": [0, 0, 6, 4], "robot": ROBOTS["box"],
                         "obstacles": [{"polygon": U_SHAPE}]})  # fmt: skip
    geo = StaticGeometry(scene)
    assert not geo.is_valid([3.2, 1.2, 0.0]) and geo.obstacle_clearance([1.5, 1.0, 0.0]) > 0.5
    assert asked and all(inspect.isfunction(f) for f in asked), asked
