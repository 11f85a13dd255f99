"""The unicycle navigator's own motions: the two-leg fan out of the start
(:func:`gfuzzy.timespace.drive.fan`) and keeping the last plan
(:func:`gfuzzy.navigation.drivenav.kept_plan`), and its evasive motions
(:func:`gfuzzy.navigation.drivenav.drive_evasion`), backing up with ``reverse``."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from gfuzzy.check.check import check_trajectory
from gfuzzy.check.rows import unicycle_problem as _unicycle_problem
from gfuzzy.navigation.crowdpolicies import piece_of
from gfuzzy.navigation.drivenav import drive_evasion
from gfuzzy.navigation.navigator import Navigator, NavMode, NavOptions, _Searched
from gfuzzy.navigation.navsim import simulate
from gfuzzy.scene.scene import Mover, parse_scene
from gfuzzy.trajectory import Trajectory

START = [1.0, 3.0, 0.0]
GOAL = [9.0, 3.0, 0.0]


@pytest.fixture(scope="module")
def open_floor():
    from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap

    doc = {
        "version": 1, "name": "open-floor", "bounds": [0, 0, 10, 6],
        "robot": {"disc": 0.3, "vmax": 1.0, "kinematics": "unicycle", "wmax": 1.0},
        "obstacles": [], "movers": [], "queries": [],
    }  # fmt: skip
    sc = parse_scene(doc, "<open-floor>")
    return sc, build_roadmap(sc, RoadmapOptions(vertices=150, seed=3))


def _turns(rows: np.ndarray) -> int:
    """Turns in place (maximal runs of rows that only change the heading), by hand."""
    d = np.hypot(np.diff(rows[:, 1]), np.diff(rows[:, 2]))
    dh = np.abs((np.diff(rows[:, 3]) + math.pi) % (2 * math.pi) - math.pi)
    turning = (d <= 1e-9) & (dh > 1e-9)
    return int(np.sum(turning[1:] & ~turning[:-1]) + turning[0])


def _min_gap(traj, person: np.ndarray, t0: float) -> float:
    """Smallest gap between the disc robot (0.3) and a person walking at constant velocity."""
    times = np.linspace(t0, traj.t_end, 4000)
    xy = traj.at(times)[:, :2]
    at = person[:2] + (times - t0)[:, None] * person[2:4]
    return float(np.min(np.hypot(*(xy - at).T)) - 0.3 - person[4])


@pytest.mark.parametrize("fan", [True, False])
def test_a_detour_obeys_the_row_rule_and_keeps_clear(open_floor, fan):
    sc, rm = open_floor
    nav = Navigator(sc, rm, GOAL, NavOptions(time_budget=5.0, fan=fan))
    person = np.array([5.0, 3.0, 0.0, 0.0, 0.3])  # standing on the straight line
    traj = nav.step(0.0, START, person[None])
    # a fresh search's plan: with the personal space, or closer when that arrives sooner
    # by more than its soft cost (NavOptions.personal_space_cost)
    assert nav.last.mode in (NavMode.PLAN, NavMode.CLOSE)
    assert _unicycle_problem(sc.robot, traj.waypoints) is None  # the checker's own row rule
    assert _min_gap(traj, person, 0.0) >= 0.0
    np.testing.assert_allclose(traj.waypoints[-1, 1:], GOAL, atol=1e-9)


def test_the_fan_detours_with_few_turns_and_never_later(open_floor):
    """The fan's graph holds the roadmap's: its time-optimal plan cannot arrive later, and
    around one person standing in the way it turns at most three times (out, back towards
    the goal, the goal's heading), where the roadmap's lanes zigzag."""
    sc, rm = open_floor
    person = np.array([[5.0, 3.0, 0.0, 0.0, 0.3]])
    with_fan = Navigator(sc, rm, GOAL, NavOptions(time_budget=5.0)).step(0.0, START, person)
    without = Navigator(sc, rm, GOAL, NavOptions(time_budget=5.0, fan=False)).step(0.0, START, person)
    assert with_fan.t_end <= without.t_end + 1e-9
    assert _turns(with_fan.waypoints) <= 3
    assert _turns(with_fan.waypoints) < _turns(without.waypoints)


def test_the_last_plan_is_kept_while_it_is_as_good(open_floor):
    sc, rm = open_floor
    walker = np.array([[5.0, 0.8, 0.0, 0.5, 0.3]])  # will cross the straight line
    nav = Navigator(sc, rm, GOAL, NavOptions(time_budget=5.0))
    first = nav.step(0.0, START, walker)
    assert nav.last.mode == NavMode.PLAN
    pose = first.at(0.25)
    seen = walker.copy()
    seen[0, :2] += 0.25 * seen[0, 2:4]
    again = nav.step(0.25, pose, seen)  # the same world, a period later: the plan is kept
    assert nav.last.mode == NavMode.KEPT
    times = np.linspace(0.25, first.t_end, 200)
    np.testing.assert_allclose(again.at(times), first.at(times), atol=1e-9)
    assert _unicycle_problem(sc.robot, again.waypoints) is None

    fresh = Navigator(sc, rm, GOAL, NavOptions(time_budget=5.0, commitment=0.0))
    fresh.step(0.0, START, walker)
    fresh.step(0.25, pose, seen)
    assert fresh.last.mode == NavMode.PLAN


def test_a_last_plan_someone_steps_into_is_dropped(open_floor):
    sc, rm = open_floor
    nav = Navigator(sc, rm, GOAL, NavOptions(time_budget=5.0))
    first = nav.step(0.0, START, np.zeros((0, 5)))
    pose = first.at(0.25)
    ahead = first.at(2.0)
    blocker = np.array([[ahead[0], ahead[1], 0.0, 0.0, 0.3]])  # standing on the plan's way
    again = nav.step(0.25, pose, blocker)
    assert nav.last.mode != NavMode.KEPT
    assert _min_gap(again, blocker[0], 0.25) >= 0.0
    assert _unicycle_problem(sc.robot, again.waypoints) is None


# ------------------------------------------------------------------------ evasion


P0 = np.array([3.0, 3.0, 0.0])


@pytest.fixture(scope="module")
def reversing_floor(open_floor):
    sc, rm = open_floor
    return replace(sc, robot=replace(sc.robot, reverse=True)), rm


def test_a_robot_that_may_reverse_backs_straight_away_from_someone_head_on(reversing_floor, open_floor):
    """Someone 1 m ahead (0.4 m gap) walking at the robot at 1 m/s: a quarter turn (1.6 s)
    comes too late, backing up keeps the gap."""
    sc, rm = reversing_floor
    nav = Navigator(sc, rm, GOAL, NavOptions())
    person = np.array([P0[0] + 1.0, P0[1], -1.0, 0.0, 0.3])
    traj = drive_evasion(nav, 0.0, P0, person[None])
    w = traj.waypoints
    # no turn first: straight back along the heading, and the gap kept (by hand)
    assert w[1, 3] == pytest.approx(P0[2]) and w[1, 1] < P0[0] - 0.5
    assert _min_gap(traj, person, 0.0) >= 0.0
    assert _unicycle_problem(sc.robot, w) is None
    assert _unicycle_problem(open_floor[0].robot, w) is not None  # the forward-only robot may not
    fwd = Navigator(open_floor[0], rm, GOAL, NavOptions())
    w = drive_evasion(fwd, 0.0, P0, person[None]).waypoints
    assert _unicycle_problem(open_floor[0].robot, w) is None


def _evading(nav, people: np.ndarray, seconds: float, period: float = 0.25):
    """The robot from ``P0`` following a fresh evasive motion every ``period`` among
    ``people`` (k, 5) walking on at constant velocity: (smallest gap, the rows driven),
    the gap sampled every 0.01 s by hand."""
    pose, t, worst, rows = P0.copy(), 0.0, math.inf, [np.array([0.0, *P0])]
    while t < seconds - 1e-9:
        obs = people.copy()
        obs[:, :2] += t * people[:, 2:4]
        traj = drive_evasion(nav, t, pose, obs)
        assert _unicycle_problem(nav.robot, traj.waypoints) is None
        s = np.linspace(t, t + period, 26)
        xy = traj.at(s)[:, :2]
        at = people[None, :, :2] + s[:, None, None] * people[None, :, 2:4]
        worst = min(worst, float(np.min(np.hypot(*(xy[:, None] - at).transpose(2, 0, 1)) - 0.3 - people[:, 4])))
        rows.extend(piece_of(traj, t, t + period)[1:])
        pose, t = traj.at(t + period), t + period
    return worst, np.array(rows)


def test_the_evasion_looks_far_enough_for_a_turn_to_pay(open_floor):
    """Two people converging on the robot from behind and from its right: driving straight
    on keeps clear for the first two seconds and then meets the second one, a turn in place
    first costs those seconds' lead; scored over two seconds (the old look-ahead, on a grid
    of headings that turned with the robot) the evasions, redone every 0.25 s, touched
    someone (-0.24 m); scored over ``drive_lookahead`` they keep clear."""
    sc, rm = open_floor
    nav = Navigator(sc, rm, GOAL, NavOptions())
    people = np.array([[1.5, 1.06, 0.33, 0.38, 0.3], [3.21, 1.03, 0.44, 0.82, 0.3]])
    worst, rows = _evading(nav, people, 6.0)
    assert worst > 0.1
    assert _unicycle_problem(sc.robot, rows) is None


def test_an_evasion_under_way_keeps_its_heading_target(open_floor):
    """A turn begun by one evasion still has its target among the next call's candidates
    (headings on a grid fixed in the world): someone 2 m ahead walking at the robot, the
    evasions redone every 0.25 s while it turns away all aim for the same heading (on a
    grid that turned with the robot they aimed at -67.5, -81.8, -73.6, -65.5 degrees)."""
    sc, rm = open_floor
    nav = Navigator(sc, rm, GOAL, NavOptions())
    person = np.array([P0[0] + 2.0, P0[1] + 0.1, -1.0, 0.0, 0.3])
    pose, aims = P0.copy(), []
    for k in range(4):
        t = 0.25 * k
        obs = person.copy()
        obs[:2] += t * person[2:4]
        traj = drive_evasion(nav, t, pose, obs[None])
        aims.append(float(traj.waypoints[1, 3]))
        pose = traj.at(t + 0.25)
    assert abs(aims[0]) > 0.5  # it turns away
    assert np.allclose(aims, aims[0])


def _turn_reversals(rows: np.ndarray) -> int:
    """How often a turn in place goes the other way than the one before it, the robot not
    having moved in between, by hand (rows driven, one a period)."""
    d = np.hypot(np.diff(rows[:, 1]), np.diff(rows[:, 2]))
    dh = (np.diff(rows[:, 3]) + math.pi) % (2 * math.pi) - math.pi
    count, last = 0, 0.0
    for moved, turned in zip(d, dh, strict=True):
        if moved > 1e-6:
            last = 0.0
        elif abs(turned) > 1e-6:
            count += last * turned < 0
            last = turned
    return count


def _evasions_only(sc, rm, p0, people, monkeypatch, seconds=4.0):
    """Rows every 0.25 s and the smallest gap of a navigator whose searches all find
    nothing (every answer an evasion), among ``people`` walking straight on."""
    monkeypatch.setattr(Navigator, "_search", lambda self, t, p, *a, **k: _Searched(None, "exhausted"))
    monkeypatch.setattr(Navigator, "_direct", lambda self, *a: None)
    nav = Navigator(sc, rm, GOAL, NavOptions())
    pose, t, rows, worst = np.array(p0, float), 0.0, [np.array([0.0, *p0])], math.inf
    while t < seconds - 1e-9:
        obs = people.copy()
        obs[:, :2] += t * people[:, 2:4]
        traj = nav.step(t, pose, obs)
        assert nav.last.mode == NavMode.EVASIVE
        worst = min(worst, *(_min_gap(Trajectory(piece_of(traj, t, t + 0.25), 0.3), p, t) for p in obs))
        pose, t = traj.at(t + 0.25), t + 0.25
        rows.append(np.array([t, *pose]))
    return np.array(rows), worst


def test_evasions_in_a_row_do_not_undo_their_turns(open_floor, monkeypatch):
    """Every search finding nothing, the navigator answers with an evasion every 0.25 s
    while two people walk up from behind on its left. Decided afresh each time (all the
    candidates keep clear over 4 s, and the gap and progress terms of their scores flip with
    every step of the turn) the evasions turned back and forth in place four times in 4 s
    and kept 0.71 m; a candidate that turns against the turn under way must now win by
    ``EVASION_COMMITMENT`` of time to contact: no turn is undone, and the gap is wider."""
    people = np.array([[1.13, 3.81, 0.8, -0.83, 0.3], [0.36, 2.43, 1.08, -0.05, 0.3]])
    rows, worst = _evasions_only(*open_floor, P0, people, monkeypatch)
    assert _turns(rows) >= 1  # it does turn away
    assert _turn_reversals(rows) == 0
    assert worst > 1.0


def test_the_commitment_leaves_contacts_to_the_time_to_contact(open_floor, monkeypatch):
    """Three people walk at the robot and every candidate meets one within the look-ahead:
    the turn under way was still preferred (the commitment's points outweighing what the
    sampled times to contact left to the gap and progress terms), and the robot drove into
    someone 0.52 m deep; it turns back and keeps clear (a reviewer's random sweep)."""
    p0 = [2.7716239269287692, 3.737411106342617, 1.3820795650498177]
    people = np.array([
        [4.952156751649621, 4.324310975389096, -0.7724280933035104, -0.2607374114652339, 0.3],
        [3.9842456757405538, 4.921971552859872, -1.020872413453967, -0.41623567065140393, 0.3],
        [0.3823335687505214, 5.733267060742783, 0.4087563308046987, -0.5183886772368607, 0.3],
    ])  # fmt: skip
    rows, worst = _evasions_only(*open_floor, p0, people, monkeypatch)
    assert worst > 0.0


def test_the_turn_under_way(open_floor):
    """``turn_under_way`` by hand: the turn left across pi keeps its sign; none when the
    robot is off the evasion, driving, past its end, or has none."""
    from gfuzzy.navigation.drivenav import turn_under_way

    ev = Trajectory(np.array([[0, 1, 1, 3.0], [0.5, 1, 1, 3.5 - 2 * math.pi], [2.0, 2.0, 1.0, 3.5 - 2 * math.pi]]), 0.3)
    assert turn_under_way(ev, 0.1, ev.at(0.1)) == pytest.approx(0.4)  # 3.1 -> 3.5 across pi
    assert turn_under_way(ev, 0.25, ev.at(0.25) + [0.1, 0, 0]) == 0.0
    assert turn_under_way(ev, 1.0, ev.at(1.0)) == 0.0
    assert turn_under_way(ev, 2.5, ev.at(2.0)) == 0.0
    assert turn_under_way(None, 0.0, np.zeros(3)) == 0.0


def test_a_reversing_robot_among_walkers_reaches_the_goal_and_passes_the_check(reversing_floor):
    """The navigator's every answer for a robot that may back up (plans over lanes driven
    both ways, evasions) is driven and verified by the independent checker."""
    sc, rm = reversing_floor
    walkers = (
        Mover("a", "disc", 0.3, (0.0, 0.0), trajectory=np.array([[0.0, 4.0, 3.0], [6.0, -2.0, 3.0]])),
        Mover("b", "disc", 0.3, (0.0, 0.0), trajectory=np.array([[0.0, 9.0, 3.2], [9.0, 0.0, 3.2]])),
        Mover("c", "disc", 0.3, (0.0, 0.0), trajectory=np.array([[0.0, 5.0, 0.5], [5.0, 5.0, 5.5]])),
    )
    scene = replace(sc, movers=walkers)
    res = simulate(scene, rm, START, GOAL, 0.0, 0.25, max_time=40.0)
    assert res.reached and res.min_separation >= 0.0
    assert check_trajectory(scene, res.trajectory.waypoints).valid


@pytest.fixture(scope="module")
def open_floor_disc():
    from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap

    doc = {
        "version": 1, "name": "open-floor-disc", "bounds": [0, 0, 10, 6],
        "robot": {"disc": 0.3, "vmax": 1.0}, "obstacles": [], "movers": [], "queries": [],
    }  # fmt: skip
    sc = parse_scene(doc, "<open-floor-disc>")
    return sc, build_roadmap(sc, RoadmapOptions(vertices=150, seed=3))


def _detour(t0: float, start, slow: float = 2.0) -> Trajectory:
    """A plan that goes round by the top edge (16 m: much later than the straight line),
    waiting at its first corner so that it takes ``slow`` times the time it needs at 1 m/s
    (a plan is run at full speed up to its first wait: the wait is what makes it late)."""
    wait = 13.0 * (slow - 1.0)
    rows = [[t0, *start], [t0 + 3.0, 2.0, 5.5]] + ([[t0 + 3.0 + wait, 2.0, 5.5]] if wait > 0 else [])
    rows += [[t0 + 10.0 + wait, 9.0, 5.5], [t0 + 13.0 + wait, *GOAL[:2]]]
    return Trajectory(np.array(rows), 0.3)


def test_a_much_sooner_last_plan_still_clear_is_kept(open_floor_disc):
    from gfuzzy.navigation.drivenav import sooner_plan

    sc, rm = open_floor_disc
    nav = Navigator(sc, rm, GOAL[:2], NavOptions(time_budget=5.0))
    person = np.array([[5.0, 0.6, 0.0, 0.0, 0.3]])  # standing 2.4 m below the straight line
    first = nav.step(0.0, START[:2], person)
    assert nav.last.mode in (NavMode.PLAN, NavMode.CLOSE)
    pose = first.at(0.25)
    infl = nav._inflation(pose, person)
    kept = sooner_plan(nav, 0.25, pose, person, infl, _detour(0.25, pose), nav.options.personal_space_cost)
    assert kept is not None
    times = np.linspace(0.25, first.t_end, 200)
    np.testing.assert_allclose(kept.at(times), first.at(times), atol=1e-9)
    # not sooner by more than the gain: the fresh plan answers
    assert sooner_plan(nav, 0.25, pose, person, infl, first, nav.options.personal_space_cost) is None
    # someone now standing on the last plan's way: dropped
    ahead = first.at(3.0)
    blocker = np.array([[ahead[0], ahead[1], 0.0, 0.0, 0.3]])
    assert sooner_plan(nav, 0.25, pose, blocker, nav._inflation(pose, blocker), _detour(0.25, pose), 0.5) is None
    # off the last plan (the robot was pushed elsewhere): dropped
    off = pose + np.array([0.0, 0.3])
    assert sooner_plan(nav, 0.25, off, person, nav._inflation(off, person), _detour(0.25, off), 0.5) is None


def test_the_navigator_answers_with_the_sooner_last_plan(open_floor_disc, monkeypatch):
    sc, rm = open_floor_disc
    nav = Navigator(sc, rm, GOAL[:2], NavOptions(time_budget=5.0))
    person = np.array([[5.0, 0.6, 0.0, 0.0, 0.3]])
    first = nav.step(0.0, START[:2], person)
    pose = first.at(0.25)
    # the fresh search finds only a long detour (as when its budget ran out on one): the last plan answers
    monkeypatch.setattr(Navigator, "_search", lambda self, t, p, *a, **k: _Searched(_detour(t, p)))
    again = nav.step(0.25, pose, person)
    assert nav.last.mode == NavMode.KEPT
    assert again.t_end == pytest.approx(first.t_end)
    assert _min_gap(again, person[0], 0.25) >= 0.2


def test_a_last_plan_sooner_by_less_than_the_soft_costs_is_not_kept(open_floor_disc, monkeypatch):
    """Sooner by more than the personal space's cost but less than the soft costs together
    (personal space and path space): the fresh plan answers, or keeping the last plan would
    undo what the path space bought (the arena's intrusions rose from 0.064 to 0.076 when the
    gain was the personal space's cost alone)."""
    sc, rm = open_floor_disc
    nav = Navigator(sc, rm, GOAL[:2], NavOptions(time_budget=5.0))
    person = np.array([[5.0, 0.6, 0.0, 0.0, 0.3]])
    first = nav.step(0.0, START[:2], person)
    pose = first.at(0.25)
    detour = _detour(0.25, pose, slow=1.0)
    late = detour.t_end - first.t_end
    assert nav.options.personal_space_cost < late < nav._soft_costs()
    bare = Navigator(sc, rm, GOAL[:2], NavOptions(time_budget=5.0, path_space=0.0))
    again = bare.step(0.0, START[:2], person)
    monkeypatch.setattr(Navigator, "_search", lambda self, t, p, *a, **k: _Searched(_detour(t, p, slow=1.0)))
    nav.step(0.25, pose, person)
    assert nav.last.mode != NavMode.KEPT
    # without the path space its cost is not owed: the last plan is kept
    bare.step(0.25, again.at(0.25), person)
    assert bare.last.mode == NavMode.KEPT


def test_the_fan_stops_at_its_share_of_the_budget(open_floor):
    """Among walls the fan's static checks cost milliseconds a heading: it adds headings
    only until ``FAN_SHARE`` of the budget (the budget's clock), so the search keeps its
    time; with the clock already past that, the graph is the roadmap's alone."""
    from gfuzzy.navigation.navigator import FAN_SHARE, SEARCH_SHARE

    sc, rm = open_floor
    opts = NavOptions(time_budget=0.1)
    nav = Navigator(sc, rm, GOAL, opts)
    pose = np.array(START)
    full, _ = nav._splice(pose, 0.0)  # no deadline: every heading
    ticks = [0.0]

    def clock():  # one tick per look at the clock
        ticks[0] += 0.01
        return ticks[0]

    nav._clock = clock
    deadline = SEARCH_SHARE * opts.time_budget  # the step began at 0: the fan's share ends at 0.03
    some, _ = nav._splice(pose, 0.0, deadline)
    ticks[0] = 1.0
    none, _ = nav._splice(pose, 0.0, deadline)
    assert FAN_SHARE < SEARCH_SHARE
    assert len(none.poses) < len(some.poses) < len(full.poses)


@pytest.mark.parametrize("start, goal", [((11.06, 2.5), (11.35, 8.5)), ((2.0, 1.0), (8.0, 1.29))])
def test_a_run_within_the_goal_tolerance_ends_at_the_goal_by_a_turn_in_place(start, goal):
    """A goal whose heading is a hair off the lane into it (a pedestrian window's crossing,
    its heading rounded to 1e-4 rad): the run stops at the first pose within the goal
    tolerance (1e-6 in the metric, heading weighted by the circumradius), which was either
    overwritten by the goal's pose, a straight move that turned by 6e-7 rad, or left 2e-6
    rad short of the goal's heading: `gfuzzy check` refused both. The rest of the turn is
    now a row of its own, in place, and the run ends exactly at the goal."""
    from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap

    doc = {"version": 1, "name": "floor", "bounds": [0, 0, 16, 12],
           "robot": {"disc": 0.3, "vmax": 1.0, "kinematics": "unicycle", "wmax": 1.0}, "obstacles": [], "movers": []}  # fmt: skip
    scene = parse_scene(doc, "<floor>")
    rm = build_roadmap(scene, RoadmapOptions(vertices=150, seed=1))
    h = round(math.atan2(goal[1] - start[1], goal[0] - start[0]), 4)
    start, goal = np.array([*start, h]), np.array([*goal, h])
    run = simulate(scene, rm, start, goal, max_time=20.0)
    w = run.trajectory.waypoints
    assert run.status.value == "solved"
    assert _unicycle_problem(scene.robot, w) is None
    np.testing.assert_array_equal(w[-1, 1:], goal)


@pytest.mark.parametrize("robot", [
    {"footprint": [[0.3, 0.0], [0.22, 0.2], [-0.2, 0.2], [-0.2, -0.2], [0.22, -0.2]], "vmax": 1.0,
     "kinematics": "unicycle", "wmax": 1.5},
    {"box": [0.6, 0.45], "vmax": 1.0},
])  # fmt: skip
def test_the_evasive_scores_compute_exact_gaps_only_where_they_count(robot, monkeypatch):
    """A footprint's evasive motion among 60 people: exact polygon gaps over every
    candidate, sample and person cost 75-150 ms of CPU on students001 (over the budget on
    their own). Gaps whose circumscribed-disc bound is above both the evasion's gap cap and
    what a gap can lose between two samples score alike: the scores are the same with that
    bound there, for a fraction of the exact gaps."""
    import gfuzzy.navigation.navigator as navmod
    from gfuzzy.navigation.drivenav import look_times, sample_rows
    from gfuzzy.navigation.evasion import evasion_scores
    from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap
    from gfuzzy.timespace.drive import evasions

    doc = {"version": 1, "name": "square", "bounds": [0, 0, 16, 14], "robot": robot, "obstacles": [], "movers": []}
    scene = parse_scene(doc, "<square>")
    rm = build_roadmap(scene, RoadmapOptions(vertices=80, seed=1))
    nav = Navigator(scene, rm, (14.0, 12.0, 0.0))
    rng = np.random.default_rng(4)
    pose = np.array([8.0, 7.0, 0.3])
    obs = np.column_stack([rng.uniform(3, 13, (60, 2)), rng.uniform(-1.5, 1.5, (60, 2)), np.full(60, 0.25)])
    t, T = 0.0, nav.options.drive_lookahead
    times = t + look_times(nav.options.evasion_time, T)
    cands = evasions(nav.geometry, t, pose, T, nav.options.cover, nav.options.evasion_headings, nav.vplan, (1.0, 0.5), ())
    pts = sample_rows(cands, times)
    ends = np.array([rows[-1, 1:] for rows in cands])
    pairs = [0]
    exact_distance = navmod.mover_distance

    def counted(robot_, poses, *args, **kwargs):
        pairs[0] += int(np.prod(np.broadcast_shapes(np.shape(poses)[:-1], np.shape(args[3])[:-1])))
        return exact_distance(robot_, poses, *args, **kwargs)

    monkeypatch.setattr(navmod, "mover_distance", counted)
    got = evasion_scores(nav, t, pose, obs, pts, times, ends)
    some = pairs[0]
    real = nav._clearance_along
    nav._clearance_along = lambda p, tt, o, exact_below=math.inf: real(p, tt, o)  # every gap exact
    pairs[0] = 0
    want = evasion_scores(nav, t, pose, obs, pts, times, ends)
    np.testing.assert_array_equal(got, want)
    assert len(set(np.round(want, 6))) > 3  # the candidates do score differently
    assert 0 < some < pairs[0] / 4


def test_a_turn_under_way_below_committed_turn_commits_to_nothing(open_floor):
    """Heading 1 rad left of the goal's direction, the best evasion turns right, towards
    the goal. An evasion under way that turns left by 5e-4 rad (under ``COMMITTED_TURN``:
    a rounding, not a turn) leaves the choice as without one; by 2e-3 rad it commits, and
    turning right loses ``EVASION_COMMITMENT``: the robot drives straight on instead."""
    from gfuzzy.navigation.drivenav import COMMITTED_TURN, _first_turn

    sc, rm = open_floor
    nav = Navigator(sc, rm, GOAL, NavOptions())
    pose = np.array([5.0, 3.0, 1.0])
    people = np.array([[5.0, 5.5, 0.0, 0.0, 0.3]])

    def under_way(turn):
        rows = [[0.0, *pose], [abs(turn) + 0.01, 5.0, 3.0, 1.0 + turn], [3.0, 5.0, 3.0, 1.0 + turn]]
        return Trajectory(np.array(rows), 0.3)

    free = drive_evasion(nav, 0.0, pose, people, None).waypoints
    assert _first_turn(free) < 0.0  # right, towards the goal
    assert 5e-4 < COMMITTED_TURN < 2e-3
    np.testing.assert_array_equal(drive_evasion(nav, 0.0, pose, people, under_way(5e-4)).waypoints, free)
    committed = drive_evasion(nav, 0.0, pose, people, under_way(2e-3)).waypoints
    assert _first_turn(committed) >= 0.0


def test_the_navigator_forgets_its_evasion_at_the_goal(open_floor, monkeypatch):
    """An evasion turning left, then the goal reached: the next evasion (the robot off the
    goal again, on the old evasion's turn, nobody about) is the one a fresh navigator
    chooses, towards the goal. Kept past the goal, the old turn committed it to go on
    left: it drove straight on instead of turning right."""
    from gfuzzy.navigation.drivenav import _first_turn

    monkeypatch.setattr(Navigator, "_search", lambda self, t, p, *a, **k: _Searched(None, "exhausted"))
    monkeypatch.setattr(Navigator, "_direct", lambda self, *a: None)
    sc, rm = open_floor
    pose = np.array([5.0, 3.0, 1.0])
    person = np.array([[6.5485538795638885, 3.302379760030929, -0.5077890853650948, -0.2090487775658575, 0.3]])
    nav = Navigator(sc, rm, GOAL, NavOptions())
    first = nav.step(0.0, pose, person)
    assert nav.last.mode == NavMode.EVASIVE and _first_turn(first.waypoints) > 0.0
    nav.step(0.1, np.array(GOAL), np.zeros((0, 5)))
    assert nav.last.mode == NavMode.GOAL
    there = first.at(0.25)
    again = nav.step(0.25, there, np.zeros((0, 5)))
    fresh = Navigator(sc, rm, GOAL, NavOptions())
    want = fresh.step(0.25, there, np.zeros((0, 5)))
    assert nav.last.mode == fresh.last.mode == NavMode.EVASIVE
    np.testing.assert_array_equal(again.waypoints, want.waypoints)
    assert _first_turn(want.waypoints) < 0.0


def test_the_evasions_gaps_are_the_centres_distance_less_both_radii_and_the_margins(open_floor):
    """``Navigator._clearance_along`` computes the evasions' (C, T, k) gaps in place (most of
    the evasion's CPU among 20 people): for a disc they must be (to 1e-12) the distance of
    the centres, less the two radii, the mover clearance and the growth of a person of unknown
    velocity, the people walking on at constant velocity; a 2-D batch of poses as well."""
    sc, rm = open_floor
    nav = Navigator(sc, rm, GOAL)
    rng = np.random.default_rng(7)
    obs = np.column_stack([rng.uniform(0, 10, (9, 2)), rng.uniform(-1.2, 1.2, (9, 2)), rng.uniform(0.2, 0.35, 9)])
    obs[2, 2:4] = 0.0  # standing where someone of unknown velocity was seen: a disc that grows
    nav._unknown = obs[2:3, :2].copy()
    times = 3.0 + np.linspace(0.0, 4.0, 41)
    pts = np.concatenate([rng.uniform(0, 10, (5, 41, 2)), rng.uniform(-3, 3, (5, 41, 1))], axis=2)  # (C, T, 3)
    got = nav._clearance_along(pts, times, obs)
    tau = times - times[0]
    for c in range(len(pts)):
        for i, person in enumerate(obs):
            at = person[:2] + tau[:, None] * person[2:4]
            grow = np.minimum(tau * 1.0, 1.0) if i == 2 else 0.0  # sensing.UNKNOWN_GROWTH, UNKNOWN_CAP
            want = np.hypot(at[:, 0] - pts[c, :, 0], at[:, 1] - pts[c, :, 1]) - 0.3 - person[4] - (nav.mover_clearance + grow)
            np.testing.assert_allclose(got[c, :, i], want, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(nav._clearance_along(pts[0], times, obs), got[0])
    assert got.shape == (5, 41, 9)
    nav._unknown = np.zeros((0, 2))  # the growth is there: the gaps to the standing person differ by it
    np.testing.assert_allclose(nav._clearance_along(pts, times, obs)[:, :, 2] - got[:, :, 2], np.broadcast_to(np.minimum(tau, 1.0), (5, 41)),
                               rtol=0, atol=1e-12)


def test_a_plan_among_nobody_near_skips_the_dijkstra_from_the_pose(open_floor, monkeypatch):
    """The exact safety windows (a Dijkstra from the pose over the whole graph, 24 ms of CPU
    a call on a house map) pay only for safety work: nobody seen, or nobody who can come
    near, none; someone near, the Dijkstra, and the answers are those of the exact windows."""
    from gfuzzy.timespace import graph_kernel, unicycle

    sc, rm = open_floor
    nav = Navigator(sc, rm, GOAL, NavOptions(time_budget=5.0))  # the goal's own Dijkstras first
    exact = Navigator(sc, rm, GOAL, NavOptions(time_budget=5.0))
    calls = []
    real = graph_kernel.fewest_steps  # the pose's Dijkstra (unipaths.steps_from_start)

    def spy(indptr, indices, steps, source):
        calls.append(source)
        return real(indptr, indices, steps, source)

    monkeypatch.setattr(graph_kernel, "fewest_steps", spy)
    far = np.array([[9.5, 0.5, 1.0, 0.0, 0.2]])  # seen, walking away out of reach
    near = np.array([[5.0, 3.0, 0.0, 0.0, 0.3]])  # standing on the straight line
    answers = [nav.step(0.0, START, np.zeros((0, 5))), nav.step(0.25, START, far)]
    assert nav.last.mode == NavMode.PLAN and nav.last.detailed == 0 and calls == []
    answers.append(nav.step(0.5, START, near))
    assert nav.last.detailed == 1 and len(calls) == 1
    splice = unicycle.UnicycleGoal.splice
    monkeypatch.setattr(unicycle.UnicycleGoal, "splice", lambda self, planner, start, exact=True, **k:
                        splice(self, planner, start, True, **k))  # fmt: skip
    for got, (t, obs) in zip(answers, [(0.0, np.zeros((0, 5))), (0.25, far), (0.5, near)], strict=True):
        np.testing.assert_array_equal(got.waypoints, exact.step(t, START, obs).waypoints)


@pytest.fixture(scope="module")
def walled_floor():
    """The open floor with a wall from the bottom up to 1.5 m below the top, between the
    start and the goal: the goal lies straight behind it."""
    from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap

    doc = {
        "version": 1, "name": "walled-floor", "bounds": [0, 0, 10, 6],
        "robot": {"disc": 0.3, "vmax": 1.0, "kinematics": "unicycle", "wmax": 1.0},
        "obstacles": [{"box": {"center": [5.0, 2.25], "size": [0.4, 4.5], "angle": 0.0}}],
        "movers": [], "queries": [],
    }  # fmt: skip
    sc = parse_scene(doc, "<walled-floor>")
    return sc, build_roadmap(sc, RoadmapOptions(vertices=150, seed=3))


def _out_of_time(self, t, pose, *a, **k):
    """A search that never has the time: the graph spliced, no plan."""
    graph, s_id = self._splice(pose, t)
    return _Searched(None, "time budget spent before the search", 0, True, graph, s_id)


def test_a_drive_out_of_time_with_nobody_near_goes_on_along_its_route(walled_floor, monkeypatch):
    """No plan ever in time and nobody about: the differential drive follows its static route
    round the wall and arrives (mode route), every answer driven and checked. The evasive
    motion, ranking its candidates by straight-line progress alone, drove up to the wall and
    stood there for ever (a newcomer's box on a house map: still standing at t = 150 s)."""
    monkeypatch.setattr(Navigator, "_search", _out_of_time)
    sc, rm = walled_floor
    start, goal = [2.0, 1.0, 0.0], [8.0, 1.0, 0.0]
    res = simulate(sc, rm, start, goal, 0.0, 0.25, max_time=40.0)
    assert res.reached, res.modes
    assert "evasive" not in res.modes and res.modes["route"] > 10  # (direct and kept: the last metres)
    assert check_trajectory(sc, res.trajectory.waypoints).valid


def test_someone_near_leaves_a_drive_out_of_time_to_the_evasive_motion(walled_floor, monkeypatch):
    """The route is not checked against people: someone who can come near within the
    look-ahead leaves the answer to the evasive motion, which scores them."""
    monkeypatch.setattr(Navigator, "_search", _out_of_time)
    sc, rm = walled_floor
    nav = Navigator(sc, rm, [8.0, 1.0, 0.0], NavOptions())
    quiet = nav.step(0.0, [2.0, 1.0, 0.0], np.array([[9.5, 5.5, 0.0, 0.0, 0.3]]))  # far, standing
    assert nav.last.mode == NavMode.ROUTE and quiet.t_end > 8.0
    nav.step(0.25, quiet.at(0.25), np.array([[3.5, 1.0, -1.0, 0.0, 0.3]]))  # walking at it
    assert nav.last.mode == NavMode.EVASIVE
