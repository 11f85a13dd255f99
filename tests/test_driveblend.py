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

import numpy as np
import pytest

from gfuzzy.check.check import check_trajectory
from gfuzzy.collision.geometry import StaticGeometry
from gfuzzy.planner.driveblend import retime_blend
from gfuzzy.planner.driveretime import retime_drive
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


def test_the_layer_alone_is_too_late_and_the_blend_gives_haste_to_the_straight():
    scene = gate_scene(4.4)
    assert retime_drive(scene, PATH, 0.0, 0.07, AMAX, 60.0).status is Status.NO_PATH
    b = retime_blend(scene, PATH, 0.0, 0.07, AMAX, 60.0)
    assert b.status is Status.SOLVED, b.message
    assert b.hasty.tolist() == [False, True, False]
    assert b.hasty_length == pytest.approx(4.0)
    rows = b.trajectory.waypoints
    rep = check_trajectory(scene, rows, scene.queries[0])
    assert rep.valid, rep.reason
    assert leg_oracle(rows, (True, False, True)) == []
    # the straight really is hasty: the layered bound would fail it
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
    assert check_trajectory(scene, out.trajectory.waypoints, q).valid


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
