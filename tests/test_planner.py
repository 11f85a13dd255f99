"""The roadmap-time search and the query API, on small scenes with real OMPL and FCL."""

from __future__ import annotations

import json
import math
import re
from dataclasses import replace
from decimal import Decimal
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import ROOT, run_python
from helpers import run_main
from helpers import scene_doc as _doc
from helpers import scene_of as _scene
from reference import brute_force_steps, contract_metric, reference_violation
from shared_scenes import CROSSING, DOOR, LINE, LOOP, PERSON

from gfuzzy.check.check import check_trajectory
from gfuzzy.errors import InputError
from gfuzzy.planner.planner import Planner, PlanOptions, Status, plan, settle_time
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap
from gfuzzy.scene.scene import Query, load_scene, parse_scene
from gfuzzy.timespace.timespace import MoverField

SCENE = ROOT / "scenes" / "sim-4s1m.yaml"
ROADMAP = ROOT / "roadmaps" / "sim-4s1m.json"

CORRIDOR = """
version: 1
name: corridor
bounds: [0, 0, 10, 3]
robot: {disc: 0.2, vmax: 1.0}
obstacles:
  - box: {center: [5, 2.25], size: [10, 1.5]}
  - box: {center: [3.0, 0.3], size: [2.0, 0.6]}
  - box: {center: [7.0, 0.3], size: [2.0, 0.6]}
movers:
  - {name: cart, disc: 0.3, speed: 1.0, path: [[5, 0.2], [5, 1.3]], mode: bounce}
queries:
  - {name: across, start: [0.5, 1.0], goal: [9.5, 1.0]}
"""

OPEN = """
version: 1
name: open
bounds: [0, 0, 5, 5]
robot: {disc: 0.2, vmax: 1.0}
obstacles:
  - disc: {center: [2.5, 2.5], radius: 0.6}
movers:
  - {name: m1, disc: 0.3, speed: 0.8, path: [[1, 4], [4, 1]], mode: bounce}
  - {name: m2, box: [0.4, 0.3], speed: 0.6, path: [[0.5, 2.5], [4.5, 2.5]], mode: loop}
queries:
  - {name: diag, start: [0.5, 0.5], goal: [4.5, 4.5]}
"""


@pytest.fixture(scope="module")
def corridor(tmp_path_factory):
    p = tmp_path_factory.mktemp("corr") / "corridor.yaml"
    p.write_text(CORRIDOR)
    scene = load_scene(p)
    return scene, build_roadmap(scene, RoadmapOptions(vertices=60, seed=3))


@pytest.fixture(scope="module")
def open_scene(tmp_path_factory):
    p = tmp_path_factory.mktemp("open") / "open.yaml"
    p.write_text(OPEN)
    scene = load_scene(p)
    return scene, build_roadmap(scene, RoadmapOptions(vertices=40, seed=5))


@pytest.mark.parametrize("backend", ["reference", "compiled"])
@pytest.mark.parametrize("fixture", ["corridor", "open_scene"])
@pytest.mark.parametrize("t0", [0.0, 1.3, 4.2])
def test_search_matches_brute_force(fixture, t0, backend, request):
    scene, rm = request.getfixturevalue(fixture)
    q = scene.queries[0]
    planner = Planner(scene, rm)
    dt = 0.1
    res = planner.plan(q.start, q.goal, t0, PlanOptions(dt=dt, horizon=40.0, stretch=1.0, backend=backend))
    # the oracle builds its own time-expanded graph from the scene file and the roadmap's
    # vertices and edges (tests/reference.py): no code shared with the planner
    doc = yaml.safe_load(Path(scene.source).read_text())
    steps = brute_force_steps(doc, rm.vertices, rm.edges, q.start, q.goal, t0, dt, int(math.ceil(40.0 / dt)))
    if steps is None:
        assert res.status is Status.NO_PATH
    else:
        assert res.status is Status.SOLVED
        assert abs(res.duration - steps * dt) <= dt + 1e-9


def test_solution_invariants(open_scene):
    scene, rm = open_scene
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal, q.t0)
    assert res.solved
    w = res.trajectory.waypoints
    assert np.allclose(w[0, 1:], q.start) and w[0, 0] == q.t0
    assert np.allclose(w[-1, 1:], q.goal)
    assert np.all(np.diff(w[:, 0]) > 0)
    assert res.trajectory.speeds().max() <= scene.robot.vmax
    rep = check_trajectory(scene, w, q)
    assert rep.valid, rep.reason
    assert res.delay_factor >= 1.0 - 1e-9
    assert res.duration == pytest.approx(w[-1, 0] - w[0, 0])


def test_waits_for_the_cart(corridor):
    """The cart crosses the corridor: the straight run at full speed would hit it."""
    scene, rm = corridor
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal, 0.0)
    assert res.solved
    w = res.trajectory.waypoints
    assert check_trajectory(scene, w, q).valid
    # timing the same path at full speed without waiting must collide, so the planner waited
    from gfuzzy.planner.retime import retime_path

    free = retime_path(scene, res.trajectory.poses, 0.0, 0.07, 60.0, wait_at=[])
    same_pose = np.all(np.abs(np.diff(w[:, 1:], axis=0)) < 1e-12, axis=1)
    assert same_pose.any() or free.status != "solved" or free.trajectory.duration > res.duration - 1e-9
    assert res.delay_factor > 1.0


def test_start_on_mover_is_invalid_query(corridor):
    scene, rm = corridor
    res = plan(scene, rm, [5.0, 0.4], [9.5, 1.0], 0.0)  # the cart starts at (5, 0.2)
    xy, _ = scene.movers[0].state(np.array([0.0]))
    assert np.hypot(*(xy[0] - [5.0, 0.4])) < 0.5
    assert res.status is Status.INVALID_QUERY
    assert "cart" in res.message


@pytest.mark.parametrize(
    "start, goal, word",
    [([3.0, 0.3], [9.5, 1.0], "static"), ([-1.0, 1.0], [9.5, 1.0], "out of bounds"), ([0.5, 1.0], [9.9, 1.0], "out of bounds")],
)
def test_invalid_queries(corridor, start, goal, word):
    scene, rm = corridor
    res = plan(scene, rm, start, goal, 0.0)
    assert res.status is Status.INVALID_QUERY
    assert word in res.message
    assert res.trajectory is None


def test_sealed_goal_is_no_path_quickly(tmp_path):
    p = tmp_path / "sealed.yaml"
    p.write_text(
        """
version: 1
name: sealed
bounds: [0, 0, 6, 4]
robot: {disc: 0.2, vmax: 1.0}
obstacles:
  - box: {center: [4.5, 0.55], size: [2.1, 0.1]}
  - box: {center: [4.5, 3.45], size: [2.1, 0.1]}
  - box: {center: [3.5, 2.0], size: [0.1, 3.0]}
  - polygon: [[5.45, 0.5], [5.55, 0.5], [5.55, 3.5], [5.45, 3.5]]
queries:
  - {name: in, start: [1, 2], goal: [4.5, 2]}
"""
    )
    scene = load_scene(p)
    rm = build_roadmap(scene, RoadmapOptions(vertices=80, seed=2))
    res = plan(scene, rm, [1, 2], [4.5, 2], 0.0)
    assert res.status is Status.NO_PATH
    assert res.stats.expansions is None  # decided on the static graph: no space-time search


def test_mover_parks_in_doorway_no_path(tmp_path):
    """A mover that stops forever in the only door: the search exhausts space-time."""
    p = tmp_path / "park.yaml"
    p.write_text(
        """
version: 1
name: park
bounds: [0, 0, 6, 3]
robot: {disc: 0.2, vmax: 1.0}
obstacles:
  - box: {center: [3, 0.75], size: [0.2, 1.5]}
  - box: {center: [3, 2.55], size: [0.2, 0.9]}
movers:
  - {name: door, disc: 0.3, speed: 1.0, path: [[3, 2.9], [3, 1.8]], mode: once}
queries:
  - {name: q, start: [1, 1.5], goal: [5, 1.5]}
"""
    )
    scene = load_scene(p)
    rm = build_roadmap(scene, RoadmapOptions(vertices=80, seed=4))
    res = plan(scene, rm, [1, 1.5], [5, 1.5], 0.0, PlanOptions(horizon=30.0))
    assert res.status is Status.NO_PATH
    early = plan(scene, rm, [2.68, 1.8], [5, 1.5], 0.0, PlanOptions(horizon=30.0))
    # the door closes at t = 1.1 (arc 1.1 at speed 1): from right beside it (0.02 m from
    # the wall) there is time to slip through on the straight line to the goal
    assert early.status is Status.SOLVED
    assert early.trajectory.at(1.1)[0] > 3.3  # through the door before it closed
    assert check_trajectory(scene, early.trajectory.waypoints).valid
    assert reference_violation(yaml.safe_load(p.read_text()), early.trajectory.waypoints) == ""


def test_timeout(open_scene):
    scene, rm = open_scene
    q = scene.queries[0]
    # the budget is looked at every few hundred (the compiled search: 4096) expansions: a
    # search long enough that it is looked at
    full = plan(scene, rm, q.start, q.goal, 0.0, PlanOptions(dt=0.001))
    assert full.solved and full.stats.expansions > 5000
    res = plan(scene, rm, q.start, q.goal, 0.0, PlanOptions(dt=0.001, time_limit=1e-9))
    assert res.status is Status.TIMEOUT
    assert res.trajectory is None and "budget" in res.message


def test_trajectory_file_formats(open_scene, tmp_path):
    scene, rm = open_scene
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal, q.t0)
    tf = res.to_file(scene.name, q.name)
    tf.save(tmp_path / "a.json")
    tf.save(tmp_path / "a.csv")
    doc = json.loads((tmp_path / "a.json").read_text())
    for key in ("version", "scene", "query", "status", "message", "duration", "roadmap_distance", "delay_factor", "planning_seconds", "waypoints"):
        assert key in doc
    assert doc["version"] == 1 and doc["status"] == "solved"
    assert doc["delay_factor"] == pytest.approx(doc["duration"] * scene.robot.vmax / doc["roadmap_distance"])
    assert doc["duration"] == pytest.approx(doc["waypoints"][-1][0] - doc["waypoints"][0][0])
    lines = (tmp_path / "a.csv").read_text().splitlines()
    assert lines[0] == "t,x,y"
    rows = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    assert np.array_equal(rows, np.asarray(doc["waypoints"]))
    assert not list(tmp_path.glob(".*tmp"))
    # at(): interpolation and clamping
    traj = res.trajectory
    mid = 0.5 * (traj.times[0] + traj.times[1])
    assert np.allclose(traj.at(mid), 0.5 * (traj.poses[0] + traj.poses[1]))
    assert np.allclose(traj.at(traj.t_end + 5), traj.poses[-1])


def test_api_and_cli_agree(open_scene, tmp_path, capsys):
    # in process: the commands' own process is tested in test_cli (plan, check)
    scene, rm = open_scene
    rm_path = tmp_path / "rm.json"
    rm.save(rm_path)
    out = tmp_path / "out.json"
    rc, _, err = run_main(capsys, "plan", scene.source, "--roadmap", rm_path, "-o", out)
    assert rc == 0, err
    doc = json.loads(out.read_text())
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal, q.t0)
    assert doc["status"] == res.status.value
    assert np.allclose(np.asarray(doc["waypoints"]), res.trajectory.waypoints)
    rc, _, err = run_main(capsys, "check", scene.source, out)
    assert rc == 0, err


def test_box_robot_heading_and_metric(tmp_path):
    p = tmp_path / "box.yaml"
    p.write_text(
        """
version: 1
name: boxrobot
bounds: [0, 0, 6, 4]
robot: {box: [0.8, 0.3], vmax: 1.0}
obstacles:
  - box: {center: [3, 0.9], size: [0.2, 1.8]}
  - box: {center: [3, 3.3], size: [0.2, 1.4]}
movers:
  - {name: m, box: [0.3, 0.3], speed: 0.5, path: [[4.5, 0.5], [4.5, 3.5]], mode: bounce}
queries:
  - {name: q, start: [1, 2, 1.57], goal: [5, 2, -1.57]}
"""
    )
    scene = load_scene(p)
    rm = build_roadmap(scene, RoadmapOptions(vertices=150, seed=1))
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal, 0.0)
    assert res.solved, res.message
    w = res.trajectory.waypoints
    assert w.shape[1] == 4
    rep = check_trajectory(scene, w, q)
    assert rep.valid, rep.reason
    assert rep.max_speed <= 1.0


def test_flees_into_a_side_room(tmp_path):
    """A mover sweeps the whole corridor towards the robot: the only escape is the side
    room, and the robot must be in it when the mover passes."""
    p = tmp_path / "flee.yaml"
    p.write_text(
        """
version: 1
name: flee
bounds: [0, 0, 10, 3]
robot: {disc: 0.2, vmax: 1.0}
obstacles:
  - box: {center: [2, 2], size: [4, 2]}
  - box: {center: [8, 2], size: [4, 2]}
movers:
  - {name: sweeper, disc: 0.3, speed: 1.0, path: [[9.6, 0.5], [0.4, 0.5]], mode: once}
queries:
  - {name: q, start: [3.0, 0.5], goal: [9.0, 0.5]}
"""
    )
    scene = load_scene(p)
    rm = build_roadmap(scene, RoadmapOptions(vertices=150, seed=2))
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal, q.t0)
    assert res.solved, res.message
    assert check_trajectory(scene, res.trajectory.waypoints, q).valid
    # when the sweeper passes it, the robot stands (at least partly) in the side room
    w = res.trajectory
    times = np.linspace(w.t0, w.t_end, 2000)
    robot = w.at(times)
    sweeper, _ = scene.movers[0].state(times)
    k = int(np.argmin(np.abs(robot[:, 0] - sweeper[:, 0])))
    assert abs(robot[k, 0] - sweeper[k, 0]) < 0.1
    assert 4.0 < robot[k, 0] < 6.0 and robot[k, 1] >= 1.0  # corridor centre line is y = 0.5


NOFIT = """
version: 1
name: nofit
bounds: [0, 0, 5, 5]
robot: {disc: 3.0, vmax: 1.0}
queries:
  - {name: q, start: [2.5, 2.5], goal: [2.5, 2.5]}
"""


# ``gfuzzy roadmap`` in a real process (a hang is a timeout, not a stuck suite) whose growth
# gives up after 2000 fruitless checks, not 200 000 (4 s of FCL): the same stall rule
GIVE_UP_SOONER = """
import sys
import gfuzzy.roadmap.roadmap as roadmap
roadmap.STALL_CHECKS = 2000
from gfuzzy.__main__ import run
sys.argv[0] = "gfuzzy"
sys.exit(run())
"""


def test_robot_that_fits_nowhere_is_reported_not_hung(tmp_path, capsys, monkeypatch):
    p = tmp_path / "nofit.yaml"
    p.write_text(NOFIT)
    out = tmp_path / "rm.json"
    proc = run_python(GIVE_UP_SOONER, "roadmap", p, "-o", out, timeout=60)
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "robot" in proc.stderr and str(p) in proc.stderr
    assert "the robot fits nowhere: the disc inside its body" in proc.stderr  # proved, before the stall rule
    assert not out.exists()
    # a body whose inscribed disc has room but which fits nowhere (7.5 m long in 5 x 5): the stall rule
    long = tmp_path / "long.yaml"
    long.write_text(NOFIT.replace("{disc: 3.0,", "{box: [7.5, 0.2],").replace("2.5, 2.5]", "2.5, 2.5, 0]"))
    import gfuzzy.roadmap.roadmap as roadmap

    monkeypatch.setattr(roadmap, "STALL_CHECKS", 2000)
    rc, _, err = run_main(capsys, "roadmap", long, "-o", out)
    assert rc == 2 and err.count("\n") == 1 and str(long) in err
    assert int(re.search(r"after (\d+) collision checks", err)[1]) < 10_000  # (the rule above)
    assert not out.exists()
    ans = tmp_path / "a.json"
    rc, _, _ = run_main(capsys, "plan", p, "-o", ans)
    assert rc == 1
    assert json.loads(ans.read_text())["status"] == "invalid_query"


def test_end_rows_repeat_the_query_headings(tmp_path):
    p = tmp_path / "h.yaml"
    p.write_text(
        """
version: 1
name: h
bounds: [0, 0, 6, 4]
robot: {box: [0.8, 0.3], vmax: 1.0}
"""
    )
    scene = load_scene(p)
    rm = build_roadmap(scene, RoadmapOptions(vertices=60, seed=1))
    res = plan(scene, rm, [1, 2, 7.0], [5, 2, -4.0])
    assert res.solved
    w = res.trajectory.waypoints
    assert w[0, 1:].tolist() == [1.0, 2.0, 7.0] and w[-1, 1:].tolist() == [5.0, 2.0, -4.0]
    assert check_trajectory(scene, w).valid
    assert res.trajectory.speeds().max() <= 1.0


def test_roadmap_distance_agrees_with_networkx(open_scene):
    """The planner's roadmap distance (scipy Dijkstra on the augmented graph) against
    networkx for a query between two roadmap vertices, on a graph built here from the
    roadmap's vertices and edges with the contract metric written afresh (and on
    Roadmap.graph(), which must agree)."""
    import networkx as nx

    scene, rm = open_scene
    g = nx.Graph()
    r = scene.robot.circumradius
    g.add_weighted_edges_from((int(u), int(v), float(contract_metric(rm.vertices[u], rm.vertices[v], r))) for u, v in rm.edges)
    a, b = 0, int(np.argmax(np.hypot(*(rm.vertices - rm.vertices[0]).T)))
    assert nx.has_path(g, a, b)
    want = nx.shortest_path_length(g, a, b, weight="weight")
    assert nx.shortest_path_length(rm.graph(), a, b, weight="weight") == pytest.approx(want)
    res = plan(scene, rm, rm.vertices[a], rm.vertices[b], 0.0)
    # start and goal may also join each other directly: never longer than the roadmap path
    assert res.roadmap_distance <= want + 1e-9
    assert res.roadmap_distance >= float(np.hypot(*(rm.vertices[b] - rm.vertices[a]))) - 1e-9


def test_a_time_step_far_too_fine_is_refused_not_swallowed(corridor, tmp_path, capsys):
    scene, rm = corridor
    q = scene.queries[0]
    with pytest.raises(ValueError, match="larger dt"):
        plan(scene, rm, q.start, q.goal, 0.0, PlanOptions(dt=1e-5))
    rm_path = tmp_path / "rm.json"
    rm.save(rm_path)
    rc, _, err = run_main(capsys, "plan", scene.source, "--roadmap", rm_path, "--dt", "1e-5", "-o", tmp_path / "a.json")
    assert rc == 2 and "larger dt" in err and err.count("\n") == 1  # one line, no traceback
    assert not (tmp_path / "a.json").exists()


def test_spanner_keeps_every_route_within_the_stretch(open_scene):
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    _, rm = open_scene
    n = len(rm.vertices)

    def apsp(mask):
        e, w = rm.edges[mask], rm.lengths[mask]
        m = coo_matrix((np.r_[w, w], (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])), shape=(n, n))
        return dijkstra(m.tocsr())

    full = apsp(np.ones(len(rm.edges), dtype=bool))
    for stretch in (1.02, 1.1):
        keep = rm.spanner(stretch)
        assert keep.sum() < len(keep)  # something is dropped
        sub = apsp(keep)
        ok = np.isfinite(full) & (full > 0)
        assert np.all(np.isfinite(sub[ok]))
        assert np.all(sub[ok] <= stretch * full[ok] + 1e-9)
    assert rm.spanner(1.0).all()


def test_search_on_the_spanner_stays_near_the_whole_roadmap(corridor, open_scene):
    for scene, rm in (corridor, open_scene):
        q = scene.queries[0]
        planner = Planner(scene, rm)
        whole = planner.plan(q.start, q.goal, q.t0, PlanOptions(stretch=1.0))
        sparse = planner.plan(q.start, q.goal, q.t0)
        assert whole.solved and sparse.solved
        assert sparse.roadmap_distance == pytest.approx(whole.roadmap_distance)  # the contract's
        assert check_trajectory(scene, sparse.trajectory.waypoints, q).valid
        assert sparse.stats.graph_nodes < whole.stats.graph_nodes


def test_bad_options_and_poses_raise_input_error():
    """Bad values are InputError (the command line's exit 2), still a ValueError."""
    from gfuzzy.errors import InputError, check_number
    from gfuzzy.navigation.navigator import NavOptions
    from gfuzzy.planner.planner import check_pose

    for kwargs in ({"dt": 0.0}, {"dt": float("nan")}, {"weight": 0.5}, {"stretch": float("inf")},
                   {"time_limit": -1.0}, {"horizon": 0.0}, {"backend": "gpu"}):  # fmt: skip
        with pytest.raises(InputError):
            PlanOptions(**kwargs)
    assert PlanOptions(time_limit=float("inf"), horizon=float("inf")).time_limit == float("inf")
    for kwargs in ({"dt": -1.0}, {"safety_buffer": -0.1}, {"stretch": 0.9}, {"cover": "x"}):
        with pytest.raises(InputError):
            NavOptions(**kwargs)
    with pytest.raises(InputError, match="start: expected 2 finite numbers"):
        check_pose([0.0, float("nan")], 2, "start")
    # strings and booleans were taken as numbers: ["0.5", "0.5"] planned, [True, False] was the
    # pose (1, 0); a scene file refuses both, and so does t0
    for pose in (["0.5", "0.5"], [True, False], [None, 1.0], [[0.5], [0.5, 1.0]]):
        with pytest.raises(InputError, match=r"start: expected 2 finite numbers \[x, y\] for a disc robot, got \["):
            check_pose(pose, 2, "start")
    np.testing.assert_array_equal(check_pose((np.float32(0.5), np.int64(2)), 2, "start"), [0.5, 2.0])
    scene = parse_scene({"version": 1, "name": "c", "bounds": [0, 0, 1, 1], "robot": {"disc": 0.1, "vmax": 1}})
    for value in ("0.1", True):
        with pytest.raises(InputError, match=r"robot.clearance must be a non-negative finite number, got"):
            scene.with_clearances(value)
    assert scene.with_clearances(np.float32(0.25), 1).robot.mover_clearance == 1.0
    # a boolean among numbers was a coordinate ([0.5, True] was (0.5, 1)); np.True_ a clearance
    # of 1; a Decimal, a Fraction and a 0-d array, numbers before, were refused
    with pytest.raises(InputError, match=r"start: expected 2 finite numbers \[x, y\] for a disc robot, got \[0.5, True\]"):
        check_pose([0.5, True], 2, "start")
    with pytest.raises(InputError, match=r"robot.clearance must be a non-negative finite number, got np.True_"):
        scene.with_clearances(np.True_)
    np.testing.assert_array_equal(check_pose([Fraction(1, 2), Decimal("2")], 2, "start"), [0.5, 2.0])
    for value in (np.array(0.25), Decimal("0.25"), Fraction(1, 4)):
        assert scene.with_clearances(value).robot.clearance == 0.25
    with pytest.raises(InputError, match="w must be a number >= 1, got 0.5"):
        check_number("w", 0.5, 1.0, strict=False)
    check_number("w", 1.0, 1.0, strict=False)
    with pytest.raises(ValueError, match="x must be a positive number"):
        check_number("x", 0)


def test_a_hold_too_long_to_sample_names_the_hold(open_scene):
    """A hold beyond what the movers can be sampled over is refused with a message that
    says the hold is the cause (it read as a horizon too long, with no word of the hold)."""
    from gfuzzy.errors import LimitError

    scene, rm = open_scene
    q = scene.queries[0]
    with pytest.raises(LimitError, match="hold"):
        Planner(scene, rm).plan(q.start, q.goal, 0.0, hold=1e6)


@pytest.fixture(scope="module")
def line_roadmap(tmp_path_factory):
    path = tmp_path_factory.mktemp("line") / "line.yaml"
    path.write_text(LINE)
    scene = load_scene(path)
    return scene, build_roadmap(scene, RoadmapOptions(vertices=40, seed=2))


@pytest.mark.parametrize(
    "start, goal, t0, where",
    [
        ([1.0, 2.5, 0.0], [9.0, 2.5], 0.0, "start"),
        ([1.0, 2.5], [9.0], 0.0, "goal"),
        ([1.0, math.nan], [9.0, 2.5], 0.0, "start"),
        ([1.0, 2.5], [math.inf, 2.5], 0.0, "goal"),
        ([1.0, 2.5], [9.0, 2.5], math.nan, "t0"),
    ],
)
def test_malformed_poses_are_bad_input_in_the_api(line_roadmap, start, goal, t0, where):
    scene, rm = line_roadmap
    with pytest.raises(ValueError, match=where):
        plan(scene, rm, start, goal, t0)


def test_a_well_formed_pose_in_collision_stays_an_invalid_query(line_roadmap):
    scene, rm = line_roadmap
    res = plan(scene, rm, [3.0, 1.0], [9.0, 2.5])
    assert res.status is Status.INVALID_QUERY and "static" in res.message


def _speed_change_rate(traj) -> float:
    """Largest change of configuration speed between consecutive rows, per second."""
    v, dt = traj.speeds(), np.diff(traj.times)
    return float(np.max(np.abs(np.diff(v)) / (0.5 * (dt[:-1] + dt[1:])), initial=0.0))


def test_the_answer_says_when_amax_is_not_honoured(line_roadmap):
    scene, rm = line_roadmap
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal, q.t0)
    assert res.solved
    doc = res.to_file(scene.name, q.name).to_dict()
    assert doc["amax_honoured"] is False and res.amax_honoured is False
    assert "speed layer" in doc["amax_note"]
    assert _speed_change_rate(res.trajectory) > scene.robot.amax  # the claim is true
    layered = plan(scene, rm, q.start, q.goal, q.t0, PlanOptions(speed_layer=True))
    assert layered.solved
    applied = layered.speed_report.applied
    doc = layered.to_file(scene.name, q.name).to_dict()
    assert doc["amax_honoured"] is applied
    if applied:  # and so is this one
        assert "amax_note" not in doc
        assert _speed_change_rate(layered.trajectory) <= scene.robot.amax * (1 + 1e-6)
    else:
        assert layered.speed_report.reason in doc["amax_note"]


def test_no_amax_no_claim():
    sc = parse_scene(
        {"version": 1, "name": "na", "bounds": [0, 0, 4, 2], "robot": {"disc": 0.2, "vmax": 1.0},
         "queries": [{"name": "q", "start": [0.5, 1.0], "goal": [3.5, 1.0]}]}
    )
    rm = build_roadmap(sc, RoadmapOptions(vertices=10, seed=1))
    res = plan(sc, rm, [0.5, 1.0], [3.5, 1.0])
    assert res.solved
    assert "amax_honoured" not in res.to_file(sc.name, "q").to_dict()


def test_the_api_refuses_a_hold_that_is_not_a_number():
    scene = load_scene(SCENE)
    from gfuzzy.roadmap.roadmap import load_roadmap

    rm = load_roadmap(ROADMAP, scene)
    q = scene.queries[0]
    for bad in ("5", True, -1.0, float("nan")):
        with pytest.raises(InputError, match="hold"):
            plan(scene, rm, q.start, q.goal, hold=bad)
    assert plan(scene, rm, q.start, q.goal, hold=np.float64(0.5)).solved


def test_roadmap_without_the_clearance_is_refused(door):
    scene, rm = door
    other = scene.with_clearances(0.0)
    with pytest.raises(ValueError, match="other static content"):
        Planner(other, rm)


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


def test_start_within_the_mover_clearance_is_invalid_query():
    scene = _scene(CROSSING, mover_clearance=0.3)
    rm = build_roadmap(scene, RoadmapOptions(vertices=40, seed=1))
    # the cart is at (3, 0.5) at t = 0; a robot at (3, 1.2) is 0.15 from it
    res = plan(scene, rm, [3.0, 1.2], [5.5, 3.0])
    assert res.status is Status.INVALID_QUERY
    assert "robot.mover_clearance" in res.message


@pytest.fixture(scope="module")
def loop():
    scene = _scene(LOOP)
    return scene, build_roadmap(scene, RoadmapOptions(vertices=60, seed=1))


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


def test_no_path_from_the_horizon_says_so(blocked, tmp_path, capsys):
    scene, rm = blocked
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal, options=PlanOptions(horizon=100.0))
    assert res.status is Status.NO_PATH
    assert "horizon" in res.message and "--horizon" in res.message
    path = tmp_path / "blocked.yaml"
    path.write_text(BLOCKED)
    rc, stdout, _ = run_main(capsys, "plan", path, "-n", "60", "--seed", "2", "--horizon", "100", "-o", tmp_path / "a.json")
    assert rc == 1 and "--horizon" in stdout


def test_a_negative_ga_seed_is_refused_where_the_options_are_made(capsys):
    with pytest.raises(InputError, match=r"seed \(the GA's, --ga-seed\) must be a whole number >= 0"):
        PlanOptions(seed=-1)
    rc, _, err = run_main(capsys, "plan", ROOT / "scenes" / "building-floor.yaml", "--refine", "--ga-seed", "-1")
    assert rc == 2 and err.startswith("gfuzzy plan: seed (the GA's")
    assert len(err.strip().splitlines()) == 1


def test_an_infinite_horizon_grows_until_the_search_is_not_cut(blocked):
    """``PlanOptions(horizon=inf)`` (and ``--horizon inf``), which the options accept, ended
    in an OverflowError; it now searches rounds until one is not cut by the horizon: the
    door blocked for 250 s is passed after it, as with the default horizon."""
    scene, rm = blocked
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal, options=PlanOptions(horizon=math.inf))
    assert res.solved, res.message
    assert res.duration > 250.0 - q.t0
    assert check_trajectory(scene, res.trajectory.waypoints, q).valid


def test_settle_time_of_periodic_and_once_movers():
    scene = _scene(LOOP)
    assert settle_time(scene) == pytest.approx(10.0)  # one period of the loop
    once = _scene(LOOP.replace("mode: loop, offset: 8.0", "mode: once"))
    assert settle_time(once) == pytest.approx(9.0)  # 9 m of polyline at 1 m/s
    assert settle_time(once, t0=4.0) == pytest.approx(5.0)


@pytest.mark.parametrize("hold", [0.0, 2.0, 5.0, 9.5])
@pytest.mark.parametrize("keep", [0.0, 0.2])
def test_hold_and_mover_clearance_match_brute_force(loop, hold, keep):
    scene, rm = loop
    scene = scene.with_clearances(mover_clearance=keep)
    q = scene.queries[0]
    planner = Planner(scene, rm)
    dt, horizon = 0.1, 15.0
    doc = _doc(LOOP, mover_clearance=keep)  # the oracle reads the scene document, not `scene`
    steps = brute_force_steps(doc, rm.vertices, rm.edges, q.start, q.goal, 0.0, dt, int(math.ceil(horizon / dt)), int(math.ceil(hold / dt - 1e-9)))
    for backend in ("reference", "compiled"):
        res = planner.plan(q.start, q.goal, 0.0, PlanOptions(dt=dt, horizon=horizon, stretch=1.0, backend=backend), hold=hold)
        if steps is None:
            assert res.status is Status.NO_PATH
        else:
            assert res.status is Status.SOLVED, res.message
            assert abs(res.duration - steps * dt) <= 1e-6
            assert check_trajectory(scene, res.trajectory.waypoints, replace(q, hold=hold)).valid


@pytest.mark.parametrize("bad", [1e308, -1e308, 2e9, math.inf, math.nan])
def test_plan_refuses_a_pose_beyond_1e9_with_the_documented_value_error(bad):
    # on a map scene 1e308 reached a cell index: OverflowError, not the InputError (a
    # ValueError) that Planner.plan documents; a scene file refuses the same number
    from gfuzzy.roadmap.roadmap import load_roadmap

    path = ROOT / "scenes" / "depot.yaml"
    if not path.is_file():
        pytest.skip("no depot scene in this tree")
    scene = load_scene(path)
    roadmap = load_roadmap(ROOT / "roadmaps" / "depot.json", scene)
    goal = scene.queries[0].goal
    with pytest.raises(InputError, match="start: "):
        plan(scene, roadmap, [bad, 1.0, 0.0], goal)
    with pytest.raises(ValueError, match="goal: "):
        plan(scene, roadmap, scene.queries[0].start, [1.0, bad, 0.0])


@pytest.mark.parametrize(
    "robot, named",
    [({"footprint": [[-0.2, -0.1], [0.2, -0.1], [0.2, 0.1], [-0.2, 0.1]]}, "for this footprint robot"),
     ({"disc": 0.2, "kinematics": "unicycle"}, "for this disc robot (unicycle)"),
     ({"box": [0.4, 0.2]}, "for this box robot")],
)  # fmt: skip
def test_a_malformed_pose_is_said_of_the_robot_the_scene_has(robot, named):
    # a footprint robot was told "[x, y, heading] for a box robot or a unicycle"
    scene = parse_scene({"version": 1, "name": "r", "bounds": [0, 0, 4, 4], "robot": dict(robot, vmax=1.0)})
    rm = build_roadmap(scene, RoadmapOptions(vertices=20, seed=1))
    with pytest.raises(InputError, match=rf"start: expected 3 finite numbers \[x, y, heading\] {re.escape(named)}, got 2"):
        plan(scene, rm, [1.0, 1.0], [3.0, 3.0, 0.0])
