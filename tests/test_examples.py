"""``gfuzzy examples DIR``: the bundled scenes, roadmaps and pedestrian data for a user who
installed the package without the repository (the wheel carries them; tests/test_packaging.py
runs the command from an installed wheel)."""

from __future__ import annotations

from pathlib import Path

from conftest import ROOT

from gfuzzy.cli.examples import EXAMPLES, examples_root
from gfuzzy.cli.main import main


def _files(root: Path) -> dict:
    return {p.relative_to(root).as_posix(): p.read_bytes() for name in EXAMPLES for p in (root / name).rglob("*")
            if p.is_file() and "__pycache__" not in p.parts}  # fmt: skip


def test_examples_are_the_repositorys_folders_and_the_readme_runs_from_them(tmp_path, capsys):
    assert examples_root() == ROOT  # run from the source tree
    dest = tmp_path / "ex"
    assert main(["examples", str(dest)]) == 0
    assert "scenes/" in capsys.readouterr().out
    got = _files(dest)
    assert got == _files(ROOT) and "scenes/building-floor.yaml" in got and "data/pedestrians/biwi_eth.txt" in got
    assert sorted(p.name for p in dest.iterdir()) == sorted(EXAMPLES)  # no staging folder left
    # the copy is self-contained: its roadmap is found beside its scene, and the plan solves
    out = tmp_path / "a.json"
    assert main(["plan", str(dest / "scenes" / "building-floor.yaml"), "-o", str(out)]) == 0
    assert "no roadmap file" not in capsys.readouterr().err


def test_examples_refuse_to_overwrite_and_bad_folders(tmp_path, capsys):
    dest = tmp_path / "ex"
    (dest / "scenes").mkdir(parents=True)
    (dest / "scenes" / "mine.yaml").write_text("kept\n")
    assert main(["examples", str(dest)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "already exists" in err
    assert sorted(p.name for p in dest.iterdir()) == ["scenes"]
    assert [p.name for p in (dest / "scenes").iterdir()] == ["mine.yaml"]
    (tmp_path / "f").write_text("x")
    assert main(["examples", str(tmp_path / "f")]) == 2
    assert main(["examples", str(tmp_path / "no" / "such")]) == 2
    err = capsys.readouterr().err
    assert "is a file" in err and "does not exist" in err and not (tmp_path / "no").exists()
