"""Pedestrian tracks (`gfuzzy tracks`, gfuzzy.read_tracks / tracks_scene): tiny hand-made
files with hand-computed answers, round trips to scenes that load and plan, bad files, and
the bundled pedestrian scenes made again from the excerpts in data/pedestrians/."""

from __future__ import annotations

import math
import shlex
import shutil
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, run_cli_process
from helpers import main_completed, run_main
from hypothesis import given, settings
from hypothesis import strategies as st

import gfuzzy
from gfuzzy.check.check import check_trajectory
from gfuzzy.errors import InputError
from gfuzzy.planner.planner import Planner, PlanOptions, Status
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap
from gfuzzy.scene.scene import load_scene, parse_scene
from gfuzzy.scene.tracks import TrackSceneOptions, read_tracks, tracks_scene

# frame step 10 (so 25 frames/s): person 1 walks +x at 2.5 m/s, person 2 appears later,
# person 3 has velocity columns; rows of different people interleave as in the data sets
ETH = """\
# frame id x y [vx vy]
0\t1\t0.0\t0.0
10\t1\t1.0\t0.0
10\t2\t5.0\t5.0
20\t1\t2.0\t0.0
20\t2\t5.0\t6.0
20\t3\t8.0\t1.0\t0.1\t0.2
30\t1\t3.0\t0.0
30\t3\t8.0\t2.0\t0.1\t0.2
"""

CSV = """\
id,t,x,y,note
a,0.0,0,0,first
b,0.5,1,1,
a,1.0,2,0,
b,1.5,1,3,
a,2.0,4,0,last
"""


@pytest.fixture
def eth_file(tmp_path):
    path = tmp_path / "walk.txt"
    path.write_text(ETH, encoding="utf-8")
    return path


@pytest.fixture
def csv_file(tmp_path):
    path = tmp_path / "walk.csv"
    path.write_text(CSV, encoding="utf-8")
    return path


def _rows(tracks, pid):
    return next(tr for tr in tracks.tracks if tr.id == pid).rows


# ------------------------------------------------------------------------- reading


def test_eth_frames_become_seconds_0_4_apart(eth_file):
    tracks = read_tracks(eth_file)
    assert tracks.format == "eth" and tracks.frame_step == 10 and tracks.fps == pytest.approx(25.0)
    assert [tr.id for tr in tracks.tracks] == ["1", "2", "3"]
    np.testing.assert_allclose(
        _rows(tracks, "1"), [[0, 0, 0], [0.4, 1, 0], [0.8, 2, 0], [1.2, 3, 0]]
    )
    np.testing.assert_allclose(_rows(tracks, "2"), [[0.4, 5, 5], [0.8, 5, 6]])
    np.testing.assert_allclose(_rows(tracks, "3"), [[0.8, 8, 1], [1.2, 8, 2]])  # vx vy ignored
    assert tracks.time_range == pytest.approx((0.0, 1.2))


def test_eth_with_a_given_frame_rate(eth_file):
    tracks = read_tracks(eth_file, "eth", fps=10.0)
    np.testing.assert_allclose(_rows(tracks, "1")[:, 0], [0, 1, 2, 3])
    assert tracks.fps == 10.0


def test_csv_columns_by_header_name(csv_file):
    tracks = read_tracks(csv_file)
    assert tracks.format == "csv" and tracks.fps is None
    np.testing.assert_allclose(_rows(tracks, "a"), [[0, 0, 0], [1, 2, 0], [2, 4, 0]])
    np.testing.assert_allclose(_rows(tracks, "b"), [[0.5, 1, 1], [1.5, 1, 3]])


def test_format_is_sniffed_from_the_content(tmp_path):
    path = tmp_path / "walk.data"
    path.write_text(CSV, encoding="utf-8")
    assert read_tracks(path).format == "csv"
    path.write_text(ETH, encoding="utf-8")
    assert read_tracks(path).format == "eth"


# ------------------------------------------------------------------------- scenes


def _movers(made):
    return {m["name"]: np.array(m["trajectory"]) for m in made.doc["movers"]}


def test_window_clips_and_interpolates_at_its_edges(eth_file):
    made = tracks_scene(
        read_tracks(eth_file), TrackSceneOptions(t_start=0.2, duration=0.4, region=(-1, -1, 10, 10))
    )
    movers = _movers(made)
    # person 1: x = 2.5 t; the window 0.2 .. 0.6 s starts mid-row and ends mid-row
    np.testing.assert_allclose(movers["ped-1"], [[0.0, 0.5, 0], [0.2, 1.0, 0], [0.4, 1.5, 0]])
    # person 2 enters at 0.4 s (0.2 s into the window), is clipped at 0.6 s (y = 5.5)
    np.testing.assert_allclose(movers["ped-2"], [[0.2, 5, 5], [0.4, 5, 5.5]])
    assert "ped-3" not in movers  # arrives at 0.8 s, after the window
    assert made.window == pytest.approx((0.2, 0.6))


def test_people_who_enter_and_leave_exist_only_while_recorded(eth_file):
    made = tracks_scene(read_tracks(eth_file), TrackSceneOptions(region=(-1, -1, 10, 10)))
    scene = parse_scene(made.doc)
    ranges = {m.name: m.time_range for m in scene.movers}
    assert ranges == {"ped-1": (0.0, 1.2), "ped-2": (0.4, 0.8), "ped-3": (0.8, 1.2)}
    person = next(m for m in scene.movers if m.name == "ped-2")
    _, present = person.state(np.array([0.3, 0.5, 0.9]))
    assert present.tolist() == [False, True, False]


def test_region_cuts_tracks_and_a_return_is_a_second_mover(csv_file):
    # a walks x 0 -> 4 (2 m/s): inside 1 <= x <= 3 from t 0.5 to 1.5; b walks y 1 -> 3
    made = tracks_scene(read_tracks(csv_file), TrackSceneOptions(region=(1, -1, 3, 2)))
    movers = _movers(made)
    np.testing.assert_allclose(movers["ped-a"], [[0.5, 1, 0], [1.0, 2, 0], [1.5, 3, 0]])
    np.testing.assert_allclose(movers["ped-b"], [[0.5, 1, 1], [1.0, 1, 2]])  # leaves at y = 2
    assert made.region == (1.0, -1.0, 3.0, 2.0)
    # c walks x 0 -> 2 -> 0: through 1 <= x <= 1.5 out and back again, two movers
    tracks = gfuzzy.Tracks(
        "mem",
        "csv",
        None,
        None,
        (gfuzzy.Track("c", np.array([[0, 0, 0], [1, 2, 0], [2, 0, 0]], float)),),
    )
    movers = _movers(tracks_scene(tracks, TrackSceneOptions(region=(1, -1, 1.5, 1))))
    np.testing.assert_allclose(movers["ped-c"], [[0.5, 1, 0], [0.75, 1.5, 0]])
    np.testing.assert_allclose(movers["ped-c-2"], [[1.25, 1.5, 0], [1.5, 1, 0]])


def test_a_part_skips_the_name_another_persons_id_gives():
    # 1 lost for 7 s is two movers; its second is not 'ped-1-2' when someone's id is '1-2'
    # (the scene had two movers of that name: `gfuzzy tracks` refused its own output, exit 2)
    rows = np.array([[0, 0, 0], [1, 1, 0], [8, 8, 0], [9, 9, 0]], float)
    other = np.array([[0, 5, 5], [1, 5, 6]], float)
    tracks = gfuzzy.Tracks("mem", "csv", None, None, (gfuzzy.Track("1", rows), gfuzzy.Track("1-2", other)))
    made = tracks_scene(tracks, TrackSceneOptions(max_gap=2.0))
    movers = _movers(made)
    assert sorted(movers) == ["ped-1", "ped-1-2", "ped-1-3"]
    np.testing.assert_allclose(movers["ped-1-2"], other)
    np.testing.assert_allclose(movers["ped-1-3"], rows[2:])
    assert [m.name for m in parse_scene(made.doc, file="mem").movers] == list(movers)


def test_a_person_unseen_for_longer_than_max_gap_is_two_movers(tmp_path, caplog, capsys):
    # a tracker lost d from 1 s to 8 s: one mover walked a straight line through the gap (a
    # phantom where nobody was seen); the rows before and after are two movers, absent between
    rows = np.array([[0, 0, 0], [1, 1, 0], [8, 8, 0], [9, 9, 0], [9.5, 9.5, 0]], float)
    tracks = gfuzzy.Tracks("mem", "csv", None, None, (gfuzzy.Track("d", rows),))
    movers = _movers(tracks_scene(tracks, TrackSceneOptions(max_gap=2.0)))
    np.testing.assert_allclose(movers["ped-d"], [[0, 0, 0], [1, 1, 0]])
    np.testing.assert_allclose(movers["ped-d-2"], rows[2:])
    assert list(_movers(tracks_scene(tracks, TrackSceneOptions(max_gap=7.0)))) == ["ped-d"]  # 7 s: not longer
    assert list(_movers(tracks_scene(tracks, TrackSceneOptions(max_gap=math.inf)))) == ["ped-d"]
    # parts of one row are dropped, the movers numbered as kept: only 9 -> 9.5 s is left
    np.testing.assert_allclose(_movers(tracks_scene(tracks, TrackSceneOptions(max_gap=0.6)))["ped-d"], rows[3:])
    # by default, five times the person's own median spacing (1 s here): cut at a 7 s or a
    # 5.05 s gap, not at 4.9 s; the cut is logged
    caplog.set_level("WARNING", logger="gfuzzy.scene.tracks")
    caplog.clear()
    assert list(_movers(tracks_scene(tracks))) == ["ped-d", "ped-d-2"]
    (msg,) = [r.getMessage() for r in caplog.records]
    assert msg.startswith("ped-d unseen for 7 s from t = 1 s (more than 5 s): absent in between")
    for gap, movers in ((5.05, ["ped-d", "ped-d-2"]), (4.9, ["ped-d"])):
        near = np.array([[0, 0, 0], [1, 1, 0], [1 + gap, 2, 0], [2 + gap, 3, 0], [2.5 + gap, 3.5, 0]], float)
        assert list(_movers(tracks_scene(gfuzzy.Tracks("mem", "csv", None, None, (gfuzzy.Track("d", near),))))) == movers
    sparse = gfuzzy.Track("e", rows[[0, 2]])  # keyframes 8 s apart are that person's pace
    assert list(_movers(tracks_scene(gfuzzy.Tracks("mem", "csv", None, None, (sparse,))))) == ["ped-e"]
    # beside someone tracked every 0.5 s, too (the file's pooled median cut e away, unnoticed)
    dense = gfuzzy.Track("a", np.array([[t, t, 1.0] for t in np.arange(0, 8.5, 0.5)]))
    assert list(_movers(tracks_scene(gfuzzy.Tracks("mem", "csv", None, None, (dense, sparse))))) == ["ped-a", "ped-e"]
    for bad in (0, -1, math.nan, True):
        with pytest.raises(gfuzzy.errors.InputError, match="max_gap must be positive"):
            TrackSceneOptions(max_gap=bad)
    csv = tmp_path / "lost.csv"
    csv.write_text("t,id,x,y\n" + "".join(f"{t:g},d,{x:g},{y:g}\n" for t, x, y in rows))
    out = tmp_path / "lost.yaml"
    run = main_completed(capsys, "tracks", str(csv), "-o", str(out), "--max-gap", "inf")
    assert run.returncode == 0, run.stderr
    assert "--max-gap inf" in out.read_text() and [m.name for m in load_scene(out).movers] == ["ped-d"]


def test_a_person_seen_once_is_dropped_aloud(tmp_path, caplog, capsys):
    # a user's file with one row for some people (a detector's single hit): they were
    # dropped without a word, and a file of such rows only was "no pedestrian in the window"
    walk = gfuzzy.Track("a", np.array([[0, 0, 0], [1, 1, 0]], float))
    once = gfuzzy.Track("b", np.array([[0.5, 2, 2]], float))
    caplog.set_level("WARNING", logger="gfuzzy.scene.tracks")
    caplog.clear()
    assert list(_movers(tracks_scene(gfuzzy.Tracks("mem", "csv", None, None, (walk, once))))) == ["ped-a"]
    (msg,) = [r.getMessage() for r in caplog.records]
    assert msg.startswith("ped-b is seen at one instant only in the window (t = 0.5 s): dropped")
    csv = tmp_path / "once.csv"
    csv.write_text("t,id,x,y\n0,a,1,1\n0,b,-1,1\n0.5,c,0,2\n")
    run = main_completed(capsys, "tracks", str(csv), "-o", str(tmp_path / "once.yaml"))  # its process: _make
    assert run.returncode == 2 and not (tmp_path / "once.yaml").exists()
    assert run.stderr.strip() == (f"{csv}: 3 pedestrian(s) in the window 0 s .. 0.5 s, each seen at one instant only: "
                                  "a mover needs two rows or more (someone standing still: a row at the first time "
                                  "and one at the last)")


def test_a_person_seen_once_once_rounded_is_dropped_aloud(tmp_path, caplog, capsys):
    # two rows 0.4 ms apart are one row at 1 ms: a was dropped without a word (counted
    # before rounding), and with b and c seen once too the error said nobody was inside
    csv = tmp_path / "close.csv"
    csv.write_text("t,id,x,y\n0,a,0,0\n0.0004,a,1,0\n0.5,b,2,2\n0.9,c,1,1\n")
    caplog.set_level("WARNING", logger="gfuzzy.scene.tracks")
    caplog.clear()
    with pytest.raises(gfuzzy.errors.SceneError) as err:
        tracks_scene(read_tracks(csv))
    assert str(err.value).endswith("3 pedestrian(s) inside the region -0.5 -0.5 2.5 2.5 during the window, each seen at "
                                   "one instant only: a mover needs two rows or more (someone standing still: a row "
                                   "at the first time and one at the last)")
    assert [r.getMessage().split(":")[0] for r in caplog.records] == [
        f"ped-{p} is seen at one instant only in the window (t = {t} s)" for p, t in (("a", 0), ("b", 0.5), ("c", 0.9))]
    run = main_completed(capsys, "tracks", str(csv), "-o", str(tmp_path / "close.yaml"))
    assert run.returncode == 2 and not (tmp_path / "close.yaml").exists()
    assert run.stderr.strip().splitlines()[-1].startswith(f"{csv}: 3 pedestrian(s) inside the region")


def test_the_warnings_say_the_recordings_time(caplog):
    # with the window starting at 0.5 s, a row at 5 s was said to be at 4.5 s (the
    # window's own time) by the seen-once and the --max-gap warnings
    rows = np.array([[0, 0, 0], [1, 1, 0], [8, 8, 0], [9, 9, 0], [9.5, 9.5, 0]], float)
    tracks = gfuzzy.Tracks("mem", "csv", None, None, (gfuzzy.Track("d", rows), gfuzzy.Track("b", np.array([[5.0, 2, 2]]))))
    caplog.set_level("WARNING", logger="gfuzzy.scene.tracks")
    caplog.clear()
    assert list(_movers(tracks_scene(tracks, TrackSceneOptions(t_start=0.5)))) == ["ped-d", "ped-d-2"]
    assert sorted(r.getMessage().split(":")[0] for r in caplog.records) == [
        "ped-b is seen at one instant only in the window (t = 5 s)",
        "ped-d unseen for 7 s from t = 1 s (more than 5 s)"]


def test_scale_and_default_region(csv_file):
    made = tracks_scene(read_tracks(csv_file), TrackSceneOptions(scale=0.5))
    np.testing.assert_allclose(_movers(made)["ped-a"], [[0, 0, 0], [1, 1, 0], [2, 2, 0]])
    # the people's extent (x 0..2, y 0..1.5) plus 0.5 m, rounded out to 0.1 m
    assert made.region == (-0.5, -0.5, 2.5, 2.0)


def test_offset_shifts_the_scaled_positions(tmp_path, csv_file, capsys):
    # a detector's CSV in a frame whose origin is not the map's could not be shifted: the
    # file had to be rewritten by hand
    made = tracks_scene(read_tracks(csv_file), TrackSceneOptions(scale=0.5, offset=(-3.25, 7.5)))
    np.testing.assert_allclose(_movers(made)["ped-a"], [[0, -3.25, 7.5], [1, -2.25, 7.5], [2, -1.25, 7.5]])
    assert made.region == (-3.8, 7.0, -0.7, 9.5)  # the shifted extent (x -3.25..-1.25, y 7.5..9) + 0.5 m, rounded out
    out = tmp_path / "shifted.yaml"
    rc, stdout, err = run_main(capsys, "tracks", csv_file, "--scale", "0.5", "--offset", "-3.25", "7.5", "-o", out)
    assert rc == 0, err
    scene = load_scene(out)
    (ped_a,) = [m for m in scene.movers if m.name == "ped-a"]
    np.testing.assert_allclose(ped_a.trajectory[:, 1:], [[-3.25, 7.5], [-2.25, 7.5], [-1.25, 7.5]])
    assert "--offset -3.25 7.5" in out.read_text().splitlines()[1]  # the command that made it, in the header
    for flags, expect in [(["--offset", "1e300", "0"], "gfuzzy tracks: offset must be two finite numbers"),
                          (["--offset", "0", "nan"], "gfuzzy tracks: offset must be two finite numbers"),
                          (["--offset", "1"], "gfuzzy tracks: argument --offset: expected 2 arguments")]:  # fmt: skip
        bad = tmp_path / "bad.yaml"
        rc, stdout, err = run_main(capsys, "tracks", csv_file, *flags, "-o", bad)
        assert rc == 2 and err.startswith(expect) and err.count("\n") == 1, err
        assert not bad.exists()
    with pytest.raises(InputError, match="offset must be two finite numbers"):
        TrackSceneOptions(offset=(1.0,))


@pytest.mark.parametrize("n", ["0", "-1"])
def test_max_movers_below_one_is_refused(tmp_path, csv_file, capsys, n):
    # 0 wrote a scene with no movers at all
    out = tmp_path / "o.yaml"
    rc, _, err = run_main(capsys, "tracks", csv_file, "--max-movers", n, "-o", out)
    assert rc == 2 and err == f"gfuzzy tracks: max_movers must be at least 1, got {n}\n", err
    assert not out.exists()


def test_max_movers_keeps_those_present_longest(eth_file):
    made = tracks_scene(
        read_tracks(eth_file), TrackSceneOptions(region=(-1, -1, 10, 10), max_movers=2)
    )
    assert sorted(_movers(made)) == ["ped-1", "ped-2"]  # 1.2 s, then the 0.4 s tie broken by id


def test_python_api_round_trip_plans(tmp_path, csv_file):
    made = gfuzzy.tracks_scene(
        gfuzzy.read_tracks(csv_file),
        gfuzzy.TrackSceneOptions(region=(-1, -1, 5, 4), name="walk", robot_radius=0.2, vmax=1.0),
        start=(4.5, 3.5),
        goal=(-0.5, 3.5),
    )
    path = tmp_path / "walk.yaml"
    path.write_text(made.to_yaml("made by a test"), encoding="utf-8")
    scene = load_scene(path)
    assert scene.name == "walk" and len(scene.movers) == 2 and scene.robot.vmax == 1.0
    assert scene.to_dict()["movers"] == made.doc["movers"]
    roadmap = build_roadmap(scene, RoadmapOptions(vertices=60, seed=1))
    q = scene.queries[0]
    res = Planner(scene, roadmap).plan(q.start, q.goal, q.t0)
    assert res.solved, res.message
    assert check_trajectory(scene, res.trajectory.waypoints, q).valid


# ------------------------------------------------------------------------- the command


def test_command_writes_a_scene_that_loads_and_plans(tmp_path, eth_file, capsys):
    out = tmp_path / "scene.yaml"
    proc = main_completed(
        capsys, "tracks", eth_file, "--region", -1, -1, 10, 10, "--start", 0, 9, "--goal", 9, 9,
        "--expect", "solved", "-o", out,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    scene = load_scene(out)
    assert scene.name == "scene" and len(scene.movers) == 3
    assert scene.queries[0].expect.status == "solved"
    assert out.read_text().splitlines()[1].startswith("#   gfuzzy tracks ")
    proc = main_completed(capsys, "regress", out, "-n", 60)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_command_takes_obstacles_and_robot_from_a_static_scene(tmp_path, eth_file, capsys):
    out = tmp_path / "office-people.yaml"
    static = ROOT / "scenes" / "office-polygons.yaml"
    proc = main_completed(capsys, "tracks", eth_file, "--static", static, "-o", out)
    assert proc.returncode == 0, proc.stderr
    scene, office = load_scene(out), load_scene(static)
    assert scene.bounds == office.bounds and scene.robot == office.robot
    assert scene.static_hash == office.static_hash and len(scene.movers) == 3
    assert scene.queries == ()
    # a smaller disc robot in the same office keeps the office robot's speed bounds
    proc = main_completed(capsys, "tracks", eth_file, "--static", static, "--robot-radius", 0.1, "-o", out)
    assert proc.returncode == 0, proc.stderr
    robot = load_scene(out).robot
    assert (robot.shape, robot.radius, robot.vmax, robot.amax) == (
        "disc",
        0.1,
        office.robot.vmax,
        office.robot.amax,
    )


def test_a_differential_drive_from_a_static_scene_is_written_as_yaml(tmp_path, eth_file, capsys):
    """A robot with `kinematics: unicycle` (a string-valued key): the scene was written
    with the scalar's document-end marker (`kinematics: unicycle` then `...`), and
    `gfuzzy tracks` refused its own output ("invalid YAML")."""
    static = tmp_path / "robot.yaml"
    static.write_text(
        "version: 1\nname: robot\nbounds: [-1, -1, 12, 8]\nobstacles: []\nrobot:\n"
        "  footprint: [[0.3, 0.0], [-0.2, 0.2], [-0.2, -0.2]]\n  kinematics: unicycle\n  wmax: 1.5\n"
        "  reverse: true\n  vmax: 1.0\n",
        encoding="utf-8",
    )
    out = tmp_path / "drive.yaml"
    proc = main_completed(capsys, "tracks", eth_file, "--static", static, "--start", 0, 0, 0, "--goal", 5, 5, 1.57, "-o", out)
    assert proc.returncode == 0, proc.stderr
    robot = load_scene(out).robot
    assert (robot.kinematics, robot.wmax, robot.reverse) == ("unicycle", 1.5, True)
    assert load_scene(out).queries[0].start == (0.0, 0.0, 0.0)


def test_tracks_writes_a_differential_drive_as_map_does(tmp_path, eth_file, capsys):
    """`--kinematics`, `--reverse` and `--wmax`, as `gfuzzy map` takes them: a tracks scene's
    robot could only be a holonomic disc, or --static's drive as it was."""
    out = tmp_path / "drive.yaml"
    argv = ["tracks", eth_file, "--kinematics", "unicycle", "--wmax", "0.5", "--reverse",
            "--start", 0, 0, 0, "--goal", 5, 5, 1.57, "-o", out]  # fmt: skip
    rc, _, err = run_main(capsys, *argv)
    assert rc == 0, err
    scene = load_scene(out)
    assert (scene.robot.shape, scene.robot.kinematics, scene.robot.wmax, scene.robot.reverse) == (
        "disc", "unicycle", 0.5, True)  # fmt: skip
    assert scene.queries[0].start == (0.0, 0.0, 0.0)  # a differential drive's poses carry a heading
    assert "--wmax 0.5" in out.read_text().splitlines()[1] and "--reverse" in out.read_text().splitlines()[1]
    # a static differential drive made holonomic: its wmax and reverse go too, poses lose the heading
    static = tmp_path / "robot.yaml"
    static.write_text("version: 1\nname: robot\nbounds: [-1, -1, 12, 8]\nobstacles: []\nrobot:\n"
                      "  disc: 0.2\n  kinematics: unicycle\n  wmax: 1.5\n  reverse: true\n  vmax: 1.0\n", encoding="utf-8")  # fmt: skip
    rc, _, err = run_main(capsys, "tracks", eth_file, "--static", static, "--kinematics", "holonomic",
                          "--start", 0, 0, "--goal", 5, 5, "-o", out)  # fmt: skip
    assert rc == 0, err
    robot = load_scene(out).robot
    assert (robot.kinematics, robot.wmax, robot.reverse) == ("holonomic", None, False)
    rc, _, err = run_main(capsys, "tracks", eth_file, "--static", static, "--wmax", "0.7", "-o", out)
    assert rc == 0 and load_scene(out).robot.wmax == 0.7, err  # --static's drive, another turning rate
    bad = tmp_path / "bad.yaml"
    for flags, expect in [(["--wmax", "0.5"], "gfuzzy tracks: wmax (--wmax) needs a differential drive"),
                          (["--reverse"], "gfuzzy tracks: reverse (--reverse) needs a differential drive"),
                          (["--kinematics", "unicycle", "--wmax", "0"], "gfuzzy tracks: wmax must be positive"),
                          (["--kinematics", "unicycle", "--wmax", "1e300"], "gfuzzy tracks: wmax must be at most 1e+09")]:  # fmt: skip
        rc, _, err = run_main(capsys, "tracks", eth_file, *flags, "-o", bad)
        assert rc == 2 and err.startswith(expect) and err.count("\n") == 1, err
        assert not bad.exists()


def test_a_smaller_disc_keeps_a_differential_drive_and_its_headings(tmp_path, eth_file, capsys):
    """`--robot-radius` on a unicycle scene makes a disc unicycle, whose poses carry a
    heading: the command took only [x, y] for its start and goal, and then refused the
    scene it had written (its start had no heading)."""
    static = ROOT / "scenes" / "building-floor-unicycle.yaml"
    out = tmp_path / "small-drive.yaml"
    args = ("--static", static, "--robot-radius", 0.2, "--start", 1, 1, 0, "--goal", 7, 1, 0, "-o", out)
    proc = main_completed(capsys, "tracks", eth_file, *args)
    assert proc.returncode == 0, proc.stderr
    scene = load_scene(out)
    assert (scene.robot.shape, scene.robot.kinematics, scene.robot.dof) == ("disc", "unicycle", 3)
    assert scene.queries[0].start == (1.0, 1.0, 0.0)
    proc = main_completed(capsys, "tracks", eth_file, *args[:4], "--start", 1, 1, "--goal", 7, 1, "-o", out)
    assert proc.returncode == 2 and "--start: expected 3 numbers (x y heading)" in proc.stderr
    with pytest.raises(InputError, match=r"start: expected 3 numbers \[x, y, heading\]"):
        tracks_scene(
            read_tracks(eth_file), TrackSceneOptions(name="drive", robot_radius=0.2), static=load_scene(static),
            start=(1, 1), goal=(7, 1),
        )  # fmt: skip


def test_static_mesh_paths_follow_the_new_file(tmp_path, csv_file, capsys):
    folder = tmp_path / "warehouse"
    shutil.copytree(ROOT / "scenes" / "meshes", folder / "meshes")
    shutil.copy(ROOT / "scenes" / "warehouse-mesh.yaml", folder / "warehouse-mesh.yaml")
    out = tmp_path / "people.yaml"  # one folder up: the mesh is now warehouse/meshes/...
    proc = main_completed(
        capsys, "tracks", csv_file, "--static", folder / "warehouse-mesh.yaml", "--scale", 2,
        "--start", 0.6, 0.6, 0, "--goal", 11.4, 0.6, 0, "-o", out,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    scene = load_scene(out)
    assert scene.static_hash == load_scene(folder / "warehouse-mesh.yaml").static_hash
    assert "file: warehouse/meshes/" in out.read_text()
    # written into a folder the mesh is not inside: refused, nothing written
    deeper = folder / "sub" / "people.yaml"
    deeper.parent.mkdir()
    proc = main_completed(
        capsys, "tracks", csv_file, "--static", folder / "warehouse-mesh.yaml", "-o", deeper
    )
    assert proc.returncode == 2 and "obstacles[0].mesh.file" in proc.stderr
    assert not deeper.exists()


@pytest.mark.parametrize(
    "name, text, where",
    [
        ("cols.txt", "0 1 0 0\n10 1 1\n", "cols.txt: line 2: expected 4 or 6 columns"),
        ("nan.txt", "0 1 0 0\n10 1 x 0\n", "nan.txt: line 2: not a number"),
        ("inf.txt", "0 1 0 0\n10 1 inf 0\n", "inf.txt: line 2: non-finite"),
        ("frac.txt", "0 1 0 0\n10.5 1 1 0\n", "frac.txt: line 2: frame and pedestrian id must be whole"),
        ("back.txt", "0 1 0 0\n10 1 1 0\n# a comment\n5 1 2 0\n", "back.txt: line 4: pedestrian 1: frame 5 does not increase"),
        ("twice.txt", "0 1 0 0\n0 1 1 0\n", "twice.txt: line 2: pedestrian 1: frame 0 does not increase"),
        ("empty.txt", "# nothing\n\n", "empty.txt: no data rows"),
        ("lonely.txt", "0 1 0 0\n10 2 1 0\n", "lonely.txt: no pedestrian has two rows"),
        ("hdr.csv", "t,x,y\n0,0,0\n", "hdr.csv: line 1: the header must name the columns t, id, x, y (missing: id)"),
        ("short.csv", "t,id,x,y\n0,a,0,0\n1,a,1\n", "short.csv: line 3: expected 4 columns, got 3"),
        ("word.csv", "t,id,x,y\n0,a,0,0\n1,a,one,0\n", "word.csv: line 3: not a number"),
        ("order.csv", "t,id,x,y\n1,a,0,0\n1,b,0,0\n0.5,a,1,0\n", "order.csv: line 4: pedestrian a: time 0.5 does not increase"),
        ("id.csv", "t,id,x,y\n0,a b,0,0\n", "id.csv: line 2: id 'a b' must be"),
        ("nohdr.csv", "\n\n", "nohdr.csv: no header line"),
        # a position past 1e9 was refused later, naming the scene about to be written
        ("far.txt", "0 1 0 0\n10 1 1e300 0\n", "far.txt: line 2: x 1e+300 is too large"),
        ("twice.csv", "t,id,x,y,X\n0,a,0,0,9\n1,a,1,0,9\n", "twice.csv: line 1: the header names column x twice"),
        # a spreadsheet's semicolons or tabs, or `time` for t: "missing: t, id, x, y" of a header naming them all
        ("semi.csv", "t;id;x;y\n0;a;0;0\n", "semi.csv: line 1: the header must name the columns t, id, x, y (missing: t, id, x, y); "
         "the header is one column, 't;id;x;y': columns are separated by commas, not ';'"),
        ("tab.csv", "t\tid\tx\ty\n0\ta\t0\t0\n", "tab.csv: line 1: the header must name the columns t, id, x, y (missing: t, id, x, y); the header is one column, 't\\tid\\tx\\ty': columns are separated by commas, not '\\t'"),
        ("nohead.csv", "0,1,1.0,1.0\n10,1,2.0,1.0\n", "nohead.csv: line 1: the header must name the columns t, id, x, y "
         "(missing: t, id, x, y); this first line holds numbers: a CSV starts with a header line such as t,id,x,y"),
        ("time.csv", "time,id,x,y\n0,a,0,0\n", "time.csv: line 1: the header must name the columns t, id, x, y (missing: t); name the time column t"),
        ("late.csv", "t,id,x,y\n0,a,0,0\n1e14,a,1,0\n", "late.csv: line 3: time 1e+14 is too large"),
        ("long.csv", "t,id,x,y\n0,a,0,0\n1e12,a,1,0\n", "long.csv: the window 0 s .. 1e+12 s is longer than 1e+09 s"),
    ],
)  # fmt: skip
def test_bad_files_are_one_line_and_exit_2(tmp_path, capsys, monkeypatch, name, text, where):
    # in this process (a traceback would be an exception here): a process each cost 0.4 s;
    # real processes refuse a file in test_unreadable_file_and_bad_output_name
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    out = tmp_path / "out.yaml"
    monkeypatch.chdir(tmp_path)
    rc, stdout, stderr = run_main(capsys, "tracks", path, "-o", out)
    assert rc == 2
    assert stderr.count("\n") == 1 and "Traceback" not in stderr
    assert stderr.startswith(str(path)) and where.split(": ", 1)[1] in stderr, stderr
    # and no wrong hint: a header "t,x,y" is no line of numbers
    hint = "this first line holds numbers"
    assert (hint in stderr) == (hint in where), stderr
    assert not out.exists() and stdout == ""


@pytest.mark.parametrize(
    "args, message",
    [
        (["--t-start", 50, "--duration", 5], "no pedestrian in the window 50 s .. 55 s"),
        (["--region", 20, 20, 30, 30], "no pedestrian inside the region 20 20 30 30"),
        (
            ["--region", -1, -1, 10, 10, "--start", 20, 0, "--goal", 1, 1],
            "start 20 0 does not fit in the region",
        ),
        (["--duration", -1], "duration must be positive"),
        (["--region", 3, 0, 1, 1], "region must be"),
        (["--start", 1, 1], "start and goal go together"),
        (["--start", 1, 1, 0, "--goal", 2, 2], "--start: expected 2 numbers"),
        (["--format", "csv"], "the header must name the columns"),
        (["--fps", 0], "fps must be positive"),
        (["--static", "nowhere.yaml"], "nowhere.yaml: cannot read"),
        # refused before as the numbers of the scene about to be written, naming that file
        (["--vmax", "1e300"], "gfuzzy tracks: vmax must be at most 1e+09 in magnitude"),
        (["--region", 0, 0, "1e12", 5], "gfuzzy tracks: region must be"),
        # a query's details without its --start/--goal were dropped without a word
        (["--expect", "solved"], "gfuzzy tracks: expect (--expect, --max-duration) fills in the query"),
        (["--max-duration", 9], "gfuzzy tracks: expect (--expect, --max-duration) fills in the query"),
        (["--query-name", "across"], "gfuzzy tracks: --query-name names the query of --start and --goal"),
    ],
)
def test_bad_requests_are_one_line_and_exit_2(tmp_path, capsys, monkeypatch, eth_file, args, message):
    # in this process, as the bad files above
    out = tmp_path / "out.yaml"
    monkeypatch.chdir(tmp_path)
    rc, stdout, stderr = run_main(capsys, "tracks", eth_file, *args, "-o", out)
    assert rc == 2, stderr
    assert stderr.count("\n") == 1 and message in stderr, stderr
    assert not out.exists()


@pytest.mark.parametrize("stem", ["12", "true", "1e3"])
def test_a_scene_named_like_a_number_reads_back(tmp_path, eth_file, stem, capsys):
    # the name (the output's stem) and a query name were written plain: 12, True, 1000.0 on
    # reading, and the scene was refused as it was written ("name: expected a non-empty string")
    out = tmp_path / f"{stem}.yaml"
    proc = main_completed(capsys, "tracks", eth_file, "--start", 1, 1, "--goal", 2, 2, "--query-name", "2e1", "-o", out)
    assert proc.returncode == 0, proc.stderr
    scene = load_scene(out)
    assert scene.name == stem and scene.queries[0].name == "2e1"


def test_unreadable_file_and_bad_output_name(tmp_path, eth_file, capsys):
    proc = main_completed(capsys, "tracks", tmp_path / "missing.txt", "-o", tmp_path / "a.yaml")
    assert proc.returncode == 2 and "missing.txt: cannot read" in proc.stderr
    proc = main_completed(capsys, "tracks", eth_file, "-o", tmp_path / "a.json")
    assert proc.returncode == 2 and "a.json: output must end in .yaml or .yml" in proc.stderr


def test_a_failed_run_keeps_the_old_scene(tmp_path, eth_file, capsys):
    out = tmp_path / "scene.yaml"
    assert main_completed(capsys, "tracks", eth_file, "-o", out).returncode == 0
    before = out.read_bytes()
    proc = main_completed(capsys, "tracks", eth_file, "--t-start", 99, "-o", out)
    assert proc.returncode == 2 and out.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temporary left


# ------------------------------------------------------------------------- bundled data


@pytest.mark.parametrize("name", ["eth-crossing", "zara-crowd"])
def test_bundled_pedestrian_scenes_are_made_again_from_the_excerpts(tmp_path, name, capsys, monkeypatch):
    """Line 2 of each pedestrian scene is the command that made it; run it again."""
    path = ROOT / "scenes" / f"{name}.yaml"
    text = path.read_text(encoding="utf-8")
    argv = shlex.split(text.splitlines()[1].lstrip("#"))
    assert argv[:2] == ["gfuzzy", "tracks"] and argv[2].startswith("data/pedestrians/")
    out = tmp_path / f"{name}.yaml"
    i = argv.index("-o")
    argv[i + 1 : i + 2] = [str(out)]
    monkeypatch.chdir(ROOT)  # the command names its input relative to the repository
    proc = main_completed(capsys, *argv[1:])
    assert proc.returncode == 0, proc.stderr
    again = out.read_text(encoding="utf-8").replace(shlex.quote(str(out)), f"scenes/{name}.yaml")
    assert again == text


def test_excerpts_are_in_the_repository():
    folder = ROOT / "data" / "pedestrians"
    sizes = {p.name: p.stat().st_size for p in folder.glob("*.txt")}
    assert set(sizes) == {"biwi_eth.txt", "biwi_hotel.txt", "crowds_zara01.txt", "students001.txt"}
    assert sum(sizes.values()) < 1_000_000
    steps = {name: read_tracks(folder / name).frame_step for name in sizes}
    assert steps == {
        "biwi_eth.txt": 6,
        "biwi_hotel.txt": 10,
        "crowds_zara01.txt": 10,
        "students001.txt": 10,
    }


# ------------------------------------------------------------------------- properties

_row_text = st.lists(
    st.one_of(
        st.integers(-5, 50).map(str),
        st.floats(-1e3, 1e3, allow_nan=False).map(lambda v: f"{v:.3f}"),
        st.sampled_from(["x", "nan", "inf", "", "1e400", "#", "1.5"]),
    ),
    min_size=0,
    max_size=7,
)


@settings(max_examples=150, deadline=None)
@given(st.lists(_row_text, min_size=0, max_size=8), st.sampled_from(["eth", "csv"]))
def test_any_text_is_read_or_refused_with_a_line(tmp_path_factory, rows, fmt):
    sep = "\t" if fmt == "eth" else ","
    head = [] if fmt == "eth" else ["t,id,x,y"]
    path = tmp_path_factory.mktemp("prop") / f"f.{fmt}"
    path.write_text("\n".join(head + [sep.join(r) for r in rows]) + "\n", encoding="utf-8")
    try:
        tracks = read_tracks(path, fmt)
    except gfuzzy.SceneError as exc:
        assert exc.file == str(path) and "\n" not in str(exc)
        return
    for tr in tracks.tracks:
        assert np.all(np.isfinite(tr.rows)) and np.all(np.diff(tr.rows[:, 0]) > 0)


@settings(max_examples=60, deadline=None)
@given(
    st.dictionaries(
        st.integers(1, 40),
        st.lists(st.tuples(st.floats(-20, 20), st.floats(-20, 20)), min_size=1, max_size=6),
        min_size=1,
        max_size=5,
    ),
    st.integers(0, 30),
)
def test_eth_written_tracks_read_back(tmp_path_factory, people, first):
    # each person walks on consecutive annotated frames (step 6) from a frame of their own
    lines = []
    for pid, points in people.items():
        for k, (x, y) in enumerate(points):
            lines.append((6 * (first + pid + k), pid, x, y))
    lines.sort()
    path = tmp_path_factory.mktemp("prop") / "f.txt"
    path.write_text("".join(f"{f}\t{p}\t{x!r}\t{y!r}\n" for f, p, x, y in lines), encoding="utf-8")
    if all(len(points) == 1 for points in people.values()):
        with pytest.raises(gfuzzy.SceneError, match="no pedestrian has two rows"):
            read_tracks(path)
        return
    tracks = read_tracks(path)
    assert tracks.frame_step == 6
    for tr in tracks.tracks:
        points = people[int(tr.id)]
        start = first + int(tr.id)
        want = [[0.4 * (start + k), x, y] for k, (x, y) in enumerate(points)]
        np.testing.assert_allclose(tr.rows, want, rtol=0, atol=1e-9)


DATA = ROOT / "data" / "pedestrians"


def _make(tmp_path: Path, data: str, *args, capsys=None) -> Path:
    """``gfuzzy tracks DATA ARGS -o OUT`` in a real process, or with ``capsys`` in process."""
    out = tmp_path / f"{Path(data).stem}.yaml"
    argv = ("tracks", DATA / data, *args, "-o", out)
    proc = main_completed(capsys, *argv) if capsys is not None else run_cli_process(*argv)
    assert proc.returncode == 0, proc.stderr
    return out


@pytest.fixture(scope="module")
def students(tmp_path_factory):
    path = _make(
        tmp_path_factory.mktemp("students"),
        "students001.txt",
        "--t-start", 100, "--duration", 40, "--region", 0, 0, 15, 14,
        "--start", 1, 1, "--goal", 14, 13, "--query-name", "across",
    )  # fmt: skip
    scene = load_scene(path)
    return scene, build_roadmap(scene, RoadmapOptions(vertices=300, seed=1))


def test_dense_crowd_answers_are_safe(students):
    scene, roadmap = students
    assert len(scene.movers) >= 40  # a crowd, not a couple of people
    planner = Planner(scene, roadmap)
    rng = np.random.default_rng(5)
    solved = 0
    for t0 in (0.0, 7.5, 15.0):
        for _ in range(2):
            start = rng.uniform([1, 1], [14, 13])
            goal = rng.uniform([1, 1], [14, 13])
            res = planner.plan(start, goal, t0, PlanOptions(time_limit=30))
            assert res.status in (Status.SOLVED, Status.NO_PATH, Status.INVALID_QUERY), res.message
            if res.solved:
                solved += 1
                rep = check_trajectory(scene, res.trajectory.waypoints)
                assert rep.valid, rep.reason
                assert np.allclose(res.trajectory.waypoints[0, 1:], start)
                assert res.trajectory.t0 == t0
    assert solved >= 3


def test_stepping_onto_a_person_is_an_invalid_query(students):
    scene, roadmap = students
    person = next(m for m in scene.movers if m.time_range[0] <= 5.0 <= m.time_range[1])
    xy, present = person.state(np.array([5.0]))
    assert present[0]
    res = Planner(scene, roadmap).plan(xy[0], [14, 13], 5.0)
    assert res.status is Status.INVALID_QUERY
    assert person.name in res.message


def test_people_who_come_and_go_are_only_there_while_recorded(tmp_path, capsys):
    path = _make(
        tmp_path, "biwi_hotel.txt", "--t-start", 50, "--duration", 30, "--start", 0, 0, "--goal", 1, 1, capsys=capsys,
    )  # fmt: skip
    scene = load_scene(path)
    ranges = np.array([m.time_range for m in scene.movers])
    assert ranges[:, 0].min() >= 0.0 and ranges[:, 1].max() <= 30.0 + 1e-9
    assert (ranges[:, 0] > 0.5).any()  # some arrive after the window opens
    late = scene.movers[int(np.argmax(ranges[:, 0]))]
    _, present = late.state(np.array([0.0, late.time_range[0]]))
    assert not present[0] and present[1]


def test_unix_time_stamps_are_rebased_to_the_window(tmp_path, capsys, monkeypatch):
    """Tracks exported from a ROS bag carry Unix times (about 1.7e9 s): the scene's times
    start at the window's start, so they load as they did before numbers beyond 1e9 were
    refused (a review found `gfuzzy tracks` refusing them)."""
    t0 = 1351651349.5
    rows = ["t,id,x,y"] + [f"{t0 + 0.1 * k:.1f},{pid},{0.5 + 0.2 * k},{y}" for k in range(30) for pid, y in (("a", 1.0), ("b", 2.0))]
    path = tmp_path / "bag.csv"
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    out = tmp_path / "bag.yaml"
    monkeypatch.chdir(tmp_path)
    p = main_completed(capsys, "tracks", path, "-o", out, "--region", 0, 0, 7, 3)
    assert p.returncode == 0, p.stderr
    scene = load_scene(out)
    assert len(scene.movers) == 2
    assert all(m.trajectory[0, 0] == 0.0 and m.trajectory[-1, 0] == pytest.approx(2.9) for m in scene.movers)
    p = main_completed(capsys, "tracks", path, "-o", tmp_path / "w.yaml", "--t-start", t0 + 1, "--duration", 1)
    assert p.returncode == 0, p.stderr
    assert load_scene(tmp_path / "w.yaml").movers[0].trajectory[-1, 0] == pytest.approx(1.0)


def test_a_mesh_folder_named_like_dot_dot_stays_in_the_folder(tmp_path):
    """The static scene's mesh paths follow the new file: ``..meshes/`` beside it is inside
    its folder (``leaves_folder``: the path's first part is ``..``, not its first two
    characters; before, refused as outside), ``../`` is not."""
    from gfuzzy.errors import SceneError
    from gfuzzy.scene.tracks import _static_obstacles

    folder = tmp_path / "warehouse"
    shutil.copytree(ROOT / "scenes" / "meshes", folder / "..meshes")
    text = (ROOT / "scenes" / "warehouse-mesh.yaml").read_text().replace("file: meshes/", "file: ..meshes/")
    (folder / "warehouse-mesh.yaml").write_text(text)
    static = load_scene(folder / "warehouse-mesh.yaml")
    obstacles = _static_obstacles(static, folder)
    assert obstacles[0]["mesh"]["file"].startswith("..meshes/")
    (folder / "sub").mkdir()
    with pytest.raises(SceneError, match=r"obstacles\[0\]\.mesh\.file"):
        _static_obstacles(static, folder / "sub")


@pytest.mark.parametrize("stem, name", [("my walk", "my-walk"), ("gang ü #2", "gang-2"), ("über", "ber"), ("ü", "tracks")])
def test_an_output_named_with_spaces_or_accents_names_the_scene_with_dashes(tmp_path, eth_file, stem, name, capsys):
    # the default name is the output's stem: `-o "my walk.yaml"` was refused, exit 2,
    # "name must be letters, digits, _ . - (got 'my walk')", a name the user never gave
    out = tmp_path / f"{stem}.yaml"
    proc = main_completed(capsys, "tracks", eth_file, "-o", out)
    assert proc.returncode == 0, proc.stderr
    assert load_scene(out).name == name


def test_speeds_that_betray_the_wrong_units_are_logged(caplog):
    """A detector's CSV with its times in milliseconds (`t` is seconds) made a scene of people
    walking at 1.2 mm/s, without a word; positions in centimetres (no `--scale 0.01`), people
    at 120 m/s. Either is logged, naming what to check; ordinary walkers are not."""
    walkers = [np.array([[t, 1.2 * t + k, 0.5 * k] for t in np.arange(0, 6, 0.4)]) for k in range(6)]
    standing = np.array([[0.0, 9.0, 9.0], [6.0, 9.0, 9.0]])

    def warnings(scale_t=1.0, scale_xy=1.0):
        tracks = [gfuzzy.Track(str(k), w * [scale_t, scale_xy, scale_xy]) for k, w in enumerate(walkers)]
        tracks.append(gfuzzy.Track("s", standing * [scale_t, scale_xy, scale_xy]))
        caplog.clear()
        tracks_scene(gfuzzy.Tracks("walk.csv", "csv", None, None, tuple(tracks)))
        return [r.getMessage() for r in caplog.records]

    caplog.set_level("WARNING", logger="gfuzzy.scene.tracks")
    assert warnings() == []
    (msg,) = warnings(scale_t=1000.0)
    assert msg.startswith("walk.csv: the people's steps are at most 0.0012 m/s") and "are the times in seconds" in msg, msg
    (msg,) = warnings(scale_xy=100.0)
    assert msg.startswith("walk.csv: the people walk at a median 120 m/s") and "--scale 0.01" in msg, msg


def test_a_queue_or_a_plaza_of_people_standing_is_no_units_alarm(caplog):
    """A review's cases of the slow-side warning on mean speeds: a queue (each person steps
    0.4 m at 1 m/s every 30 s: 0.013 m/s on average) and twelve people standing with one
    walker among them (the fastest tenth's slowest was a standing one: "0 m/s at most").
    People's steps are what the units betray, not their mean speeds."""
    caplog.set_level("WARNING", logger="gfuzzy.scene.tracks")

    def queue(k):
        rows, x = [], float(k)
        for t in np.arange(0.0, 60.0, 0.1):
            phase = t % 30.0
            step = min(max(phase - 29.6, 0.0), 0.4)  # 0.4 m at 1 m/s, the last 0.4 s of each 30
            rows.append([t, x + 0.4 * (t // 30.0) + step, 2.0])
        return np.array(rows)

    plaza = [np.array([[0.0, 1.0 + k, 5.0], [30.0, 1.0 + k, 5.0], [60.0, 1.0 + k, 5.0]]) for k in range(12)]
    plaza.append(np.array([[t, 1.2 * t, 7.0] for t in np.arange(0.0, 10.0, 0.4)]))
    for name, rows in (("queue.csv", [queue(k) for k in range(8)]), ("plaza.csv", plaza)):
        caplog.clear()
        tracks = tuple(gfuzzy.Track(str(k), r) for k, r in enumerate(rows))
        tracks_scene(gfuzzy.Tracks(name, "csv", None, None, tracks))
        assert [r.getMessage() for r in caplog.records] == [], name
