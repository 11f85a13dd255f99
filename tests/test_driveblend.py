"""gfuzzy.planner.driveblend: a differential drive's speed layer on the legs where it fits.

The scene: a disc drive turns a quarter in place, drives 4 m east and turns back. A gate (a
mover) appears on its way at x = 3 at time T and stays. Driven wholly under the speed layer
(from rest to rest, amax 1) the robot is too late for T = 4.4; at the search's pace on the
straight it passes. The oracle reads only the rows and the test's own description of the
path (which rows belong to which leg): no code of the planner or the profile.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np
import pytest

from gfuzzy.check.check import check_trajectory
from gfuzzy.collision.geometry import StaticGeometry
from gfuzzy.planner.driveblend import _blend_of, _prune, blend_chain, retime_blend, retime_legs
from gfuzzy.planner.driveretime import drive_chain, retime_drive
from gfuzzy.planner.planner import PlanOptions
from gfuzzy.planner.stages import StageContext, apply_stages
from gfuzzy.scene.scene import Query, parse_scene
from gfuzzy.status import Status
from gfuzzy.trajectory import Trajectory

VMAX, AMAX, R = 1.0, 1.0, 0.2
WMAX = VMAX / R  # the default turning rate
PATH = np.array([[0.5, 0.5, math.pi / 2], [0.5, 0.5, 0.0], [4.5, 0.5, 0.0], [4.5, 0.5, math.pi / 2]])


def gate_scene(t_gate: float):
    doc = {
        "version": 1,
        "name": "gate",
        "bounds": [0, 0, 5, 2],
        "robot": {"disc": R, "vmax": VMAX, "amax": AMAX, "kinematics": "unicycle"},
        "movers": [{"name": "gate", "disc": 0.25, "trajectory": [[t_gate, 3.0, 0.5], [1000.0, 3.0, 0.5]]}],
        "queries": [{"name": "q", "start": PATH[0].tolist(), "goal": PATH[-1].tolist()}],
    }
    return parse_scene(doc)


def _wrap(a):
    return (np.asarray(a) + math.pi) % (2 * math.pi) - math.pi


def leg_oracle(rows: np.ndarray, layered: tuple[bool, bool, bool]) -> list[str]:
    """Problems of the rows on PATH: the row rule everywhere; on a layered turn the turning
    rate and angular acceleration bounds with rest at both ends; on a layered straight the
    linear ones; on any leg the speed bounds."""
    bad = []
    t, x, y, h = rows.T
    dt = np.diff(t)
    dx, dy, dh = np.diff(x), np.diff(y), _wrap(np.diff(h))
    moving = np.hypot(dx, dy) > 1e-12
    turning = np.abs(dh) > 1e-12
    if np.any(moving & turning):
        bad.append("turns while moving")
    if np.any(np.abs(dy) > 1e-12) or np.any(dx < -1e-12):
        bad.append("leaves the eastward straight")
    v, w = dx / dt, dh / dt
    if v.max() > VMAX * (1 + 1e-9) or np.abs(w).max() > WMAX * (1 + 1e-9):
        bad.append("speed bound")
    # the leg of each row pair: 0 before the straight, 1 on it, 2 after it
    leg = np.where((x[:-1] > 0.5 + 1e-12) | moving, 1, 0)
    leg = np.where(x[:-1] >= 4.5 - 1e-12, 2, leg)
    bound = (AMAX / R, AMAX, AMAX / R)
    for g in range(3):
        if not layered[g]:
            continue
        idx = np.flatnonzero((leg == g) & (moving | turning))
        if idx.size == 0:
            bad.append(f"leg {g} has no motion")
            continue
        rate = w if g != 1 else v
        seq = rate[idx]
        mids = 0.5 * (dt[idx][1:] + dt[idx][:-1])
        if np.any(np.abs(np.diff(seq)) > bound[g] * mids * (1 + 1e-6)):
            bad.append(f"leg {g}: acceleration above its bound")
        for k in (idx[0], idx[-1]):  # starts and ends at rest: the first and last pair cover at most a dt^2 / 2
            if abs(rate[k]) > bound[g] * dt[k] / 2 * (1 + 1e-6):
                bad.append(f"leg {g}: does not start or end at rest")
    return bad


def assert_minimal_blend(scene, path, b, hold=0.0, max_rounds=5):
    """A partial answer's properties: it checks; the layered legs keep their bounds (on
    PATH); some leg is layered and some hasty; each hasty leg is needed (given the layer
    back alone, the chain has no timing)."""
    assert b.status is Status.SOLVED, b.message
    assert b.hasty.any() and not b.hasty.all(), b.hasty
    q = replace(scene.queries[0], hold=hold)
    rep = check_trajectory(scene, b.trajectory.waypoints, q)
    assert rep.valid, rep.reason
    if path is PATH:
        assert leg_oracle(b.trajectory.waypoints, tuple(~b.hasty)) == []
    assert b.hasty_length == pytest.approx(float(np.sum(np.diff(b.legs)[b.hasty])))
    for g in np.flatnonzero(b.hasty):
        trial = b.hasty.copy()
        trial[g] = False
        r = retime_legs(scene, path, trial, 0.0, 0.07, AMAX, 60.0, hold=hold, max_rounds=max_rounds)
        assert r.status is not Status.SOLVED, f"leg {g} could keep the layer"


def test_the_layer_alone_is_too_late_and_the_blend_gives_haste_to_the_straight():
    scene = gate_scene(4.4)
    assert retime_drive(scene, PATH, 0.0, 0.07, AMAX, 60.0).status is Status.NO_PATH
    b = retime_blend(scene, PATH, 0.0, 0.07, AMAX, 60.0)
    assert b.status is Status.SOLVED, b.message
    assert_minimal_blend(scene, PATH, b)
    rows = b.trajectory.waypoints
    # the hasty legs really are hasty: the layered bounds on every leg would fail them
    assert leg_oracle(rows, (True, True, True)) != []
    # the robot is past the gate (x = 3, discs 0.25 + 0.2) when it appears
    assert np.interp(4.4, rows[:, 0], rows[:, 1]) >= 3.45


def test_without_a_blocking_mover_the_blend_is_the_layer_on_the_whole_path():
    scene = gate_scene(6.0)
    whole = retime_drive(scene, PATH, 0.0, 0.07, AMAX, 60.0)
    b = retime_blend(scene, PATH, 0.0, 0.07, AMAX, 60.0)
    assert b.status is Status.SOLVED and not b.hasty.any() and b.hasty_length == 0.0
    np.testing.assert_array_equal(b.trajectory.waypoints, whole.trajectory.waypoints)
    assert leg_oracle(b.trajectory.waypoints, (True, True, True)) == []


def test_a_gate_too_early_even_for_haste_is_no_path():
    b = retime_blend(gate_scene(2.0), PATH, 0.0, 0.07, AMAX, 30.0)
    assert b.status is Status.NO_PATH and b.trajectory is None
    assert "search's pace" in b.message


def test_haste_on_every_leg_is_not_a_layer():
    # one straight, no turn: at full speed from the start the robot passes x = 3.45 at
    # 2.95 s, under the layer (1 m/s reached after 0.5 m) at 3.45 s
    straight = np.array([[0.5, 0.5, 0.0], [4.5, 0.5, 0.0]])
    b = retime_blend(gate_scene(3.3), straight, 0.0, 0.07, AMAX, 30.0)
    assert b.status is Status.NO_PATH and b.hasty.all(), b.message
    assert "only the search's pace" in b.message
    late = retime_blend(gate_scene(2.5), straight, 0.0, 0.07, AMAX, 30.0)
    assert late.status is Status.NO_PATH and "not even the search's pace" in late.message
    assert retime_blend(gate_scene(3.8), straight, 0.0, 0.07, AMAX, 30.0).status is Status.SOLVED


def test_when_the_first_turn_must_be_hasty_the_blend_gives_it_haste():
    scene = gate_scene(3.8)
    # no timing keeps the layer on the first turn, even with haste on every other leg
    assert retime_legs(scene, PATH, [False, True, True], 0.0, 0.07, AMAX, 60.0).status is not Status.SOLVED
    b = retime_blend(scene, PATH, 0.0, 0.07, AMAX, 60.0)
    assert_minimal_blend(scene, PATH, b)
    assert b.hasty[0]


def test_a_hold_at_the_goal_does_not_block_the_rests_on_the_way():
    # a mover sits on the start during [3, 4] s and the query holds the goal 5 s: a rest
    # on the way is only passed, it need not stay safe for the hold
    scene = parse_scene(
        {
            "version": 1,
            "name": "gate-hold",
            "bounds": [0, 0, 5, 2],
            "robot": {"disc": R, "vmax": VMAX, "amax": AMAX, "kinematics": "unicycle"},
            "movers": [
                {"name": "gate", "disc": 0.25, "trajectory": [[3.8, 3.0, 0.5], [1000.0, 3.0, 0.5]]},
                {"name": "sitter", "disc": 0.25, "trajectory": [[3.0, 0.5, 0.5], [4.0, 0.5, 0.5]]},
            ],
            "queries": [{"name": "q", "start": PATH[0].tolist(), "goal": PATH[-1].tolist(), "hold": 5.0}],
        }
    )
    b = retime_blend(scene, PATH, 0.0, 0.07, AMAX, 60.0, hold=5.0)
    assert_minimal_blend(scene, PATH, b, hold=5.0)


def test_the_prune_gives_the_layer_back_to_a_leg_the_greedy_choice_made_hasty():
    scene = gate_scene(4.0)
    blend = _blend_of(scene, PATH, 0.0, 0.07, AMAX, 60.0, None, math.inf, 0.0)
    every = np.ones(3, dtype=bool)
    res, stops = blend.rounds(every, 5)
    assert res.status is Status.SOLVED
    res, stops, hasty = _prune(blend, every, res, stops, 5)
    assert res.status is Status.SOLVED and 0 < hasty.sum() < 3, hasty
    assert check_trajectory(scene, res.trajectory.waypoints, scene.queries[0]).valid
    assert_minimal_blend(scene, PATH, retime_blend(scene, PATH, 0.0, 0.07, AMAX, 60.0))


def crossing_scene():
    """A mover bouncing across the straight at x = 2.5: the layer waits for it mid-straight."""
    doc = {
        "version": 1,
        "name": "crossing",
        "bounds": [0, 0, 5, 3],
        "robot": {"disc": R, "vmax": VMAX, "amax": AMAX, "kinematics": "unicycle"},
        "movers": [{"name": "m", "disc": 0.25, "speed": 0.5, "path": [[2.5, 2.9], [2.5, 0.1]], "mode": "bounce"}],
        "queries": [{"name": "q", "start": PATH[0].tolist(), "goal": PATH[-1].tolist()}],
    }
    return parse_scene(doc)


def test_reachable_rests_but_too_few_rounds_give_haste_where_the_free_search_waits():
    scene = crossing_scene()
    whole = retime_blend(scene, PATH, 0.0, 0.07, AMAX, 60.0)
    assert whole.status is Status.SOLVED and not whole.hasty.any() and whole.waits
    # one round cannot add the stops the mover needs: every rest is reachable (waits
    # anywhere), so the leg where the free search waits mid-leg gets haste
    b = retime_blend(scene, PATH, 0.0, 0.07, AMAX, 60.0, max_rounds=1)
    assert_minimal_blend(scene, PATH, b, max_rounds=1)


def test_the_layer_and_the_blend_share_one_chain_and_one_timing():
    scene = crossing_scene()
    drive = retime_drive(scene, PATH, 0.0, 0.07, AMAX, 60.0)
    legs = retime_legs(scene, PATH, [False, False, False], 0.0, 0.07, AMAX, 60.0)
    blend = retime_blend(scene, PATH, 0.0, 0.07, AMAX, 60.0)
    assert drive.status is Status.SOLVED and drive.waits
    np.testing.assert_array_equal(drive.trajectory.waypoints, legs.trajectory.waypoints)
    np.testing.assert_array_equal(drive.trajectory.waypoints, blend.trajectory.waypoints)
    assert tuple(drive.waits) == blend.waits
    knots = np.array([0.0, 1.0, 2.0])
    path = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    s_p, v_p = np.array([0.0, 0.5, 1.0, 1.5, 2.0]), np.array([0.0, 0.7, 0.0, 0.7, 0.0])
    rests = np.array([0.0, 1.0, 2.0])
    a = drive_chain(path, knots, s_p, v_p, rests, 0.07)
    b = blend_chain(path, knots, s_p, v_p, rests, np.zeros(2), 0.07)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)


def test_the_stage_keeps_the_blends_reason_when_no_blend_solves():
    straight = np.array([[0.5, 0.5, 0.0], [4.5, 0.5, 0.0]])
    scene = gate_scene(3.3)
    ctx = StageContext(scene, StaticGeometry(scene))
    searched = Trajectory(np.column_stack([[0.0, 4.0 / VMAX], straight]), R)
    q = Query("q", tuple(straight[0]), tuple(straight[-1]), 0.0)
    assert check_trajectory(scene, searched.waypoints, q).valid
    out = apply_stages(ctx, searched, q, PlanOptions(speed_layer=True), time.perf_counter() + 60)
    rep = out.speed_report
    assert not rep.applied and "only the search's pace" in rep.reason, rep.reason
    assert out.trajectory is searched or np.array_equal(out.trajectory.waypoints, searched.waypoints)


def test_a_deadline_passed_is_a_timeout_in_the_blend_and_the_stage():
    scene = gate_scene(4.4)
    assert retime_blend(scene, PATH, 0.0, 0.07, AMAX, 60.0, deadline=time.perf_counter() - 1).status is Status.TIMEOUT
    ctx = StageContext(scene, StaticGeometry(scene))
    times = np.cumsum([0.0, (math.pi / 2) / WMAX, 4.0 / VMAX, (math.pi / 2) / WMAX])
    searched = Trajectory(np.column_stack([times, PATH]), R)
    q = Query("q", tuple(PATH[0]), tuple(PATH[-1]), 0.0)
    out = apply_stages(ctx, searched, q, PlanOptions(speed_layer=True), time.perf_counter() - 1)
    assert not out.speed_report.applied and "time limit passed" in out.speed_report.reason


def test_the_stage_reports_the_hasty_legs():
    scene = gate_scene(4.4)
    ctx = StageContext(scene, StaticGeometry(scene))
    # the search's kind of answer: full turning rate, full speed
    times = np.cumsum([0.0, (math.pi / 2) / WMAX, 4.0 / VMAX, (math.pi / 2) / WMAX])
    searched = Trajectory(np.column_stack([times, PATH]), R)
    q = Query("q", tuple(PATH[0]), tuple(PATH[-1]), 0.0)
    assert check_trajectory(scene, searched.waypoints, q).valid
    out = apply_stages(ctx, searched, q, PlanOptions(speed_layer=True), time.perf_counter() + 60)
    rep = out.speed_report
    assert rep.applied and not rep.whole
    info = rep.to_dict()["hasty"]
    assert (info["legs"], info["of"]) == (1, 3)
    assert info["length"] == pytest.approx(4.0) and info["total"] == pytest.approx(4.0 + 2 * R * math.pi / 2)
    rows = out.trajectory.waypoints
    assert check_trajectory(scene, rows, q).valid
    # the spans are the straight's: the robot leaves x = 0.5 at the first, reaches 4.5 at the second
    ((t_a, t_b),) = info["spans"]
    assert np.interp(t_a, rows[:, 0], rows[:, 1]) == pytest.approx(0.5)
    assert np.interp(t_a + 0.07, rows[:, 0], rows[:, 1]) > 0.5
    assert np.interp(t_b, rows[:, 0], rows[:, 1]) == pytest.approx(4.5)
    assert np.interp(t_b - 0.07, rows[:, 0], rows[:, 1]) < 4.5


@pytest.mark.slow
def test_gfuzzy_plan_applies_the_layer_in_part_on_the_building_floor(tmp_path, capsys):
    from conftest import ROOT
    from helpers import run_main

    scene = ROOT / "scenes" / "building-floor-unicycle.yaml"
    out = tmp_path / "bf.json"
    rc, stdout, err = run_main(capsys, "plan", scene, "--speed-layer", "-o", out)
    assert rc == 0 and "speed layer: applied in part" in stdout, stdout
    assert "not honoured on" in err
    rc, _, err = run_main(capsys, "check", scene, out)
    assert rc == 0, err
