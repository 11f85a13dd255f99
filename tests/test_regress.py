"""gfuzzy.regress: expectations met and missed, on a hand-made scene."""

from __future__ import annotations

import io

import yaml

from gfuzzy.regress import format_row, regress_scene, run_regression
from gfuzzy.roadmap import RoadmapOptions, build_roadmap
from gfuzzy.scene import parse_scene

SCENE = """
version: 1
name: tiny
bounds: [0, 0, 4, 2]
robot: {disc: 0.2, vmax: 1.0}
queries:
  - {name: met, start: [0.5, 1], goal: [3.5, 1], expect: {status: solved, max_duration: 3.2}}
  - {name: slow, start: [0.5, 1], goal: [3.5, 1], expect: {max_duration: 2.0}}
  - {name: wrong, start: [0.5, 1], goal: [3.5, 1], expect: {status: no_path}}
  - {name: free, start: [0.5, 1], goal: [3.5, 1]}
"""


def _scene():
    return parse_scene(yaml.safe_load(SCENE))


def test_rows_say_which_expectation_failed():
    scene = _scene()
    rows = {r.query: r for r in regress_scene(scene, build_roadmap(scene, RoadmapOptions(vertices=20, seed=1)))}
    assert rows["met"].ok and rows["met"].valid is True and rows["met"].status == "solved"
    assert rows["slow"].problems == (f"duration {rows['slow'].duration:.3f} > max 2",)
    assert rows["wrong"].problems == ("status solved, expected no_path",)
    assert rows["free"].ok
    line = format_row(rows["wrong"])
    assert "tiny" in line and "wrong" in line and "expected no_path" in line


def test_run_regression_prints_a_table_and_the_count():
    scene = _scene()
    out = io.StringIO()
    ok = run_regression([scene], lambda sc: build_roadmap(sc, RoadmapOptions(vertices=20, seed=1)), None, out)
    lines = out.getvalue().splitlines()
    assert ok is False
    assert len(lines) == 1 + 4 + 1
    assert lines[-1] == "2 of 4 queries met their expectations"
