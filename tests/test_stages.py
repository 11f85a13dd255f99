"""gfuzzy.planner.stages: the GA refinement and the speed layer run on a context, not a planner."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
import pytest
import yaml
from conftest import ROOT
from helpers import BUNDLED_PARAMS, bundled_params
from helpers import BUNDLED_SCENES as SCENES
from helpers import bundled_answers as _answers
from helpers import bundled_setup as _setup
from helpers import scene_doc as _doc
from helpers import scene_of as _scene
from reference import reference_violation
from shared_scenes import CROSSING

from gfuzzy.check.check import check_trajectory
from gfuzzy.collision.geometry import StaticGeometry
from gfuzzy.planner.planner import Planner, PlanOptions, plan
from gfuzzy.planner.stages import (
    GA_FEASIBLE_KNOTS,
    RefineReport,
    SpeedReport,
    StageContext,
    apply_stages,
)
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap
from gfuzzy.scene.scene import Query, parse_scene
from gfuzzy.trajectory import Trajectory

# an L-shaped hall: the search's answer turns a corner, the stages have work to do
HALL = """
version: 1
name: hall
bounds: [0, 0, 6, 6]
robot: {disc: 0.2, vmax: 1.0}
obstacles:
  - box: {center: [3.5, 3.5], size: [5, 5]}
movers:
  - {name: cart, disc: 0.25, trajectory: [[0, 3.0, 0.5], [4, 3.0, 0.5]]}  # stands in the way until t = 4
queries:
  - {name: corner, start: [5.5, 0.5], goal: [0.5, 5.5]}
"""


@pytest.fixture(scope="module")
def hall():
    doc = yaml.safe_load(HALL)
    scene = parse_scene(doc)
    return doc, scene, build_roadmap(scene, RoadmapOptions(vertices=60, seed=3))


def _query(q):
    return Query(q.name, tuple(q.start), tuple(q.goal), q.t0, hold=q.hold)


def _searched(scene, rm, q):
    res = Planner(scene, rm).plan(q.start, q.goal, q.t0)
    assert res.solved
    return res


def test_both_stages_report_and_keep_a_safe_answer(hall):
    doc, scene, rm = hall
    q = scene.queries[0]
    base = _searched(scene, rm, q)
    ctx = StageContext(scene, StaticGeometry(scene))
    opts = PlanOptions(refine=True, speed_layer=True, seed=2)
    out = apply_stages(ctx, base.trajectory, _query(q), opts, time.perf_counter() + opts.time_limit)
    assert isinstance(out.refine_report, RefineReport) and isinstance(out.speed_report, SpeedReport)
    # the file keeps its keys: its stats hold the reports' dict forms
    file_stats = replace(base, trajectory=out.trajectory, refine_report=out.refine_report,
                         speed_report=out.speed_report).to_file("s", "q").to_dict()["stats"]  # fmt: skip
    assert file_stats["refine"] == out.refine_report.to_dict()
    assert file_stats["speed_layer"] == out.speed_report.to_dict()
    assert out.speed_report.amax == 2.0  # AMAX_PER_VMAX * vmax for a robot without amax
    assert out.speed_report.applied, out.speed_report.reason
    assert set(file_stats["speed_layer"]) >= {"applied", "amax", "profile_seconds", "stops", "before", "after"}
    assert reference_violation(doc, out.trajectory.waypoints) == ""
    r = out.refine_report
    assert r.applied, r.reason
    assert r.after["length"] < r.before["length"] and r.knots == 12  # the paper's knots sufficed
    assert out.speed_report.stops >= 1  # the cart stands in the corridor until t = 4


def test_a_ga_past_the_time_limit_keeps_the_search_answer(hall):
    """`--refine` ran the GA to its end whatever `--time-limit` said (a refined answer
    came back at 23 s with a limit of 10 s): past the deadline the generations stop and the
    search's answer is kept, said in the report; the GA alone shows it stopped at once."""
    _, scene, rm = hall
    q = scene.queries[0]
    base = _searched(scene, rm, q)
    ctx = StageContext(scene, StaticGeometry(scene))
    opts = PlanOptions(refine=True, seed=2, time_limit=7.0)
    out = apply_stages(ctx, base.trajectory, _query(q), opts, time.perf_counter() - 1.0)
    r = out.refine_report
    assert not r.applied and r.generations == 0
    assert r.reason.startswith("the planning budget (7 s, --time-limit) ran out while the GA refined")
    np.testing.assert_array_equal(out.trajectory.waypoints, base.trajectory.waypoints)
    # with time left the same call refines (the hall has a corner to cut)
    assert apply_stages(ctx, base.trajectory, _query(q), opts, time.perf_counter() + 60).refine_report.applied


def test_a_straight_answer_is_left_to_the_search(hall):
    _, scene, rm = hall
    ctx = StageContext(scene, StaticGeometry(scene))
    wps = np.array([[0.0, 5.5, 0.5], [1.0, 5.5, 1.5]])
    query = Query("q", tuple(wps[0, 1:]), tuple(wps[-1, 1:]), 0.0)
    out = apply_stages(ctx, Trajectory(wps, scene.robot.radius), query, PlanOptions(refine=True), time.perf_counter() + 60)
    assert out.refine_report == RefineReport(False, "the path is a straight segment already")
    assert out.refine_report.to_dict() == {"applied": False, "reason": "the path is a straight segment already"}
    np.testing.assert_array_equal(out.trajectory.waypoints, wps)


def test_a_straight_answer_through_several_points_is_left_to_the_search(hall):
    """zara-crowd's cross-flow waits and walks one straight line: the GA ran 48 knots for 2.9 s
    and said 'the GA found nothing better than the corridor'; a straight corridor is said
    to be straight, whatever its points and waits, and the GA is not run."""
    _, scene, rm = hall
    ctx = StageContext(scene, StaticGeometry(scene))
    wps = np.array([[0.0, 5.5, 0.5], [0.5, 5.5, 1.0], [1.5, 5.5, 1.0], [2.0, 5.5, 1.5], [2.5, 5.5, 2.0]])
    query = Query("q", tuple(wps[0, 1:]), tuple(wps[-1, 1:]), 0.0)
    out = apply_stages(ctx, Trajectory(wps, scene.robot.radius), query, PlanOptions(refine=True), time.perf_counter() + 60)
    assert out.refine_report == RefineReport(False, "the path is a straight segment already")
    np.testing.assert_array_equal(out.trajectory.waypoints, wps)


def test_start_is_goal_has_nothing_to_slow():
    scene = parse_scene(yaml.safe_load(HALL))
    ctx = StageContext(scene, StaticGeometry(scene))
    wps = np.array([[0.0, 5.5, 0.5]])
    query = Query("q", tuple(wps[0, 1:]), tuple(wps[0, 1:]), 0.0)
    out = apply_stages(ctx, Trajectory(wps, 0.2), query, PlanOptions(speed_layer=True), time.perf_counter() + 60)
    assert out.speed_report == SpeedReport(False, 2.0, "the start is the goal")
    assert out.speed_report.to_dict() == {"applied": False, "amax": 2.0, "reason": "the start is the goal"}


def test_the_planner_hands_the_stages_a_context(hall):
    _, scene, rm = hall
    q = scene.queries[0]
    res = Planner(scene, rm).plan(q.start, q.goal, q.t0, PlanOptions(speed_layer=True))
    assert res.speed_report is not None and res.refine_report is None
    assert res.to_file(scene.name, q.name).to_dict()["stats"]["speed_layer"]["applied"] == res.speed_report.applied


def test_ga_and_speed_layer_keep_the_clearances():
    scene = _scene(CROSSING, clearance=0.05, mover_clearance=0.2)
    rm = build_roadmap(scene, RoadmapOptions(vertices=60, seed=1))
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal, options=PlanOptions(refine=True, speed_layer=True))
    assert res.solved
    # the stages keep only answers check_trajectory accepts: the oracle is the independent
    # shapely reference, which shares no code with the planner or the checker
    assert reference_violation(_doc(CROSSING, clearance=0.05, mover_clearance=0.2), res.trajectory.waypoints) == ""


# the GA costs 8-22 s on the larger scenes: those run in `make slow`; the drive
# (building-floor-unicycle), the replays and the small mover scenes stay in `make test`
REFINE_SLOW = ("depot", "small-house", "tb3-arena", "tb3-arena-unicycle", "drive-tight", "footprint-office",
               "building-floor", "office-polygons", "warehouse-mesh")  # fmt: skip


@pytest.mark.parametrize("path", bundled_params(slow=REFINE_SLOW))
def test_refined_answers_keep_the_guarantees(path):
    scene = _setup(path)[0]
    for (q, plain), (_, refined) in zip(_answers(path, False, False), _answers(path, True, False), strict=True):
        assert refined.status == plain.status
        if not refined.solved:
            continue
        rep = check_trajectory(scene, refined.trajectory.waypoints, q)
        assert rep.valid, f"{q.name}: {rep.reason}"
        info = refined.refine_report.to_dict()
        if info["applied"]:
            before, after = info["before"], info["after"]
            assert after["length"] < before["length"] - 1e-9 or after["smoothness"] < before["smoothness"] - 1e-9
            assert refined.duration <= plain.duration * 1.1 + 1e-9
        else:
            assert np.array_equal(refined.trajectory.waypoints, plain.trajectory.waypoints)


@pytest.mark.slow  # an experiment: how often the stage helps, on every bundled scene
def test_refinement_applies_on_most_queries():
    applied = solved = boxes = 0
    for path in SCENES:
        scene = _setup(path)[0]
        for _, r in _answers(path, True, False):
            if r.solved:
                solved += 1
                applied += r.refine_report.applied
                boxes += r.refine_report.applied and scene.robot.shape == "box"
    assert applied >= 0.75 * solved
    assert boxes >= 1  # box robots too, through 0.6 m doors


def test_a_corridor_hugging_walls_is_refined_with_more_knots():
    """office-polygons' sw-to-ne on its bundled roadmap passes 5 mm from a wall: the chords
    of 12 and of 24 knots cut into the walls, no individual was feasible, and `--refine`
    said "the GA found nothing better than the corridor" of a path turning 6.2 rad; 48
    knots follow its corners and halve the turning."""
    path = ROOT / "scenes" / "office-polygons.yaml"
    ((q, r),) = [(q, r) for q, r in _answers(path, True, False) if q.name == "sw-to-ne"]
    rep = r.refine_report
    assert rep.applied and rep.knots == GA_FEASIBLE_KNOTS, rep.reason
    assert rep.after["smoothness"] < 0.6 * rep.before["smoothness"]
    assert check_trajectory(_setup(path)[0], r.trajectory.waypoints, q).valid


def test_refinement_is_reproducible():
    path = ROOT / "scenes" / "sim-4s1m.yaml"
    scene, _, planner = _setup(path)
    q = scene.queries[0]
    a = planner.plan(q.start, q.goal, q.t0, PlanOptions(refine=True, seed=11))
    b = planner.plan(q.start, q.goal, q.t0, PlanOptions(refine=True, seed=11))
    assert np.array_equal(a.trajectory.waypoints, b.trajectory.waypoints)


@pytest.mark.parametrize("path", BUNDLED_PARAMS)  # the large scenes: slow
def test_speed_layer_answers_keep_the_guarantees(path):
    scene = _setup(path)[0]
    robot = scene.robot
    amax = robot.amax if robot.amax is not None else 2 * robot.vmax
    for q, res in _answers(path, False, True):
        if not res.solved:
            continue
        w = res.trajectory.waypoints
        rep = check_trajectory(scene, w, q)
        assert rep.valid, f"{q.name}: {rep.reason}"
        info = res.speed_report.to_dict()
        if not info["applied"]:
            continue
        dt = np.diff(w[:, 0])
        kept = dt < 0.07 + 1e-9  # row pairs that must keep amax: steps, not long waits
        if info.get("hasty"):  # in part: its hasty legs break amax, and the answer says so
            h = info["hasty"]
            assert res.amax_honoured is not True and 0 < h["legs"] < h["of"] and len(h["spans"]) == h["legs"]
            for a, b in h["spans"]:  # amax is kept outside the hasty legs' times
                kept &= ~((w[1:, 0] > a + 1e-9) & (w[:-1, 0] < b - 1e-9))
        # the profile respects the acceleration bound: speed changes between steps stay
        # within amax * dt (plus the discretization of the profile onto the time grid)
        v = res.trajectory.speeds()
        dv = np.abs(np.diff(v))[kept[1:] & kept[:-1]]
        assert dv.max(initial=0.0) <= amax * 0.07 * 1.5 + 1e-9, (q.name, dv.max())


@pytest.mark.parametrize("scene, query", [("footprint-office", "dock"), ("sealed-room", "into-open-room")])
def test_the_speed_layer_applies_where_its_stops_needed_more_rounds(scene, query):
    """The speed layer said "the speed-limited path could not be timed among the movers (no
    safe trajectory within the planning horizon)" of both: the stops the free searches found
    were merged back onto the same places and the rounds gave up (retime.next_stops). Their
    answers keep the guarantees (test above)."""
    path = ROOT / "scenes" / f"{scene}.yaml"
    ((q, r),) = [(q, r) for q, r in _answers(path, False, True) if q.name == query]
    assert r.speed_report.applied, r.speed_report.reason
    assert r.speed_report.stops >= 1
    assert check_trajectory(_setup(path)[0], r.trajectory.waypoints, q).valid


@pytest.mark.slow  # an experiment: how often the stage helps, on every bundled scene
def test_speed_layer_applies_on_most_queries():
    applied = total = 0
    for path in SCENES:
        for _, r in _answers(path, False, True):
            if r.solved:
                total += 1
                applied += r.speed_report.applied
    assert applied >= 0.6 * total


# ---------------------------------------------------------------- a differential drive

# the L-shaped hall with a box differential drive: the answer turns in place at corners
HALL_DRIVE = HALL.replace("robot: {disc: 0.2, vmax: 1.0}", "robot: {box: [0.5, 0.3], vmax: 1.0, kinematics: unicycle}").replace(
    "start: [5.5, 0.5], goal: [0.5, 5.5]", "start: [5.5, 0.5, 3.14159], goal: [0.5, 5.5, 1.5708]"
)


@pytest.fixture(scope="module")
def hall_drive():
    doc = yaml.safe_load(HALL_DRIVE)
    scene = parse_scene(doc)
    rm = build_roadmap(scene, RoadmapOptions(vertices=80, seed=3))
    q = scene.queries[0]
    return doc, scene, q, plan(scene, rm, q.start, q.goal, options=PlanOptions(speed_layer=True, seed=1))


def test_the_speed_layer_applies_to_a_differential_drive(hall_drive):
    from test_driveprofile import oracle

    doc, scene, q, res = hall_drive
    assert res.solved and res.speed_report.applied, res.speed_report.reason
    w = res.trajectory.waypoints
    rep = check_trajectory(scene, w, q)
    assert rep.valid, rep.reason  # the row rule included
    assert reference_violation(doc, w) == ""
    r = scene.robot
    path = w[np.concatenate([[True], np.any(np.abs(np.diff(w[:, 1:], axis=0)) > 0, axis=1)]), 1:]
    assert oracle(w, path, r.vmax, r.turn_rate, 2.0 * r.vmax, r.circumradius) == []
    info = res.speed_report.to_dict()
    assert info["corners"]["after"] <= info["corners"]["before"]
    # the cart stands in the way until t = 4: the layered answer still waits for it
    assert w[-1, 0] > 4.0


def test_the_drive_layer_reports_in_the_file(hall_drive):
    _, scene, q, res = hall_drive
    stats = res.to_file(scene.name, q.name).to_dict()["stats"]["speed_layer"]
    assert stats == res.speed_report.to_dict() and stats["applied"] and "corners" in stats


def test_gfuzzy_plan_speed_layer_applies_on_the_bundled_drive(tmp_path, capsys):
    from helpers import run_main

    out = tmp_path / "hop.json"
    rc, stdout, _ = run_main(capsys, "plan", ROOT / "scenes" / "tb3-arena-unicycle.yaml", "--query", "lane-hop",
                             "--speed-layer", "-o", out)  # fmt: skip
    assert rc == 0 and "speed layer: applied" in stdout, stdout
    rc, _, err = run_main(capsys, "check", ROOT / "scenes" / "tb3-arena-unicycle.yaml", out)
    assert rc == 0, err


def test_a_drive_segment_is_certified_at_its_own_heading_and_turns():
    from gfuzzy.planner.stages import _clearance_functions

    # a long box drive; the corridor runs along x (heading 0) but the segment goes up from
    # (2, 1): the robot turns in place there to heading pi/2, sweeping the point at
    # (-0.32, -0.32) from it, which the box sliding up at heading 0 never touches
    doc = {"version": 1, "name": "seg", "bounds": [0, 0, 5, 4],
           "robot": {"box": [1.0, 0.3], "vmax": 1.0, "kinematics": "unicycle"},
           "obstacles": [{"disc": {"center": [2.0 - 0.32, 1.0 - 0.32], "radius": 0.03}}]}  # fmt: skip
    scene = parse_scene(doc)
    ctx = StageContext(scene, StaticGeometry(scene))
    corridor = np.array([[0.8, 1.0, 0.0], [4.0, 1.0, 0.0]])
    static_segment = _clearance_functions(ctx, corridor)[2]
    bound, clearance = static_segment(np.array([[2.0, 1.0]]), np.array([[2.0, 2.5]]))
    assert bound[0] < 0 and clearance[0] < 0
    holonomic = parse_scene({**doc, "robot": {"box": [1.0, 0.3], "vmax": 1.0}})
    slide = _clearance_functions(StageContext(holonomic, StaticGeometry(holonomic)), corridor)[2]
    assert slide(np.array([[2.0, 1.0]]), np.array([[2.0, 2.5]]))[0][0] == 0.0  # free for a box that slides
    # along the corridor the drive's segment is free
    assert static_segment(np.array([[1.2, 1.0]]), np.array([[3.5, 1.0]]))[0][0] == 0.0


def test_a_refined_drive_path_keeps_the_turning_rate():
    path = ROOT / "scenes" / "tb3-arena-unicycle.yaml"
    scene, rm, planner = _setup(path)
    q = scene.queries[2]
    res = planner.plan(q.start, q.goal, q.t0, PlanOptions(refine=True, seed=1))
    assert res.refine_report.applied, res.refine_report.reason
    rep = check_trajectory(scene, res.trajectory.waypoints, q)
    assert rep.valid, rep.reason


def test_a_drive_that_may_reverse_backs_out_where_it_cannot_turn():
    """drive-tight's back-out: the cart is parked nose against the bounds (touching them) in a
    0.44 m arm and backs out. The GA's segment model drove every straight forwards (a turn
    round in the arm: not free) and could not leave a pose touching the bounds, so no
    individual was feasible and --refine said 'nothing better than the corridor'; the path
    through its via-points drove forwards too. With ``reverse`` a straight may be driven
    backwards, and a motion from a touching pose is certified as the roadmap certifies it."""
    from gfuzzy.planner.stages import _clearance_functions
    from gfuzzy.planner.straighten import drive_path
    from gfuzzy.scene.scene import load_scene

    scene = load_scene(ROOT / "scenes" / "drive-tight.yaml")
    geometry = StaticGeometry(scene)
    start = np.array([5.3, 5.375, np.pi / 2])
    corridor = np.array([start, [5.3, 4.0, np.pi / 2]])
    static_segment = _clearance_functions(StageContext(scene, geometry), corridor)[2]
    # the search's lane is off the arm's axis by 1e-12 m, as its answers are
    bound, clearance = static_segment(start[None, :2], np.array([[5.3 - 1e-12, 4.7]]))
    assert bound[0] == 0.0 and clearance[0] >= 0.0
    path = drive_path(geometry, start, np.array([[5.3, 4.7]]), np.array([5.3, 4.0, np.pi / 2]), reverse=True,
                      prefer=lambda xy: np.pi / 2)  # fmt: skip
    assert path is not None and np.all(path[:, 2] == np.pi / 2)  # straight back, never turned
    assert drive_path(geometry, start, np.array([[5.3, 4.7]]), np.array([5.3, 4.0, np.pi / 2])) is None  # forwards: no


def test_a_mover_bound_that_refuses_the_search_answer_is_left_to_the_retiming(hall):
    """building-floor-unicycle: the GA's mover bound (the box at the corridor's heading)
    put the search's own answer 0.038 m inside mover A, so no individual near it was
    feasible with 12, 24 or 48 knots and --refine said 'nothing better than the corridor'.
    A bound that refuses the answer the exact search accepted cannot guide the GA: it then
    refines against the walls alone, and the re-timing decides among the movers."""
    from gfuzzy.planner.stages import _clearance_functions, _run_ga

    _, scene, rm = hall
    q = scene.queries[0]
    base = _searched(scene, rm, q)
    ctx = StageContext(scene, StaticGeometry(scene))
    funcs = _clearance_functions(ctx, base.trajectory.poses)

    def refusing(xy, t):  # 1 cm inside a mover wherever asked, the search's answer included
        return np.full(len(np.atleast_2d(xy)), -0.01)

    res, _, _, _ = _run_ga(ctx, base.trajectory, PlanOptions(refine=True, seed=2), funcs[:3] + (refusing,),
                        time.perf_counter() + 60)  # fmt: skip
    assert res.improved and res.length_after < res.length_before


def test_feasible_individuals_of_any_try_count_not_only_the_last(hall, monkeypatch):
    """The 12 knots found feasible paths (none better), the 24 none: the GA did weigh paths,
    so the third try (48 knots, for corridors where no try was feasible) is not run and the
    report is 'nothing better', not 'no feasible path' (both looked at the last try only)."""
    import types

    import gfuzzy.ga
    from gfuzzy.planner.stages import GA_RETRY_KNOTS, _clearance_functions, _run_ga

    knots = []

    def stub(*args, **kwargs):  # the GA itself is not what this test is about
        knots.append(args[5].n_knots)  # (path, times, radius, static, movers, options)
        history = np.array([1.0, 1.0]) if len(knots) == 1 else np.array([np.inf, np.inf])
        return types.SimpleNamespace(improved=False, out_of_time=False, fitness_history=history)

    monkeypatch.setattr(gfuzzy.ga, "refine_path", stub)
    _, scene, rm = hall
    base = _searched(scene, rm, scene.queries[0])
    ctx = StageContext(scene, StaticGeometry(scene))
    funcs = _clearance_functions(ctx, base.trajectory.poses)
    *_, feasible = _run_ga(ctx, base.trajectory, PlanOptions(refine=True, seed=2), funcs, time.perf_counter() + 60)
    assert feasible and knots[1:] == [GA_RETRY_KNOTS]


def test_a_ga_without_a_feasible_individual_says_so(hall, monkeypatch):
    """depot's dock-to-east (8 mm from a rack): no individual of 12, 24 or 48 knots was
    feasible, and the report said 'the GA found nothing better than the corridor' as if
    the GA had weighed paths and kept the search's; it says that none was feasible."""
    from gfuzzy.planner import stages

    real = stages._clearance_functions

    def walled(ctx, corridor):  # every segment refused: no individual can be feasible
        poses_of, static_clearance, _, mover_clearance = real(ctx, corridor)
        return poses_of, static_clearance, lambda a, b: (np.full(len(a), -1.0), np.full(len(a), -1.0)), mover_clearance

    monkeypatch.setattr(stages, "_clearance_functions", walled)
    _, scene, rm = hall
    q = scene.queries[0]
    base = _searched(scene, rm, q)
    out = apply_stages(StageContext(scene, StaticGeometry(scene)), base.trajectory, _query(q),
                       PlanOptions(refine=True, seed=2), time.perf_counter() + 60)  # fmt: skip
    r = out.refine_report
    assert not r.applied and r.reason.startswith("the GA found no feasible path near the corridor (up to 48 knots")
