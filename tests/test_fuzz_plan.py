"""tools/fuzz_plan.py: random scenes load, draw the same from the same seed, keep their
queries clear of the static obstacles, and classify a rejected answer and a raising
planner as failures (exit status 1) with the scene dumped to reproduce them."""

from __future__ import annotations

import csv
import sys
from types import SimpleNamespace

import numpy as np
import yaml
from conftest import ROOT

sys.path.insert(0, str(ROOT))

import tools.fuzz_plan as fuzz  # noqa: E402
from gfuzzy.collision.geometry import StaticGeometry  # noqa: E402
from gfuzzy.planner.queries import query_problem  # noqa: E402
from gfuzzy.scene.scene import load_scene  # noqa: E402
from gfuzzy.status import Status  # noqa: E402


def test_scenes_load_and_the_same_seed_draws_the_same_scene(tmp_path):
    shapes, kinematics = set(), set()
    for i in range(12):
        doc = fuzz.make_scene(5, i)
        assert doc == fuzz.make_scene(5, i)
        path = tmp_path / f"{i}.yaml"
        path.write_text(yaml.safe_dump(doc, sort_keys=False))
        scene = load_scene(path)
        shapes.add(next(k for k in ("disc", "box", "footprint") if k in doc["robot"]))
        kinematics.add(scene.robot.unicycle)
        geometry = StaticGeometry(scene)
        clear = [query_problem(geometry, q.start, q.goal) == "" for q in scene.queries]
        assert sum(clear) >= 2, (i, [query_problem(geometry, q.start, q.goal) for q in scene.queries])
    assert shapes == {"disc", "box", "footprint"} and len(kinematics) == 2
    assert fuzz.make_scene(5, 0) != fuzz.make_scene(6, 0)


def test_an_answer_the_check_refuses_and_an_exception_are_failures(tmp_path, monkeypatch, capsys):
    doc = fuzz.make_scene(1, 0)
    calls = []

    def bad_plan(scene, rm, start, goal, t0=0.0, hold=0.0, options=None):
        calls.append(start)
        if len(calls) == 1:  # straight across everything, far too fast
            rows = np.array([[t0, *start], [t0 + 1e-3, *goal]])
            return SimpleNamespace(status=Status.SOLVED, trajectory=SimpleNamespace(waypoints=rows), message="")
        raise RuntimeError("planner bug")

    monkeypatch.setattr(fuzz, "plan", bad_plan)
    rows = fuzz.run_scene(doc, vertices=30, time_limit=5.0, refine=(False,))
    assert [r["outcome"] for r in rows] == ["check_reject", "error", "error"], rows
    assert rows[0]["message"]  # the check's reason
    assert "RuntimeError: planner bug" in rows[1]["message"] and "traceback" in rows[1]

    monkeypatch.setattr(fuzz, "make_scene", lambda seed, i: doc)
    out, folder = tmp_path / "rows.csv", tmp_path / "dump"
    assert fuzz.main(["--scenes", "1", "-n", "30", "--refine", "off", "-o", str(out), "--dump", str(folder)]) == 1
    got = list(csv.DictReader(out.open()))
    assert [r["outcome"] for r in got] == ["error"] * 3  # calls go on: every plan now raises
    dumped = folder / f"{doc['name']}.yaml"
    assert dumped.exists() and yaml.safe_load(dumped.read_text()) == doc
    assert "python -m gfuzzy plan" in dumped.read_text()


def test_one_small_scene_is_planned_and_checked_end_to_end(tmp_path, capsys):
    out = tmp_path / "rows.csv"
    assert fuzz.main(["--scenes", "1", "--only", "1", "-n", "60", "--refine", "off", "-o", str(out)]) == 0
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 3 and {r["outcome"] for r in rows} <= set(fuzz.OUTCOMES) - {"check_reject", "error"}
    assert "| all | 3 |" in capsys.readouterr().out
