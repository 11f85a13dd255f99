"""The bundled scenes as a regression suite: adding a scene file adds its tests.

Each scene's queries are answered with its bundled roadmap, checked independently and
held to their ``expect`` blocks; the GA refinement and the speed layer run on every solved
query and must keep the contract's guarantees.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np
import pytest

from gfuzzy.check import check_trajectory
from gfuzzy.planner import Planner, PlanOptions
from gfuzzy.regress import regress_scene
from gfuzzy.roadmap import load_roadmap
from gfuzzy.scene import load_scene

ROOT = Path(__file__).resolve().parent.parent
SCENES = sorted((ROOT / "scenes").glob("*.yaml"))


@cache
def _setup(path: Path):
    scene = load_scene(path)
    roadmap = load_roadmap(ROOT / "roadmaps" / f"{scene.name}.json", scene)
    return scene, roadmap, Planner(scene, roadmap)


@cache
def _answers(path: Path, refine: bool, speed_layer: bool):
    scene, _, planner = _setup(path)
    opts = PlanOptions(refine=refine, speed_layer=speed_layer, seed=3)
    return [(q, planner.plan(q.start, q.goal, q.t0, opts)) for q in scene.queries]


def test_there_are_bundled_scenes():
    names = {p.stem for p in SCENES}
    assert {"building-floor", "sim-4s1m", "sim-6s1m", "sim-5s2m"} <= names
    assert len(SCENES) >= 8


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_regression(path):
    scene, roadmap, _ = _setup(path)
    assert scene.queries, "a bundled scene needs queries"
    rows = regress_scene(scene, roadmap)
    for row in rows:
        assert row.ok, f"{row.query}: {'; '.join(row.problems)}"
    assert all(q.expect is not None and q.expect.status for q in scene.queries)


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
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


def test_refinement_is_reproducible():
    path = ROOT / "scenes" / "sim-4s1m.yaml"
    scene, _, planner = _setup(path)
    q = scene.queries[0]
    a = planner.plan(q.start, q.goal, q.t0, PlanOptions(refine=True, seed=11))
    b = planner.plan(q.start, q.goal, q.t0, PlanOptions(refine=True, seed=11))
    assert np.array_equal(a.trajectory.waypoints, b.trajectory.waypoints)


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
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
        # the profile respects the acceleration bound: speed changes between steps stay
        # within amax * dt (plus the discretization of the profile onto the time grid)
        v = res.trajectory.speeds()
        dt = np.diff(w[:, 0])
        moving = dt < 0.07 + 1e-9
        dv = np.abs(np.diff(v))[moving[1:] & moving[:-1]]
        assert dv.max(initial=0.0) <= amax * 0.07 * 1.5 + 1e-9, (q.name, dv.max())


def test_speed_layer_applies_on_most_queries():
    applied = total = 0
    for path in SCENES:
        for _, r in _answers(path, False, True):
            if r.solved:
                total += 1
                applied += r.speed_report.applied
    assert applied >= 0.6 * total
