"""The command line's behaviour: exit statuses, one-line errors, what it writes and removes.

The CLI runs in-process (``gfuzzy.cli.main``) so that its exit status, stdout and stderr are
what a user sees, or as ``python -m gfuzzy`` in a fresh process.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT
from helpers import run_main as _run
from helpers import write_trajectory_file as _trajectory_file
from shared_scenes import DOOR, LOOP

import gfuzzy
from gfuzzy.check.check import check_trajectory
from gfuzzy.cli import main
from gfuzzy.errors import InputError, LimitError, check_number
from gfuzzy.rng import create_rng
from gfuzzy.roadmap.roadmap import RoadmapOptions
from gfuzzy.scene.scene import load_scene
from gfuzzy.settings import MAX_POINTS


def test_unsolved_plan_removes_a_stale_csv_and_says_what_it_wrote(line_scene, tmp_path, capsys):
    out = tmp_path / "x.csv"
    out.write_text("t,x,y\n0.0,1.0,1.0\n")  # an older, solved answer's rows
    # the start lies in the first disc: invalid_query, answered without a roadmap
    rc, stdout, stderr = _run(capsys, "plan", line_scene, "--start", 3.0, 1.0, "--goal", 9, 2.5, "-o", out)
    assert rc == 1
    assert "invalid_query" in stdout
    assert not out.exists(), "a controller would drive the stale rows"
    doc = json.loads((tmp_path / "x.json").read_text())
    assert doc["status"] == "invalid_query" and "waypoints" not in doc
    assert f"removed {out}" in stderr
    assert f"wrote {tmp_path / 'x.json'}" in stderr
    assert not list(tmp_path.glob(".x.*"))  # no temporary left behind


def test_unsolved_plan_replaces_an_older_json(line_scene, tmp_path, capsys):
    out = tmp_path / "y.json"
    _trajectory_file(out, [[0, 1, 2.5], [8, 9, 2.5]])
    rc, _, stderr = _run(capsys, "plan", line_scene, "--start", 6.0, 1.0, "--goal", 9, 2.5, "-o", out)
    assert rc == 1
    doc = json.loads(out.read_text())
    assert doc["status"] == "invalid_query" and "waypoints" not in doc
    assert f"wrote {out}" in stderr


def test_check_of_a_csv_gives_a_hint(line_scene, tmp_path, capsys):
    csv = tmp_path / "x.csv"
    csv.write_text("t,x,y\n0.0,1.0,2.5\n8.0,9.0,2.5\n")
    rc, _, stderr = _run(capsys, "check", line_scene, csv)
    assert rc == 2
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert str(csv) in lines[0] and "JSON" in lines[0] and "x.json" in lines[0]


@pytest.mark.parametrize(
    "rows, check_rc",
    [
        ([[0, 1, 1], [4, 5, 1], [8, 9, 1]], 1),  # well formed, hits both discs: invalid
        ([[0, 1, 2.5], [1, 4, 2.5]], 1),  # too fast: invalid
        ([[0, 1, 2.5], [4, 5, 2.5], [4, 6, 2.5]], 2),  # t does not increase: not a trajectory
        ([[0, 1, 2.5, 0], [8, 9, 2.5, 0]], 2),  # rows of a box robot: not for this scene
    ],
)
def test_check_and_render_agree_on_what_is_bad_input(line_scene, tmp_path, capsys, rows, check_rc):
    traj = _trajectory_file(tmp_path / "t.json", rows)
    rc_check, _, err_check = _run(capsys, "check", line_scene, traj)
    assert rc_check == check_rc, err_check
    rc_render, _, err_render = _run(capsys, "render", line_scene, traj, "-o", tmp_path / "t.png", "--no-roadmap")
    if check_rc == 2:  # bad input for one is bad input for the other, one line each
        assert rc_render == 2 and len(err_render.strip().splitlines()) == 1, err_render
        assert not (tmp_path / "t.png").exists()
    else:  # drawn, and the user told it is invalid
        assert rc_render == 0, err_render
        assert (tmp_path / "t.png").exists()
        assert "invalid" in err_render


def test_regress_names_itself_in_option_errors(line_scene, capsys):
    rc, out, err = _run(capsys, "regress", line_scene, "--dt", 0)
    assert rc == 2 and out == ""
    assert err.startswith("gfuzzy regress:"), err


def test_regress_checks_its_arguments_before_printing(line_scene, capsys):
    rc, out, err = _run(capsys, "regress", line_scene, "-n", 0)
    assert rc == 2
    assert out == "", "the table header was printed before the arguments were checked"
    assert len(err.strip().splitlines()) == 1 and "vert" in err


@pytest.mark.parametrize(
    ("args", "prog"),
    [(("navigate", "s.yaml", "--start", 1, 2, 0), "gfuzzy navigate"), (("plan", "s.yaml", "extra"), "gfuzzy plan"),
     (("--bogus",), "gfuzzy"), (("--bogus", "plan", "s.yaml"), "gfuzzy")],
)
def test_an_unknown_argument_names_the_command_whose_help_lists_the_options(capsys, args, prog):
    """`gfuzzy navigate --start ...` (navigate takes --query only) said `gfuzzy: unrecognized
    arguments ... (see gfuzzy --help)`, whose help lists the commands, not navigate's options."""
    rc, out, err = _run(capsys, *args)
    assert rc == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"{prog}: unrecognized arguments: "), err
    assert lines[0].endswith(f"(see {prog} --help)"), err

def test_the_cli_calls_a_malformed_pose_bad_input(line_scene, capsys):
    rc, out, err = _run(capsys, "plan", line_scene, "--start", 1, 2.5, 0, "--goal", 9, 2.5)
    assert rc == 2 and out == "" and len(err.strip().splitlines()) == 1


def test_the_cli_notes_an_amax_it_does_not_honour(line_scene, tmp_path, capsys):
    rc, _, err = _run(capsys, "plan", line_scene, "-n", 40, "--seed", 2, "-o", tmp_path / "a.json")
    assert rc == 0, err
    assert "amax" in err and "not honoured" in err
    assert json.loads((tmp_path / "a.json").read_text())["amax_honoured"] is False


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


@pytest.mark.parametrize("command", ["roadmap", "plan"])
def test_a_vertex_count_no_query_could_search_is_refused_at_once(tmp_path, capsys, command):
    # -n 1000000000000 ran OMPL's PRM for ever (no output, no end) before it was refused
    out = tmp_path / "r.json"
    n = MAX_POINTS + 1
    with pytest.raises(LimitError, match="vertices"):  # first: the old code never returns below
        RoadmapOptions(vertices=n)
    assert main([command, str(SCENE), "-n", str(n), "--seed", "1", "-o", str(out)]) == 2
    line = _one_line(capsys.readouterr().err)
    assert f"{n:,} vertices" in line and line.startswith(("gfuzzy roadmap:", "-n/--seed:"))
    assert not out.exists()


@pytest.mark.parametrize(("flag", "value"), [("--t0", "1e300"), ("--t0", "5e9"), ("--hold", "1e300")])
def test_a_time_past_what_a_scene_allows_is_bad_input(tmp_path, capsys, flag, value):
    # --t0 1e300 was answered "solved", exit 0, with rows all at t=1e300 (t0 + dt == t0),
    # which check then refused; --hold 1e300 printed three 300-digit step counts
    out = tmp_path / "a.json"
    args = ["plan", str(SCENE), "--roadmap", str(ROADMAP), "--start", "1", "1", "--goal", "4", "4", flag, value]
    assert main([*args, "-o", str(out)]) == 2
    line = _one_line(capsys.readouterr().err)
    assert line.startswith(flag) and "1e+09" in line and len(line) < 200
    assert not out.exists()
    scene = load_scene(SCENE)
    with pytest.raises(InputError, match="1e\\+09"):
        gfuzzy.plan(scene, gfuzzy.load_roadmap(ROADMAP, scene), (1, 1), (4, 4), **{flag[2:]: float(value)})


@pytest.mark.parametrize("command", ["plan", "navigate"])
def test_a_finite_option_past_1e9_is_bad_input(tmp_path, capsys, command):
    # --dt 1e300: navigate (and crowd) died in an IndexError traceback, plan answered
    # no_path "the start is too close to a mover"
    out = tmp_path / "a.json"
    assert main([command, str(SCENE), "--roadmap", str(ROADMAP), "--dt", "1e300", "-o", str(out)]) == 2
    line = _one_line(capsys.readouterr().err)
    assert line == f"gfuzzy {command}: dt must be at most 1e+09, got 1e+300"
    assert not out.exists()
    with pytest.raises(InputError, match="at most 1e\\+09"):
        check_number("dt", 1e300)
    check_number("horizon", math.inf, finite=False)  # an unbounded option stays so


def test_a_negative_noise_seed_is_bad_input(tmp_path, capsys):
    # numpy refused it where the sensor first drew noise: a traceback, exit 1
    out = tmp_path / "a.json"
    assert main(["navigate", str(SCENE), "--roadmap", str(ROADMAP), "--seed", "-1", "-o", str(out)]) == 2
    assert "seed must be a whole number >= 0, got -1" in _one_line(capsys.readouterr().err)
    assert not out.exists()
    with pytest.raises(InputError):
        create_rng(-1)


def test_a_saved_roadmap_that_does_not_fit_is_noted_once(tmp_path, capsys, monkeypatch):
    # run from the scene's parent folder, roadmaps/<name>.json "here" and "beside the scene's
    # folder" are one file: it was refused twice, then called "no roadmap file"
    (tmp_path / "scenes").mkdir()
    (tmp_path / "roadmaps").mkdir()
    (tmp_path / "scenes" / "sim-4s1m.yaml").write_text(SCENE.read_text())
    (tmp_path / "roadmaps" / "sim-4s1m.json").write_text((ROOT / "roadmaps" / "building-floor.json").read_text())
    monkeypatch.chdir(tmp_path)
    assert main(["plan", "scenes/sim-4s1m.yaml", "-o", "a.json"]) == 0
    err = capsys.readouterr().err
    assert err.count("note: not using") == 1 and "built for scene 'building-floor'" in err
    assert "note: no roadmap file fits 'sim-4s1m'; building one" in err


def test_every_argument_of_every_command_has_a_help_text():
    # `gfuzzy plan --help` listed SCENE with nothing beside it (10 arguments so)
    from gfuzzy.cli.main import _parser

    (sub,) = [a for a in _parser()._actions if a.dest == "command"]
    bare = [(name, a.dest) for name, p in sub.choices.items() for a in p._actions if not a.help]
    assert bare == []


def test_plan_help_says_which_robots_give_a_heading(capsys):
    # it said "X Y (disc) or X Y H (box)": a footprint, and a unicycle disc, need H too
    with pytest.raises(SystemExit):
        main(["plan", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "footprint" in text and "unicycle" in text


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


def _in_process(capsys, monkeypatch, folder):
    """``run(*args)`` -> (returncode, stdout, stderr) of ``gfuzzy ARGS`` in this process, run
    from ``folder`` (a real process costs a second of imports a call; the program's own
    process is tested in tests/test_scene.py's *_subprocess tests and tests/test_interrupt.py)."""
    import types

    monkeypatch.chdir(folder)

    def run(*args):
        rc, out, err = _run(capsys, *args)
        return types.SimpleNamespace(returncode=rc, stdout=out, stderr=err)

    return run


def test_cli_hold_and_check(tmp_path, capsys, monkeypatch):
    run = _in_process(capsys, monkeypatch, tmp_path)
    path = tmp_path / "loop.yaml"
    path.write_text(LOOP)
    out = tmp_path / "a.json"
    r = run("plan", path, "-n", "60", "--seed", "1", "-o", out)
    assert r.returncode == 0, r.stderr
    assert run("check", path, out).returncode == 0
    # the same start and goal as an ad-hoc query with --hold 2: it waits
    r = run("plan", path, "-n", "60", "--seed", "1", "--start", "1", "3", "--goal", "4", "3",
                        "--hold", "2", "-o", out)  # fmt: skip
    assert r.returncode == 0, r.stderr
    wps = np.array(json.loads(out.read_text())["waypoints"])
    scene = load_scene(path)
    assert check_trajectory(scene, wps, scene.queries[0]).valid
    assert run("check", path, out, "--hold", "2").returncode == 0
    # without the hold the ad-hoc answer arrives as early as it can, and parks in the cart's way
    r = run("plan", path, "-n", "60", "--seed", "1", "--start", "1", "3", "--goal", "4", "3",
                        "-o", out)  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert run("check", path, out).returncode == 0
    bad = run("check", path, out, "--hold", "2")
    assert bad.returncode == 1 and "cart" in bad.stderr
    bad = run("plan", path, "--hold", "-1")
    assert bad.returncode == 2 and "--hold" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1


def test_cli_overrides_rebuild_the_roadmap_and_check_enforces_them(tmp_path, capsys, monkeypatch):
    """--clearance changes the roadmap (said on stderr, built with the saved options);
    check with the same overrides accepts the answer, with a larger one refuses it."""
    run = _in_process(capsys, monkeypatch, tmp_path)
    path = tmp_path / "scenes" / "door.yaml"
    path.parent.mkdir()
    path.write_text(DOOR.replace(", clearance: 0.05", ""))
    r = run("roadmap", path, "-n", "80", "--seed", "2")
    assert r.returncode == 0, r.stderr
    out = tmp_path / "a.json"
    r = run("plan", path, "--clearance", "0.05", "--mover-clearance", "0.1", "-o", out)
    assert r.returncode == 0, r.stderr
    assert "robot.clearance=0.05" in r.stderr and "80 vertices, seed 2" in r.stderr
    assert run("check", path, out, "--clearance", "0.05").returncode == 0
    bad = run("check", path, out, "--clearance", "0.25")
    assert bad.returncode == 1 and "robot.clearance=0.25" in bad.stderr
    r = run("regress", path, "--clearance", "0.05")
    assert r.returncode == 0 and "valid" in r.stdout
    for cmd in ("plan", "regress", "check"):
        args = (path, out) if cmd == "check" else (path,)
        bad = run(cmd, *args, "--mover-clearance", "nan")
        assert bad.returncode == 2 and "--mover-clearance" in bad.stderr
        assert len(bad.stderr.strip().splitlines()) == 1


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux's /proc")
def test_an_output_folder_nothing_can_be_written_in_is_refused_before_the_work(capsys):
    # /proc: its permission bits let root write, yet no file can be made there; the old check
    # (os.access) passed for root and `gfuzzy crowd -o /proc/x.csv` ran every episode, then
    # lost them all at the write ("No such file or directory")
    code = main(["crowd", "--humans", "0", "--episodes", "1", "--policy", "orca", "-o", "/proc/x.csv"])
    err = capsys.readouterr()
    assert code == 2 and err.out == ""
    assert err.err.strip() == "/proc/x.csv: cannot write in folder /proc (No such file or directory)" or (
        "is not writable" in err.err)  # fmt: skip
    assert len(err.err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    "argv, victim",
    [
        (["plan", "{scene}", "--roadmap", "{roadmap}", "-o", "{roadmap}"], "{roadmap}"),
        (["plan", "{scene}", "--roadmap", "{roadmap}", "-o", "{roadmap_csv}"], "{roadmap}"),  # its JSON beside
        (["navigate", "{scene}", "--roadmap", "{roadmap}", "-o", "{roadmap}"], "{roadmap}"),
        (["map", "{map}", "-o", "{map}"], "{map}"),
        (["export", "{scene}", "--map", "{scene}"], "{scene}"),
        (["tracks", "{tracks}", "--static", "{scene}", "-o", "{scene}"], "{scene}"),
        (["populate", "{scene}", "--people", "2", "-o", "{scene}"], "{scene}"),
        (["plan", "{scene}", "-o", "{default_roadmap}"], "{default_roadmap}"),  # no --roadmap: read by default
        (["navigate", "{scene}", "-o", "{default_roadmap}"], "{default_roadmap}"),
    ],
)
def test_an_output_that_is_an_input_is_bad_input(tmp_path, capsys, monkeypatch, argv, victim):
    # each of these replaced the file it was reading: a roadmap by a trajectory, a map's
    # YAML by a scene naming itself as its map, a scene by a Nav2 map
    names = {
        "scene": tmp_path / "s.yaml",
        "roadmap": tmp_path / "rm.json",
        "roadmap_csv": tmp_path / "rm.csv",
        "map": tmp_path / "tb3_sandbox.yaml",
        "tracks": tmp_path / "walk.csv",
        "default_roadmap": tmp_path / "roadmaps" / "sim-4s1m.json",  # roadmaps/ in the folder run from
    }
    monkeypatch.chdir(tmp_path)
    (tmp_path / "roadmaps").mkdir()
    names["default_roadmap"].write_text((ROOT / "roadmaps" / "sim-4s1m.json").read_text())
    names["scene"].write_text((ROOT / "scenes" / "sim-4s1m.yaml").read_text())
    names["roadmap"].write_text((ROOT / "roadmaps" / "sim-4s1m.json").read_text())
    for f in ("tb3_sandbox.yaml", "tb3_sandbox.pgm"):
        (tmp_path / f).write_bytes((ROOT / "scenes" / "maps" / f).read_bytes())
    names["tracks"].write_text("t,id,x,y\n0,a,1,1\n1,a,2,2\n")
    before = {p: p.read_bytes() for p in names.values() if p.exists()}
    rc, _, err = _run(capsys, *[a.format(**names) for a in argv])
    assert rc == 2, err
    named = victim.format(**names)  # the default roadmap is named as the command finds it
    assert err.count("\n") == 1 and f"would overwrite {os.path.relpath(named) if 'roadmaps' in named else named}" in err, err
    assert {p: p.read_bytes() for p in names.values() if p.exists()} == before


def test_check_says_a_body_touching_by_a_rounding_has_clearance_0(tmp_path, capsys):
    """A box sliding along a side of the bounds at decimal coordinates (x 4.8 + half-length
    0.2 = 5) is 3.6e-16 m out of them: valid, and its clearance is 0.0000, not -0.0000."""
    scene = tmp_path / "touch.yaml"
    scene.write_text("version: 1\nname: touch\nbounds: [0, 0, 5, 5]\nrobot: {box: [0.4, 0.2], vmax: 1}\n")
    traj = _trajectory_file(tmp_path / "t.json", [[0.0, 4.8, 4.9, 0.0], [3.0, 4.8, 2.0, 0.0]], scene="touch")
    rc, out, _ = _run(capsys, "check", str(scene), str(traj))
    assert rc == 0 and "valid (min clearance 0.0000," in out, out


@pytest.mark.parametrize(
    "argv, flag",
    [
        (["plan", "scenes/depot.yaml", "--start", "1e308", "1", "0", "--goal", "2", "2", "0"], "--start"),
        (["plan", "scenes/depot.yaml", "--start", "2", "2", "0", "--goal", "-1e308", "1", "0"], "--goal"),
        (["tracks", "WALK", "--static", "scenes/depot.yaml",
          "--start", "1", "1", "0", "--goal", "1e10", "1", "0", "-o", "OUT"], "--goal"),  # fmt: skip
    ],
)
def test_a_pose_beyond_1e9_on_the_command_line_is_bad_input(tmp_path, capsys, monkeypatch, argv, flag):
    # on a map scene, 1e308 reached a cell index: an OverflowError traceback (a scene file's
    # number that large is refused: "number too large")
    monkeypatch.chdir(ROOT)
    (tmp_path / "walk.csv").write_text("t,id,x,y\n0,a,1,1\n1,a,2,2\n")
    names = {"OUT": str(tmp_path / "o.yaml"), "WALK": str(tmp_path / "walk.csv")}
    rc, _, err = _run(capsys, *[names.get(a, a) for a in argv])
    assert rc == 2 and err.count("\n") == 1, err
    assert err.startswith(f"{flag}: number too large") and "at most 1e+09 in magnitude" in err, err
    assert not (tmp_path / "o.yaml").exists()


def test_export_at_an_absurdly_fine_resolution_is_one_line(tmp_path, capsys):
    # 1e-300 m: ceil(inf) / a float of an int of 300 digits, an OverflowError traceback
    rc, _, err = _run(capsys, "export", str(ROOT / "scenes" / "sim-4s1m.yaml"), "--map", str(tmp_path / "m.yaml"),
                      "--resolution", "1e-300")  # fmt: skip
    assert rc == 2 and err.count("\n") == 1 and "use a coarser resolution" in err, err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    "argv, expect",
    [
        (["plan", "scenes/sim-4s1m.yaml", "--dt", "1e-308"], "the time step is too fine"),
        (["plan", "scenes/tb3-arena-unicycle.yaml", "--dt", "1e-308"], "the time step is too fine"),
        (["export", "scenes/sim-4s1m.yaml", "-o", "OUT.mcap", "--step", "1e-308"], "use a larger step"),
    ],
)
def test_a_step_of_1e_308_is_refused_as_too_fine_in_one_line(tmp_path, capsys, monkeypatch, argv, expect):
    # a length / 1e-308 is inf: cast to a negative count (plan: "negative dimensions", a
    # ValueError traceback) or int(inf) (export: an OverflowError traceback)
    monkeypatch.chdir(ROOT)
    rc, _, err = _run(capsys, *[str(tmp_path / "x.mcap") if a == "OUT.mcap" else a for a in argv])
    assert rc == 2 and err.count("\n") == 1 and expect in err, err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("command", ["plan", "navigate"])
def test_a_time_step_too_fine_names_the_option_as_regress_does(capsys, monkeypatch, command):
    # plan said "gfuzzy plan: the time step is too fine ..." and navigate only "the time step
    # is too fine ...", naming neither the command nor --dt (regress: "gfuzzy regress: --dt ...")
    monkeypatch.chdir(ROOT)
    rc, _, err = _run(capsys, command, "scenes/sim-4s1m.yaml", "--dt", "1e-9")
    assert rc == 2 and err.count("\n") == 1, err
    assert err.startswith(f"gfuzzy {command}: --dt 1e-09: the time step is too fine for this roadmap"), err


def test_regress_refuses_a_time_step_too_fine_before_its_table(capsys, monkeypatch):
    # the table's header went to stdout first, then the one-line error: bad input prints
    # nothing else (as _check_roadmap_flags already ensured for the roadmap flags)
    monkeypatch.chdir(ROOT)
    rc, out, err = _run(capsys, "regress", "scenes/sim-4s1m.yaml", "scenes/sealed-room.yaml", "--dt", "1e-6")
    assert rc == 2 and out == "" and err.count("\n") == 1, (out, err)
    assert err.startswith("gfuzzy regress: --dt 1e-06: scenes/sim-4s1m.yaml: the time step is too fine"), err


def test_a_differential_drive_whose_rings_are_too_many_is_refused_before_they_are_made(capsys, monkeypatch):
    # each ring alone fits (31,000 points at dt 1e-4), the 200 vertices' rings do not: they
    # were certified one by one until the planning budget ran out (timeout, exit 1, 60 s)
    monkeypatch.chdir(ROOT)
    rc, _, err = _run(capsys, "plan", "scenes/building-floor-unicycle.yaml", "--dt", "1e-4", "--time-limit", "5")
    assert rc == 2 and err.count("\n") == 1, err
    assert err.startswith("gfuzzy plan: --dt 0.0001: the time step is too fine for this roadmap"), err


def _timed_out_file(path, executed, scene="line"):
    """A navigate run that did not arrive: no waypoints, its motion under ``executed``."""
    doc = json.loads(_trajectory_file(path, None, scene=scene, query="up", status="timeout").read_text())
    doc["executed"] = executed
    path.write_text(json.dumps(doc))
    return path


@pytest.mark.parametrize(
    "executed, place",
    [
        ([[0, 1, 2.5], [1, 1.5, 2.5, 0]], "executed[1]: expected 3 numbers"),  # was a traceback
        ([["0", "1", "2.5"], ["1", "1.5", "2.5"]], "executed[0][0]: expected a finite number, got '0'"),
        ([[0, 1, 2.5], [True, 1.5, 2.5]], "executed[1][0]: expected a finite number, got True"),
        # a JSON integer past a float's range: an OverflowError traceback (check, render, export)
        ([[0, 1, 2.5], [10**400, 1.5, 2.5]], "executed[1][0]: expected a finite number, got 1000000"),
        ([[0, 1, 2.5], [0, 1.5, 2.5]], "executed[1][0]: t=0.0 does not increase"),
        # beyond a scene's bound: shapely's two-line overflow warning, then a verdict (check, render)
        ([[0, 1, 2.5], [1, 1e300, 2.5]], "executed[1][1]: number too large (1e+300; at most 1e+09 in magnitude)"),
        # rows of a box robot ("there is no trajectory to check")
        ([[0, 1, 2.5, 0], [1, 1.5, 2.5, 0]], "executed: rows of 4 numbers, but scene 'line' expects [t, x, y] for this disc robot"),
    ],
)
@pytest.mark.parametrize("command", ["check", "render", "export"])
def test_a_timed_out_runs_executed_rows_are_read_one_way(line_scene, tmp_path, capsys, executed, place, command):
    nav = _timed_out_file(tmp_path / "nav.json", executed)
    out = {"check": [], "render": ["-o", tmp_path / "t.png", "--no-roadmap"], "export": ["-o", tmp_path / "t.mcap"]}
    rc, _, err = _run(capsys, command, line_scene, nav, *out[command])
    assert rc == 2 and err.strip().splitlines() == [err.strip()], err
    assert err.startswith(f"{nav}: {place}"), err
    assert not list(tmp_path.glob("t.*"))


def test_check_of_a_timed_out_run_says_what_is_wrong_with_its_motion(line_scene, tmp_path, capsys):
    # too fast (3 m in 1 s at vmax 1): called valid when the verdict was dropped
    nav = _timed_out_file(tmp_path / "nav.json", [[0, 1, 2.5], [1, 4, 2.5]])
    rc, _, err = _run(capsys, "check", line_scene, nav)
    assert rc == 1 and err == (
        f"{nav}: status is timeout: the goal was not reached, no answer to check; the motion it "
        "executed (2 rows, t 0 to 1) is invalid: speed 3 exceeds vmax 1 between t=0.0 and t=1.0\n"
    ), err
    # one row is "1 row"; a file of another scene is noted, as a solved one is
    nav = _timed_out_file(tmp_path / "nav.json", [[0, 1, 2.5]], scene="elsewhere")
    rc, _, err = _run(capsys, "check", line_scene, nav)
    assert rc == 1 and err.splitlines()[0] == f"note: {nav} was planned for scene 'elsewhere', checking against 'line'"
    assert "the motion it executed (1 row, t 0 to 0) is valid" in err.splitlines()[1], err


@pytest.mark.parametrize("duration", ["NaN", "Infinity"])
def test_check_refuses_a_duration_that_is_no_number(line_scene, tmp_path, capsys, duration):
    # a hand-edited "duration": NaN (Python's json reads it) passed check as valid (found by s39-newuser)
    path = _trajectory_file(tmp_path / "t.json", [[0, 1, 2.5], [1, 1.5, 2.5]])
    doc = json.loads(path.read_text())
    path.write_text(json.dumps({**doc, "duration": 0.0}).replace('"duration": 0.0', f'"duration": {duration}'))
    rc, _, err = _run(capsys, "check", line_scene, path)
    assert rc == 1 and err.splitlines()[-1] == f"{path}: duration is {float(duration)!r} but the rows span 1.0", err


def test_render_and_export_note_a_duration_the_rows_disagree_with_as_check_says_it(line_scene, tmp_path, capsys):
    # check said "duration is 5.0 but the rows span 1.0"; render and export drew it silently
    path = _trajectory_file(tmp_path / "t.json", [[0, 1, 2.5], [1, 1.5, 2.5]])
    doc = json.loads(path.read_text())
    path.write_text(json.dumps({**doc, "duration": 5.0}))
    said = f"{path}: duration is 5.0 but the rows span 1.0"
    rc, _, err = _run(capsys, "check", line_scene, path)
    assert rc == 1 and err.splitlines()[-1] == said, err
    rc, _, err = _run(capsys, "render", line_scene, path, "--no-roadmap", "-o", tmp_path / "t.png")
    assert rc == 0 and err == f"note: {said} (`gfuzzy check` exits 1); drawing it anyway\n", err
    rc, _, err = _run(capsys, "export", line_scene, path, "-o", tmp_path / "t.mcap")
    assert rc == 0 and err == f"note: {said} (`gfuzzy check` exits 1); exported anyway\n", err
