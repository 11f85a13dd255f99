"""Issue 9, items 1-4: clearances, parking at the goal, a start beside a person, the horizon.

Real OMPL and FCL on small scenes; every solved answer is verified by the independent check
with the clearances and the hold.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest
from conftest import run_cli_process
from reference import reference_violation
from shared_scenes import LOOP
from test_planner import _brute_force_steps

from gfuzzy.check import check_trajectory
from gfuzzy.geometry import StaticGeometry
from gfuzzy.planner import Planner, PlanOptions, Status, plan, settle_time
from gfuzzy.roadmap import RoadmapOptions, build_roadmap
from gfuzzy.scene import Query, load_scene, parse_scene
from gfuzzy.timespace import MoverField

# a room with a door 0.8 wide in a wall at x = 3
DOOR = """
version: 1
name: door
bounds: [0, 0, 6, 3]
robot: {disc: 0.2, vmax: 1.0, clearance: 0.05}
obstacles:
  - box: {center: [3, 0.55], size: [0.2, 1.1]}
  - box: {center: [3, 2.45], size: [0.2, 1.1]}
  - disc: {center: [1.5, 1.5], radius: 0.3}
queries:
  - {name: q, start: [0.5, 1.5], goal: [5.5, 1.5]}
"""


def _doc(text: str, **robot) -> dict:
    import yaml

    doc = yaml.safe_load(text)
    doc["robot"].update(robot)
    return doc


def _scene(text: str, **robot):
    return parse_scene(_doc(text, **robot))


@pytest.fixture(scope="module")
def door():
    scene = _scene(DOOR)
    return scene, build_roadmap(scene, RoadmapOptions(vertices=80, seed=2))


# --------------------------------------------------------------------------- 1. clearances


def test_clearance_keys_are_read_and_validated():
    scene = _scene(DOOR, mover_clearance=0.3)
    assert scene.robot.clearance == 0.05 and scene.robot.mover_clearance == 0.3
    plain = _scene(DOOR)
    assert plain.robot.mover_clearance == 0.0
    assert _scene(DOOR.replace(", clearance: 0.05", "")).robot.clearance == 0.0
    for key, value in (("clearance", -0.1), ("mover_clearance", float("inf")), ("clearance", "a")):
        with pytest.raises(ValueError, match=f"robot.{key}"):
            _scene(DOOR, **{key: value})


def test_static_hash_changes_with_the_static_clearance_only():
    a = _scene(DOOR, clearance=0.0)
    b = _scene(DOOR, clearance=0.05)
    c = _scene(DOOR, clearance=0.05, mover_clearance=0.4)
    assert a.static_hash != b.static_hash
    assert b.static_hash == c.static_hash
    # an override gives the same hash as the file would
    assert a.with_clearances(0.05).static_hash == b.static_hash
    assert b.with_clearances(0.0).static_hash == a.static_hash


def test_roadmap_without_the_clearance_is_refused(door):
    scene, rm = door
    other = scene.with_clearances(0.0)
    with pytest.raises(ValueError, match="other static content"):
        Planner(other, rm)


def test_the_roadmap_keeps_the_static_clearance(door):
    """Every vertex and every edge of a roadmap built with a clearance keeps it."""
    scene, rm = door
    free = StaticGeometry(scene.with_clearances(0.0))

    def to_obstacles(poses):  # the bounds are not held to the clearance
        return min(free.obstacle_clearance(p) for p in poses)

    assert to_obstacles(rm.vertices) >= 0.05 - 1e-9
    assert to_obstacles(rm.vertices) < 0.1  # some vertex does go near the walls
    for a, b in rm.edges[:: max(1, len(rm.edges) // 60)]:
        f = np.linspace(0, 1, 25)
        poses = rm.vertices[a] + f[:, None] * (rm.vertices[b] - rm.vertices[a])
        assert to_obstacles(poses) >= 0.05 - 1e-6


def test_answer_keeps_the_static_clearance_and_check_enforces_it(door):
    scene, rm = door
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal)
    assert res.solved
    rep = check_trajectory(scene, res.trajectory.waypoints, q)
    assert rep.valid, rep.reason
    assert rep.min_clearance >= -1e-9
    # the same answer against a larger clearance than it was planned for: the door
    # (0.8 wide, robot 0.4) leaves at most 0.2 on each side
    strict = scene.with_clearances(0.25)
    bad = check_trajectory(strict, res.trajectory.waypoints, q)
    assert not bad.valid
    assert "robot.clearance=0.25" in bad.reason and "comes within" in bad.reason


def test_a_clearance_wider_than_the_door_closes_it():
    scene = _scene(DOOR, clearance=0.21)  # 0.2 + 0.21 on each side > 0.4
    rm = build_roadmap(scene, RoadmapOptions(vertices=60, seed=2))
    res = plan(scene, rm, [0.5, 1.5], [5.5, 1.5])
    assert res.status is Status.NO_PATH


def test_start_too_close_to_an_obstacle_is_invalid_query(door):
    scene, rm = door
    # the static disc at (1.5, 1.5) r 0.3: a robot of radius 0.2 at x = 1.0 is 0.0 away ...
    res = plan(scene, rm, [0.97, 1.5], [5.5, 1.5])
    assert res.status is Status.INVALID_QUERY
    assert "closer than robot.clearance=0.05" in res.message
    res = plan(scene, rm, [1.1, 1.5], [5.5, 1.5])
    assert res.status is Status.INVALID_QUERY and "collides" in res.message
    assert plan(scene, rm, [0.9, 1.5], [5.5, 1.5]).solved  # 0.1 clear: fine


CROSSING = """
version: 1
name: crossing
bounds: [0, 0, 6, 6]
robot: {disc: 0.25, vmax: 1.0}
movers:
  - {name: cart, disc: 0.3, speed: 1.0, path: [[3, 0.5], [3, 5.5]], mode: bounce}
  - {name: ped, disc: 0.3, trajectory: [[0, 0.2, 1.0], [10, 5.8, 4.0]]}
queries:
  - {name: across, start: [0.5, 3.0], goal: [5.5, 3.0]}
"""


@pytest.mark.parametrize("keep", [0.0, 0.3])
def test_answer_keeps_the_mover_clearance(keep):
    scene = _scene(CROSSING, mover_clearance=keep)
    rm = build_roadmap(scene, RoadmapOptions(vertices=60, seed=1))
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal)
    assert res.solved
    assert check_trajectory(scene, res.trajectory.waypoints, q).valid
    if keep > 0:
        # the clearance costs time here (the straight run at 0 passes within 0.3 of the cart)
        loose = plan(scene.with_clearances(mover_clearance=0.0), rm, q.start, q.goal)
        tight_check = check_trajectory(scene, loose.trajectory.waypoints, q)
        assert not tight_check.valid and "robot.mover_clearance=0.3" in tight_check.reason
        assert res.duration >= loose.duration - 1e-9


def test_mover_clearance_is_in_the_margin_table():
    scene = _scene(CROSSING, mover_clearance=0.2)
    base = MoverField(scene.with_clearances(mover_clearance=0.0), 0.0, 0.07, 50, 1.0)
    kept = MoverField(scene, 0.0, 0.07, 50, 1.0)
    np.testing.assert_allclose(kept.margin - base.margin, 0.2)


def test_start_within_the_mover_clearance_is_invalid_query():
    scene = _scene(CROSSING, mover_clearance=0.3)
    rm = build_roadmap(scene, RoadmapOptions(vertices=40, seed=1))
    # the cart is at (3, 0.5) at t = 0; a robot at (3, 1.2) is 0.15 from it
    res = plan(scene, rm, [3.0, 1.2], [5.5, 3.0])
    assert res.status is Status.INVALID_QUERY
    assert "robot.mover_clearance" in res.message


def test_ga_and_speed_layer_keep_the_clearances():
    scene = _scene(CROSSING, clearance=0.05, mover_clearance=0.2)
    rm = build_roadmap(scene, RoadmapOptions(vertices=60, seed=1))
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal, options=PlanOptions(refine=True, speed_layer=True))
    assert res.solved
    # the stages keep only answers check_trajectory accepts: the oracle is the independent
    # shapely reference, which shares no code with the planner or the checker
    assert reference_violation(_doc(CROSSING, clearance=0.05, mover_clearance=0.2), res.trajectory.waypoints) == ""


# --------------------------------------------------------------------------- 2. hold



@pytest.fixture(scope="module")
def loop():
    scene = _scene(LOOP)
    return scene, build_roadmap(scene, RoadmapOptions(vertices=60, seed=1))


def test_hold_is_read_and_validated():
    scene = _scene(LOOP)
    assert scene.queries[0].hold == 2.0
    import yaml

    doc = yaml.safe_load(LOOP)
    doc["queries"][0]["hold"] = -1
    with pytest.raises(ValueError, match=r"queries\[0\].hold"):
        parse_scene(doc)


def test_without_hold_the_parked_robot_is_run_over(loop):
    scene, rm = loop
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal)  # no hold
    assert res.solved
    no_hold = Query(q.name, q.start, q.goal, q.t0)
    assert check_trajectory(scene, res.trajectory.waypoints, no_hold).valid
    rep = check_trajectory(scene, res.trajectory.waypoints, q)  # the cart comes back
    assert not rep.valid and "cart" in rep.reason


def test_hold_waits_until_the_goal_stays_clear(loop):
    scene, rm = loop
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal, hold=q.hold)
    assert res.solved
    rep = check_trajectory(scene, res.trajectory.waypoints, q)
    assert rep.valid, rep.reason
    early = plan(scene, rm, q.start, q.goal)
    assert res.duration > early.duration  # it had to arrive later
    # the stages keep the hold too
    staged = plan(scene, rm, q.start, q.goal, options=PlanOptions(refine=True, speed_layer=True), hold=q.hold)
    assert staged.solved  # (the stages filter through check_trajectory: the oracle is the reference)
    assert reference_violation(_doc(LOOP), staged.trajectory.waypoints, hold=q.hold) == ""


def test_hold_longer_than_the_gap_is_refused(loop):
    scene, rm = loop
    q = scene.queries[0]
    # the cart passes the goal every 10 s (loop length 10): a 13 s hold is impossible
    res = plan(scene, rm, q.start, q.goal, options=PlanOptions(horizon=60.0), hold=13.0)
    assert res.status is Status.NO_PATH


def test_cli_hold_and_check(tmp_path):
    path = tmp_path / "loop.yaml"
    path.write_text(LOOP)
    out = tmp_path / "a.json"
    r = run_cli_process("plan", path, "-n", "60", "--seed", "1", "-o", out, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert run_cli_process("check", path, out, cwd=tmp_path).returncode == 0
    # the same start and goal as an ad-hoc query with --hold 2: it waits
    r = run_cli_process("plan", path, "-n", "60", "--seed", "1", "--start", "1", "3", "--goal", "4", "3",
                        "--hold", "2", "-o", out, cwd=tmp_path)  # fmt: skip
    assert r.returncode == 0, r.stderr
    wps = np.array(json.loads(out.read_text())["waypoints"])
    scene = load_scene(path)
    assert check_trajectory(scene, wps, scene.queries[0]).valid
    assert run_cli_process("check", path, out, "--hold", "2", cwd=tmp_path).returncode == 0
    # without the hold the ad-hoc answer arrives as early as it can, and parks in the cart's way
    r = run_cli_process("plan", path, "-n", "60", "--seed", "1", "--start", "1", "3", "--goal", "4", "3",
                        "-o", out, cwd=tmp_path)  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert run_cli_process("check", path, out, cwd=tmp_path).returncode == 0
    bad = run_cli_process("check", path, out, "--hold", "2", cwd=tmp_path)
    assert bad.returncode == 1 and "cart" in bad.stderr
    bad = run_cli_process("plan", path, "--hold", "-1", cwd=tmp_path)
    assert bad.returncode == 2 and "--hold" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1


# --------------------------------------------------------------------------- 3. start beside a person

# a person walks east along y = 1.0 at 1.3 m/s; at t0 = 2 it is at x = 2.6
PERSON = """
version: 1
name: person
bounds: [0, 0, 6, 6]
robot: {disc: 0.25, vmax: 1.0}
movers:
  - {name: ped, disc: 0.3, trajectory: [[0, 0.0, 1.0], [4.6, 5.98, 1.0]]}
"""


@pytest.fixture(scope="module")
def person():
    scene = _scene(PERSON)
    return scene, build_roadmap(scene, RoadmapOptions(vertices=60, seed=1))


def test_start_beside_a_walking_person_is_solved(person):
    scene, rm = person
    gap = 0.036
    start = [2.6, 1.0 + 0.25 + 0.3 + gap]
    q = Query("beside", tuple(start), (2.6, 5.0), 2.0)
    field_ = MoverField(scene, 2.0, 0.07, 10, 1.0)
    assert field_.margin[0, 0] > gap  # the margin alone refuses this start
    res = plan(scene, rm, q.start, q.goal, q.t0)
    assert res.solved, res.message
    assert check_trajectory(scene, res.trajectory.waypoints, q).valid
    # touching the person at t0 is still an invalid query
    on = plan(scene, rm, [2.6, 1.5], [2.6, 5.0], 2.0)
    assert on.status is Status.INVALID_QUERY


def test_large_dt_with_nobody_near_is_solved(person):
    scene, rm = person
    start = [2.6, 2.05]  # 0.5 clear of the person at t0 = 2
    q = Query("far", tuple(start), (2.6, 5.0), 2.0)
    res = plan(scene, rm, q.start, q.goal, q.t0, options=PlanOptions(dt=1.0))
    assert res.solved, res.message
    assert check_trajectory(scene, res.trajectory.waypoints, q).valid


def test_first_motion_is_decided_exactly():
    """motion_safe agrees with a dense sampling of the first step."""
    scene = _scene(PERSON)
    field_ = MoverField(scene, 2.0, 0.07, 4, 1.0)
    mv = scene.movers[0]
    rng = np.random.default_rng(3)
    agree = 0
    for _ in range(60):
        a = np.array([2.6, 1.5]) + rng.uniform(-0.15, 0.15, 2)
        step = rng.normal(size=2)
        b = a + step / np.linalg.norm(step) * rng.uniform(0, 0.07)
        ts = np.linspace(2.0, 2.07, 2001)
        f = (ts - 2.0) / 0.07
        p = a + f[:, None] * (b - a)
        xy, _ = mv.state(ts)
        dense = (np.hypot(*(xy - p).T) - 0.55).min()
        got = field_.motion_safe(a, b, 0)
        if dense < -1e-6:
            assert not got
        elif dense > 1e-4:
            assert got
        agree += 1
    assert agree == 60


# --------------------------------------------------------------------------- 4. horizon

# a person stands in the only door for 250 s, then leaves
BLOCKED = """
version: 1
name: blocked
bounds: [0, 0, 6, 3]
robot: {disc: 0.2, vmax: 1.0}
obstacles:
  - box: {center: [3, 0.6], size: [0.2, 1.2]}
  - box: {center: [3, 2.4], size: [0.2, 1.2]}
movers:
  - {name: blocker, disc: 0.3, trajectory: [[0, 3.0, 1.5], [250, 3.0, 1.5]]}
queries:
  - {name: q, start: [0.5, 1.5], goal: [5.5, 1.5]}
"""


@pytest.fixture(scope="module")
def blocked():
    scene = _scene(BLOCKED)
    return scene, build_roadmap(scene, RoadmapOptions(vertices=60, seed=2))


def test_door_blocked_for_250_s_is_solved_by_default(blocked):
    scene, rm = blocked
    assert settle_time(scene) == pytest.approx(250.0)
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal)
    assert res.solved, res.message
    assert res.duration > 250.0 - q.t0
    assert check_trajectory(scene, res.trajectory.waypoints, q).valid


def test_no_path_from_the_horizon_says_so(blocked, tmp_path):
    scene, rm = blocked
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal, options=PlanOptions(horizon=100.0))
    assert res.status is Status.NO_PATH
    assert "horizon" in res.message and "--horizon" in res.message
    path = tmp_path / "blocked.yaml"
    path.write_text(BLOCKED)
    r = run_cli_process("plan", path, "-n", "60", "--seed", "2", "--horizon", "100", cwd=tmp_path)
    assert r.returncode == 1 and "--horizon" in r.stdout


def test_settle_time_of_periodic_and_once_movers():
    scene = _scene(LOOP)
    assert settle_time(scene) == pytest.approx(10.0)  # one period of the loop
    once = _scene(LOOP.replace("mode: loop, offset: 8.0", "mode: once"))
    assert settle_time(once) == pytest.approx(9.0)  # 9 m of polyline at 1 m/s
    assert settle_time(once, t0=4.0) == pytest.approx(5.0)


# --------------------------------------------------------------------------- bundled scenes


def test_every_bundled_query_with_clearances_passes_check(repo_root):
    """Clearance answers on every bundled scene: the same statuses, each answer valid
    under the check with the clearances."""
    from gfuzzy.regress import regress_scene

    for path in sorted((repo_root / "scenes").glob("*.yaml")):
        scene = load_scene(path).with_clearances(0.05, 0.1)
        rm = build_roadmap(scene, RoadmapOptions())
        for row, q in zip(regress_scene(scene, rm), scene.queries, strict=True):
            if q.expect is not None and q.expect.status is not None:
                assert row.status == q.expect.status, (scene.name, q.name, row.status)
            if row.status == "solved":
                assert row.valid, (scene.name, q.name, row.problems)


def test_cli_overrides_rebuild_the_roadmap_and_check_enforces_them(tmp_path):
    """--clearance changes the roadmap (said on stderr, built with the saved options);
    check with the same overrides accepts the answer, with a larger one refuses it."""
    path = tmp_path / "scenes" / "door.yaml"
    path.parent.mkdir()
    path.write_text(DOOR.replace(", clearance: 0.05", ""))
    r = run_cli_process("roadmap", path, "-n", "80", "--seed", "2", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    out = tmp_path / "a.json"
    r = run_cli_process("plan", path, "--clearance", "0.05", "--mover-clearance", "0.1", "-o", out, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "robot.clearance=0.05" in r.stderr and "80 vertices, seed 2" in r.stderr
    assert run_cli_process("check", path, out, "--clearance", "0.05", cwd=tmp_path).returncode == 0
    bad = run_cli_process("check", path, out, "--clearance", "0.25", cwd=tmp_path)
    assert bad.returncode == 1 and "robot.clearance=0.25" in bad.stderr
    r = run_cli_process("regress", path, "--clearance", "0.05", cwd=tmp_path)
    assert r.returncode == 0 and "valid" in r.stdout
    for cmd in ("plan", "regress", "check"):
        args = (path, out) if cmd == "check" else (path,)
        bad = run_cli_process(cmd, *args, "--mover-clearance", "nan", cwd=tmp_path)
        assert bad.returncode == 2 and "--mover-clearance" in bad.stderr
        assert len(bad.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("hold", [0.0, 2.0, 5.0, 9.5])
@pytest.mark.parametrize("keep", [0.0, 0.2])
def test_hold_and_mover_clearance_match_brute_force(loop, hold, keep):
    scene, rm = loop
    scene = scene.with_clearances(mover_clearance=keep)
    q = scene.queries[0]
    planner = Planner(scene, rm)
    dt, horizon = 0.1, 15.0
    res = planner.plan(q.start, q.goal, 0.0, PlanOptions(dt=dt, horizon=horizon, stretch=1.0), hold=hold)
    steps = _brute_force_steps(planner, q.start, q.goal, 0.0, dt, int(math.ceil(horizon / dt)), int(math.ceil(hold / dt - 1e-9)))
    if steps is None:
        assert res.status is Status.NO_PATH
    else:
        assert res.status is Status.SOLVED, res.message
        assert abs(res.duration - steps * dt) <= 1e-6
        assert check_trajectory(scene, res.trajectory.waypoints, replace(q, hold=hold)).valid


def test_render_draws_the_clearances(tmp_path):
    from gfuzzy.render import _clearance_outline, render

    box = _scene(DOOR.replace("disc: 0.2", "box: [0.4, 0.2]").replace("start: [0.5, 1.5], goal: [5.5, 1.5]",
                                                                       "start: [0.5, 1.5, 0], goal: [5.5, 1.5, 0]"))  # fmt: skip
    pose = np.array([1.0, 1.0, 0.3])
    ring = _clearance_outline(box, pose, 0.05)
    xy = ring.get_xy()
    local = (xy - pose[:2]) @ np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
    assert np.abs(local[:, 0]).max() == pytest.approx(0.25, abs=1e-6)  # half length + clearance
    assert np.abs(local[:, 1]).max() == pytest.approx(0.15, abs=1e-6)
    assert ring.get_linestyle() == "--" and not ring.get_fill()
    assert _clearance_outline(box, pose, 0.0) is None
    disc = _scene(DOOR)
    assert _clearance_outline(disc, pose[:2], 0.05).get_radius() == pytest.approx(0.25)
    wps = np.array([[0.0, 0.5, 1.5], [5.0, 5.5, 1.5]])
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    render(disc, a, trajectory=wps)
    render(disc.with_clearances(0.0), b, trajectory=wps)
    assert a.read_bytes() != b.read_bytes()
