"""Defects found by trying the command line and the API (issue 9, item 6).

Each test reproduces one reported defect; the CLI runs in-process (``gfuzzy.cli.main``)
so that its exit status, stdout and stderr are what a user sees.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from matplotlib.colors import to_rgb
from matplotlib.text import Text
from PIL import Image

from gfuzzy import render as R
from gfuzzy.check import check_trajectory
from gfuzzy.cli import main
from gfuzzy.errors import SceneError
from gfuzzy.planner import PlanOptions, Status, plan
from gfuzzy.roadmap import RoadmapOptions, build_roadmap
from gfuzzy.scene import load_scene, parse_scene

# A corridor with two static discs on the line y = 1 and a mover crossing it: a robot
# driving straight along y = 1 hits the first disc at x = 3, the second at x = 6.
LINE = """
version: 1
name: line
bounds: [0, 0, 10, 3]
robot: {disc: 0.2, vmax: 1.0, amax: 1.5}
obstacles:
  - disc: {center: [3.0, 1.0], radius: 0.1}
  - disc: {center: [6.0, 1.0], radius: 0.3}
movers:
  - {name: cart, disc: 0.3, speed: 1.0, path: [[8, 0.2], [8, 2.8]], mode: bounce}
queries:
  - {name: up, start: [1.0, 2.5], goal: [9.0, 2.5]}
"""


@pytest.fixture
def line_scene(tmp_path):
    path = tmp_path / "line.yaml"
    path.write_text(LINE)
    return path


def _run(capsys, *args):
    """``gfuzzy ARGS`` in-process: (exit status, stdout, stderr)."""
    rc = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return rc, out, err


def _trajectory_file(path, waypoints, scene="line", query="", status="solved"):
    doc = {"version": 1, "scene": scene, "query": query, "status": status, "message": ""}
    if waypoints is not None:
        doc["waypoints"] = [list(map(float, row)) for row in waypoints]
    path.write_text(json.dumps(doc))
    return path


# ----------------------------------------------------------------------- stale outputs


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


# ----------------------------------------------------------------------- check


def test_check_reports_the_first_collision_between_rows():
    sc = parse_scene(
        {
            "version": 1,
            "name": "two",
            "bounds": [0, 0, 10, 3],
            "robot": {"disc": 0.2, "vmax": 1.0},
            "obstacles": [
                {"disc": {"center": [3.0, 1.0], "radius": 0.1}},
                {"disc": {"center": [5.0, 1.0], "radius": 0.1}},
            ],
        }
    )
    # two rows only: the first evaluation between them (t = 4, x = 5) lands in the second disc
    wp = np.array([[0.0, 1.0, 1.0], [8.0, 9.0, 1.0]])
    rep = check_trajectory(sc, wp)
    assert not rep.valid
    assert "[3.0, 1.0]" in rep.reason, rep.reason
    # the robot (radius 0.2) touches the disc at x = 3 - 0.3 = 2.7, i.e. t = 1.7
    assert rep.time is not None and 1.69 <= rep.time <= 1.75, rep.time


def test_check_reports_the_first_collision_before_a_colliding_row():
    doc = {
        "version": 1,
        "name": "two",
        "bounds": [0, 0, 10, 3],
        "robot": {"disc": 0.2, "vmax": 1.0},
        "obstacles": [{"disc": {"center": [6.0, 1.0], "radius": 0.3}}],
        # down x = 2.5, through y = 1 at t = 1.5, where the robot is then
        "movers": [{"name": "early", "disc": 0.1, "speed": 1.0, "path": [[2.5, 2.9], [2.5, 0.1]],
                    "mode": "once", "offset": 0.4}],
    }
    # rows every second: the row at t = 5 (x = 6) sits in the static disc; the mover is
    # clear of the rows at t = 1 and t = 2 and hit between them
    t = np.arange(0.0, 9.0)
    wp = np.column_stack([t, 1.0 + t, np.full(t.size, 1.0)])
    alone = check_trajectory(parse_scene({**doc, "obstacles": []}), wp)
    assert not alone.valid and "early" in alone.reason  # the mover alone is hit
    rep = check_trajectory(parse_scene(doc), wp)
    assert not rep.valid
    assert "early" in rep.reason, rep.reason
    assert 1.0 < rep.time < 1.5


def test_check_of_a_csv_gives_a_hint(line_scene, tmp_path, capsys):
    csv = tmp_path / "x.csv"
    csv.write_text("t,x,y\n0.0,1.0,2.5\n8.0,9.0,2.5\n")
    rc, _, stderr = _run(capsys, "check", line_scene, csv)
    assert rc == 2
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert str(csv) in lines[0] and "JSON" in lines[0] and "x.json" in lines[0]


# ----------------------------------------------------------------------- check vs render


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


def test_render_marks_the_first_violation(line_scene, tmp_path):
    sc = load_scene(line_scene)
    wp = np.array([[0, 1, 1], [4, 5, 1], [8, 9, 1]], float)
    rep = check_trajectory(sc, wp)
    plain, marked = tmp_path / "plain.png", tmp_path / "marked.png"
    R.render_scene(sc, plain, trajectory=wp)
    R.render_scene(sc, marked, trajectory=wp, violation=(rep.time, rep.reason))
    a = np.asarray(Image.open(plain).convert("RGB"), float)
    b = np.asarray(Image.open(marked).convert("RGB"), float)
    assert _near(b, R.VIOLATION_COLOR).sum() > _near(a, R.VIOLATION_COLOR).sum() + 20


# ----------------------------------------------------------------------- regress


def test_regress_names_itself_in_option_errors(line_scene, capsys):
    rc, out, err = _run(capsys, "regress", line_scene, "--dt", 0)
    assert rc == 2 and out == ""
    assert err.startswith("gfuzzy regress:"), err


def test_regress_checks_its_arguments_before_printing(line_scene, capsys):
    rc, out, err = _run(capsys, "regress", line_scene, "-n", 0)
    assert rc == 2
    assert out == "", "the table header was printed before the arguments were checked"
    assert len(err.strip().splitlines()) == 1 and "vert" in err


# ----------------------------------------------------------------------- scene


def test_a_mover_with_both_path_and_trajectory():
    doc = {
        "version": 1,
        "name": "both",
        "bounds": [0, 0, 5, 5],
        "robot": {"disc": 0.2, "vmax": 1.0},
        "movers": [
            {"name": "m", "disc": 0.3, "speed": 1.0, "path": [[1, 1], [2, 2]], "mode": "loop",
             "trajectory": [[0, 1, 1], [1, 2, 2]]},
        ],
    }
    with pytest.raises(SceneError) as exc:
        parse_scene(doc, "both.yaml")
    assert exc.value.place == "movers[0]"
    assert "either path" in exc.value.message and "trajectory" in exc.value.message
    assert "unknown key" not in exc.value.message
    doc["movers"][0] = {"name": "m", "disc": 0.3, "path": [[1, 1], [2, 2]], "trajectory": [[0, 1, 1]]}
    with pytest.raises(SceneError, match="either path"):
        parse_scene(doc, "both.yaml")


# ----------------------------------------------------------------------- API vs CLI


@pytest.fixture(scope="module")
def line_roadmap(tmp_path_factory):
    path = tmp_path_factory.mktemp("line") / "line.yaml"
    path.write_text(LINE)
    scene = load_scene(path)
    return scene, build_roadmap(scene, RoadmapOptions(vertices=40, seed=2))


@pytest.mark.parametrize(
    "start, goal, t0, where",
    [
        ([1.0, 2.5, 0.0], [9.0, 2.5], 0.0, "start"),
        ([1.0, 2.5], [9.0], 0.0, "goal"),
        ([1.0, math.nan], [9.0, 2.5], 0.0, "start"),
        ([1.0, 2.5], [math.inf, 2.5], 0.0, "goal"),
        ([1.0, 2.5], [9.0, 2.5], math.nan, "t0"),
    ],
)
def test_malformed_poses_are_bad_input_in_the_api(line_roadmap, start, goal, t0, where):
    scene, rm = line_roadmap
    with pytest.raises(ValueError, match=where):
        plan(scene, rm, start, goal, t0)


def test_a_well_formed_pose_in_collision_stays_an_invalid_query(line_roadmap):
    scene, rm = line_roadmap
    res = plan(scene, rm, [3.0, 1.0], [9.0, 2.5])
    assert res.status is Status.INVALID_QUERY and "static" in res.message


def test_the_cli_calls_a_malformed_pose_bad_input(line_scene, capsys):
    rc, out, err = _run(capsys, "plan", line_scene, "--start", 1, 2.5, 0, "--goal", 9, 2.5)
    assert rc == 2 and out == "" and len(err.strip().splitlines()) == 1


# ----------------------------------------------------------------------- render --speed on a GIF


def _frames(path):
    with Image.open(path) as im:
        out = []
        for k in range(im.n_frames):
            im.seek(k)
            out.append(im.convert("RGB"))
        return out


def _near(img, color, tol=12.0):
    rgb = np.asarray(img.convert("RGB") if isinstance(img, Image.Image) else img, dtype=float)
    want = 255 * np.asarray(to_rgb(color))
    return np.linalg.norm(rgb - want, axis=-1) <= tol


def test_gif_colours_the_trail_by_speed(line_scene, tmp_path, capsys):
    sc = load_scene(line_scene)
    # full speed along y = 2.5, then a crawl at a tenth of vmax
    wp = np.array([[0.0, 1.0, 2.5], [4.0, 5.0, 2.5], [14.0, 6.0, 2.5]])
    fast = R.colormaps[R.SPEED_CMAP](1.0)[:3]
    slow = R.colormaps[R.SPEED_CMAP](0.1)[:3]
    R.render_animation(sc, wp, tmp_path / "plain.gif", fps=2, max_frames=8)
    R.render_animation(sc, wp, tmp_path / "speed.gif", fps=2, max_frames=8, speed=True)
    last_plain, last_speed = _frames(tmp_path / "plain.gif")[-1], _frames(tmp_path / "speed.gif")[-1]
    assert _near(last_speed, fast, 30).sum() > 50
    assert _near(last_speed, slow, 30).sum() > 20
    assert _near(last_plain, fast, 30).sum() < 10
    # the command line passes --speed on to the animation instead of dropping it
    traj = _trajectory_file(tmp_path / "t.json", wp)
    rc, _, err = _run(capsys, "render", line_scene, traj, "-o", tmp_path / "cli.gif", "--speed")
    assert rc == 0, err
    assert _near(_frames(tmp_path / "cli.gif")[-1], fast, 30).sum() > 50


# ----------------------------------------------------------------------- wait labels


def _label_boxes(scene, wp):
    fig, ax = R._figure(scene, 8.0, False, 3)
    R._draw_obstacles(ax, scene)
    R._draw_trajectory(ax, fig, scene, wp, None, 6)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    waits = [t for t in ax.texts if t.get_text().startswith("wait")]
    stamps = [t for t in ax.texts if t.get_text().startswith("t=")]
    # the text itself (an annotation's own extent spans its leader line too)
    return (
        [Text.get_window_extent(t, renderer) for t in waits],
        [Text.get_window_extent(t, renderer) for t in stamps],
        [t.get_text() for t in waits],
    )


def test_wait_labels_do_not_overlap(line_scene):
    sc = load_scene(line_scene)
    # four short waits close together (as the planner makes when it dodges a mover), and
    # one long one
    wp = np.array(
        [
            [0.0, 1.0, 2.5], [1.0, 2.0, 2.5], [1.5, 2.0, 2.5], [1.6, 2.1, 2.5], [2.0, 2.1, 2.5],
            [2.1, 2.2, 2.5], [2.4, 2.2, 2.5], [2.5, 2.3, 2.4], [3.0, 2.3, 2.4], [8.0, 7.0, 2.4],
            [11.0, 7.0, 2.4], [13.0, 9.0, 2.4],
        ]
    )
    assert len(R.wait_intervals(wp)) == 5
    waits, stamps, texts = _label_boxes(sc, wp)
    joined = "\n".join(texts)
    for ta, tb, _ in R.wait_intervals(wp):  # every wait is labelled, close ones may share a label
        assert f"(t={R._fmt_time(ta)} to {R._fmt_time(tb)})" in joined
    for i, a in enumerate(waits):
        for b in waits[i + 1 :] + stamps:
            assert not a.overlaps(b), (a, b)


# ----------------------------------------------------------------------- amax


def _speed_change_rate(traj) -> float:
    """Largest change of configuration speed between consecutive rows, per second."""
    v, dt = traj.speeds(), np.diff(traj.times)
    return float(np.max(np.abs(np.diff(v)) / (0.5 * (dt[:-1] + dt[1:])), initial=0.0))


def test_the_answer_says_when_amax_is_not_honoured(line_roadmap):
    scene, rm = line_roadmap
    q = scene.queries[0]
    res = plan(scene, rm, q.start, q.goal, q.t0)
    assert res.solved
    doc = res.to_file(scene.name, q.name).to_dict()
    assert doc["amax_honoured"] is False and res.amax_honoured is False
    assert "speed layer" in doc["amax_note"]
    assert _speed_change_rate(res.trajectory) > scene.robot.amax  # the claim is true
    layered = plan(scene, rm, q.start, q.goal, q.t0, PlanOptions(speed_layer=True))
    assert layered.solved
    applied = layered.speed_report.applied
    doc = layered.to_file(scene.name, q.name).to_dict()
    assert doc["amax_honoured"] is applied
    if applied:  # and so is this one
        assert "amax_note" not in doc
        assert _speed_change_rate(layered.trajectory) <= scene.robot.amax * (1 + 1e-6)
    else:
        assert layered.speed_report.reason in doc["amax_note"]


def test_no_amax_no_claim():
    sc = parse_scene(
        {"version": 1, "name": "na", "bounds": [0, 0, 4, 2], "robot": {"disc": 0.2, "vmax": 1.0},
         "queries": [{"name": "q", "start": [0.5, 1.0], "goal": [3.5, 1.0]}]}
    )
    rm = build_roadmap(sc, RoadmapOptions(vertices=10, seed=1))
    res = plan(sc, rm, [0.5, 1.0], [3.5, 1.0])
    assert res.solved
    assert "amax_honoured" not in res.to_file(sc.name, "q").to_dict()


def test_the_cli_notes_an_amax_it_does_not_honour(line_scene, tmp_path, capsys):
    rc, _, err = _run(capsys, "plan", line_scene, "-n", 40, "--seed", 2, "-o", tmp_path / "a.json")
    assert rc == 0, err
    assert "amax" in err and "not honoured" in err
    assert json.loads((tmp_path / "a.json").read_text())["amax_honoured"] is False
