"""``gfuzzy populate``: walking people for a scene, checked independently of the code
that made them (closed-form point-to-box distances, no shapely, no FCL)."""

from __future__ import annotations

import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers import main_completed, run_main

pytest.importorskip("pyrvo")

import gfuzzy  # noqa: E402
from gfuzzy.errors import InputError  # noqa: E402
from gfuzzy.navigation.populate import PopulateOptions, populate  # noqa: E402
from gfuzzy.scene.scene import load_scene, parse_scene  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]

# a 10 x 6 room split by a wall with a 1.4 m door, and a pillar
ROOM = {
    "version": 1, "name": "room", "bounds": [0, 0, 10, 6],
    "robot": {"disc": 0.3, "vmax": 1.0},
    "obstacles": [
        {"box": {"center": [5.0, 1.3], "size": [0.2, 2.6]}},
        {"box": {"center": [5.0, 5.0], "size": [0.2, 2.0]}},
        {"box": {"center": [2.5, 3.0], "size": [0.6, 0.6]}},
    ],
    "movers": [], "queries": [{"name": "q", "start": [1.0, 1.0], "goal": [9.0, 5.0]}],
}  # fmt: skip


def _box_distance(p, center, size):
    """Distance from points p (n, 2) to an axis-aligned box (0 inside)."""
    d = np.abs(p - np.asarray(center)) - np.asarray(size) / 2
    return np.hypot(np.maximum(d[:, 0], 0), np.maximum(d[:, 1], 0))


def _check_people(doc, movers):
    """Every person's disc, along the straight motion between rows (sampled every 1 cm of
    it), stays clear of every box and inside the bounds."""
    x0, y0, x1, y1 = doc["bounds"]
    for m in movers:
        rows = np.asarray(m["trajectory"], float)
        r = m["disc"]
        assert np.all(np.diff(rows[:, 0]) > 0)
        for a, b in zip(rows[:-1, 1:], rows[1:, 1:], strict=True):
            n = max(2, int(np.ceil(np.hypot(*(b - a)) / 0.01)) + 1)
            pts = a + np.linspace(0, 1, n)[:, None] * (b - a)
            for ob in doc["obstacles"]:
                box = ob["box"]
                assert _box_distance(pts, box["center"], box["size"]).min() >= r - 1e-6, m["name"]
            assert pts[:, 0].min() >= x0 + r - 1e-6 and pts[:, 0].max() <= x1 - r + 1e-6
            assert pts[:, 1].min() >= y0 + r - 1e-6 and pts[:, 1].max() <= y1 - r + 1e-6


def _run(*args):
    return subprocess.run([sys.executable, "-m", "gfuzzy", *args], capture_output=True, text=True, cwd=ROOT)


_main = main_completed  # answered as :func:`_run` answers (the command's own process: ``_run`` where the tests below use it)


def test_populate_writes_a_scene_that_loads_and_whose_people_avoid_the_walls(tmp_path, capsys):
    src = tmp_path / "room.yaml"
    src.write_text(yaml.safe_dump(ROOM))
    out = tmp_path / "room-people.yaml"
    p = _main(capsys, "populate", str(src), "--people", "8", "--seed", "2", "--duration", "40", "-o", str(out))
    assert p.returncode == 0, p.stderr
    scene = gfuzzy.load_scene(out)
    assert len(scene.movers) == 8
    doc = yaml.safe_load(out.read_text())
    assert doc["obstacles"] == ROOM["obstacles"] and doc["queries"][0]["name"] == "q"
    _check_people(doc, doc["movers"])
    # they walk: most cover real distance, some through the door (both halves visited)
    moved = [np.hypot(*np.diff(np.asarray(m["trajectory"])[:, 1:], axis=0).T).sum() for m in doc["movers"]]
    assert sum(d > 10 for d in moved) >= 6
    xs = np.concatenate([np.asarray(m["trajectory"])[:, 1] for m in doc["movers"]])
    assert (xs < 4.5).any() and (xs > 5.5).any()
    # nobody starts on the query's start
    starts = np.array([m["trajectory"][0][1:] for m in doc["movers"]])
    assert np.hypot(*(starts - [1.0, 1.0]).T).min() >= 1.0
    # same seed, same file (and in another process)
    again = tmp_path / "again.yaml"
    assert _run("populate", str(src), "--people", "8", "--seed", "2", "--duration", "40", "-o", str(again)).returncode == 0
    assert again.read_text() == out.read_text()


def test_populate_between_given_waypoints():
    scene = parse_scene(ROOM)
    wps = ((1.0, 5.0), (8.5, 1.0), (8.5, 5.0))
    res = populate(scene, PopulateOptions(people=4, seed=1, duration=30.0, waypoints=wps))
    movers = [{"name": m.name, "disc": m.radius, "trajectory": m.trajectory.tolist()} for m in res.movers]
    _check_people(ROOM, movers)
    # they go near the waypoints (within a metre of at least two of them each)
    for m in res.movers:
        near = [np.hypot(*(m.trajectory[:, 1:] - w).T).min() < 1.0 for w in wps]
        assert sum(near) >= 2


def test_populate_refuses_bad_input(tmp_path, capsys):
    scene = parse_scene(ROOM)
    with pytest.raises(InputError):
        populate(scene, PopulateOptions(people=2, waypoints=((5.0, 1.0), (8.0, 5.0))))  # inside the wall
    with pytest.raises(InputError):
        PopulateOptions(people=0)
    src = tmp_path / "room.yaml"
    src.write_text(yaml.safe_dump(ROOM))
    out = tmp_path / "o.yaml"
    for flags in (["--people", "0"], ["--people", "3", "--waypoints", "1,2;x"], ["--people", "3", "--radius", "-1"],
                  ["--people", "2", "--waypoints", "5,1;8,5"],
                  # --speed 1e20 overflowed ORCA: a GEOS traceback; --duration 0.1 wrote nobody
                  ["--people", "2", "--speed", "1e20"], ["--people", "2", "--duration", "0.1"],
                  ["--people", "2", "--seed", "-1"],
                  # a NaN waypoint reached the grid's lookup: a ValueError traceback, exit 1
                  ["--people", "2", "--waypoints", "1,1;nan,2"], ["--people", "2", "--waypoints", "1,1;2,inf"]):  # fmt: skip
        # in this process (a traceback would be an exception here); a real process once, below
        rc, _, err = run_main(capsys, "populate", src, *flags, "-o", out)
        assert rc == 2, flags
        assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
        assert not out.exists()
        if "--seed" in flags:  # named by the command (it came from deep in populate, unnamed)
            assert err.startswith("gfuzzy populate: seed must be")
    p = _main(capsys, "populate", str(src), "--people", "2", "--speed", "1e20", "-o", str(out))
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr
    assert not out.exists()


def test_too_long_a_walk_is_refused_in_seconds():
    # "duration / dt must be at most 100000 samples": dt is no option of `gfuzzy populate`
    with pytest.raises(InputError, match=r"^duration must be at most 25000 s \(100000 steps of 0.25 s\), got 1e\+06$"):
        PopulateOptions(people=2, duration=1e6)


def test_a_waypoint_outside_the_bounds_is_refused_even_where_the_grid_is_coarse():
    # on a long floor the grid's cells are 1.2 m and its border cells are free: the lookup
    # clamped (1000, 5) to one of them and people were sent 700 m beyond the bounds
    doc = {"version": 1, "name": "long", "bounds": [0, 0, 300, 10], "robot": {"disc": 0.3, "vmax": 1.0},
           "obstacles": [], "movers": [], "queries": []}  # fmt: skip
    scene = parse_scene(doc, "<long>")
    with pytest.raises(InputError, match=r"waypoints\[1\] \(1000, 5\) lies outside the scene's bounds"):
        populate(scene, PopulateOptions(people=2, waypoints=((10.0, 5.0), (1000.0, 5.0)), duration=1.0))
    populate(scene, PopulateOptions(people=2, waypoints=((10.0, 5.0), (290.0, 5.0)), duration=1.0))


def test_a_waypoint_whose_cell_is_free_but_itself_is_not_is_refused():
    # on a coarse grid (1.2 m cells) a waypoint on the bounds' edge or inside a small box
    # has a free cell: people walked to within their radius of it and stood there for
    # the rest of the run, never arriving
    doc = {"version": 1, "name": "long", "bounds": [0, 0, 300, 10], "robot": {"disc": 0.3, "vmax": 1.0},
           "obstacles": [{"box": {"center": [49.2, 5.4], "size": [0.2, 0.2]}}], "movers": [], "queries": []}  # fmt: skip
    scene = parse_scene(doc, "<long>")
    for bad in ((0.0, 5.0), (300.0, 10.0), (49.1, 5.4)):
        with pytest.raises(InputError, match=r"waypoints\[0\] .* is not free for a person of radius 0.3 m"):
            populate(scene, PopulateOptions(people=2, waypoints=(bad, (20.0, 5.0)), duration=1.0))
    populate(scene, PopulateOptions(people=2, waypoints=((0.5, 5.0), (20.0, 5.0)), duration=1.0))
    for wps in ((), ((1.0, 2.0),), ((1.0, 2.0, 3.0), (4.0, 5.0, 6.0))):  # read as other points, or a ValueError
        with pytest.raises(InputError, match="waypoints"):
            PopulateOptions(people=2, waypoints=wps)


def test_random_free_points_are_clear_of_the_obstacles_on_a_coarse_grid():
    # a person's new goal is drawn anywhere within a free cell: on a coarse grid such a
    # point can lie within the person's radius of a box, and they were cut short there
    from gfuzzy.navigation.populate import _FreePoints, _Grid, obstacle_union

    scene = parse_scene(PILLARS, "<pillars>")
    grid = _Grid(scene, 0.3, obstacle_union(scene))
    draw = _FreePoints(grid.cells(), grid, np.random.default_rng(3))
    pts = np.array([draw() for _ in range(3000)])
    centers = np.array([ob["box"]["center"] for ob in PILLARS["obstacles"]])
    gaps = np.min([_box_distance(pts, c, (0.4, 0.4)) for c in centers], axis=0)
    assert gaps.min() >= 0.3


def test_the_readme_populate_example_runs_and_a_full_room_says_why(tmp_path, capsys, monkeypatch):
    # the README's example asked building-floor for 15 people of radius 0.3: its 0.6 m doors
    # keep them in one room, which holds about 12; it exited 2 with no hint why. In process
    # (populate's own process: the test above)
    line = next(x for x in (ROOT / "README.md").read_text(encoding="utf-8").splitlines() if x.startswith("gfuzzy populate "))
    argv = shlex.split(line, comments=True)[1:]
    shutil.copytree(ROOT / "scenes", tmp_path / "scenes")
    monkeypatch.chdir(tmp_path)
    p = _main(capsys, *argv)
    assert p.returncode == 0, p.stderr
    assert load_scene(tmp_path / argv[argv.index("-o") + 1]).movers
    out = tmp_path / "busy.yaml"
    p = _main(capsys, "populate", str(ROOT / "scenes" / "building-floor.yaml"), "--people", "15", "--seed", "1", "-o", str(out))
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1
    assert "largest free region" in p.stderr and "gap narrower than 0.70 m" in p.stderr
    assert not out.exists()


def test_the_command_says_how_many_people_stop_short(tmp_path, capsys):
    # at 100 m/s ORCA takes every person into an obstacle within seconds: each walk is cut
    # there (the mover disappears), and the command said "3 people walking for 60 s"
    out = tmp_path / "p.yaml"
    p = _main(capsys, "populate", str(ROOT / "scenes" / "sim-4s1m.yaml"), "--people", "3", "--speed", "100", "-o", str(out))
    assert p.returncode == 0, p.stderr
    assert "3 people walking for 60 s" in p.stdout and "3 of them stop short" in p.stdout


def test_the_command_tells_people_left_out_from_people_cut_short():
    # Nav2's depot tiled 3 x 4, 200 people: "193 people walking ... (12 of them stop short)",
    # when 7 of the 12 were not in the file at all
    from gfuzzy.cli.crowds import _cut_note
    from gfuzzy.navigation.populate import Populated

    assert _cut_note(200, Populated(movers=tuple(range(193)), cut=12)) == (
        " (5 of them stop short, where ORCA would take them into an obstacle; 7 more left out, whose first step it would)")
    assert _cut_note(3, Populated(movers=(1, 2, 3), cut=3)) == " (3 of them stop short, where ORCA would take them into an obstacle)"
    assert _cut_note(3, Populated(movers=(1, 2, 3), cut=0)) == ""


def test_a_scene_named_like_a_number_keeps_its_name(tmp_path, capsys):
    # yaml.safe_dump wrote the name "1e3" plain, which reads back as 1000.0
    src = tmp_path / "n.yaml"
    src.write_text(yaml.safe_dump(dict(ROOM, name="NAME"), sort_keys=False).replace("name: NAME", 'name: "1e3"', 1))
    out = tmp_path / "o.yaml"
    p = _main(capsys, "populate", str(src), "--people", "2", "-o", str(out))
    assert p.returncode == 0, p.stderr
    assert load_scene(out).name == "1e3"


def _wall_map(folder: Path) -> tuple[dict, np.ndarray]:
    """ROOM's walls and pillar as a Nav2 map (0.1 m cells), written beside a scene in folder;
    returns the scene document and the occupied mask (row 0 at the top)."""
    from PIL import Image

    h, w, res = 60, 100, 0.1
    xs, ys = (np.arange(w) + 0.5) * res, (h - 1 - np.arange(h) + 0.5) * res
    X, Y = np.meshgrid(xs, ys)
    occupied = np.zeros((h, w), bool)
    for ob in ROOM["obstacles"]:
        (cx, cy), (sx, sy) = ob["box"]["center"], ob["box"]["size"]
        occupied |= (np.abs(X - cx) < sx / 2) & (np.abs(Y - cy) < sy / 2)
    Image.fromarray(np.where(occupied, 0, 254).astype(np.uint8)).save(folder / "room.pgm")
    (folder / "room-map.yaml").write_text(
        "image: room.pgm\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    doc = dict(ROOM, obstacles=[{"map": {"file": "room-map.yaml"}}])
    return doc, occupied


def test_people_avoid_the_walls_of_a_map(tmp_path):
    doc, occupied = _wall_map(tmp_path)
    (tmp_path / "room.yaml").write_text(yaml.safe_dump(doc))
    scene = gfuzzy.load_scene(tmp_path / "room.yaml")
    res = populate(scene, PopulateOptions(people=6, seed=3, duration=30.0))
    assert res.movers
    for m in res.movers:  # every sampled centre lies in a free cell, a radius from any blocked one
        rows = m.trajectory
        for a, b in zip(rows[:-1, 1:], rows[1:, 1:], strict=True):
            n = max(2, int(np.ceil(np.hypot(*(b - a)) / 0.02)) + 1)
            pts = a + np.linspace(0, 1, n)[:, None] * (b - a)
            col, row = (pts[:, 0] / 0.1).astype(int), 59 - (pts[:, 1] / 0.1).astype(int)
            assert not occupied[row, col].any(), m.name
            blocked = np.argwhere(occupied)
            cx, cy = (blocked[:, 1] + 0.5) * 0.1, (59 - blocked[:, 0] + 0.5) * 0.1
            gap = np.hypot(np.maximum(np.abs(pts[:, None, 0] - cx) - 0.05, 0),
                           np.maximum(np.abs(pts[:, None, 1] - cy) - 0.05, 0)).min()  # fmt: skip
            assert gap >= m.radius - 1e-6, m.name


def test_people_stay_inside_a_map_whose_unknown_cells_enclose_the_room():
    """The tb3 arena's free room is a hole in the map's blocked cells (its walls and the
    unknown outside are one region): ORCA must keep people inside that hole too. Before
    holes were given to RVO2, 2-4 of 6 people walked into the arena's walls within the
    minute and were cut short; now everyone walks the whole minute."""
    scene = gfuzzy.load_scene(ROOT / "scenes" / "tb3-arena.yaml")
    for seed in (1, 2):
        res = populate(scene, PopulateOptions(people=6, radius=0.2, seed=seed, duration=60.0))
        assert res.cut == 0
        assert len(res.movers) == 6
        assert all(m.trajectory[-1, 0] == pytest.approx(60.0) for m in res.movers)


# a 14 m room, a 1 m wall, and beyond it a closed 11 m room (people cannot reach it: a
# smaller free region) holding sixty small boxes: outlines that no person can come near
TWO_ROOMS = {
    "version": 1, "name": "two-rooms", "bounds": [0, 0, 26, 6],
    "robot": {"disc": 0.3, "vmax": 1.0},
    "obstacles": [
        {"box": {"center": [14.5, 3.0], "size": [1.0, 6.0]}},
        {"box": {"center": [5.0, 3.0], "size": [0.8, 0.8]}},
        *({"box": {"center": [18.0 + 0.5 * (i % 12), 1.0 + 1.0 * (i // 12)], "size": [0.2, 0.2]}} for i in range(60)),
    ],
    "movers": [], "queries": [],
}  # fmt: skip


def test_orca_is_given_only_the_outlines_people_can_come_near(monkeypatch):
    # RVO2 builds its obstacle tree in time that grows with the square of the edges (Nav2's
    # depot map repeated 3 x 4: 56,000 vertices, 141 s for 20 people); edges far from the
    # people's region change nothing an agent sees: they are left out, the walks stay the same
    from gfuzzy.navigation import populate as P

    scene = parse_scene(TWO_ROOMS, "<two-rooms>")
    given = []
    real = P._rvo_obstacles

    def spy(sim, scene_, union):
        given.append(union)
        return real(sim, scene_, union)

    monkeypatch.setattr(P, "_rvo_obstacles", spy)
    opts = PopulateOptions(people=8, seed=2, duration=30.0)
    near = populate(scene, opts)
    xs = np.concatenate([np.asarray(g.exterior.coords)[:, 0] for g in given[-1].geoms])
    assert xs.max() <= 15.0 + 1e-9  # the left room and its wall only: none of the sixty boxes
    monkeypatch.setattr(P, "_near_walks", lambda union, grid, reach: union)  # everything, as before
    every = populate(scene, opts)
    assert len(near.movers) == len(every.movers) == 8 and near.cut == every.cut == 0
    for a, b in zip(near.movers, every.movers, strict=True):
        np.testing.assert_array_equal(a.trajectory, b.trajectory)
    _check_people(TWO_ROOMS, [{"name": m.name, "disc": m.radius, "trajectory": m.trajectory} for m in near.movers])


# a 100 m floor of pillars: the grid's cells are 0.4 m, and a point jittered within a free
# cell may lie closer to a pillar than a person's radius
PILLARS = {
    "version": 1, "name": "pillars", "bounds": [0, 0, 100, 9], "robot": {"disc": 0.3, "vmax": 1.0},
    "obstacles": [{"box": {"center": [1.5 + 1.2 * i, 1.5 + 1.4 * j], "size": [0.4, 0.4]}}
                  for i in range(82) for j in range(6)],
    "movers": [], "queries": [],
}  # fmt: skip


def test_on_a_coarse_grid_nobody_starts_within_a_radius_of_an_obstacle():
    # people were placed anywhere in a free cell: on coarse grids (maps wider than about
    # 22 m) some started within their radius of a wall and were left out of the file
    # altogether (Nav2's depot tiled 3 x 4, 200 people: 7 of them, seed 2)
    scene = parse_scene(PILLARS, "<pillars>")
    centers = np.array([ob["box"]["center"] for ob in PILLARS["obstacles"]])
    for seed in (1, 2):
        res = populate(scene, PopulateOptions(people=60, seed=seed, duration=0.5))
        assert len(res.movers) == 60
        starts = np.array([m.trajectory[0, 1:] for m in res.movers])
        gaps = [_box_distance(starts[i : i + 1], c, (0.4, 0.4)).min() for i in range(60) for c in centers]
        assert min(gaps) >= 0.3


def test_a_file_named_like_dot_dot_stays_in_the_folder(tmp_path):
    """``write_scene`` keeps a scene's map file in the new file's folder: a map named
    ``..room-map.yaml`` beside the scene is inside it (``leaves_folder``: the path's first
    part is ``..``, not its first two characters; before, refused as "outside the new
    file's folder"), and writing one folder down from it is refused."""
    from gfuzzy.navigation.populate import Populated, write_scene

    doc, _ = _wall_map(tmp_path)
    (tmp_path / "room-map.yaml").rename(tmp_path / "..room-map.yaml")
    doc["obstacles"] = [{"map": {"file": "..room-map.yaml"}}]
    (tmp_path / "room.yaml").write_text(yaml.safe_dump(doc))
    write_scene(tmp_path / "room.yaml", Populated(()), tmp_path / "people.yaml")
    assert load_scene(tmp_path / "people.yaml").static_hash == load_scene(tmp_path / "room.yaml").static_hash
    (tmp_path / "sub").mkdir()
    with pytest.raises(InputError, match="outside the new file's folder"):
        write_scene(tmp_path / "room.yaml", Populated(()), tmp_path / "sub" / "people.yaml")
    assert not (tmp_path / "sub" / "people.yaml").exists()


def test_an_output_folder_without_the_scenes_files_is_refused_before_the_people_walk(tmp_path, capsys, monkeypatch):
    # the folder was refused by write_scene, after the walk (about 4 s on the mesh warehouse)
    from gfuzzy.navigation import populate as P

    doc, _ = _wall_map(tmp_path)
    (tmp_path / "room.yaml").write_text(yaml.safe_dump(doc))
    (tmp_path / "sub").mkdir()

    def walked(*args, **kwargs):
        raise AssertionError("the people walked before the output was checked")

    monkeypatch.setattr(P, "populate", walked)
    out = tmp_path / "sub" / "people.yaml"
    rc, _, err = run_main(capsys, "populate", tmp_path / "room.yaml", "--people", "2", "-o", out)
    assert rc == 2 and err == (f"{out}: the scene refers to room-map.yaml, which would lie outside the new file's "
                               f"folder: write it in {tmp_path} or a folder above room-map.yaml\n")  # fmt: skip
    assert list((tmp_path / "sub").iterdir()) == []


def test_waypoints_may_start_with_a_minus_and_their_errors_name_the_option(tmp_path, capsys):
    # --waypoints "-1.5,3.0;..." (a map with a negative origin): argparse took the value for
    # an option, "expected one argument"; a waypoint in a wall named neither --waypoints nor
    # the scene file
    from helpers import run_main

    doc = dict(ROOM, bounds=[-2, 0, 10, 6], queries=[])
    src = tmp_path / "room.yaml"
    src.write_text(yaml.safe_dump(doc))
    out = tmp_path / "o.yaml"
    rc, _, err = run_main(capsys, "populate", str(src), "--people", "2", "--waypoints", "-1.5,3.0;8,5",
                          "--duration", "2", "-o", str(out))  # fmt: skip
    assert rc == 0 and out.is_file(), err
    out.unlink()
    for wps, what in (("-1.5,3.0;5,1", "point 2 (5, 1) is not free"), ("-1e3,3;8,5", "point 1 (-1000, 3) lies outside"),
                      ("-1.5,nan;8,5", "point 1 must be two finite numbers"),
                      ("-1.5,3;8,1e300", "point 2 must be two finite numbers of at most 1e+09")):  # fmt: skip
        rc, _, err = run_main(capsys, "populate", str(src), "--people", "2", "--waypoints", wps, "-o", str(out))
        assert rc == 2 and err.count("\n") == 1, err
        assert err.startswith(f"{src}: --waypoints: {what}"), err
        assert not out.exists()


@pytest.mark.parametrize("flags", [["--start", "-1e0", "1"], ["--start", "-.5", "1"]])
def test_a_pose_may_start_with_a_minus_as_a_number_does(tmp_path, capsys, flags):
    from helpers import run_main

    src = tmp_path / "room.yaml"
    src.write_text(yaml.safe_dump(ROOM))
    rc, out, err = run_main(capsys, "plan", str(src), *flags, "--goal", "9", "5")
    assert rc == 1 and "invalid_query" in out and "out of bounds" in out, (out, err)  # a pose, read as one
