"""Planner.prepare / plan_from (replanning to a fixed goal) against fresh plans."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from gfuzzy.check import check_trajectory
from gfuzzy.planner import Planner, PlanOptions
from gfuzzy.roadmap import load_roadmap
from gfuzzy.scene import load_scene

ROOT = Path(__file__).resolve().parent.parent


def _setup(name):
    scene = load_scene(ROOT / "scenes" / f"{name}.yaml")
    return scene, Planner(scene, load_roadmap(ROOT / "roadmaps" / f"{name}.json", scene))


@pytest.mark.parametrize("name", ["building-floor", "zara-crowd", "wait-corridor", "sim-5s2m", "office-polygons"])
def test_plan_from_matches_fresh_plans_along_a_run(name):
    """From the start and from poses along the first answer (mid-edge, later t0): the same
    status and duration as a fresh plan, and a valid answer."""
    scene, planner = _setup(name)
    q = scene.queries[0]
    prepared = planner.prepare(q.goal)
    first = planner.plan(q.start, q.goal, q.t0)
    assert first.solved
    wps = first.trajectory.waypoints
    checked = 0
    for frac in (0.0, 0.17, 0.4, 0.63):
        t = q.t0 + frac * first.duration
        pose = first.trajectory.at(t) if frac else np.asarray(q.start, float)
        fresh = planner.plan(pose, q.goal, t)
        again = planner.plan_from(prepared, pose, t)
        assert again.status == fresh.status, (frac, fresh.message, again.message)
        assert again.roadmap_distance == pytest.approx(fresh.roadmap_distance)
        if fresh.solved:
            assert again.duration == pytest.approx(fresh.duration, abs=1e-9)
            np.testing.assert_allclose(again.trajectory.waypoints[-1, 1:], q.goal)
            ok = check_trajectory(scene, again.trajectory.waypoints)
            assert ok.valid, ok.reason
            checked += 1
    assert checked >= 2
    assert len(wps) > 2


def test_plan_from_with_other_movers_and_the_reference_backend():
    """Movers given per call (a navigator's prediction) replace the scene's; both backends
    agree with a fresh plan on a scene holding those movers."""
    scene, planner = _setup("wait-corridor")
    q = scene.queries[0]
    moved = [dataclasses.replace(m, offset=m.offset + 1.5) if m.trajectory is None else m for m in scene.movers]
    other = dataclasses.replace(scene, movers=tuple(moved))
    fresh = Planner(other, planner.roadmap).plan(q.start, q.goal, q.t0)
    for backend in ("compiled", "reference"):
        prepared = planner.prepare(q.goal, PlanOptions(backend=backend))
        again = planner.plan_from(prepared, q.start, q.t0, movers=moved)
        assert (again.status, again.duration) == (fresh.status, fresh.duration)
    base = planner.plan(q.start, q.goal, q.t0)
    assert base.duration != fresh.duration  # the movers given did change the problem
