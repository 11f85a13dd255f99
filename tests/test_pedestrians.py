"""Planning among real people: scenes made from the ETH/UCY excerpts in data/pedestrians/.

The dense UCY "students" square is the hard case (over a hundred people); each test builds
its scene with `gfuzzy tracks`, plans with real OMPL/FCL, and checks every answer with the
independent checker. The excerpts are part of the repository: nothing is skipped.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, run_cli_process

from gfuzzy.check import check_trajectory
from gfuzzy.planner import Planner, PlanOptions, Status
from gfuzzy.roadmap import RoadmapOptions, build_roadmap
from gfuzzy.scene import load_scene

DATA = ROOT / "data" / "pedestrians"


def _make(tmp_path: Path, data: str, *args) -> Path:
    out = tmp_path / f"{Path(data).stem}.yaml"
    proc = run_cli_process("tracks", DATA / data, *args, "-o", out)
    assert proc.returncode == 0, proc.stderr
    return out


@pytest.fixture(scope="module")
def students(tmp_path_factory):
    path = _make(
        tmp_path_factory.mktemp("students"),
        "students001.txt",
        "--t-start", 100, "--duration", 40, "--region", 0, 0, 15, 14,
        "--start", 1, 1, "--goal", 14, 13, "--query-name", "across",
    )  # fmt: skip
    scene = load_scene(path)
    return scene, build_roadmap(scene, RoadmapOptions(vertices=300, seed=1))


def test_dense_crowd_answers_are_safe(students):
    scene, roadmap = students
    assert len(scene.movers) >= 40  # a crowd, not a couple of people
    planner = Planner(scene, roadmap)
    rng = np.random.default_rng(5)
    solved = 0
    for t0 in (0.0, 7.5, 15.0):
        for _ in range(2):
            start = rng.uniform([1, 1], [14, 13])
            goal = rng.uniform([1, 1], [14, 13])
            res = planner.plan(start, goal, t0, PlanOptions(time_limit=30))
            assert res.status in (Status.SOLVED, Status.NO_PATH, Status.INVALID_QUERY), res.message
            if res.solved:
                solved += 1
                rep = check_trajectory(scene, res.trajectory.waypoints)
                assert rep.valid, rep.reason
                assert np.allclose(res.trajectory.waypoints[0, 1:], start)
                assert res.trajectory.t0 == t0
    assert solved >= 3


def test_stepping_onto_a_person_is_an_invalid_query(students):
    scene, roadmap = students
    person = next(m for m in scene.movers if m.time_range[0] <= 5.0 <= m.time_range[1])
    xy, present = person.state(np.array([5.0]))
    assert present[0]
    res = Planner(scene, roadmap).plan(xy[0], [14, 13], 5.0)
    assert res.status is Status.INVALID_QUERY
    assert person.name in res.message


def test_people_who_come_and_go_are_only_there_while_recorded(tmp_path):
    path = _make(
        tmp_path, "biwi_hotel.txt", "--t-start", 50, "--duration", 30, "--start", 0, 0, "--goal", 1, 1,
    )  # fmt: skip
    scene = load_scene(path)
    ranges = np.array([m.time_range for m in scene.movers])
    assert ranges[:, 0].min() >= 0.0 and ranges[:, 1].max() <= 30.0 + 1e-9
    assert (ranges[:, 0] > 0.5).any()  # some arrive after the window opens
    late = scene.movers[int(np.argmax(ranges[:, 0]))]
    _, present = late.state(np.array([0.0, late.time_range[0]]))
    assert not present[0] and present[1]
