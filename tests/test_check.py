"""The independent checker: every instant, touching allowed, overlap refused."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from gfuzzy.check.check import check_trajectory
from gfuzzy.scene.scene import parse_scene


def scene(robot, obstacles=(), movers=()):
    return parse_scene(
        {
            "version": 1,
            "name": "c",
            "bounds": [0, 0, 10, 4],
            "robot": robot,
            "obstacles": list(obstacles),
            "movers": list(movers),
        }
    )


WALL = {"box": {"center": [5, 3], "size": [8, 2]}}  # its lower face is y = 2


def slide(y, heading=None, t_end=8.0, n=17):
    t = np.linspace(0, t_end, n)
    x = 1.0 + t
    cols = [t, x, np.full(n, y)]
    if heading is not None:
        cols.append(np.full(n, heading))
    return np.column_stack(cols)


@pytest.mark.parametrize(
    "robot, y, heading",
    [({"disc": 0.5, "vmax": 1.0}, 1.5, None), ({"box": [0.8, 0.6], "vmax": 1.0}, 1.7, 0.0)],
)
def test_long_touching_contact_is_valid_and_decided_fast(robot, y, heading):
    sc = scene(robot, [WALL])
    rep = check_trajectory(sc, slide(y, heading))
    assert rep.valid, rep.reason
    assert rep.min_clearance == pytest.approx(0.0, abs=1e-9)
    assert rep.evaluations < 200_000


@pytest.mark.parametrize(
    "robot, y, heading",
    [({"disc": 0.5, "vmax": 1.0}, 1.5 + 1e-6, None), ({"box": [0.8, 0.6], "vmax": 1.0}, 1.7 + 1e-6, 0.0)],
)
def test_a_micrometre_of_overlap_is_a_collision(robot, y, heading):
    rep = check_trajectory(scene(robot, [WALL]), slide(y, heading))
    assert not rep.valid
    assert "static obstacle" in rep.reason


@pytest.mark.parametrize(
    "robot, rows, words",
    [
        ({"disc": 0.3, "vmax": 1.0, "kinematics": "unicycle"}, slide(1.0), "[t, x, y, heading] for this disc robot (unicycle)"),
        ({"disc": 0.3, "vmax": 1.0}, slide(1.0, 0.0), "[t, x, y] for this disc robot"),
        ({"box": [0.8, 0.6], "vmax": 1.0}, slide(1.0), "[t, x, y, heading] for this box robot"),
    ],
)
def test_rows_of_the_wrong_width_are_named_with_what_a_row_holds(robot, rows, words):
    """A disc unicycle's rows carry a heading: the reason used to say only `[t, x, y,
    heading] for this robot`, not which robot nor why."""
    rep = check_trajectory(scene(robot), rows)
    assert not rep.valid and rep.reason == f"waypoints must be rows of {words}"


def test_riding_alongside_a_mover_at_contact():
    mover = {"name": "m", "disc": 0.3, "speed": 1.0, "path": [[1.0, 2.5], [9.0, 2.5]], "mode": "once"}
    sc = scene({"disc": 0.2, "vmax": 1.0}, movers=[mover])
    ok = check_trajectory(sc, slide(2.0, t_end=8.0))  # centres 0.5 apart = 0.2 + 0.3
    assert ok.valid, ok.reason
    bad = check_trajectory(sc, slide(2.0 + 1e-6, t_end=8.0))
    assert not bad.valid and "mover 'm'" in bad.reason


def test_a_mover_crossing_between_two_rows_is_caught():
    # rows 4 s apart, the robot far from the mover at both; the mover crosses its path between
    mover = {"name": "fast", "disc": 0.2, "trajectory": [[0.0, 5.0, 0.3], [4.0, 5.0, 3.7]]}
    sc = scene({"disc": 0.2, "vmax": 1.0}, movers=[mover])
    w = np.array([[0.0, 3.0, 2.0], [4.0, 7.0, 2.0]])
    assert np.hypot(*(sc.movers[0].state(np.array([0.0, 4.0]))[0] - w[:, 1:]).T).min() > 1.5
    rep = check_trajectory(sc, w)
    assert not rep.valid and "fast" in rep.reason


def test_formal_faults():
    sc = scene({"disc": 0.2, "vmax": 1.0})
    assert "vmax" in check_trajectory(sc, np.array([[0, 1, 1], [1, 3, 1]])).reason
    assert "increase" in check_trajectory(sc, np.array([[0, 1, 1], [0, 1, 1]])).reason
    assert "rows of" in check_trajectory(sc, np.array([[0, 1, 1, 0]])).reason
    out = check_trajectory(sc, np.array([[0, 0.1, 1], [1, 0.5, 1]]))
    assert not out.valid and "bounds" in out.reason


def test_check_reports_the_first_collision_between_rows():
    sc = parse_scene(
        {
            "version": 1,
            "name": "two",
            "bounds": [0, 0, 10, 3],
            "robot": {"disc": 0.2, "vmax": 1.0},
            "obstacles": [
                {"disc": {"center": [3.0, 1.0], "radius": 0.1}},
                {"disc": {"center": [5.0, 1.0], "radius": 0.1}},
            ],
        }
    )
    # two rows only: the first evaluation between them (t = 4, x = 5) lands in the second disc
    wp = np.array([[0.0, 1.0, 1.0], [8.0, 9.0, 1.0]])
    rep = check_trajectory(sc, wp)
    assert not rep.valid
    assert "[3.0, 1.0]" in rep.reason, rep.reason
    # the robot (radius 0.2) touches the disc at x = 3 - 0.3 = 2.7, i.e. t = 1.7
    assert rep.time is not None and 1.69 <= rep.time <= 1.75, rep.time


def test_check_reports_the_first_collision_before_a_colliding_row():
    doc = {
        "version": 1,
        "name": "two",
        "bounds": [0, 0, 10, 3],
        "robot": {"disc": 0.2, "vmax": 1.0},
        "obstacles": [{"disc": {"center": [6.0, 1.0], "radius": 0.3}}],
        # down x = 2.5, through y = 1 at t = 1.5, where the robot is then
        "movers": [{"name": "early", "disc": 0.1, "speed": 1.0, "path": [[2.5, 2.9], [2.5, 0.1]],
                    "mode": "once", "offset": 0.4}],
    }
    # rows every second: the row at t = 5 (x = 6) sits in the static disc; the mover is
    # clear of the rows at t = 1 and t = 2 and hit between them
    t = np.arange(0.0, 9.0)
    wp = np.column_stack([t, 1.0 + t, np.full(t.size, 1.0)])
    alone = check_trajectory(parse_scene({**doc, "obstacles": []}), wp)
    assert not alone.valid and "early" in alone.reason  # the mover alone is hit
    rep = check_trajectory(parse_scene(doc), wp)
    assert not rep.valid
    assert "early" in rep.reason, rep.reason
    assert 1.0 < rep.time < 1.5


def _penetration(reason: str) -> tuple[float, float]:
    """(the deepest, the onset's) penetration of a collision's reason."""
    told = reason.split("(penetration ")[1]
    deepest = float(told.split(" ")[0])
    onset = float(told.split("; ")[1].split(" at the onset")[0]) if " at the onset" in told else deepest
    return deepest, onset


def test_a_collision_report_tells_how_deep_it_went():
    """The first contact in time is found at its onset, where the depth is tiny whenever
    the robot's motion is sampled finely; the penetration reported is the deepest overlap
    with what it hits (searched, not sampled), the onset's depth follows, so that a 20 cm
    collision does not read as a 0.1 mm graze."""
    sc = scene(
        {"disc": 0.25, "vmax": 1.0},
        movers=[{"name": "P", "disc": 0.25, "trajectory": [[0.0, 5.0, 2.3], [20.0, 5.0, 2.3]]}],
    )
    rep = check_trajectory(sc, slide(2.0, t_end=8.0, n=801))  # passes 0.3 from P's centre: 0.2 deep
    assert not rep.valid
    deepest, first = _penetration(rep.reason)
    assert first < 0.05 and abs(deepest - 0.2) < 1e-3, rep.reason
    shallow = check_trajectory(sc, slide(1.8, t_end=8.0, n=801))  # 0.5 from P's centre: touching
    assert shallow.valid, shallow.reason


@pytest.mark.parametrize(
    "robot, mover, depth",
    [
        # a footprint 0.4 x 0.4 about its centre, a person of radius 0.3 whose centre passes
        # 0.05 m from the robot's centre: 0.15 m inside its outline, 0.45 m deep
        ({"footprint": [[0.2, 0.2], [-0.2, 0.2], [-0.2, -0.2], [0.2, -0.2]], "vmax": 1.0},
         {"name": "P", "disc": 0.3, "trajectory": [[0.0, 6.0, 2.0], [20.0, 6.0, 2.0]]}, 0.45),
        # a disc robot of radius 0.25 whose centre passes 0.1 m inside a 1 x 0.8 cart (its
        # lower side at y = 1.85): 0.35 m deep
        ({"disc": 0.25, "vmax": 1.0},
         {"name": "P", "box": [1.0, 0.8], "trajectory": [[0.0, 6.0, 2.25], [20.0, 6.0, 2.25]]}, 0.35),
    ],
)
def test_an_overlap_with_a_centre_inside_is_reported_in_metres(robot, mover, depth):
    """A disc's centre inside the other body (a person inside a footprint, a disc robot's
    centre inside a cart): the deepest overlap is the distance to the outline plus the
    radius, the depth in metres (it read 1.3 for a person of radius 0.3, a sentinel)."""
    sc = scene(robot, movers=[mover])
    heading = 0.0 if "footprint" in robot else None
    rep = check_trajectory(sc, slide(1.95, heading, t_end=8.0, n=801))
    assert not rep.valid and rep.reason.startswith("collides with mover 'P'"), rep.reason
    deepest, _ = _penetration(rep.reason)
    assert abs(deepest - depth) < 0.01, rep.reason


def test_the_deepest_overlap_is_the_bodies_own_with_a_mover_clearance():
    """With ``mover_clearance`` > 0 the deepest overlap reported is how far the bodies
    overlap (not that plus the required distance), against the object it is with."""
    # P appears at t = 3, 0.45 from the robot's centre (0.05 deep); the robot then passes
    # 0.3 from P's centre: 0.25 + 0.25 - 0.3 = 0.2 deep (the old report said 0.5)
    px = 4.0 + math.sqrt(0.45**2 - 0.3**2)
    sc = scene(
        {"disc": 0.25, "vmax": 1.0, "mover_clearance": 0.3},
        movers=[{"name": "P", "disc": 0.25, "trajectory": [[3.0, px, 2.3], [20.0, px, 2.3]]}],
    )
    w = slide(2.0, t_end=8.0, n=801)
    rep = check_trajectory(sc, w)
    assert not rep.valid and rep.reason.startswith("collides with mover 'P'"), rep.reason
    # the oracle: the discs' centre distance at every row from t = 3 on
    live = w[:, 0] >= 3.0
    depth = 0.5 - np.hypot(w[live, 1] - px, w[live, 2] - 2.3).min()
    deepest, first = _penetration(rep.reason)
    assert abs(first - 0.05) < 1e-3, rep.reason
    assert abs(deepest - depth) < 1e-3 and abs(depth - 0.2) < 1e-3, rep.reason


def test_a_collisions_times_are_said_to_bracket_its_onset():
    # "collides with mover 'P' between t=0.5 and t=0.50098" read as the collision's span;
    # it is the interval where the contact starts (the robot overlaps P until t=0.75 and on)
    scene = parse_scene(
        {"version": 1, "name": "t", "bounds": [0, 0, 10, 4], "robot": {"disc": 0.2, "vmax": 5.0},
         "obstacles": [{"box": {"center": [5, 2], "size": [0.4, 0.4]}}],
         "movers": [{"name": "P", "disc": 0.3, "speed": 1e-4, "path": [[2, 1], [2, 1.0001]], "mode": "once"}]}
    )  # fmt: skip
    for y, what in ((1.0, "mover 'P'"), (2.0, "a static obstacle")):
        rep = check_trajectory(scene, np.array([[0.0, 0.5, y], [4.0, 8.5, y]]))
        assert not rep.valid and rep.reason.startswith(f"collides with {what} starting between t="), rep.reason
        start, end = (float(v) for v in re.findall(r"t=([0-9.e+-]+) and t=([0-9.e+-]+)", rep.reason)[0])
        assert start <= rep.time <= end < start + 0.01, rep.reason


LOOPER = {"name": "loop", "disc": 0.3, "speed": 0.6, "path": [[1.0, 1.0], [3.0, 1.0], [3.0, 3.0]], "mode": "loop"}
WALKER = {"name": "walk", "box": [0.4, 0.4], "trajectory": [[0.0, 9.0, 0.5], [5.0, 9.0, 3.5], [6.0, 8.0, 3.5]]}


@pytest.mark.parametrize("last", [1e4, 1e300])
def test_a_long_wait_far_from_every_movers_reach_is_decided_by_counting_rows(last):
    # rendering a plan whose last row was edited to t = 1e300 spent ~21 s in its check: the
    # bisection halved the last interval (movers' speed times 1e300) until the evaluations ran
    # out, then said "could not decide"; no mover's path comes near the robot's last stretch
    sc = scene({"disc": 0.2, "vmax": 1.0}, movers=[LOOPER, WALKER])
    w = np.array([[0.0, 5.0, 3.0], [1.0, 6.0, 3.0], [last, 6.5, 2.0]])
    rep = check_trajectory(sc, w, max_evaluations=100_000)
    assert rep.valid, rep.reason
    assert rep.evaluations == 4  # the rows and the instant the walker vanishes, nothing more


def test_a_long_crawl_beside_a_parked_mover_is_decided_once_it_stands_still():
    # a `once` mover runs along y = 0.5 until t = 4, then stands at (6, 0.5) for ever, 0.1 m
    # from the robot's crawl: within its reach, but the clearance no longer moves with it
    parker = {"name": "park", "disc": 0.3, "speed": 1.0, "path": [[2.0, 0.5], [6.0, 0.5]], "mode": "once"}
    sc = scene({"disc": 0.2, "vmax": 1.0}, movers=[parker])
    w = np.array([[0.0, 6.0, 1.1], [10.0, 6.0, 1.1], [1e300, 7.0, 1.1]])
    rep = check_trajectory(sc, w, max_evaluations=100_000)
    assert rep.valid, rep.reason
    assert rep.evaluations < 1_000  # the wait while it runs; nothing after


@pytest.mark.parametrize("x, valid", [(8.55, True), (8.65, False)])
def test_a_long_wait_beside_a_repeating_mover_is_decided_over_one_period(x, valid):
    # a box bounces along x = 9 (a period of 6 s) past a robot standing still for 1e300 s,
    # 0.05 m from it (or 0.05 m into it): the clearance repeats, so one period decides; it was
    # bisected until the evaluations ran out ("could not decide")
    bouncer = {"name": "b", "box": [0.4, 0.4], "speed": 1.0, "path": [[9.0, 0.5], [9.0, 3.5]], "mode": "bounce"}
    sc = scene({"disc": 0.2, "vmax": 1.0}, movers=[bouncer])
    rep = check_trajectory(sc, np.array([[0.0, x, 2.0], [1e300, x, 2.0]]), max_evaluations=100_000)
    assert rep.valid == valid, rep.reason
    assert valid or "collides with mover 'b' starting between t=1.16" in rep.reason
    assert rep.evaluations < 5_000


def test_a_long_wait_within_a_movers_reach_is_still_bisected():
    # the walker's box passes 0.05 m from the disc waiting at (8.55, 2), closer than its
    # extent (the box's half-diagonal) allows the reach bound to prove
    sc = scene({"disc": 0.2, "vmax": 1.0}, movers=[WALKER])
    rep = check_trajectory(sc, np.array([[0.0, 8.55, 2.0], [100.0, 8.55, 2.0]]))
    assert rep.valid, rep.reason
    assert rep.evaluations > 3
    # closer, it hits: the reach bound never hides a collision
    bad = check_trajectory(sc, np.array([[0.0, 8.65, 2.0], [100.0, 8.65, 2.0]]))
    assert not bad.valid and "walk" in bad.reason


def test_a_trajectory_movers_reach_is_its_rows_between_the_intervals_ends():
    from gfuzzy.check.reach import _rows_distance

    tr = scene({"disc": 0.2, "vmax": 1.0}, movers=[WALKER]).movers[0].trajectory
    rng = np.random.default_rng(3)
    points = rng.uniform([0, 0], [10, 4], (200, 2))
    ta = rng.uniform(-2, 7, 200)
    tb = ta + rng.choice([0.0, 0.3, 2.0, 9.0], 200)
    got = _rows_distance(tr, points, ta, tb)
    for p, a, b, d in zip(points, ta, tb, got, strict=True):
        times = np.linspace(max(a, 0.0), min(b, 6.0), 20001)
        if len(times) == 0 or times[0] > times[-1]:
            assert d == math.inf
            continue
        xy = np.column_stack([np.interp(times, tr[:, 0], tr[:, 1]), np.interp(times, tr[:, 0], tr[:, 2])])
        assert d == pytest.approx(np.hypot(*(xy - p).T).min(), abs=1e-3)


BOUNCER = {"name": "B", "box": [0.4, 0.4], "speed": 0.5, "path": [[1.0, 2.5], [4.0, 2.5]], "mode": "bounce"}


def test_one_period_end_stops_where_the_float_spacing_exceeds_the_period():
    from gfuzzy.check.reach import one_period_end

    # at t = 1e20 the floats are 16384 s apart: halving towards a 11.3 s period reached
    # a + spacing, whose midpoint rounds back to it, and looped for ever (no evaluation counted)
    a = np.array([1.0000000000000002e20, 1e20, 0.0, 5.0, 0.0])
    b = np.array([1.5e307, 1.5e307, 1e300, 7.0, np.inf])
    got = one_period_end(a, b, np.array([11.3, 11.3, 12.0, 0.0, 12.0]))
    assert got[:2].tolist() == b[:2].tolist()  # no point of the bisection leaves a period: not cut
    assert 12.0 <= got[2] < 24.0 and got[3] == 7.0 and got[4] == np.inf


def test_a_wait_at_a_huge_time_beside_a_repeating_mover_ends():
    # a robot 0.03 m clear of a bouncing box from t = 1e20 to 1e21: `gfuzzy check` never
    # returned (the period's end above); now it ends as before the period cut did
    sc = scene({"disc": 0.2, "vmax": 1.0}, movers=[BOUNCER])
    w = np.array([[1.0000000000000002e20, 2.5, 2.93], [1e21, 2.5, 2.93]])
    rep = check_trajectory(sc, w, max_evaluations=20_000)
    assert not rep.valid and rep.reason.startswith("could not decide")


@pytest.mark.parametrize("start", [1e15, 1e16])
def test_an_interval_as_short_as_the_float_spacing_is_undecided_at_once(start):
    # floats 0.125-2 s apart: one period's bisection reaches two adjacent floats, which it
    # cannot split; it went on one evaluation a round (20 000 in 1.2 s, 5 million for ever)
    sc = scene({"disc": 0.2, "vmax": 1.0}, movers=[BOUNCER])
    rep = check_trajectory(sc, np.array([[start, 2.5, 2.93], [1e21, 2.5, 2.93]]), max_evaluations=20_000)
    assert rep.reason == "could not decide: an interval as short as the float spacing (near-grazing contact)"
    assert rep.evaluations < 1_000
    # earlier, the same wait is decided over one period
    assert check_trajectory(sc, np.array([[1e10, 2.5, 2.93], [1e21, 2.5, 2.93]])).valid


REACH_WITNESSES = json.loads((Path(__file__).parent / "reach_witnesses.json").read_text())


@pytest.mark.parametrize("edit", sorted(REACH_WITNESSES))
def test_the_reach_bound_never_hides_these_contacts(edit):
    # randomized cases (a review's, 2026-11-28) each of which an unsound one-line edit of the
    # reach bound (keyed by the review's name for it) made valid while all the other tests
    # passed: the robot's mover_clearance or its own motion left out of its reach (M3, M4), a
    # loop's closing segment (M5), a once mover's offset (M7), the shortest period kept (M8),
    # the cut to one period where the robot moves (M9), half a period (M10), the last near
    # mover's speed, not the fastest (M16)
    w = REACH_WITNESSES[edit]
    rep = check_trajectory(parse_scene(w["scene"]), np.array(w["waypoints"]), deepest=False)
    assert not rep.valid
    assert rep.reason.split(" (")[0] == w["check_says"].split(" (")[0]
    assert rep.evaluations < 20_000
