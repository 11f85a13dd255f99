"""gfuzzy.runs.regress: expectations met and missed, on a hand-made scene."""

from __future__ import annotations

import io

import pytest
import yaml
from helpers import BUNDLED_SCENES as SCENES
from helpers import bundled_setup as _setup

from gfuzzy.cli import main
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap
from gfuzzy.runs.regress import format_row, regress_scene, run_regression
from gfuzzy.scene.scene import load_scene, parse_scene

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


def test_a_query_beyond_the_memory_bounds_names_the_scene_file_and_the_query(tmp_path, capsys):
    # `gfuzzy regress` of many scenes said only "gfuzzy regress: 3 movers over 14,285,716 time
    # steps (the hold's ...) are too many to sample ...": which file, which query?
    doc = yaml.safe_load(SCENE)
    doc["movers"] = [{"name": f"m{i}", "disc": 0.2, "speed": 0.5, "path": [[1, 0.3], [3, 0.3]], "mode": "bounce"}
                     for i in range(3)]
    doc["queries"] = [doc["queries"][3], {"name": "parked", "start": [0.5, 1], "goal": [3.5, 1], "hold": 1e6}]
    path = tmp_path / "tiny.yaml"
    path.write_text(yaml.safe_dump(doc))
    assert main(["regress", str(path), "-n", "20"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"{path}: queries[1] (parked): 3 movers over"), err
    assert "too many to sample" in err


def test_a_time_step_too_fine_for_the_roadmap_names_the_option_not_a_query(tmp_path, capsys):
    # it said "tiny.yaml: queries[0] (...): the time step is too fine ...": the first query
    # blamed for --dt, which no query can satisfy
    path = tmp_path / "tiny.yaml"
    path.write_text(SCENE)
    assert main(["regress", str(path), "-n", "20", "--dt", "1e-7"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"gfuzzy regress: --dt 1e-07: {path}: the time step is too fine"), err


def test_a_scene_without_queries_gets_a_line_and_no_roadmap():
    """A scene without queries is said to have none, in one line, and no roadmap is built
    or loaded for it (``roadmap_for`` refuses here). Before: a 200-vertex roadmap was built
    (3.6 s for a 12 x 4 m scene) and the table said nothing of the scene."""
    empty = parse_scene({**yaml.safe_load(SCENE), "name": "empty", "queries": []})

    def refuse(sc):
        raise AssertionError(f"a roadmap was asked for {sc.name!r}")

    out = io.StringIO()
    assert run_regression([empty], refuse, None, out) is True
    lines = out.getvalue().splitlines()
    assert lines[1] == "empty                  (no queries: nothing answered, no roadmap built or loaded)"
    assert lines[-1] == "0 of 0 queries met their expectations" and len(lines) == 3


def _clearance_answers_pass_check(path) -> None:
    """A scene's queries with clearances (0.05 static, 0.1 to movers) on a roadmap built
    for them: the statuses the scene expects, each answer valid under the check."""
    scene = load_scene(path).with_clearances(0.05, 0.1)
    rm = build_roadmap(scene, RoadmapOptions())
    for row, q in zip(regress_scene(scene, rm), scene.queries, strict=True):
        if q.expect is not None and q.expect.status is not None:
            assert row.status == q.expect.status, (scene.name, q.name, row.status)
        if row.status == "solved":
            assert row.valid, (scene.name, q.name, row.problems)


@pytest.mark.slow
def test_every_bundled_query_with_clearances_passes_check(repo_root):
    """Clearance answers on every bundled scene: the same statuses, each answer valid
    under the check with the clearances."""
    for path in sorted((repo_root / "scenes").glob("*.yaml")):
        _clearance_answers_pass_check(path)


def test_small_bundled_scenes_with_clearances_pass_check(repo_root):
    """The fast sibling of the slow test above: three small bundled scenes (movers, a wait
    forced by one, an unreachable goal), the same assertions."""
    for name in ("sim-4s1m", "wait-corridor", "sealed-room"):
        _clearance_answers_pass_check(repo_root / "scenes" / f"{name}.yaml")


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
