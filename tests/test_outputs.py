"""Outputs that cannot be written, seeds out of range, and what `check` cannot verify:
found by trying the command line as a new user (one line, exit 2, nothing written)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from gfuzzy.cli import main
from gfuzzy.errors import InputError
from gfuzzy.planner import plan
from gfuzzy.roadmap import RoadmapOptions
from gfuzzy.scene import load_scene

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "sim-4s1m.yaml"
ROADMAP = ROOT / "roadmaps" / "sim-4s1m.json"


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


@pytest.mark.parametrize("command", ["plan", "render", "navigate"])
def test_an_output_that_is_a_folder_is_bad_input(tmp_path, capsys, command):
    out = tmp_path / ("a.png" if command == "render" else "a.json")
    out.mkdir()
    args = [command, str(SCENE), "-o", str(out)]
    if command != "render":
        args[2:2] = ["--roadmap", str(ROADMAP)]
    assert main(args) == 2
    line = _one_line(capsys.readouterr().err)
    assert str(out) in line and "folder" in line
    assert list(tmp_path.iterdir()) == [out] and not any(out.iterdir())


@pytest.mark.parametrize(("command", "name"), [("plan", "a.json"), ("render", "a.png"), ("roadmap", "r.json")])
def test_an_output_the_system_refuses_is_one_line(capsys, command, name):
    # /proc refuses new files even to root, whom permission bits do not stop
    out = Path("/proc") / name
    args = [command, str(SCENE), "-o", str(out)]
    if command == "roadmap":
        args[2:2] = ["-n", "20"]
    assert main(args) == 2
    line = _one_line(capsys.readouterr().err)
    assert line.startswith(f"{out}:")  # the file asked for, not a temporary one


@pytest.mark.parametrize("seed", [-1, 2**31])
def test_a_seed_out_of_range_is_bad_input(tmp_path, capsys, seed):
    out = tmp_path / "r.json"
    assert main(["roadmap", str(SCENE), "-n", "20", "--seed", str(seed), "-o", str(out)]) == 2
    assert "seed" in _one_line(capsys.readouterr().err)
    assert not out.exists()
    with pytest.raises(InputError, match="seed"):
        RoadmapOptions(seed=seed)


def test_check_says_what_it_cannot_verify_without_the_query(tmp_path, capsys):
    out = tmp_path / "a.json"
    assert main(["plan", str(SCENE), "--roadmap", str(ROADMAP), "-o", str(out)]) == 0
    capsys.readouterr()
    doc = json.loads(out.read_text())
    assert main(["check", str(SCENE), str(out)]) == 0
    assert "not checked" not in capsys.readouterr().err
    doc["query"] = "nope"
    out.write_text(json.dumps(doc))
    assert main(["check", str(SCENE), str(out)]) == 0  # the motion itself is valid
    err = capsys.readouterr().err
    assert "'nope'" in err and "not checked" in err


def test_the_api_refuses_a_hold_that_is_not_a_number():
    scene = load_scene(SCENE)
    from gfuzzy.roadmap import load_roadmap

    rm = load_roadmap(ROADMAP, scene)
    q = scene.queries[0]
    for bad in ("5", True, -1.0, float("nan")):
        with pytest.raises(InputError, match="hold"):
            plan(scene, rm, q.start, q.goal, hold=bad)
    assert plan(scene, rm, q.start, q.goal, hold=np.float64(0.5)).solved
