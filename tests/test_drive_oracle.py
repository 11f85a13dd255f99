"""tools/drive_oracle.py: the lattice oracle of a differential drive's static solvability.

It shares no code with the planner (its own moves, its own distance field); what it finds
must pass ``gfuzzy check``, and where it finds a way the planner must too (issue 18).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gfuzzy.planner.planner import Planner  # noqa: E402
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap  # noqa: E402
from gfuzzy.scene.scene import parse_scene  # noqa: E402
from tools.drive_oracle import LADDER, solve  # noqa: E402


def door_scene(door: float, reverse: bool = False) -> object:
    """A 0.7 x 0.4 box drive; a wall across a 4 x 3 room at x = 2 with a door ``door`` wide."""
    half = door / 2
    return parse_scene({
        "version": 1, "name": "door", "bounds": [0, 0, 4, 3],
        "robot": {"box": [0.7, 0.4], "vmax": 0.5, "kinematics": "unicycle", "reverse": reverse},
        "obstacles": [{"box": {"center": [2, (1.5 - half) / 2], "size": [0.1, 1.5 - half]}},
                      {"box": {"center": [2, 3 - (1.5 - half) / 2], "size": [0.1, 1.5 - half]}}],
        "queries": [{"name": "q", "start": [0.8, 0.8, math.pi / 2], "goal": [3.2, 2.2, -math.pi / 2]}],
    })  # fmt: skip


def test_oracle_path_passes_check_through_a_door():
    scene = door_scene(0.5)
    res = solve(scene, scene.queries[0])
    assert res["found"] and res["verified"]
    wp = res["waypoints"]
    assert np.allclose(wp[0, 1:], scene.queries[0].start) and np.allclose(
        wp[-1, 1:], scene.queries[0].goal
    )


def test_oracle_finds_nothing_through_a_door_narrower_than_the_body():
    scene = door_scene(0.38)
    res = solve(scene, scene.queries[0], LADDER[:1])
    assert not res["found"] and not res["verified"]


def test_planner_solves_what_the_oracle_solves_on_the_door():
    scene = door_scene(0.46)  # 3 cm per side
    q = scene.queries[0]
    assert solve(scene, q)["verified"]
    rm = build_roadmap(scene, RoadmapOptions(vertices=200, seed=1))
    assert Planner(scene, rm).plan(q.start, q.goal, q.t0).solved
