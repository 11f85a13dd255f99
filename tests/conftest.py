"""Shared fixtures: scene files in a temporary folder, the repository root, the CLI, and the
small scenes (line, door, the open square) that several test modules plan on."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap

ROOT = Path(__file__).resolve().parent.parent
TESTS = ROOT / "tests"
BAD_SCENES = TESTS / "bad_scenes"

if str(TESTS) not in sys.path:  # lets test modules import the helper `reference`
    sys.path.insert(0, str(TESTS))

from helpers import scene_of as _scene  # noqa: E402
from shared_scenes import DOOR, LINE  # noqa: E402


def cli_present() -> bool:
    """True once the CLI (``gfuzzy/cli/``) exists (the CLI is written separately)."""
    return (ROOT / "gfuzzy" / "cli" / "__init__.py").exists() or (ROOT / "gfuzzy" / "cli.py").exists()


needs_cli = pytest.mark.skipif(not cli_present(), reason="gfuzzy/cli/ is not there yet")


def pytest_collection_modifyitems(config, items):
    """Tests marked ``long`` (a minute or more: a module sets ``pytestmark``) run first, the
    rest in their order: under ``pytest -n`` the file that starts last ends the run, and a
    long one there left the other worker idle for a minute."""
    items.sort(key=lambda item: item.get_closest_marker("long") is None)


@pytest.fixture(scope="session")
def repo_root() -> Path:
    """The repository root (holds ``gfuzzy/``, ``scenes/``, ``roadmaps/``)."""
    return ROOT


@pytest.fixture
def tmp_scene(tmp_path):
    """Factory writing scene text to ``tmp_path``: ``tmp_scene(text, name="scene.yaml")``.

    ``text`` is dedented; ``bytes`` are written unchanged. Returns the file's path.
    """

    def make(text: str | bytes, name: str = "scene.yaml") -> Path:
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(text, bytes):
            path.write_bytes(text)
        else:
            path.write_text(textwrap.dedent(text).lstrip("\n"), encoding="utf-8")
        return path

    return make


def run_cli_process(*args, cwd=None, timeout: float = 120.0) -> subprocess.CompletedProcess:
    """Run ``python -m gfuzzy ARGS`` in a fresh process; text output captured."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    env.setdefault("MPLBACKEND", "Agg")
    return subprocess.run(
        [sys.executable, "-m", "gfuzzy", *map(str, args)],
        cwd=str(cwd or ROOT),
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def run_python(code: str, *args, cwd=None, timeout: float = 120.0) -> subprocess.CompletedProcess:
    """Run ``python -c CODE ARGS`` in a fresh process (for cross-process checks)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    return subprocess.run(
        [sys.executable, "-c", code, *map(str, args)],
        cwd=str(cwd or ROOT),
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


@pytest.fixture
def run_cli():
    """``run_cli(*args, cwd=None)`` -> CompletedProcess of ``python -m gfuzzy ARGS``."""
    return run_cli_process


@pytest.fixture
def line_scene(tmp_path):
    path = tmp_path / "line.yaml"
    path.write_text(LINE)
    return path


@pytest.fixture(scope="module")
def door():
    scene = _scene(DOOR)
    return scene, build_roadmap(scene, RoadmapOptions(vertices=80, seed=2))


def unhurried(**options):
    """Navigator options whose time budget no call reaches, counted in the process's CPU
    time (5 s): a test that is not about the budget must not depend on the machine's load
    (at load 10-19 on 2 cores the default 0.1 s wall-clock budget ran out before the search
    answered, or before it ran at all)."""
    from gfuzzy.navigation.navigator import NavOptions

    return NavOptions(time_budget=5.0, budget_clock="cpu", **options)


@pytest.fixture(scope="module")
def open_square():
    """A 10 x 10 m room without obstacles, a disc robot (radius 0.3, vmax 1) from (0, -4) to
    (0, 4), and a 150-vertex roadmap: the navigator's tests' open floor."""
    from gfuzzy.scene.scene import parse_scene

    scene = parse_scene({
        "version": 1, "name": "open-square", "bounds": [-5.0, -5.0, 5.0, 5.0], "robot": {"disc": 0.3, "vmax": 1.0},
        "obstacles": [], "movers": [], "queries": [{"name": "q", "start": [0.0, -4.0], "goal": [0.0, 4.0]}],
    })  # fmt: skip
    return scene, build_roadmap(scene, RoadmapOptions(vertices=150, seed=3))
