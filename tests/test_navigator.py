"""The navigator among movers whose future it does not know (CONTRACT.md section 5)."""

from __future__ import annotations

import json
import math
import time

import numpy as np
import pytest
from conftest import ROOT, run_cli_process, unhurried
from helpers import main_completed, run_main

import gfuzzy
from gfuzzy.errors import InputError
from gfuzzy.navigation.brisk import brisk_arrival
from gfuzzy.navigation.navigator import Navigator, NavOptions
from gfuzzy.navigation.navsim import min_separation, observe, simulate
from gfuzzy.navigation.navtypes import NavMode
from gfuzzy.scene.scene import parse_scene


def _scene(movers=(), obstacles=(), bounds=(-5.0, -5.0, 5.0, 5.0), start=(0.0, -4.0), goal=(0.0, 4.0), robot=None):
    return parse_scene(
        {
            "version": 1,
            "name": "nav-test",
            "bounds": list(bounds),
            "robot": robot or {"disc": 0.3, "vmax": 1.0},
            "obstacles": list(obstacles),
            "movers": list(movers),
            "queries": [{"name": "q", "start": list(start), "goal": list(goal)}],
        }
    )


@pytest.fixture(scope="module")
def two_doors():
    """A wall across y = 0 with a door at x = 0 (on the straight line) and one at x = 3."""
    obstacles = [
        {"box": {"center": [-2.75, 0.0], "size": [4.5, 0.2]}},
        {"box": {"center": [1.5, 0.0], "size": [2.0, 0.2]}},
        {"box": {"center": [4.5, 0.0], "size": [1.0, 0.2]}},
    ]
    scene = _scene(obstacles=obstacles)
    return scene, gfuzzy.build_roadmap(scene, gfuzzy.RoadmapOptions(vertices=250, seed=2))


def _speeds_ok(traj: gfuzzy.Trajectory, vmax: float) -> bool:
    return bool(np.all(traj.speeds() <= vmax * (1 + 1e-9)))


def test_nobody_seen_goes_straight_to_the_goal(open_square):
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), unhurried())
    traj = nav.step(0.0, np.array([0.0, -4.0]), np.zeros((0, 5)))
    assert nav.last.mode == "plan"
    np.testing.assert_allclose(traj.waypoints[0], [0.0, 0.0, -4.0])
    np.testing.assert_allclose(traj.waypoints[-1, 1:], [0.0, 4.0])
    assert _speeds_ok(traj, 1.0)
    # no one to wait for: the roadmap route at full speed, up to a step per edge
    rd = nav.roadmap_distance([0.0, -4.0])
    assert traj.duration <= rd / 1.0 + 0.1 * 12
    assert gfuzzy.check_trajectory(scene, traj.waypoints, scene.queries[0]).valid


def test_mid_edge_start(open_square):
    scene, rm = open_square
    e = int(np.argmax(rm.lengths))
    a, b = rm.vertices[rm.edges[e]]
    pose = 0.37 * a + 0.63 * b  # strictly inside a roadmap edge, not a vertex
    nav = Navigator(scene, rm, (0.0, 4.0), unhurried())
    traj = nav.step(2.5, pose, np.zeros((0, 5)))
    assert nav.last.mode == "plan"
    np.testing.assert_allclose(traj.waypoints[0], [2.5, *pose])
    np.testing.assert_allclose(traj.waypoints[-1, 1:], [0.0, 4.0])
    assert _speeds_ok(traj, 1.0)
    assert gfuzzy.check_trajectory(scene, traj.waypoints).valid


def test_a_plan_leaves_at_full_speed(open_square):
    # the robot follows a plan for a period and replans: the search's whole steps per
    # piece of edge must not slow what it runs of it. The 7.00006 m to the goal take 71
    # steps of 0.1 s either way; cut into equal pieces the robot ran 0.0986 m a step, the
    # connection cut into whole steps runs 0.1 m a step and leaves the remainder last
    scene, rm = open_square
    pose = np.array([0.03, -3.0])
    traj = Navigator(scene, rm, (0.0, 4.0), unhurried()).step(0.0, pose, np.array([[4.0, 0.0, 0.0, 0.0, 0.3]]))
    assert traj.duration == pytest.approx(7.1)
    step = np.hypot(*np.diff(traj.waypoints[:4, 1:], axis=0).T)
    np.testing.assert_allclose(step, 0.1, rtol=1e-6)
    assert _speeds_ok(traj, 1.0)
    assert gfuzzy.check_trajectory(scene, traj.waypoints).valid


def test_the_plan_runs_at_full_speed_up_to_its_first_wait(open_square, monkeypatch):
    # the search takes a whole number of steps per piece of edge: the straight 7.00006 m
    # to the goal in sight took 71 steps of 0.1 s; the answer runs it at vmax when that
    # keeps the gaps the search kept (someone standing far away), not otherwise
    scene, rm = open_square
    pose, goal = np.array([0.03, -3.0]), (0.0, 4.0)
    far = np.array([[4.0, 0.0, 0.0, 0.0, 0.3]])
    length = math.hypot(0.03, 7.0)
    fast = unhurried(full_speed=True)
    traj = Navigator(scene, rm, goal, fast).step(0.0, pose, far)
    assert traj.duration == pytest.approx(length / scene.robot.vmax, rel=1e-6)
    assert _speeds_ok(traj, 1.0)
    assert gfuzzy.check_trajectory(scene, traj.waypoints).valid
    assert Navigator(scene, rm, goal, unhurried()).step(0.0, pose, far).duration == pytest.approx(7.1)  # off by default
    monkeypatch.setattr(Navigator, "_keeps_gaps", lambda *args: False)
    slow = Navigator(scene, rm, goal, fast).step(0.0, pose, far)
    assert slow.duration == pytest.approx(7.1)


def _box_room():
    """An empty 10 x 10 m room, a 0.6 x 0.4 m box robot (vmax 1), its 150-vertex roadmap."""
    scene = parse_scene({"version": 1, "name": "box", "bounds": [-5.0, -5.0, 5.0, 5.0],
                         "robot": {"box": [0.6, 0.4], "vmax": 1.0}})  # fmt: skip
    return scene, gfuzzy.build_roadmap(scene, gfuzzy.RoadmapOptions(vertices=150, seed=3))


@pytest.mark.parametrize("seen", [0, 1])
@pytest.mark.parametrize(("shape", "full_speed"), [("disc", False), ("box", False), ("box", True)])
def test_a_step_longer_than_the_period_does_not_creep_into_the_goal(open_square, seen, shape, full_speed):
    # a search step of 0.4 s, the robot replanned every 0.25 s (an outside harness's
    # setting): the last move into the goal took a whole step however short it was, so
    # each call covered 5/8 of what was left and the robot crept in (the 7 m, planned in
    # 7.2 s, reached at 10.25 s; 8 m took 19.5 s at a step of 1 s). Now that move runs at
    # vmax, when it keeps the search's gaps (someone seen far away); a box's too, with
    # full_speed on as well (that ran only the disc's brisk: the box crept, 11 s for 8 m)
    scene, rm = open_square
    goal, pose = (0.0, 4.0), np.array([0.0, -3.0])
    if shape == "box":
        scene, rm = _box_room()
        goal, pose = (0.0, 4.0, 0.0), np.array([0.0, -3.0, 0.0])
    obs = np.array([[4.0, 0.0, 0.0, 0.0, 0.3]])[:seen]
    opts = NavOptions(dt=0.4, time_budget=5.0, budget_clock="cpu", full_speed=full_speed)
    nav = Navigator(scene, rm, goal, opts)
    t, first = 0.0, None
    while not nav.reached and t < 20.0:
        traj = nav.step(t, pose, obs)
        first = traj.t_end if first is None else first
        assert _speeds_ok(traj, 1.0)
        t += 0.25
        pose = traj.at(t)
    assert nav.reached and t - 0.25 <= first + 0.25 + 1e-9  # the call that found it there, a period after


def _arrival(nav: Navigator, rows, obs=None, since: float = 0.25) -> np.ndarray:
    """brisk_arrival's answer (its rows) to the plan ``rows`` at their first time (nobody seen: ``obs`` None)."""
    obs = np.zeros((0, 5)) if obs is None else obs
    traj = gfuzzy.Trajectory(np.array(rows, float), nav.robot.circumradius)
    keep = lambda: nav._inflation(traj.waypoints[0, 1:], obs)  # noqa: E731
    return brisk_arrival(nav, float(rows[0][0]), traj.waypoints[0, 1:], traj, obs, keep, False, since).waypoints


def test_the_last_move_into_the_goal_runs_at_full_speed_only_then(open_square, monkeypatch):
    # brisk_arrival's guards, each on its own (the plans are made up, the robot the
    # tests' disc): the sliver into the goal at vmax and nothing else of the plan ...
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(dt=0.4))
    plan = [[1.0, 0.0, 3.9], [1.4, 0.0, 4.0], [2.4, 0.0, 4.0]]
    fast = _arrival(nav, plan)
    np.testing.assert_allclose(fast[1, 0], 1.0 + 0.1 / nav.vplan)
    np.testing.assert_array_equal(np.delete(fast, 1, axis=0), np.delete(np.array(plan), 1, axis=0))
    np.testing.assert_array_equal(fast[:, 1:], np.array(plan)[:, 1:])
    # ... not a short move that does not end at the goal ...
    mid = [[1.0, 0.0, 0.0], [1.4, 0.0, 0.1], [2.4, 0.0, 1.1]]
    np.testing.assert_array_equal(_arrival(nav, mid), mid)
    # ... nor one that ends before the next call (a step of 0.1 s, calls every 0.25 s) ...
    short = [[1.0, 0.0, 3.95], [1.1, 0.0, 4.0], [2.1, 0.0, 4.0]]
    np.testing.assert_array_equal(_arrival(Navigator(scene, rm, (0.0, 4.0)), short), short)
    # ... nor one that would not keep the search's gaps from someone seen
    far = np.array([[4.0, 0.0, 0.0, 0.0, 0.3]])
    assert _arrival(nav, plan, far)[1, 0] < 1.4
    monkeypatch.setattr(Navigator, "_keeps_gaps", lambda *args: False)
    np.testing.assert_array_equal(_arrival(nav, plan, far), plan)


def test_the_last_move_into_the_goal_turns_within_the_speed_bound(open_square):
    # a box turning a quarter while it moves 0.1 m into the goal: its time is the
    # configuration metric's (the turn counts), not the 0.1 m's; a unicycle keeps its plan
    box = Navigator(*_box_room(), (0.0, 4.0, math.pi / 2), NavOptions(dt=0.4))
    plan = [[1.0, 0.0, 3.9, 0.0], [2.0, 0.0, 4.0, math.pi / 2], [3.0, 0.0, 4.0, math.pi / 2]]
    fast = _arrival(box, plan)
    assert 1.1 < fast[1, 0] < 2.0
    assert _speeds_ok(gfuzzy.Trajectory(fast, box.robot.circumradius), box.vplan)
    drive = parse_scene({"version": 1, "name": "drive", "bounds": [-5.0, -5.0, 5.0, 5.0],
                         "robot": {"disc": 0.3, "vmax": 1.0, "kinematics": "unicycle", "wmax": 1.0}})  # fmt: skip
    rm = gfuzzy.build_roadmap(drive, gfuzzy.RoadmapOptions(vertices=60, seed=3))
    unicycle = Navigator(drive, rm, (0.0, 4.0, math.pi / 2), NavOptions(dt=0.4))
    ahead = [[1.0, 0.0, 3.9, math.pi / 2], [1.4, 0.0, 4.0, math.pi / 2], [2.4, 0.0, 4.0, math.pi / 2]]
    np.testing.assert_array_equal(_arrival(unicycle, ahead), ahead)


def test_person_walking_straight_at_the_robot_is_dodged(open_square):
    scene0, rm = open_square
    # a person walks down the robot's straight line at 1 m/s, start to finish
    person = {"name": "p", "disc": 0.3, "trajectory": [[0.0, 0.0, 4.0], [9.0, 0.0, -5.0]]}
    scene = _scene(movers=[person])
    q = scene.queries[0]
    res = simulate(scene, rm, q.start, q.goal, 0.0, 0.25, max_time=30.0)
    assert res.reached
    assert res.min_separation >= 0.0
    assert gfuzzy.check_trajectory(scene, res.trajectory.waypoints, q).valid
    xy = res.trajectory.poses
    assert np.max(np.abs(xy[:, 0])) > 0.3  # stepped aside ...
    assert res.duration < 8.0 + 4.0  # ... rather than waiting for the person to pass by


def test_person_standing_in_a_doorway(two_doors):
    scene0, rm = two_doors
    person = {"name": "door", "disc": 0.3, "trajectory": [[0.0, 0.0, 0.0], [200.0, 0.0, 0.0]]}
    scene = _scene(movers=[person], obstacles=scene0.raw["obstacles"])
    q = scene.queries[0]
    res = simulate(scene, rm, q.start, q.goal, 0.0, 0.25, max_time=60.0, options=unhurried())
    assert res.reached
    assert gfuzzy.check_trajectory(scene, res.trajectory.waypoints, q).valid
    # it went through the other door
    at_wall = res.trajectory.at(np.linspace(res.trajectory.t0, res.trajectory.t_end, 400))
    crossing = at_wall[np.argmin(np.abs(at_wall[:, 1]))]
    assert crossing[0] > 2.0


def test_surrounded_robot_gets_an_evasive_motion(open_square):
    scene, rm = open_square
    pose = np.array([0.0, 0.0])
    ang = np.arange(8) * (2 * math.pi / 8)
    # eight people 0.05 m from the robot, all walking at it
    pos = np.column_stack([np.cos(ang), np.sin(ang)]) * 0.65
    obs = np.column_stack([pos, -np.column_stack([np.cos(ang), np.sin(ang)]), np.full(8, 0.3)])
    nav = Navigator(scene, rm, (0.0, 4.0))
    traj = nav.step(1.0, pose, obs)
    assert nav.last.mode == "evasive"
    np.testing.assert_allclose(traj.waypoints[0], [1.0, 0.0, 0.0])
    assert _speeds_ok(traj, 1.0)
    assert traj.duration >= nav.options.cover - 1e-9


def test_evasive_motion_steps_away_from_a_close_person(open_square):
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0))
    pose = np.array([0.0, 0.0])
    obs = np.array([[0.65, 0.0, -1.0, 0.0, 0.3]])  # touching distance soon, walking at the robot
    traj = nav._evasive(0.0, pose, obs)
    ts = np.linspace(0.0, 2.0, 2001)
    person = obs[0, :2] + ts[:, None] * obs[0, 2:4]
    gap = np.hypot(*(traj.at(ts) - person).T) - 0.6
    assert gap.min() > 0.0  # out of the way for the whole look-ahead
    # standing still would have been hit within 0.05 s
    assert np.hypot(*(pose - person[ts > 0.06][0])) < 0.6


def test_time_budget_falls_back_to_the_previous_plan(open_square):
    """A budget of 1e-9 s is spent before any search (on any machine): the previous plan if
    there is one, else the evasive motion. The first plan has all the time it needs."""
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), unhurried())
    first = nav.step(0.0, np.array([0.0, -4.0]), np.zeros((0, 5)))
    assert nav.last.mode == "plan"
    hurried = Navigator(scene, rm, (0.0, 4.0), NavOptions(time_budget=1e-9))
    hurried._previous = first
    pose = first.at(0.25)
    traj = hurried.step(0.25, pose, np.zeros((0, 5)))
    assert hurried.last.mode == "previous"
    np.testing.assert_allclose(traj.waypoints[0], [0.25, *pose])
    np.testing.assert_allclose(traj.at(1.0), first.at(1.0))
    # nothing to fall back on: the evasive motion, still a valid trajectory
    alone = Navigator(scene, rm, (0.0, 4.0), NavOptions(time_budget=1e-9))
    traj = alone.step(0.0, np.array([0.0, -4.0]), np.zeros((0, 5)))
    assert alone.last.mode == "evasive"
    assert _speeds_ok(traj, 1.0)


def test_start_inside_the_inflated_prediction_still_moves(open_square):
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0))
    pose = np.array([0.0, -2.0])
    obs = np.array([[0.7, -2.0, 0.0, 0.0, 0.3]])  # 0.1 m away: inside the safety buffer
    traj = nav.step(0.0, pose, obs)
    assert nav.last.mode in ("plan", "evasive")
    assert traj.at(1.0)[1] != pose[1] or traj.at(1.0)[0] != pose[0]


def test_goal_reached(open_square):
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0))
    traj = nav.step(3.0, np.array([0.0, 4.0]), np.zeros((0, 5)))
    assert nav.reached
    np.testing.assert_allclose(traj.poses, [[0.0, 4.0], [0.0, 4.0]])


def test_bad_arguments_raise(open_square):
    scene, rm = open_square
    with pytest.raises(ValueError):
        Navigator(scene, rm, (0.0, 9.0))  # out of bounds
    nav = Navigator(scene, rm, (0.0, 4.0))
    with pytest.raises(ValueError):
        nav.step(0.0, np.array([0.0, math.nan]), np.zeros((0, 5)))
    with pytest.raises(ValueError):
        NavOptions(time_budget=0.0)


@pytest.mark.parametrize("name", ["sim-5s2m", "building-floor"])  # a disc robot, a box robot
def test_among_loop_movers(name):
    scene = gfuzzy.load_scene(ROOT / "scenes" / f"{name}.yaml")
    rm = gfuzzy.load_roadmap(ROOT / "roadmaps" / f"{name}.json", scene)
    q = scene.queries[0]
    # the budget on the process's CPU time: on the wall clock the run depended on the machine's
    # load (at load 6-7 with the suite on both cores, building-floor's run touched mover B)
    opts = NavOptions(budget_clock="cpu")
    res = simulate(scene, rm, q.start, q.goal, q.t0, 0.25, max_time=60.0, options=opts)
    report = gfuzzy.check_trajectory(scene, res.trajectory.waypoints, q if res.reached else None)
    assert report.valid, report.reason
    assert res.reached


def test_observe_reports_true_velocity_and_range():
    movers = [
        {"name": "a", "disc": 0.3, "trajectory": [[0.0, 0.0, 0.0], [2.0, 2.0, 0.0]]},
        {"name": "b", "box": [0.4, 0.2], "speed": 0.5, "path": [[3.0, 3.0], [3.0, -3.0]], "mode": "bounce"},
    ]
    scene = _scene(movers=movers)
    obs = observe(scene, 1.0, np.array([0.0, -4.0]))
    np.testing.assert_allclose(obs[0], [1.0, 0.0, 1.0, 0.0, 0.3], atol=1e-6)
    np.testing.assert_allclose(obs[1, 2:4], [0.0, -0.5], atol=1e-6)
    assert obs[1, 4] == pytest.approx(0.5 * math.hypot(0.4, 0.2))
    near = observe(scene, 1.0, np.array([0.0, -4.0]), sense=3.6)
    assert len(near) == 1 and near[0, 0] == pytest.approx(1.0)  # a is 3.52 m away, b 6.6 m


def test_min_separation_exact_matches_sampling():
    rng = np.random.default_rng(5)
    track = np.column_stack([np.linspace(0, 4, 9), rng.uniform(-2, 2, 9), rng.uniform(-2, 2, 9)])
    scene = _scene(movers=[{"name": "p", "disc": 0.3, "trajectory": track.tolist()}])
    robot = np.column_stack([np.linspace(-1, 5, 7), rng.uniform(-2, 2, 7), rng.uniform(-2, 2, 7)])
    exact = min_separation(scene, robot)
    ts = np.linspace(0, 4, 40001)
    r = gfuzzy.Trajectory(robot).at(ts)
    m = np.column_stack([np.interp(ts, track[:, 0], track[:, 1]), np.interp(ts, track[:, 0], track[:, 2])])
    sampled = float(np.min(np.hypot(*(r - m).T)) - 0.6)
    assert exact <= sampled + 1e-9
    assert exact == pytest.approx(sampled, abs=1e-3)


@pytest.mark.parametrize("backend", ["compiled", "reference"])
def test_navigate_cli_on_a_pedestrian_replay(tmp_path, backend, capsys):
    out = tmp_path / "eth.json"
    scene = ROOT / "scenes" / "eth-crossing.yaml"
    p = main_completed(capsys, "navigate", scene, "--backend", backend, "-o", out)
    assert p.returncode == 0, p.stdout + p.stderr
    doc = json.loads(out.read_text())
    assert doc["status"] == "solved"
    for key in ("replans", "replan_seconds_p95", "replan_seconds_max", "min_separation"):
        assert key in doc
    assert doc["replans"] >= 1 and doc["min_separation"] >= 0
    assert doc["waypoints"][0][1:] == [7.0, 0.6] and doc["waypoints"][-1][1:] == [7.0, 9.4]
    c = main_completed(capsys, "check", scene, out)
    assert c.returncode == 0, c.stderr
    # and a checker that shares no code with the navigator agrees
    s = gfuzzy.load_scene(scene)
    assert gfuzzy.check_trajectory(s, np.array(doc["waypoints"]), s.queries[0]).valid


@pytest.mark.parametrize(
    "args",
    [["--period", "0"], ["--period", "-1"], ["--sense", "0"], ["--max-time", "nan"], ["--query", "nope"],
     ["--path-space", "nan"], ["--personal-space", "-1"], ["--budget-clock", "gpu"]],
)
def test_navigate_bad_input(tmp_path, capsys, args):
    # in this process (a traceback would be an exception here); one real process below
    out = tmp_path / "o.json"
    rc, stdout, stderr = run_main(capsys, "navigate", ROOT / "scenes" / "eth-crossing.yaml", *args, "-o", out)
    assert rc == 2, stdout + stderr
    assert len(stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_navigate_bad_input_from_a_real_process(tmp_path):
    out = tmp_path / "o.json"
    p = run_cli_process("navigate", ROOT / "scenes" / "eth-crossing.yaml", "--period", "0", "-o", out)
    assert p.returncode == 2
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr
    assert not out.exists()


@pytest.mark.parametrize(
    "args",
    [["--soft-search", "--intrusion-cost", "-1"], ["--soft-search", "--intrusion-cost", "nan"],
     ["--soft-search", "--intrusion-cost", "1e308"], ["--intrusion-cost", "3"]],
)
def test_navigate_refuses_a_bad_intrusion_cost_by_its_flag(tmp_path, capsys, args):
    """As ``gfuzzy crowd``: one line naming ``--intrusion-cost`` (not NavOptions' field),
    exit 2, no file; without ``--soft-search`` the flag would change nothing."""
    out = tmp_path / "o.json"
    rc, stdout, stderr = run_main(capsys, "navigate", ROOT / "scenes" / "eth-crossing.yaml", *args, "-o", out)
    assert rc == 2, stdout + stderr
    assert len(stderr.strip().splitlines()) == 1 and "Traceback" not in stderr
    assert stderr.startswith("gfuzzy navigate: --intrusion-cost ")
    assert not out.exists()


def test_navigate_takes_the_navigator_options_crowd_takes(monkeypatch, tmp_path):
    """``--budget-clock``, ``--personal-space``, ``--path-space``, ``--soft-search`` and
    ``--intrusion-cost`` reach the navigator of ``gfuzzy navigate`` as they reach ``gfuzzy
    crowd``'s (a user measuring on a loaded machine needs the CPU clock)."""
    from gfuzzy.cli.main import main
    from gfuzzy.navigation import navigator

    seen = []
    real = navigator.Navigator.__init__

    def spy(self, scene, roadmap, goal, options=None):
        seen.append(options)
        real(self, scene, roadmap, goal, options)

    monkeypatch.setattr(navigator.Navigator, "__init__", spy)
    out = tmp_path / "eth.json"
    args = ["navigate", str(ROOT / "scenes" / "eth-crossing.yaml"), "--budget-clock", "cpu",
            "--personal-space", "0.3", "--path-space", "0", "--max-time", "0.5", "-o", str(out)]  # fmt: skip
    assert main(args) in (0, 1)
    assert out.exists()
    assert main([*args[:-2], "--soft-search", "--intrusion-cost", "4", "-o", str(tmp_path / "soft.json")]) in (0, 1)
    opts, soft = seen
    assert (opts.budget_clock, opts.personal_space, opts.path_space) == ("cpu", 0.3, 0.0)
    assert not opts.soft_search and (soft.soft_search, soft.intrusion_cost) == (True, 4.0)


def test_crowd_episodes():
    pytest.importorskip("pyrvo")
    from gfuzzy.navigation.crowd import CROWD, circle_crossing, orca_robot

    scene0 = circle_crossing(0, 1)
    rm = gfuzzy.build_roadmap(scene0, gfuzzy.RoadmapOptions(vertices=250, seed=1))
    for seed in (11, 12, 13):
        scene = circle_crossing(5, seed, duration=30.0)
        # the protocol: humans start near the circle and walk to the opposite point
        for mv in scene.movers:
            start, end = mv.trajectory[0, 1:], mv.trajectory[-1, 1:]
            assert 3.2 < np.hypot(*start) < 4.8
            assert np.hypot(*(end + start)) < 0.5
        q = scene.queries[0]
        res = simulate(scene, rm, q.start, q.goal, 0.0, CROWD["time_step"], max_time=CROWD["time_limit"])
        assert res.reached
        sep = min_separation(scene, res.trajectory.waypoints)
        assert sep >= 0.0
        assert gfuzzy.check_trajectory(scene, res.trajectory.waypoints, q).valid
    # the same seed, the same humans
    a, b = circle_crossing(5, 11, duration=5.0), circle_crossing(5, 11, duration=5.0)
    np.testing.assert_array_equal(a.movers[0].trajectory, b.movers[0].trajectory)
    rows, _ = orca_robot(a, time_limit=5.0)
    assert np.all(np.hypot(*np.diff(rows[:, 1:], axis=0).T) <= 0.25 + 1e-9)


def test_render_shows_the_predictions(tmp_path):
    from PIL import Image

    from gfuzzy.render.render import render_animation

    scene = gfuzzy.load_scene(ROOT / "scenes" / "zara-crowd.yaml")
    rm = gfuzzy.load_roadmap(ROOT / "roadmaps" / "zara-crowd.json", scene)
    q = scene.queries[0]
    res = simulate(scene, rm, q.start, q.goal, q.t0, 0.25, log_every=2)
    assert res.log and all(len(e["predicted"]) for e in res.log)
    plain, overlay = tmp_path / "plain.gif", tmp_path / "nav.gif"
    render_animation(scene, res.trajectory, plain, max_frames=6)
    render_animation(scene, res.trajectory, overlay, max_frames=6, predictions=res.log)
    a, b = Image.open(plain), Image.open(overlay)
    assert a.n_frames == b.n_frames == 6
    a.seek(3)
    b.seek(3)
    # the dashed predicted discs and the dotted plan change the picture
    assert np.any(np.asarray(a.convert("RGB")) != np.asarray(b.convert("RGB")))


def test_navigate_timeout_still_writes_the_executed_motion(tmp_path, capsys):
    out = tmp_path / "open.json"  # the open room, 5.3 s away
    p = main_completed(
        capsys, "navigate", ROOT / "scenes" / "sealed-room.yaml", "--query", "into-open-room", "--max-time", "3", "-o", out
    )
    assert p.returncode == 1, p.stdout + p.stderr
    doc = json.loads(out.read_text())
    assert doc["status"] == "timeout" and "waypoints" not in doc
    rows = np.array(doc["executed"])
    assert rows[0, 0] == 0.0 and rows[-1, 0] == pytest.approx(3.0)
    assert doc["replans"] == 12
    # the shortest route alone takes longer than --max-time: said before the run and in the
    # file (it said only "the goal was not reached within 3 s")
    assert doc["roadmap_distance"] == pytest.approx(3.92, abs=0.05)  # on the bundled roadmap; 3.8 m in a straight line
    why = "the goal is 3.8 m away in a straight line: at least 3.84 s at vmax 1, more than --max-time 3 s"
    assert f"({why}: give a larger --max-time)" in doc["message"] and f"note: {why}" in p.stderr
    # `check` said only "there is no trajectory to check" of the motion render and export show
    c = main_completed(capsys, "check", ROOT / "scenes" / "sealed-room.yaml", out)
    assert c.returncode == 1 and c.stderr.startswith(
        f"{out}: status is timeout: the goal was not reached, no answer to check; "
        f"the motion it executed ({len(rows)} rows, t 0 to 3) is valid (min clearance"
    ), c.stderr


def test_the_too_long_route_note_is_for_a_route_longer_than_max_time_only():
    from gfuzzy.cli.experiments import _beyond_max_time

    assert _beyond_max_time(4.0, 1.0, 4.0, 3.0) == ""  # just in time: it can arrive
    assert _beyond_max_time(4.0, 2.0, 2.0, 3.0) == "" and _beyond_max_time(math.inf, 1.0, 3.0, 2.0) == ""
    # the roadmap's route is no lower bound: a differential drive's roadmap distance counts its
    # turns, and its fan's lanes and the direct motion leave the roadmap (a footprint on the
    # TurtleBot3 map, 30.7 m at 0.5 m/s, "takes at least 61.4 s", arrived in 59.7 s)
    assert _beyond_max_time(4.0, 1.0, 3.999, 3.0).startswith("the shortest roadmap route (4.0 m) takes 4.0 s at vmax 1")
    assert "at least" not in _beyond_max_time(30.7, 0.5, 60.0, 25.0)
    # the straight line is one: at least
    assert _beyond_max_time(40.0, 1.0, 30.0, 35.0).startswith("the goal is 35.0 m away in a straight line: at least 35 s")
    # rounded up (a review: 3.04 s against --max-time 3 read "at least 3.0 s ... more than 3 s")
    assert "at least 3.05 s at vmax 1, more than --max-time 3 s" in _beyond_max_time(4.0, 1.0, 3.0, 3.041)


def test_navigate_into_a_sealed_room_is_no_path_at_once(tmp_path, capsys):
    # it replanned until --max-time (with 1e6: for hours) and said only "timeout": no mover
    # can open a way the free space does not have, as plan says
    out = tmp_path / "sealed.json"
    p = main_completed(
        capsys, "navigate", ROOT / "scenes" / "sealed-room.yaml", "--query", "into-sealed-room", "--max-time", "30", "-o", out
    )
    assert p.returncode == 1, p.stdout + p.stderr
    doc = json.loads(out.read_text())
    assert doc["status"] == "no_path" and "separate parts of the free space" in doc["message"]
    assert "waypoints" not in doc and "replans" not in doc


BOX_BEHIND_A_DOOR = """
version: 1
name: boxdoor
bounds: [0, 0, 10, 6]
robot: {box: [0.8, 0.6], vmax: 1.0}
obstacles:
  - box: {center: [5, 1.355], size: [0.2, 2.71]}
  - box: {center: [5, 4.645], size: [0.2, 2.71]}
queries:
  - {name: q, start: [1, 3, 0], goal: [9, 3, 0]}
"""


def test_navigate_of_a_box_robot_the_roadmap_does_not_join_is_no_path_at_once(tmp_path, capsys):
    # a 0.58 m door, a box 0.6 m across: plan said no_path at once, navigate replanned until
    # --max-time (120 s by default) and said timeout; it now asks the planner's own test
    scene = tmp_path / "boxdoor.yaml"
    scene.write_text(BOX_BEHIND_A_DOOR)
    out = tmp_path / "nav.json"
    rc, stdout, err = run_main(capsys, "navigate", scene, "-n", "40", "--budget-clock", "cpu", "--max-time", "5", "-o", out)
    # the disc inside the box (radius 0.3) proves it: no "more vertices may find it" (s39-newuser)
    assert rc == 1 and stdout == "boxdoor q: no_path (start and goal lie in separate parts of the free space of " \
        "the disc inside the robot's body (radius 0.300 m, clearance 0 m), so no way exists for this robot; the " \
        "start's part comes nearest another near (5.000, 3.000))\n", (stdout, err)
    doc = json.loads(out.read_text())
    assert doc["status"] == "no_path" and doc["message"] in stdout and "replans" not in doc


def test_navigate_start_on_a_person_is_an_invalid_query(tmp_path, tmp_scene, capsys):
    scene = tmp_scene(
        """
        version: 1
        name: on-a-person
        bounds: [0, 0, 6, 4]
        robot: {disc: 0.3, vmax: 1.0}
        obstacles: []
        movers:
          - {name: p, disc: 0.3, trajectory: [[0, 1.2, 2.0], [5, 5.0, 2.0]]}
        queries:
          - {name: q, start: [1.0, 2.0], goal: [5.0, 1.0]}
        """
    )
    out = tmp_path / "o.json"
    p = main_completed(capsys, "navigate", scene, "-n", "60", "-o", out)
    assert p.returncode == 1
    doc = json.loads(out.read_text())
    assert doc["status"] == "invalid_query" and "'p'" in doc["message"]


def test_goal_beside_a_person_standing_still(open_square):
    scene0, rm = open_square
    # 0.045 m between the person and the robot parked at the goal: less than the search's
    # own margin at dt 0.1, so the last metres are a checked straight dash
    person = {"name": "p", "disc": 0.3, "trajectory": [[0.0, 0.645, 4.0], [60.0, 0.645, 4.0]]}
    scene = _scene(movers=[person])
    q = scene.queries[0]
    res = simulate(scene, rm, q.start, q.goal, 0.0, 0.25, max_time=30.0)
    assert res.reached
    assert 0.0 <= res.min_separation < 0.05
    assert gfuzzy.check_trajectory(scene, res.trajectory.waypoints, q).valid
    assert res.modes.get("direct", 0) >= 1


# ----------------------------------------------------------------------------------------
# predictions: one mover per person with the inflation in the margin, who is left out,
# what the budget skips, which exceptions fall back


def _chain_field(nav, t, pose, obs, steps, relaxed=False):
    """The predictions as they were first written (a reference for ``Navigator._field``):
    each person a chain of short trajectory movers, one per slice, each disc inflated by
    its slice's inflation, in the stock :class:`MoverField`."""
    from dataclasses import replace

    from gfuzzy.navigation.navigator import STILL_SPEED
    from gfuzzy.scene.scene import Mover
    from gfuzzy.timespace.movers import MoverField

    opts = nav.options
    infl = nav._inflation(pose, obs, relaxed)
    movers = []
    for i, (x, y, vx, vy, r) in enumerate(obs.tolist()):
        still = math.hypot(vx, vy) < STILL_SPEED
        if still:
            vx = vy = 0.0
        for s in range(infl.shape[1]):
            ta = s * opts.slice
            tb = min((s + 1) * opts.slice, opts.prediction_horizon)
            rows = np.array([[t + ta, x + vx * ta, y + vy * ta], [t + tb, x + vx * tb, y + vy * tb]])
            if s == infl.shape[1] - 1 and still and opts.stationary_hold > 0:
                rows[1, 0] = t + tb + opts.stationary_hold
            movers.append(Mover(f"p{i}s{s}", "disc", float(r + infl[i, s]), (0.0, 0.0), trajectory=rows))
    scene = replace(nav.scene, robot=nav._pred_robot, movers=tuple(movers))
    return MoverField(scene, t, opts.dt, steps, nav.vplan), infl


def _crowd(rng, k, centre, spread=3.0):
    xy = centre[:2] + rng.uniform(-spread, spread, size=(k, 2))
    v = rng.uniform(-1.3, 1.3, size=(k, 2)) * (rng.random((k, 1)) > 0.25)
    return np.column_stack([xy, v, rng.uniform(0.15, 0.35, k)])


@pytest.mark.parametrize("robot", [None, {"box": [0.6, 0.3], "vmax": 1.0, "mover_clearance": 0.1}])
@pytest.mark.parametrize("relaxed", [False, True])
def test_prediction_field_matches_a_chain_of_slice_movers(robot, relaxed):
    box = robot is not None
    start, goal = ((0.0, -4.0, 0.0), (0.0, 4.0, 0.0)) if box else ((0.0, -4.0), (0.0, 4.0))
    scene = _scene(robot=robot, bounds=(-6.0, -6.0, 6.0, 6.0), start=start, goal=goal)
    rm = gfuzzy.build_roadmap(scene, gfuzzy.RoadmapOptions(vertices=60, seed=1))
    nav = Navigator(scene, rm, goal, NavOptions(backend="reference"))
    rng = np.random.default_rng(7)
    pose = np.array([0.2, -0.3] if robot is None else [0.2, -0.3, 0.4])
    obs = _crowd(rng, 12, pose)
    obs[0] = [pose[0] + 0.75, pose[1], -0.8, 0.0, 0.3]  # walked up to the robot: shrunk inflation
    obs[1, 2:4] = 0.05  # standing (under STILL_SPEED): held past the horizon
    steps = 90
    ref, infl = _chain_field(nav, 3.0, pose, obs, steps, relaxed)
    ours = nav._field(3.0, obs, infl, steps)
    assert len(ours.movers) == len(obs) < len(ref.movers)
    pts = pose[None] + np.column_stack([rng.uniform(-4, 4, (400, 2)), rng.uniform(-3, 3, (400, int(box)))])
    got, want = ours.unsafe(pts), ref.unsafe(pts)
    assert want.any() and not want.all()
    np.testing.assert_array_equal(got, want)
    ours.compiled = ref.compiled = True  # the compiled kernel's answers: the same
    np.testing.assert_array_equal(ours.unsafe(pts), want)
    np.testing.assert_array_equal(ref.unsafe(pts), want)
    # the first motions' exact check: the same answers for short motions from the pose
    for _ in range(60):
        d = rng.normal(size=pose.shape)
        b = pose + d / np.linalg.norm(d) * nav.step_len * rng.uniform(0, 1)
        assert ours.motion_safe(pose, b, 0) == ref.motion_safe(pose, b, 0)


def test_people_who_cannot_come_within_reach_are_left_out(open_square):
    scene, rm = open_square
    # the ring below is laid out for the inflation without the personal space; the compiled
    # fields answer the 5900 poses below as the reference ones do (0.2 s, not 6.6)
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(backend="compiled", personal_space=0.0))
    pose = np.array([0.0, -4.0])
    rng = np.random.default_rng(3)
    # people walking straight away from the robot, at 1 m/s from 0.9 to 2.05 m (the robot,
    # at 0.99 m/s, closes on them only slowly while their inflation grows) and at 0.5 m/s
    # from 2.6 to 3.75 m (it catches up): whether it can reach a far one's inflated disc
    # before the prediction ends is a close call
    ang = np.radians(np.arange(48) * 7.5)
    u = np.column_stack([np.cos(ang), np.sin(ang)])
    dist = np.concatenate([0.9 + 0.05 * np.arange(24), 2.6 + 0.05 * np.arange(24)])
    speed = np.repeat([1.0, 0.5], 24)
    ring = np.column_stack([pose + u * dist[:, None], u * speed[:, None], np.full(48, 0.3)])
    obs = np.vstack([
        ring,
        _crowd(rng, 20, np.array([0.0, 0.0]), 4.5),
        [[4.5, 4.5, 1.0, 1.0, 0.3], [-4.5, 4.0, 0.0, 1.2, 0.3]],  # far, walking away: out
    ])  # fmt: skip
    infl = nav._inflation(pose, obs)
    steps = 80
    keep = nav._relevant(pose, obs, infl, steps * nav.options.dt)
    assert not keep[-2:].any()
    assert keep[:24].any() and not keep[:24].all() and keep[24:48].any() and not keep[24:48].all()
    full = nav._field(0.0, obs, infl, steps)
    some = nav._field(0.0, obs[keep], infl[keep], steps)
    # poses the robot can reach at step n: within vplan * n * dt of where it is; on the
    # rim toward each ring person (where it comes closest), and anywhere inside
    n_rim = np.tile(np.arange(steps + 1), 48)
    rim = pose + np.repeat(u, steps + 1, axis=0) * (nav.vplan * n_rim * nav.options.dt)[:, None]
    n_in = rng.integers(0, steps + 1, 2000)
    a_in = rng.uniform(0, 2 * math.pi, 2000)
    r_in = np.sqrt(rng.uniform(0, 1, 2000)) * nav.vplan * n_in * nav.options.dt
    pts = np.vstack([rim, pose + np.column_stack([r_in * np.cos(a_in), r_in * np.sin(a_in)])])
    n = np.concatenate([n_rim, n_in])
    i = np.arange(len(pts))
    a, b = full.unsafe(pts)[i, n], some.unsafe(pts)[i, n]
    assert a[: len(rim)].any() and a[len(rim) :].any()
    np.testing.assert_array_equal(a, b)


def test_fallbacks_only_look_at_people_who_can_matter(open_square):
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0))
    pose = np.array([0.0, -1.0])
    near = np.array([[0.0, 0.2, 0.0, -1.0, 0.3], [1.2, -1.0, -0.5, 0.0, 0.3]])
    far = np.array([[4.0, 4.0, 1.0, 0.5, 0.3], [-4.0, 3.0, -1.0, 0.0, 0.3]])
    assert len(nav._near(pose, np.vstack([near, far]), nav.options.evasion_time, 0.5)) == 2
    one = nav._evasive(0.0, pose, near)
    both = nav._evasive(0.0, pose, np.vstack([near, far]))
    np.testing.assert_array_equal(one.waypoints, both.waypoints)


def test_exhausted_budget_builds_no_prediction(open_square, monkeypatch):
    scene, rm = open_square
    calls = []
    real = Navigator._field

    def counting(self, *args):
        calls.append(args)
        return real(self, *args)

    monkeypatch.setattr(Navigator, "_field", counting)
    obs = np.array([[0.0, 0.0, 0.0, -1.0, 0.3], [2.0, 1.0, -1.0, 0.0, 0.3]])
    nav = Navigator(scene, rm, (0.0, 4.0), unhurried())
    nav.step(0.0, np.array([0.0, -4.0]), obs)
    assert calls and nav.last.mode in ("plan", "close", "relaxed")  # with time: the predictions are built, a search answers
    calls.clear()
    late = Navigator(scene, rm, (0.0, 4.0))
    ticks = iter([0.0] + [1.0] * 100)  # the clock: the call began, then a whole second went by
    late._clock = lambda: next(ticks)
    traj = late.step(0.0, np.array([0.0, -4.0]), obs)
    assert not calls
    assert late.last.mode in ("direct", "previous", "evasive")
    assert "budget" in late.last.message
    np.testing.assert_allclose(traj.waypoints[0], [0.0, 0.0, -4.0])


def _field_case(open_square, people):
    """A navigator at (0, -4) of the open square (reference search), ``people`` seen about
    the centre, their inflation, and the kept graph with the robot spliced in."""
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(backend="reference"))
    pose = np.array([0.0, -4.0])
    obs = _crowd(np.random.default_rng(5), people, np.array([0.0, 0.0]), 4.0)
    return nav, obs, nav._inflation(pose, obs), nav._splice(pose)[0]


def test_the_field_answers_in_pieces_and_stops_at_the_deadline(open_square):
    from gfuzzy.navigation.navigator import PIECE_WORK, _OutOfTime

    nav, obs, infl, graph = _field_case(open_square, 25)
    pts = graph.poses[: 3 * PIECE_WORK // len(obs) + 17]  # groups of the kept graph: several pieces
    groups = graph.groups[graph.groups <= len(pts)]
    ptr = np.unique(np.concatenate([np.arange(nav._nv + 2), groups, [len(pts)]]))
    rng = np.random.default_rng(1)
    lo = rng.integers(0, 20, len(ptr) - 1)
    hi = lo + rng.integers(0, 60, len(ptr) - 1)
    timed = nav._field(0.0, obs, infl, 80)
    whole = nav._field(0.0, obs, infl, 80)
    whole.__class__ = gfuzzy.timespace.movers.MoverField  # the same field, answering in one piece
    want = set(zip(*whole.unsafe_pairs(pts, ptr, lo, hi), strict=True))
    assert want
    assert set(zip(*timed.unsafe_pairs(pts, ptr, lo, hi), strict=True)) == want
    if hasattr(whole, "safe_intervals"):  # a store that asks for intervals (compiled kernel)
        for x, y in zip(timed.safe_intervals(pts, ptr, lo, hi), whole.safe_intervals(pts, ptr, lo, hi), strict=True):
            np.testing.assert_array_equal(x, y)
    ticks = iter([0.0, 0.01, 5.0, 5.0])  # the deadline passes after the second piece
    late = nav._field(0.0, obs, infl, 80, deadline=1.0)
    late.clock, late.pace = (lambda: next(ticks)), None  # a piece of 10 ms: the pieces stay as they are
    with pytest.raises(_OutOfTime):
        late.unsafe_pairs(pts, ptr, lo, hi)


def test_the_field_cuts_its_pieces_by_the_steps_asked_too(open_square):
    """Few points over many steps each are several pieces (a differential drive's store
    asked 8,400 points over 280 steps among 5 people in one piece, 92 ms past its deadline)."""
    from gfuzzy.navigation.timedfield import PIECE_STEP_WORK, PIECE_WORK, _OutOfTime

    nav, obs, infl, graph = _field_case(open_square, 5)
    steps = 400
    n = 3 * PIECE_STEP_WORK // (len(obs) * steps) + 7  # three pieces' worth of triples
    assert n < PIECE_WORK // len(obs)  # one piece by the points alone
    pts = graph.poses[:n]
    ptr = np.arange(n + 1)
    lo, hi = np.zeros(n, dtype=np.int64), np.full(n, steps - 1, dtype=np.int64)
    whole = nav._field(0.0, obs, infl, steps)
    whole.__class__ = gfuzzy.timespace.movers.MoverField
    timed = nav._field(0.0, obs, infl, steps)
    asked = []
    timed.clock, timed.pace = (lambda: asked.append(1) or 0.01 * len(asked)), None  # each piece 10 ms
    assert set(zip(*timed.unsafe_pairs(pts, ptr, lo, hi), strict=True)) == set(
        zip(*whole.unsafe_pairs(pts, ptr, lo, hi), strict=True))
    assert len(asked) >= 3  # the clock looked at before each piece
    ticks = iter([0.0, 5.0, 5.0])  # the deadline passes during the first piece
    late = nav._field(0.0, obs, infl, steps, deadline=1.0)
    late.clock, late.pace = (lambda: next(ticks)), None
    with pytest.raises(_OutOfTime):
        late.unsafe_pairs(pts, ptr, lo, hi)


def test_the_fields_pieces_grow_to_a_few_ms_and_keep_the_deadline(open_square, monkeypatch):
    """Once a piece has been timed, the next ones are as many of the fixed bounds as take
    about ``PIECE_SECONDS`` (each piece costs Python beyond the kernels), never fewer than
    one; the deadline is still looked at between two, and a batch runs past it by about a
    piece at most. The clock here ticks with the work done: 20 ns per (point, person, step)."""
    from gfuzzy.navigation import timedfield as T

    monkeypatch.setattr(T, "PIECE_STEP_WORK", 50_000)  # a fixed piece: 1 ms on this clock
    nav, obs, infl, graph = _field_case(open_square, 5)
    steps, n = 400, 500  # 1,000,000 triples: 20 fixed pieces
    pts = np.resize(graph.poses, (n, graph.poses.shape[1]))
    ptr = np.arange(n + 1)
    lo, hi = np.zeros(n, dtype=np.int64), np.full(n, steps - 1, dtype=np.int64)
    whole = nav._field(0.0, obs, infl, steps)
    whole.__class__ = gfuzzy.timespace.movers.MoverField
    want = set(zip(*whole.unsafe_pairs(pts, ptr, lo, hi), strict=True))
    now, pieces = [0.0], []
    plain = gfuzzy.timespace.movers.MoverField.unsafe_pairs

    def worked(self, p, sub, a, b):  # each piece advances the clock by its work
        triples = int((np.diff(sub) * (np.asarray(b) - np.asarray(a) + 1)).sum()) * len(self.movers)
        pieces.append(triples)
        now[0] += 2e-8 * triples
        return plain(self, p, sub, a, b)

    monkeypatch.setattr(gfuzzy.timespace.movers.MoverField, "unsafe_pairs", worked)
    timed = nav._field(0.0, obs, infl, steps)
    timed.clock, timed.pace = (lambda: now[0]), None
    assert set(zip(*timed.unsafe_pairs(pts, ptr, lo, hi), strict=True)) == want
    assert sum(pieces) == 1_000_000 and len(pieces) <= 8  # fixed pieces: 20
    assert pieces[0] <= 50_000 and max(pieces) <= T.PIECE_SECONDS / 2e-8 * 1.01  # about 4 ms each
    assert timed.pace.unit == pytest.approx(1e-3, rel=0.02)
    pieces.clear()
    late = nav._field(0.0, obs, infl, steps, deadline=0.0065)
    now[0] = 0.0
    late.clock, late.pace = (lambda: now[0]), timed.pace  # measured already: 4 ms pieces from the start
    with pytest.raises(T._OutOfTime):
        late.unsafe_pairs(pts, ptr, lo, hi)
    assert len(pieces) >= 3 and now[0] <= 0.0065 + 1e-3 * 1.01  # grown 1, 2, 3.5 ms: out one fixed piece late


def test_a_pace_timed_on_cheap_pieces_sends_no_large_piece_among_the_people(open_square, monkeypatch):
    """A batch of points far from everyone times the pieces cheap (0.1 ms a fixed piece), a
    later batch among the people costs 100 times more per triple: its first piece is one
    fixed piece (10 ms here), so it runs past a deadline by about that, not by the 40 fixed
    pieces the cheap pace allows (400 ms)."""
    from gfuzzy.navigation import timedfield as T

    monkeypatch.setattr(T, "PIECE_STEP_WORK", 50_000)
    nav, obs, infl, graph = _field_case(open_square, 5)
    steps, n = 400, 500
    pts = np.resize(graph.poses, (n, graph.poses.shape[1]))
    ptr = np.arange(n + 1)
    lo, hi = np.zeros(n, dtype=np.int64), np.full(n, steps - 1, dtype=np.int64)
    now, cost = [0.0], [2e-9]
    plain = gfuzzy.timespace.movers.MoverField.unsafe_pairs

    def worked(self, p, sub, a, b):
        now[0] += cost[0] * int((np.diff(sub) * (np.asarray(b) - np.asarray(a) + 1)).sum()) * len(self.movers)
        return plain(self, p, sub, a, b)

    monkeypatch.setattr(gfuzzy.timespace.movers.MoverField, "unsafe_pairs", worked)
    cheap = nav._field(0.0, obs, infl, steps)
    cheap.clock, cheap.pace = (lambda: now[0]), None
    cheap.unsafe_pairs(pts, ptr, lo, hi)
    assert cheap.pace.scale() > 30  # 4 ms / 0.1 ms
    cost[0], now[0] = 2e-7, 0.0
    dense = nav._field(0.0, obs, infl, steps, deadline=1e-4)
    dense.clock, dense.pace = (lambda: now[0]), cheap.pace
    with pytest.raises(T._OutOfTime):
        dense.unsafe_pairs(pts, ptr, lo, hi)
    assert now[0] <= 1e-4 + 0.010 * 1.01


def test_a_search_out_of_time_inside_a_batch_falls_back(open_square):
    """The budget runs out once the predictions are built, inside the search's safety work:
    the fallback answers and says where the time went. Until then the budget (5 s of CPU)
    is never reached, so the clock, not the machine's load, decides where it runs out."""
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), unhurried())
    obs = np.array([[0.0, 0.0, 0.0, -1.0, 0.3], [2.0, 1.0, -1.0, 0.0, 0.3]])
    late, clock = [0.0], nav._clock
    nav._clock = lambda: clock() + late[0]  # the search keeps the real clock
    real = Navigator._field

    def field_then_late(self, *args):  # the budget is gone once the search asks for safety
        field_ = real(self, *args)
        late[0] = 1e6
        return field_

    nav._field = field_then_late.__get__(nav)
    traj = nav.step(0.0, np.array([0.0, -4.0]), obs)
    assert nav.last.mode in ("direct", "previous", "evasive")
    assert nav.last.message == "time budget spent on the predicted people's safety"
    assert _speeds_ok(traj, 1.0)


@pytest.mark.parametrize("error", [RuntimeError("a bug"), TypeError("a bug")])
def test_a_bug_in_the_search_propagates(open_square, monkeypatch, error):
    scene, rm = open_square

    def broken(graph, field_, start, goal, **kw):
        raise error

    monkeypatch.setattr("gfuzzy.navigation.navigator.search_function", lambda backend: broken)
    nav = Navigator(scene, rm, (0.0, 4.0), unhurried())  # the search is reached: no budget runs out before it
    with pytest.raises(type(error), match="a bug"):
        nav.step(0.0, np.array([0.0, -4.0]), np.array([[0.0, 0.0, 0.0, -1.0, 0.3]]))


@pytest.mark.parametrize("family", ["LimitError", "InputError"])
def test_a_refused_search_falls_back(open_square, monkeypatch, family):
    import gfuzzy.errors

    scene, rm = open_square
    error = getattr(gfuzzy.errors, family)

    def refusing(graph, field_, start, goal, **kw):
        raise error("horizon beyond the memory bounds")

    monkeypatch.setattr("gfuzzy.navigation.navigator.search_function", lambda backend: refusing)
    nav = Navigator(scene, rm, (0.0, 4.0), unhurried())  # the search is reached: no budget runs out before it
    traj = nav.step(0.0, np.array([0.0, -4.0]), np.array([[0.0, 0.0, 0.0, -1.0, 0.3]]))
    assert nav.last.mode in ("direct", "previous", "evasive")
    assert "refused" in nav.last.message
    np.testing.assert_allclose(traj.waypoints[0], [0.0, 0.0, -4.0])


def test_evasive_motion_backs_out_of_a_contact(open_square):
    """Already touching a person (everyone's gap is the same now), the evasive motion opens
    the gap rather than heading on to the goal through them (found by the budget bench:
    60 people, the robot pushed 9 cm into a person walking across its way)."""
    scene, rm = open_square
    nav = Navigator(scene, rm, (-3.0, 0.0))
    pose = np.array([0.0, 0.0])
    # a person overlapping the robot by 1 cm, between it and the goal, walking slowly away
    obs = np.array([[-0.59, 0.0, -0.3, 0.0, 0.3]])
    traj = nav._evasive(0.0, pose, obs)
    ts = np.linspace(0.0, 0.25, 26)
    person = obs[0, :2] + ts[:, None] * obs[0, 2:4]
    gap = np.hypot(*(traj.at(ts)[:, :2] - person).T) - 0.6
    assert gap[0] < 0  # in contact at the start
    assert np.all(np.diff(gap) >= -1e-12) and gap[-1] > 0  # the gap only opens, and is open by one period


def _standing_row(xs, y=0.0, r=0.3):
    return np.array([[x, y, 0.0, 0.0, r] for x in xs])


def _gap_to_standing(traj, people, robot_radius, step=0.005):
    """Smallest gap between the disc robot along ``traj`` and people standing still,
    sampled finely (a standing person's gap changes by at most vmax * step / 2 in between)."""
    times = np.arange(traj.waypoints[0, 0], traj.t_end, step)
    xy = np.array([np.interp(times, traj.waypoints[:, 0], traj.waypoints[:, i]) for i in (1, 2)]).T
    d = np.hypot(xy[:, None, 0] - people[None, :, 0], xy[:, None, 1] - people[None, :, 1])
    return float((d - robot_radius - people[None, :, 4]).min())


def test_personal_space_is_a_soft_cost(open_square):
    """A row of people standing across the way, 0.12 m on either side of the robot in each
    gap: keeping 0.2 m from them costs a detour round the row (over 2 s); the navigator
    passes through a gap (keeping its safety buffer) unless the cost says the detour is worth it."""
    scene, rm = open_square
    people = _standing_row([-2.16, -0.72, 0.72, 2.16])
    start = np.array([0.0, -4.0])
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(time_budget=5.0))
    traj = nav.step(0.0, start, people)
    assert nav.last.mode == "close"
    assert traj.duration <= nav.roadmap_distance(start) / 1.0 + 1.5
    assert _gap_to_standing(traj, people, 0.3) >= 0.0
    patient = Navigator(scene, rm, (0.0, 4.0), NavOptions(time_budget=5.0, personal_space_cost=10.0))
    detour = patient.step(0.0, start, people)
    assert patient.last.mode == "plan"
    assert detour.duration > traj.duration + 1.0
    assert _gap_to_standing(detour, people, 0.3) >= 0.2


def test_previous_plan_is_refused_when_it_grazes_someone_between_samples(open_square):
    """The last plan passes 0.1 mm inside a person standing beside it, at an instant between
    two samples of a coarse check; it must not be followed (the robot would touch them)."""
    scene, rm = open_square
    nav = Navigator(scene, rm, (4.6, 0.0))
    nav._previous = gfuzzy.Trajectory(np.array([[0.0, 0.0, 0.0], [5.0, 4.6, 0.0]]), 0.3)
    x0 = 0.92 * (2.5 / 12)  # midway between two samples 1/12 s apart
    for y0, clear in ((0.6 - 1e-4, False), (0.7, True)):
        person = _standing_row([x0], y=y0)
        traj = nav._previous_if_clear(0.0, np.array([0.0, 0.0]), person)
        assert (traj is not None) == clear
        if traj is not None:
            assert _gap_to_standing(traj, person, 0.3) > 0.0


def test_the_close_tier_keeps_off_the_ways_the_first_plan_kept_off(open_square):
    """The path space's soft cost (5 s) is not undone by the personal space's (0.5 s): when
    the plan kept off the people's ways (their ghosts), the search without the personal
    space keeps off them too; only the path space's own tier may drop them."""
    scene, rm = open_square
    people = _standing_row([-2.16, -0.72, 0.72, 2.16])
    people[:, 3] = -0.4  # the row walks towards the robot, slowly: they have ways to keep off
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(time_budget=5.0, personal_space_cost=0.0))
    calls = []
    search = nav._search

    def spy(t, pose, obs, infl, deadline, before=None):
        calls.append(np.asarray(obs).shape)
        return search(t, pose, obs, infl, deadline, before)

    nav._search = spy
    nav.step(0.0, np.array([0.0, -4.0]), people)
    assert len(calls) >= 2, calls  # the first search and the one without the personal space
    assert calls[0][0] > len(people) and calls[0][1] == 7  # the people and their ghosts
    assert calls[1] == calls[0]  # the close tier: the same ghosts, less inflation


def test_a_kept_plan_keeps_the_gaps_of_the_tier_that_planned(open_square):
    """A unicycle keeps its last plan only while it keeps the gaps of the fresh plan's
    tier: after a 'close' plan, the safety buffer and the uncertainty (not the bare
    mover clearance of the relaxed tier)."""
    scene, rm = open_square
    opts = NavOptions()
    nav = Navigator(scene, rm, (0.0, 4.0), opts)
    person = np.array([[3.0, 0.0, 0.0, 1.0, 0.3]])  # 3 m away, walking
    pose = np.array([0.0, -4.0])
    close = nav._kept_inflation(pose, person, nav._inflation(pose, person), NavMode.CLOSE)
    n = close.shape[1]
    tau = np.arange(n) * opts.slice
    growth = opts.uncertainty_growth * min(1.0 / opts.reference_speed, 1.0) * tau
    want = nav.mover_clearance + opts.safety_buffer + growth  # far away: nothing shrunk
    np.testing.assert_allclose(close[0], want)
    relaxed = nav._kept_inflation(pose, person, None, NavMode.RELAXED)
    np.testing.assert_allclose(relaxed[0], nav.mover_clearance)


@pytest.mark.parametrize("clock, searched", [("wall", False), ("cpu", True)])
def test_the_budget_runs_on_the_chosen_clock(open_square, clock, searched):
    """A pause that is not the navigator's work (a loaded machine) spends a wall-clock
    budget, not a CPU-time one: with ``budget_clock="cpu"`` the search still answers."""
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(budget_clock=clock))
    real = Navigator._field

    def field_after_a_pause(self, *args):
        time.sleep(0.2)  # twice the budget, asleep
        return real(self, *args)

    nav._field = field_after_a_pause.__get__(nav)
    obs = np.array([[0.0, 0.0, 0.0, -1.0, 0.3], [2.0, 1.0, -1.0, 0.0, 0.3]])
    nav.step(0.0, np.array([0.0, -4.0]), obs)
    assert (nav.last.mode in ("plan", "close", "relaxed", "kept")) == searched, nav.last


def test_an_unknown_budget_clock_is_refused():
    with pytest.raises(InputError, match="budget_clock"):
        NavOptions(budget_clock="sundial")


def test_a_goal_someone_stands_on_skips_the_search_that_cannot_reach_it(open_square):
    """Someone standing 0.15 m from the goal: the first search (which keeps the personal
    space) cannot end there at any step, and says so without expanding the reachable
    space-time (among people standing round the goal that took the whole budget, so the
    next tier never ran); the search without the personal space answers."""
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(time_budget=5.0))  # a loaded machine's clock decides nothing
    pose = np.array([0.0, -2.0])
    obs = np.array([[0.0, 4.75, 0.0, 0.0, 0.3]])  # 0.15 m from a robot on the goal
    first = nav._search(0.0, pose, obs, nav._inflation(pose, obs), math.inf)
    assert first.trajectory is None and not first.out_of_time
    assert first.message.startswith("the goal is taken")
    traj = nav.step(0.0, pose, obs)
    assert nav.last.mode == "close"
    np.testing.assert_allclose(traj.waypoints[-1, 1:], [0.0, 4.0])
    ts = np.linspace(0.0, traj.t_end, 2001)
    assert np.min(np.hypot(*(traj.at(ts) - obs[0, :2]).T)) - 0.6 > 0.05  # the buffer kept


def test_the_search_leaves_the_measured_tail_of_its_calls_free(open_square):
    """A call that went on past the search's deadline (the last piece of safety work, the
    evasive motion: a footprint differential drive's costs 20-28 ms of CPU) moves the next
    calls' deadline earlier by 1.25 times that tail, so that they end within the budget
    (on a pedestrian replay such calls ended at 92-108 ms of a 100 ms budget); a short
    tail leaves the search its 75 %."""
    from gfuzzy.navigation.navigator import _Searched

    scene, rm = open_square
    obs = np.array([[0.0, -3.0, 0.0, -1.0, 0.3]])
    for tail, want in ((0.040, 0.1 - 1.25 * 0.041), (0.010, 0.075)):
        nav = Navigator(scene, rm, (0.0, 4.0))
        now = [0.0]
        nav._clock = lambda now=now: now[0]
        seen = []

        def search(t, pose, o, infl, deadline, *rest, now=now, seen=seen, start=None):
            seen.append(deadline - now[0])
            now[0] = deadline + 0.001  # the search ran into its deadline
            return _Searched(None, "planning time budget exhausted", 1, True)

        evade = nav._evasive

        def slow_evasive(*args, now=now, tail=tail, evade=evade):
            now[0] += tail
            return evade(*args)

        nav._search, nav._evasive = search, slow_evasive
        nav._direct = nav._previous_if_clear = lambda *args: None
        for k in range(2):
            now[0] = 10.0 * k
            nav.step(0.25 * k, np.array([0.0, -4.0]), obs)
            assert nav.last.mode == "evasive"
        assert seen[0] == pytest.approx(0.075)
        assert seen[-1] == pytest.approx(want)


def test_one_stalled_call_does_not_halve_the_search_for_the_rest_of_the_run(open_square):
    """A review found the measured tail decaying only on calls that went past the deadline:
    one stall of 0.3 s (a loaded machine), then quick calls, left every later search 37.5
    ms of its 75. Now the stall counts for at most half the budget and the tail decays every
    call: the search has its 75 % again within a few dozen quick calls."""
    from gfuzzy.navigation.navigator import SEARCH_SHARE, _Searched

    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0))
    now = [0.0]
    nav._clock = lambda: now[0]
    seen, stall = [], [0.3]

    def search(t, pose, o, infl, deadline, *rest, start=None):
        seen.append(deadline - now[0])
        now[0] += stall[0] + 0.005  # the first call stalls, the others answer in 5 ms
        stall[0] = 0.0
        return _Searched(None, "planning time budget exhausted", 1, True)

    nav._search = search
    nav._direct = nav._previous_if_clear = lambda *args: None
    obs = np.array([[0.0, -3.0, 0.0, -1.0, 0.3]])
    for k in range(60):
        now[0] = 10.0 * k
        nav.step(0.25 * k, np.array([0.0, -4.0]), obs)
    assert seen[0] == pytest.approx(SEARCH_SHARE * 0.1)
    assert seen[1] < SEARCH_SHARE * 0.1  # the stall is reserved for a while
    assert seen[-1] == pytest.approx(SEARCH_SHARE * 0.1)  # and then forgotten


def test_the_exact_first_motions_stop_at_the_deadline(open_square):
    """The first motions from a start the margin refuses are decided one by one before the
    search's first expansion (dozens for a differential drive); each now looks at the
    deadline first, as the field's pieces of safety work do."""
    from gfuzzy.navigation.navigator import _OutOfTime

    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0))
    obs = np.array([[0.0, -3.4, 0.0, 0.0, 0.3]])
    infl = nav._inflation(np.array([0.0, -4.0]), obs)
    ticks = iter([0.0, 5.0])
    field_ = nav._field(0.0, obs, infl, 40, deadline=1.0)
    field_.clock = lambda: next(ticks)
    assert field_.motion_safe(np.array([0.0, -4.0]), np.array([0.0, -4.05]), 0) in (True, False)
    with pytest.raises(_OutOfTime):
        field_.motion_safe(np.array([0.0, -4.0]), np.array([0.0, -4.05]), 0)


@pytest.mark.parametrize("seen", [np.zeros((5, 2)), np.zeros((2, 4)), np.zeros(10), np.zeros((1, 1, 5))])
def test_observations_of_another_shape_are_refused_not_reshaped(open_square, seen):
    # a transposed (5, k) array was read as k other people, a row of 4 numbers raised numpy's error
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0))
    with pytest.raises(InputError, match=r"shape \(k, 5\)"):
        nav.step(0.0, np.array([0.0, -4.0]), seen)
    one = np.array([3.0, 0.0, -1.0, 0.0, 0.3])  # a single row alone is one person, as before
    assert nav.step(0.0, np.array([0.0, -4.0]), one).duration > 0


def test_a_bad_observation_row_is_named(open_square):
    # a tracker's NaN row among many was refused without saying which (a user could not find it)
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0))
    seen = np.tile([3.0, 0.0, -1.0, 0.0, 0.3], (6, 1))
    seen[3, 2] = math.nan
    seen[5, 4] = -0.1
    with pytest.raises(InputError, match=r"^observations\[3\] = \[3.0, 0.0, nan, 0.0, 0.3\] \(and 1 more\): rows must be finite"):
        nav.step(0.0, np.array([0.0, -4.0]), seen)
    with pytest.raises(InputError, match=r"^observations\[0\] = \[3.0, 0.0, -1.0, 0.0, -0.1\]: rows must be"):
        nav.step(0.0, np.array([0.0, -4.0]), seen[5])
    assert nav.step(0.0, np.array([0.0, -4.0]), seen[[0, 1, 2, 4]]).duration > 0  # the rest is fine


@pytest.mark.parametrize("pose", [[1e308, -4.0], [0.0, -2e9]])
def test_a_pose_beyond_1e9_is_refused_as_the_planner_refuses_it(open_square, pose):
    # it returned a hold trajectory at x = 1e308 (docs/formats.md: the API refuses it)
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0))
    with pytest.raises(InputError, match="number too large"):
        nav.step(0.0, np.array(pose), np.zeros((0, 5)))


def test_a_step_earlier_than_the_last_is_refused(open_square):
    # a call at an earlier time was answered from predictions, kept plans and look-outs of the
    # later one; the same time twice, and later times, serve
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(budget_clock="cpu"))
    start, nobody = np.array([0.0, -4.0]), np.zeros((0, 5))
    nav.step(1.0, start, nobody)
    with pytest.raises(InputError, match=r"^t: 0.75 is before the last call's t = 1.0 \(a new run needs a new Navigator\)$"):
        nav.step(0.75, start, nobody)
    with pytest.raises(InputError, match=r"^t: 0.9999999999 is before the last call's t = 1.0 "):  # no tolerance
        nav.step(0.9999999999, start, nobody)
    assert nav.step(1.0, start, nobody).t0 == 1.0
    with pytest.raises(InputError, match="observations"):  # a refused call does not move the clock on
        nav.step(5.0, start, np.full((1, 5), np.nan))
    assert nav.step(1.25, start, nobody).t0 == 1.25


def test_step_and_goal_name_what_is_wrong_and_take_no_strings_or_booleans():
    # nav.step("a", ...) raised "could not convert string to float: 'a'"; strings were taken as
    # coordinates (["0.5", "0.5"]) and so were booleans; the message said only "pose must be
    # 2 finite numbers and t finite"
    scene = parse_scene({"version": 1, "name": "n", "bounds": [0, 0, 4, 2], "robot": {"disc": 0.2, "vmax": 1.0}})
    rm = gfuzzy.build_roadmap(scene, gfuzzy.RoadmapOptions(vertices=20, seed=1))
    with pytest.raises(InputError, match=r"^goal: expected 2 finite numbers \[x, y\] for this disc robot, got \[True, False\]$"):
        Navigator(scene, rm, [True, False])
    nav = Navigator(scene, rm, (3.5, 1.0), NavOptions(budget_clock="cpu"))
    with pytest.raises(InputError, match=r"^t: expected a finite number, got 'a'$"):
        nav.step("a", (0.5, 1.0), [])
    with pytest.raises(InputError, match=r"^pose: expected 2 finite numbers \[x, y\] for this disc robot, got \['0.5', '1'\]$"):
        nav.step(0.0, ["0.5", "1"], [])
    with pytest.raises(InputError, match=r"^pose: expected 2 finite numbers .*, got \[nan, 1.0\]$"):
        nav.step(0.0, (math.nan, 1.0), [])
    assert nav.step(np.float32(0.5), [[0.5, 1.0]], []).t0 == 0.5  # numpy numbers and a (1, 2) pose serve
    with pytest.raises(InputError, match=r"^t: expected a finite number, got True$"):
        nav.step(True, (0.5, 1.0), [])


@pytest.mark.parametrize("bad", [[0.5, True], np.array([0.5, True], dtype=object), [[np.True_, 1.0]]])
def test_a_boolean_among_numbers_is_no_coordinate(bad):
    # numpy made [0.5, True] the pose [0.5, 1.0]: only an all-boolean pose was refused
    scene = parse_scene({"version": 1, "name": "n", "bounds": [0, 0, 4, 2], "robot": {"disc": 0.2, "vmax": 1.0}})
    rm = gfuzzy.build_roadmap(scene, gfuzzy.RoadmapOptions(vertices=20, seed=1))
    with pytest.raises(InputError, match=r"^goal: expected 2 finite numbers"):
        Navigator(scene, rm, bad)
    nav = Navigator(scene, rm, (3.5, 1.0), NavOptions(budget_clock="cpu"))
    with pytest.raises(InputError, match=r"^pose: expected 2 finite numbers"):
        nav.step(0.0, bad, [])
    with pytest.raises(InputError, match=r"^start: expected 2 finite numbers"):
        gfuzzy.plan(scene, rm, bad, (3.5, 1.0))


def test_the_goal_takes_what_step_takes_as_a_pose():
    # Navigator refused a (1, 2) goal (traj.at([t_end]) gives one) that step took as a pose;
    # a 0-d array t, a Fraction and a Decimal were numbers before, and are again
    from decimal import Decimal
    from fractions import Fraction

    scene = parse_scene({"version": 1, "name": "n", "bounds": [0, 0, 4, 2], "robot": {"disc": 0.2, "vmax": 1.0}})
    rm = gfuzzy.build_roadmap(scene, gfuzzy.RoadmapOptions(vertices=20, seed=1))
    for goal in (np.array([[3.5, 1.0]]), [[3.5], [1.0]], [Fraction(7, 2), Decimal(1)], (np.float32(3.5), np.array(1.0))):
        assert Navigator(scene, rm, goal).goal.tolist() == [3.5, 1.0]
    nav = Navigator(scene, rm, (3.5, 1.0), NavOptions(budget_clock="cpu"))
    assert nav.step(np.array(0.25), np.array([[0.5, 1.0]]), []).t0 == 0.25
    assert nav.step(Fraction(1, 2), [Decimal("0.5"), Fraction(1)], []).waypoints[0].tolist() == [0.5, 0.5, 1.0]
    assert nav.step(Decimal("0.75"), (0.5, 1.0), []).t0 == 0.75
    with pytest.raises(InputError, match=r"^t: expected a finite number, got array\(\[1.\]\)$"):
        nav.step(np.array([1.0]), (0.5, 1.0), [])  # a 1-element array is no number (nor was it)
    # and plan's t0 is read the same way (it refused a Decimal and a 0-d array)
    assert gfuzzy.plan(scene, rm, (0.5, 1.0), (3.5, 1.0), t0=Decimal("0.5")).trajectory.t0 == 0.5
    assert gfuzzy.plan(scene, rm, (0.5, 1.0), (3.5, 1.0), t0=np.array(0.5)).trajectory.t0 == 0.5
    with pytest.raises(InputError, match=r"^t0: expected a finite number, got np.True_$"):
        gfuzzy.plan(scene, rm, (0.5, 1.0), (3.5, 1.0), t0=np.True_)


def test_the_kept_gaps_are_computed_only_for_a_faster_motion(open_square, monkeypatch):
    # brisk_arrival's cheap guards come first: a first move that does not end at the goal
    # costs no kept inflation (it was computed at every PLAN and CLOSE call)
    scene, rm = open_square
    calls = []
    kept = Navigator._kept_inflation
    monkeypatch.setattr(Navigator, "_kept_inflation", lambda *args: calls.append(1) or kept(*args))
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(dt=0.4, time_budget=5.0, budget_clock="cpu"))
    nav.step(0.0, np.array([0.0, -3.0]), np.array([[4.0, 0.0, 0.0, 0.0, 0.3]]))
    assert nav.last.mode == "plan" and calls == []


def test_navigate_says_when_its_searches_ran_out_of_the_budget(tmp_path, capsys):
    """A newcomer's differential drive (a 0.5 x 0.4 m box, wmax 0.3) on a SLAM map stood still
    for 150 s, every one of 600 replans an evasive motion, and neither the line nor the file
    said why: splicing its pose into the heading graph alone took longer than the 100 ms
    budget (time budget spent before the search). The run now counts such replans
    (`replans_out_of_time`) and says so when they are most of them. Here a budget of 0.1 ms
    of CPU time runs out every time; 5 s never does on this 5 x 5 m scene."""
    scene = ROOT / "scenes" / "sim-4s1m.yaml"
    starved, ample = tmp_path / "starved.json", tmp_path / "ample.json"
    p = main_completed(capsys, "navigate", scene, "--time-budget", "0.0001", "--budget-clock", "cpu",
                       "--max-time", "1", "-o", starved)  # fmt: skip
    doc = json.loads(starved.read_text())
    assert doc["replans_out_of_time"] == doc["replans"] == 4, doc["modes"]
    assert "note: 4 of 4 replans ran out of --time-budget 0.0001 s" in p.stderr, p.stderr
    p = main_completed(capsys, "navigate", scene, "--time-budget", "5", "--budget-clock", "cpu", "--max-time", "1",
                       "-o", ample)  # fmt: skip
    doc = json.loads(ample.read_text())
    assert doc["replans_out_of_time"] == 0 and "ran out of" not in p.stderr, p.stderr


def test_a_relaxed_search_that_ran_out_of_the_budget_counts_as_out_of_time(open_square, monkeypatch):
    """A review: the relaxed tier's search (after the tiers found no plan in time) dropped
    its out_of_time, so a call whose last search ran out was not counted in
    ``replans_out_of_time``. The tiers and the relaxed search are stood in for here: what is
    tested is the call's bookkeeping."""
    from gfuzzy.navigation.navtypes import NavMode, _Searched

    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), unhurried())
    monkeypatch.setattr(nav, "_tiers", lambda *a: (None, NavMode.PLAN, _Searched(None, "blocked"), False))
    for ran_out in (True, False):
        monkeypatch.setattr(nav, "_relaxed", lambda *a, ran_out=ran_out: _Searched(None, "relaxed", out_of_time=ran_out))
        nav.step(0.0, np.array([0.0, -4.0]), np.array([[0.0, 0.0, 0.0, 0.0, 0.3]]))
        assert nav.last.out_of_time is ran_out


def test_a_slow_measurement_of_the_predictions_does_not_stop_every_later_search(open_square):
    """The cost per person of setting up the predictions is measured only when a search runs;
    a call that refuses to search for want of it lowers the estimate (`PERSON_DECAY`), so the
    searches run again a few calls later. Before, one slow measurement (a stall of a loaded
    machine) left every later call of a crowd episode evasive ("time budget spent before the
    search", 26 calls in a row)."""
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), unhurried())
    nav._person_seconds = 10.0  # as if one set-up had stalled: 10 s a person, the budget 5 s
    person = np.array([[2.0, 0.0, 0.0, 0.0, 0.3]])  # standing aside, within reach
    messages = []
    for k in range(8):
        nav.step(0.25 * k, np.array([0.0, -4.0]), person)
        messages.append(nav.last.message)
        if nav.last.mode == NavMode.PLAN:
            break
    assert messages[0] == "time budget spent before the search"
    assert nav.last.mode == NavMode.PLAN and len(messages) < 8


def test_the_close_search_starts_from_the_first_searchs_safe_points(open_square, monkeypatch):
    """The search without the personal space takes the first search's store as its prior
    (every point the first found safe all through is safe without the personal space),
    computes fewer points' safety, and answers the same rows, to the bit, as with every
    point computed again."""
    import gfuzzy.navigation.navigator as N
    import gfuzzy.timespace.spacetime as S

    scene, rm = open_square
    people = _standing_row([-2.16, -0.72, 0.72, 2.16])
    start = np.array([0.0, -4.0])
    given, real, computed, shared = [], N.prior_store, [0], S._safe_intervals_shared

    def spied(*args):
        given.append(real(*args))
        return given[-1]

    def counted(field_, poses, *args):  # the points whose safety is computed
        computed[0] += len(poses)
        return shared(field_, poses, *args)

    monkeypatch.setattr(S, "_safe_intervals_shared", counted)
    monkeypatch.setattr(N, "prior_store", spied)
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(time_budget=5.0))
    traj = nav.step(0.0, start, people)
    assert nav.last.mode == "close" and given[0] is None and any(g is not None for g in given[1:])
    with_prior, computed[0] = computed[0], 0
    monkeypatch.setattr(N, "prior_store", lambda *args: None)
    again = Navigator(scene, rm, (0.0, 4.0), NavOptions(time_budget=5.0)).step(0.0, start, people)
    assert np.array_equal(traj.waypoints, again.waypoints)
    assert with_prior < computed[0]  # some groups skipped


def test_an_earlier_search_vouches_only_for_a_field_no_more_cautious():
    """``prior_store``: the earlier store only for the same people (or the plain rows after
    the ones with the ghosts), each inflated no more at any slice, none kept that it left out."""
    from gfuzzy.navigation.prediction import prior_store

    class Pool:
        pool = True

    store = Pool()
    obs = np.array([[0.0, 0.0, 0.0, 0.0, 0.3], [2.0, 1.0, -1.0, 0.0, 0.3]])
    infl = np.array([[0.5, 0.6], [0.5, 0.7]])
    keep = np.array([True, False])
    earlier = (store, obs, infl, keep)
    assert prior_store(earlier, obs, infl - 0.2, keep) is store  # no personal space
    assert prior_store(earlier, obs, infl, keep) is store
    assert prior_store(None, obs, infl, keep) is None
    assert prior_store(earlier, obs, infl + np.array([[0.0, 1e-9], [0.0, 0.0]]), keep) is None  # more at one slice
    assert prior_store(earlier, obs, infl, np.array([True, True])) is None  # someone it left out
    moved = obs.copy()
    moved[1, 0] += 1e-9
    assert prior_store(earlier, moved, infl, keep) is None
    ghosts = np.array([[1.0, 1.0, 0.0, 0.0, 0.3, 0.5, 2.0]])
    rows = np.vstack([np.column_stack([obs, np.zeros(2), np.full(2, np.inf)]), ghosts])
    with_ghosts = (store, rows, np.vstack([infl, [[0.4, 0.4]]]), np.array([True, False, True]))
    assert prior_store(with_ghosts, obs, infl, keep) is store  # the plain search after the ghosts'
    rows[0, 6] = 3.0  # a row present only until 3 s is not the plain person
    assert prior_store(with_ghosts, obs, infl, keep) is None
    Pool.pool = False
    assert prior_store(earlier, obs, infl, keep) is None  # a reference store: lists, no pool
