"""Every command that writes refuses an output that is a file it reads (docs/formats.md
section 6): the scene, its maps' YAMLs and images, meshes, roadmaps, trajectories, tracks;
the second file an output writes (a Nav2 map's .pgm) included, through links and ``..``."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT
from helpers import run_main as _run
from PIL import Image

from gfuzzy.cli.common import _scene_reads
from gfuzzy.scene.scene import load_scene

SCENE = """version: 1
name: m
robot: {disc: 0.2, vmax: 1.0}
obstacles:
  - map: {file: maps/a.yaml}
  - map: {file: maps/b.yaml, unknown: free}
queries:
  - {name: q, start: [1.0, 1.0], goal: [4.0, 4.0]}
"""


def _map(folder: Path, name: str, suffix: str) -> None:
    pixels = np.full((20, 20), 254, dtype=np.uint8)
    pixels[8:12, 8:12] = 0
    Image.fromarray(pixels).save(folder / f"{name}{suffix}")
    (folder / f"{name}.yaml").write_text(
        f"image: {name}{suffix}\nresolution: 0.25\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )


@pytest.fixture
def world(tmp_path, monkeypatch):
    """A scene on two maps (a PGM and a PNG image), a tracks file, a link to a map."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "maps").mkdir()
    _map(tmp_path / "maps", "a", ".pgm")
    _map(tmp_path / "maps", "b", ".png")
    (tmp_path / "s.yaml").write_text(SCENE)
    (tmp_path / "walk.csv").write_text("t,id,x,y\n0,p,1,3\n1,p,2,3\n")
    os.symlink("maps/a.yaml", tmp_path / "link.yaml")
    return tmp_path


def _files(folder: Path) -> dict:
    return {p: p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.mark.parametrize(
    "argv, victim",
    [
        (["export", "s.yaml", "--map", "maps/a.yaml"], "maps/a.yaml"),  # the scene's own map
        (["export", "s.yaml", "--map", "maps/a.yml"], "maps/a.pgm"),  # its image, written beside
        (["export", "s.yaml", "--map", "link.yaml"], "maps/a.yaml"),  # through a link
        (["export", "s.yaml", "--map", "maps/../maps/b.yaml"], "maps/b.yaml"),  # another spelling
        (["populate", "s.yaml", "--people", "1", "-o", "maps/a.yaml"], "maps/a.yaml"),
        (["tracks", "walk.csv", "--static", "s.yaml", "-o", "maps/b.yaml"], "maps/b.yaml"),
        (["render", "s.yaml", "-o", "maps/b.png"], "maps/b.png"),  # a map's PNG image
        (["roadmap", "s.yaml", "-o", "link.yaml.json"], None),  # not an input: written
    ],
)
def test_no_command_overwrites_a_file_its_scene_reads(world, capsys, argv, victim):
    if argv[0] == "populate":
        pytest.importorskip("pyrvo")
    if victim is None:  # the control: an output beside the inputs is fine
        rc, _, err = _run(capsys, *argv[:-1], "rm.json")
        assert rc == 0, err
        return
    before = _files(world)
    rc, _, err = _run(capsys, *argv)
    assert rc == 2, err
    assert err.count("\n") == 1 and "would overwrite" in err and "this command reads" in err, err
    assert Path(err.split("would overwrite ")[1].split(",")[0].split(" (")[0]).samefile(world / victim), err
    assert _files(world) == before  # nothing written, nothing replaced


@pytest.mark.parametrize(
    "argv, folder",
    [
        (["export", "s.yaml", "--map", "out.yaml"], "out.pgm"),
        (["batch", "s.yaml", "--workers", "1", "-o", "out.csv"], "out.parquet"),
        (["plan", "s.yaml", "-o", "out.csv"], "out.json"),
    ],
)
def test_a_file_written_beside_an_output_that_is_a_folder_is_refused_first(world, capsys, argv, folder):
    # found once the work was done: export named its temporary file ('.out.x1y2.pgm: Is a
    # directory'), batch had written the CSV and not its Parquet, plan said 'out.json: Is a directory'
    (world / folder).mkdir()
    before = _files(world)
    rc, _, err = _run(capsys, *argv)
    assert rc == 2 and err == f"{argv[-1]}: {folder}, written with it, is a folder, not a file\n", err
    assert _files(world) == before


def test_batch_refuses_a_trajectory_file_that_is_a_scene(tmp_path, capsys, monkeypatch):
    # --trajectories DIR writes DIR/<scene>-<query>.json: here the scene file itself
    monkeypatch.chdir(tmp_path)
    (tmp_path / "out").mkdir()
    scene = tmp_path / "out" / "line-go.json"
    scene.write_text('{"version": 1, "name": "line", "bounds": [0, 0, 4, 2], "robot": {"disc": 0.2, "vmax": 1},'
                     ' "queries": [{"name": "go", "start": [0.5, 1], "goal": [3.5, 1]}]}')  # fmt: skip
    before = scene.read_bytes()
    rc, _, err = _run(capsys, "batch", str(scene), "--workers", "1", "-o", "r.csv", "--trajectories", "out")
    assert rc == 2 and err.count("\n") == 1 and "would overwrite" in err and "the scene" in err, err
    assert scene.read_bytes() == before and not (tmp_path / "r.csv").exists()


def test_batch_refuses_trajectory_files_that_are_folders_or_shared(tmp_path, capsys, monkeypatch):
    # found once every query had run: the table was lost ('out/a-b-c.json: Is a directory'),
    # or one answer silently replaced the other (scene a-b query c, scene a query b-c)
    monkeypatch.chdir(tmp_path)
    for scene, query in (("a-b", "c"), ("a", "b-c")):
        (tmp_path / f"{scene}.json").write_text(
            f'{{"version": 1, "name": "{scene}", "bounds": [0, 0, 4, 2], "robot": {{"disc": 0.2, "vmax": 1}},'
            f' "queries": [{{"name": "{query}", "start": [0.5, 1], "goal": [3.5, 1]}}]}}'
        )
    (tmp_path / "out" / "a-b-c.json").mkdir(parents=True)
    argv = ("batch", "a-b.json", "--workers", "1", "-o", "r.csv", "--trajectories", "out")
    rc, _, err = _run(capsys, *argv)
    assert (rc, err) == (2, "--trajectories out: out/a-b-c.json is a folder, not a file\n")
    (tmp_path / "out" / "a-b-c.json").rmdir()
    rc, _, err = _run(capsys, *argv[:2], "a.json", *argv[2:])
    assert rc == 2 and err == ("--trajectories out: out/a-b-c.json would hold the answers of both scene 'a-b' "
                               "query 'c' and scene 'a' query 'b-c'\n"), err  # fmt: skip
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["a-b.json", "a.json", "out"]


def test_scene_reads_names_every_file_a_scene_reads(world):
    mesh = world / "shelves.stl"
    mesh.write_bytes((ROOT / "scenes" / "meshes" / "shelves.stl").read_bytes())
    (world / "s.yaml").write_text(SCENE.replace("queries:", "  - mesh: {file: shelves.stl}\nqueries:"))
    reads = {Path(p).resolve() for p, _ in _scene_reads(load_scene(world / "s.yaml"))}
    want = {world / f for f in ("s.yaml", "maps/a.yaml", "maps/a.pgm", "maps/b.yaml", "maps/b.png", "shelves.stl")}
    assert reads == {p.resolve() for p in want}


def test_batch_refuses_a_table_whose_parquet_beside_it_is_a_scene(tmp_path, capsys, monkeypatch):
    # -o r.csv writes r.parquet beside it (with pyarrow): here the scene file
    monkeypatch.chdir(tmp_path)
    scene = tmp_path / "r.parquet"
    scene.write_text((ROOT / "scenes" / "sim-4s1m.yaml").read_text())
    before = scene.read_bytes()
    rc, _, err = _run(capsys, "batch", "r.parquet", "--workers", "1", "-o", "r.csv")
    assert rc == 2 and err.count("\n") == 1, err
    assert "would overwrite r.parquet (the file r.parquet written with it), the scene" in err, err
    assert scene.read_bytes() == before and not (tmp_path / "r.csv").exists()


@pytest.mark.parametrize(
    "argv",
    [
        ["roadmap", "s.json", "-n", "20", "-o", "s.json"],  # a roadmap over its JSON scene
        ["roadmap", "s.json", "-n", "20", "-o", "./s.json"],  # another spelling
        ["navigate", "s.json", "-n", "20", "-o", "s.json"],  # the run over the scene it runs
        ["plan", "s.json", "-n", "20", "-o", "s.json"],
    ],
)
def test_a_json_scene_is_not_overwritten_by_what_is_made_from_it(tmp_path, capsys, monkeypatch, argv):
    # the review's surviving mutants: a JSON scene named as the output was replaced
    monkeypatch.chdir(tmp_path)
    scene = tmp_path / "s.json"
    scene.write_text('{"version": 1, "name": "line", "bounds": [0, 0, 4, 2], "robot": {"disc": 0.2, "vmax": 1},'
                     ' "queries": [{"name": "go", "start": [0.5, 1], "goal": [3.5, 1]}]}')  # fmt: skip
    before = _files(tmp_path)
    rc, _, err = _run(capsys, *argv)
    assert rc == 2 and err.count("\n") == 1 and "would overwrite" in err and "this command reads" in err, err
    assert _files(tmp_path) == before
