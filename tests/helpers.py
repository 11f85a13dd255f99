"""Helpers that several test modules share (importable: conftest puts tests/ on the path).

The in-process command line, trajectory files written by hand, scenes from YAML text with
robot overrides, and the bundled scenes with their roadmaps and answers (cached per process).
"""

from __future__ import annotations

import json
import subprocess
from functools import cache
from pathlib import Path

import pytest
import yaml

from gfuzzy.cli import main
from gfuzzy.planner.planner import Planner, PlanOptions
from gfuzzy.roadmap.roadmap import load_roadmap
from gfuzzy.scene.scene import load_scene, parse_scene

ROOT = Path(__file__).resolve().parent.parent


def run_main(capsys, *args):
    """``gfuzzy ARGS`` in-process: (exit status, stdout, stderr)."""
    rc = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return rc, out, err


def main_completed(capsys, *args) -> subprocess.CompletedProcess:
    """``gfuzzy ARGS`` in-process, answered as ``conftest.run_cli_process`` answers (exit
    status, stdout, stderr): a real process costs a second of imports a call, for tests
    whose subject is the command, not its process. Logged warnings are not in its stderr
    (pytest's handlers take them): a test of them reads ``caplog`` or keeps a real process."""
    rc, out, err = run_main(capsys, *args)
    return subprocess.CompletedProcess([str(a) for a in args], rc, out, err)


def write_trajectory_file(path, waypoints, scene="line", query="", status="solved"):
    doc = {"version": 1, "scene": scene, "query": query, "status": status, "message": ""}
    if waypoints is not None:
        doc["waypoints"] = [list(map(float, row)) for row in waypoints]
    path.write_text(json.dumps(doc))
    return path


def scene_doc(text: str, **robot) -> dict:
    doc = yaml.safe_load(text)
    doc["robot"].update(robot)
    return doc


def scene_of(text: str, **robot):
    return parse_scene(scene_doc(text, **robot))


BUNDLED_SCENES = sorted((ROOT / "scenes").glob("*.yaml"))

#: A bundled scene whose roadmap has this many vertices or more is a slow case of the tests
#: run on every bundled scene (the GA on it takes tens of seconds): marked slow, the smaller
#: scenes keep guarding the same behaviour in the fast suite.
SLOW_ROADMAP_VERTICES = 500


def _roadmap_vertices(path: Path) -> int:
    import json

    try:
        doc = json.loads((ROOT / "roadmaps" / f"{path.stem}.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return 0
    return len(doc.get("vertices") or [])


#: The bundled scenes as pytest parameters (ids: the scene names), the large ones marked slow.
BUNDLED_PARAMS = [
    pytest.param(p, id=p.stem, marks=[pytest.mark.slow] if _roadmap_vertices(p) >= SLOW_ROADMAP_VERTICES else [])
    for p in BUNDLED_SCENES
]


def bundled_params(slow: tuple[str, ...] = (), names: bool = False) -> list:
    """The bundled scenes as pytest parameters (paths, or with ``names`` their names), ids the
    names, the scenes named in ``slow`` marked slow: a test run on every bundled scene keeps
    its cheap scenes, one of each kind, in `make test` and runs the costly ones (seconds to
    half a minute each) in `make slow` (``tools/run_slow.sh``)."""
    unknown = set(slow) - {p.stem for p in BUNDLED_SCENES}
    assert not unknown, f"no bundled scene {sorted(unknown)}"
    return [
        pytest.param(p.stem if names else p, id=p.stem, marks=[pytest.mark.slow] if p.stem in slow else [])
        for p in BUNDLED_SCENES
    ]


@cache
def bundled_setup(path: Path):
    scene = load_scene(path)
    roadmap = load_roadmap(ROOT / "roadmaps" / f"{scene.name}.json", scene)
    return scene, roadmap, Planner(scene, roadmap)


@cache
def bundled_answers(path: Path, refine: bool, speed_layer: bool):
    scene, _, planner = bundled_setup(path)
    opts = PlanOptions(refine=refine, speed_layer=speed_layer, seed=3)
    return [(q, planner.plan(q.start, q.goal, q.t0, opts)) for q in scene.queries]
