"""Pictures and animations: files written atomically, right format and size, not blank."""

from __future__ import annotations

import math
import re
from types import SimpleNamespace

import numpy as np
import pytest
from helpers import run_main as _run
from helpers import scene_of as _scene
from helpers import write_trajectory_file as _trajectory_file
from matplotlib.colors import to_rgb
from matplotlib.text import Text
from PIL import Image
from shared_scenes import DOOR

from gfuzzy.check.check import check_trajectory
from gfuzzy.render import render as R
from gfuzzy.scene.scene import load_scene

SCENE = """\
version: 1
name: render-test
bounds: [0.0, 0.0, 6.0, 4.0]
robot:
  {robot}
  vmax: 1.0
obstacles:
  - box: {{center: [3.0, 1.0], size: [0.2, 2.0], angle: 0.3}}
  - disc: {{center: [1.5, 3.0], radius: 0.4}}
  - polygon: [[4.2, 2.6], [5.2, 2.6], [5.0, 3.5], [4.4, 3.4]]
movers:
  - name: A
    box: [0.4, 0.3]
    speed: 1.0
    path: [[1.0, 1.0], [1.0, 2.5], [2.0, 2.5]]
    mode: loop
  - name: B
    disc: 0.25
    speed: 0.8
    path: [[4.0, 0.5], [5.5, 0.5]]
    mode: bounce
  - name: ped-1
    disc: 0.3
    trajectory: [[2.0, 5.5, 3.7], [5.0, 3.5, 2.0], [7.0, 2.0, 3.6]]
queries:
  - name: q
    start: {start}
    goal: {goal}
"""

# t, x, y: a wait from t=2 to t=3.5
DISC_WP = np.array(
    [[0.0, 0.5, 0.5], [2.0, 2.3, 0.5], [3.5, 2.3, 0.5], [5.0, 3.5, 2.2], [8.0, 5.5, 3.5]]
)
BOX_WP = np.column_stack([DISC_WP, [0.0, 0.0, 0.0, 1.0, 1.57]])


@pytest.fixture
def disc_scene(tmp_path):
    path = tmp_path / "disc.yaml"
    path.write_text(SCENE.format(robot="disc: 0.2", start="[0.5, 0.5]", goal="[5.5, 3.5]"))
    return load_scene(path)


@pytest.fixture
def box_scene(tmp_path):
    path = tmp_path / "box.yaml"
    path.write_text(
        SCENE.format(robot="box: [0.6, 0.3]", start="[0.5, 0.5, 0.0]", goal="[5.5, 3.5, 1.57]")
    )
    return load_scene(path)


def _near(img: Image.Image | np.ndarray, color, tol: float = 12.0) -> np.ndarray:
    """(h, w) bool: pixels of an image or an (h, w, 3) array within ``tol`` (0-255 RGB
    distance) of ``color``."""
    rgb = np.asarray(img.convert("RGB") if isinstance(img, Image.Image) else img, dtype=float)
    want = 255 * np.asarray(to_rgb(color))
    return np.linalg.norm(rgb - want, axis=-1) <= tol


def _blend(color, alpha: float):
    """``color`` drawn with ``alpha`` over white."""
    return tuple(alpha * np.asarray(to_rgb(color)) + (1 - alpha))


def _frames(path) -> list[Image.Image]:
    with Image.open(path) as im:
        out = []
        for k in range(im.n_frames):
            im.seek(k)
            out.append(im.convert("RGB"))
        return out


def _only(folder, name):
    """The folder holds ``name`` and no temporary leftovers."""
    return sorted(p.name for p in folder.iterdir() if not p.name.endswith(".yaml")) == [name]


# --------------------------------------------------------------------------- pictures


def test_a_huge_time_is_written_short(tmp_scene, tmp_path, capsys):
    # '.2f' wrote t = 1e300 as 301 digits in the title: matplotlib warned on stderr that the
    # axes had collapsed, and the picture was a title with no drawing. The scene has no
    # movers: among movers, render's check of 1e300 s bisects to its evaluation cap (20 s)
    import warnings

    assert R._fmt_time(1e300) == "1e+300" and R._fmt_time(22.6) == "22.6"
    scene = tmp_scene(DOOR, "door.yaml")
    traj = _trajectory_file(tmp_path / "far.json", [[0, 1, 2.5], [1e300, 1.1, 2.5]])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rc, _, err = _run(capsys, "render", scene, traj, "-o", tmp_path / "far.png")
    assert rc == 0, err
    assert not [w for w in caught if "collapsed" in str(w.message)]


def test_png_box_robot_with_roadmap_and_speed(box_scene, tmp_path):
    roadmap = SimpleNamespace(
        vertices=np.array([[0.5, 0.5, 0.0], [2.0, 3.5, 1.0], [5.5, 1.5, 0.0]]),
        edges=np.array([[0, 1], [1, 2]]),
    )
    out = tmp_path / "box.png"
    R.render_scene(box_scene, out, roadmap=roadmap, trajectory=BOX_WP, speed=True, dpi=80)
    assert _only(tmp_path, "box.png")
    with Image.open(out) as im:
        assert im.format == "PNG"
        assert im.size[0] == 8 * 80 and im.size[1] > 100
        assert _near(im, R.OBSTACLE_FACE).sum() > 500  # static obstacles are filled
        assert _near(im, R.START_COLOR).sum() > 10 and _near(im, R.GOAL_COLOR).sum() > 10
        with_edges = np.asarray(im.convert("RGB"))
    roadmap.edges = np.zeros((0, 2), dtype=int)
    R.render_scene(box_scene, out, roadmap=roadmap, trajectory=BOX_WP, speed=True, dpi=80)
    with Image.open(out) as im:
        without = np.asarray(im.convert("RGB"))
    # the edges, not only the legend's edge count, make the difference
    changed = np.any(with_edges != without, axis=-1)
    assert changed[: int(0.7 * len(changed))].sum() > 300


def test_png_disc_robot_accepts_waypoints_object_and_speed_array(disc_scene, tmp_path):
    out = tmp_path / "disc.png"
    traj = SimpleNamespace(waypoints=DISC_WP.tolist())
    speed = np.array([0.9, 0.0, 0.5, 0.7])  # one per segment
    R.render_scene(disc_scene, out, trajectory=traj, speed=speed, title="hello", dpi=50)
    with Image.open(out) as im:
        assert im.size[0] == 400
        assert _near(im, R.MOVER_COLORS[0], tol=40).sum() > 20  # mover A's dashed path
        assert _near(im, R.WAIT_COLOR).sum() > 10  # the wait marker
    # per-waypoint speeds and a plain JSON-like document work too
    R.render_scene(disc_scene, out, trajectory={"waypoints": DISC_WP}, speed=np.ones(5), dpi=50)
    with pytest.raises(ValueError, match="speed has 3 values"):
        R.render_scene(disc_scene, out, trajectory=DISC_WP, speed=np.ones(3))


def test_png_without_trajectory_draws_the_robot_path_nowhere(disc_scene, tmp_path):
    out = tmp_path / "scene.png"
    R.render_scene(disc_scene, out, dpi=50)
    with Image.open(out) as im:
        assert _near(im, R.OBSTACLE_FACE).sum() > 300
        assert _near(im, R.ROBOT_COLOR).sum() == 0


def test_still_gif(disc_scene, tmp_path):
    out = tmp_path / "still.gif"
    R.render_scene(disc_scene, out, trajectory=DISC_WP, dpi=40)
    with Image.open(out) as im:
        assert im.format == "GIF" and im.n_frames == 1


# --------------------------------------------------------------------------- animations


def test_gif_animates_robot_and_movers(box_scene, tmp_path):
    out = tmp_path / "anim.gif"
    n = R.render_animation(box_scene, BOX_WP, out, fps=5, max_frames=300, dpi=50)
    assert n == 41  # 8 s at 5 frames per second, both ends included
    assert _only(tmp_path, "anim.gif")
    frames = _frames(out)
    assert len(frames) == n > 1
    assert frames[0].size == (round(6.5 * 50), frames[0].size[1])
    assert _near(frames[0], R.OBSTACLE_FACE).sum() > 200

    # mover A (a box, drawn with alpha 0.75) is somewhere else 2 s later
    a_color = _blend(R.MOVER_COLORS[0], 0.75)
    m0, m10 = _near(frames[0], a_color), _near(frames[10], a_color)
    assert m0.sum() > 20 and m10.sum() > 20
    c0, c10 = np.argwhere(m0).mean(axis=0), np.argwhere(m10).mean(axis=0)
    assert np.hypot(*(c0 - c10)) > 10  # pixels

    # the timed mover ped-1 exists only from t=2: absent in the first frame, present at t=4
    ped = _blend(R.MOVER_COLORS[2], 0.75)
    assert _near(frames[0], ped).sum() < 0.3 * _near(frames[20], ped).sum()

    # the robot moves too: the frames differ
    assert np.any(np.asarray(frames[0]) != np.asarray(frames[-1]))


def test_gif_caps_frames_and_keeps_real_time(disc_scene, tmp_path):
    wp = np.column_stack(
        [np.linspace(0, 35, 200), np.linspace(0.5, 5.5, 200), np.linspace(0.5, 3.5, 200)]
    )
    out = tmp_path / "long.gif"
    n = R.render_animation(disc_scene, wp, out, fps=15, max_frames=30, dpi=30)
    assert n == 30
    with Image.open(out) as im:
        assert im.n_frames == 30
        total = 0
        for k in range(im.n_frames):
            im.seek(k)
            total += im.info["duration"]
    # 29 intervals of 35/29 s (the last frame is shown one interval too)
    assert total == pytest.approx(35_000 * 30 / 29, abs=10)


def test_gif_of_movers_only(disc_scene, tmp_path):
    out = tmp_path / "movers.gif"
    n = R.render_animation(disc_scene, None, out, fps=2, duration=3.0, dpi=30)
    assert n == 7
    frames = _frames(out)
    assert np.any(np.asarray(frames[0]) != np.asarray(frames[3]))


def test_render_picks_from_suffix(disc_scene, tmp_path):
    R.render(disc_scene, tmp_path / "a.png", trajectory=DISC_WP, dpi=30)
    R.render(disc_scene, tmp_path / "a.GIF", trajectory=DISC_WP, fps=1, dpi=30)
    with Image.open(tmp_path / "a.png") as im:
        assert im.format == "PNG"
    with Image.open(tmp_path / "a.GIF") as im:
        assert im.format == "GIF" and im.n_frames == 9


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "call",
    [
        lambda s, d: R.render_scene(s, d / "out.jpg"),
        lambda s, d: R.render_scene(s, d / "out"),
        lambda s, d: R.render_animation(s, DISC_WP, d / "out.png"),
        lambda s, d: R.render(s, d / "out.svg", trajectory=DISC_WP),
    ],
)
def test_bad_suffix_raises_and_writes_nothing(disc_scene, tmp_path, call):
    folder = tmp_path / "o"
    folder.mkdir()
    with pytest.raises(ValueError, match="use .(png|gif)"):
        call(disc_scene, folder)
    assert list(folder.iterdir()) == []


@pytest.mark.parametrize(
    "waypoints, message",
    [
        (BOX_WP, "disc robot"),  # [t, x, y, heading] rows for a disc robot
        (np.zeros((0, 3)), "no waypoints"),
        (DISC_WP[[0, 2, 1]], "does not increase"),
        (DISC_WP[:, :2], "rows"),
        ([[0.0, 1.0, math.nan]], "non-finite"),
    ],
)
def test_bad_trajectory_raises_and_keeps_old_file(disc_scene, tmp_path, waypoints, message):
    out = tmp_path / "keep.png"
    out.write_bytes(b"old")
    with pytest.raises(ValueError, match=message):
        R.render_scene(disc_scene, out, trajectory=waypoints)
    with pytest.raises(ValueError, match=message):
        R.render_animation(disc_scene, waypoints, tmp_path / "keep.gif")
    assert out.read_bytes() == b"old"
    assert _only(tmp_path, "keep.png")


# --------------------------------------------------------------------------- helpers


def test_interpolation_takes_the_shorter_arc():
    wp = np.array([[0.0, 0.0, 0.0, 3.0], [2.0, 2.0, 4.0, -3.0]])
    pose = R.poses_at_times(wp, [1.0, -5.0, 9.0])
    # from 3 rad to -3 rad the short way passes pi, not 0 (pi and -pi are one heading)
    assert pose[0, :2] == pytest.approx([1.0, 2.0])
    assert [math.cos(pose[0, 2]), math.sin(pose[0, 2])] == pytest.approx([-1.0, 0.0])
    assert pose[1] == pytest.approx([0.0, 0.0, 3.0])  # clamped to the ends
    assert pose[2, :2] == pytest.approx([2.0, 4.0])
    assert math.cos(pose[2, 2]) == pytest.approx(math.cos(-3.0))


def test_speeds_and_waits():
    assert R.segment_speeds(DISC_WP)[:2] == pytest.approx([0.9, 0.0])
    turn = np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.5]])
    assert R.segment_speeds(turn, circumradius=2.0) == pytest.approx([1.0])
    waits = R.wait_intervals(np.vstack([DISC_WP[:3], [4.0, 2.3, 0.5], DISC_WP[3:]]))
    assert [(a, b) for a, b, _ in waits] == [(2.0, 4.0)]
    assert waits[0][2] == pytest.approx([2.3, 0.5])
    assert len(R.wait_intervals(BOX_WP)) == 1
    turning = BOX_WP.copy()
    turning[2, 3] = 0.3  # turning in place is not a wait
    assert R.wait_intervals(turning) == []


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


def test_render_draws_the_clearances(tmp_path):
    from gfuzzy.render.render import _clearance_outline, render

    box = _scene(DOOR.replace("disc: 0.2", "box: [0.4, 0.2]").replace("start: [0.5, 1.5], goal: [5.5, 1.5]",
                                                                       "start: [0.5, 1.5, 0], goal: [5.5, 1.5, 0]"))  # fmt: skip
    pose = np.array([1.0, 1.0, 0.3])
    ring = _clearance_outline(box, pose, 0.05)
    xy = ring.get_xy()
    local = (xy - pose[:2]) @ np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
    assert np.abs(local[:, 0]).max() == pytest.approx(0.25, abs=1e-6)  # half length + clearance
    assert np.abs(local[:, 1]).max() == pytest.approx(0.15, abs=1e-6)
    assert ring.get_linestyle() == "--" and not ring.get_fill()
    assert _clearance_outline(box, pose, 0.0) is None
    disc = _scene(DOOR)
    assert _clearance_outline(disc, pose[:2], 0.05).get_radius() == pytest.approx(0.25)
    wps = np.array([[0.0, 0.5, 1.5], [5.0, 5.5, 1.5]])
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    render(disc, a, trajectory=wps)
    render(disc.with_clearances(0.0), b, trajectory=wps)
    assert a.read_bytes() != b.read_bytes()


def test_a_gif_of_a_trajectory_ending_at_1e300_keeps_its_delays_and_clock_in_bounds():
    # a plan whose last row was edited to t = 1e300: the frames' running clock overflowed
    # the int cast (a RuntimeWarning, then every delay 10 ms), and each frame drew its
    # clock's 300 digits (92,000 glyphs, most of the animation's 17 s)
    import warnings

    from gfuzzy.render.animate import GIF_MAX_DELAY_CS, _clock_text, _gif_durations

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert _gif_durations(300, 1e303 / 299) == [10 * GIF_MAX_DELAY_CS] * 300
    assert _gif_durations(4, 1000.0 / 15) == [70, 60, 70, 70]  # real time kept below the bound
    assert _clock_text(1e300) == "t = 1e+300 s"
    assert _clock_text(6.65) == "t =   6.65 s"


def test_queries_from_one_start_share_one_label():
    # three queries leaving one place printed their names over each other at that start
    from gfuzzy.scene.scene import parse_scene

    doc = {"version": 1, "name": "starts", "bounds": [0, 0, 6, 4], "robot": {"disc": 0.2, "vmax": 1.0},
           "queries": [{"name": n, "start": s, "goal": [5, 3]} for n, s in
                       (("q", [1, 1]), ("late", [1, 1]), ("other", [2, 1]), ("hold", [1, 1]))]}  # fmt: skip
    fig, ax = R._figure(parse_scene(doc), 8.0, False, 3)
    R._draw_queries(ax, parse_scene(doc))
    labels = sorted((t.get_text(), tuple(t.xy)) for t in ax.texts)
    assert labels == [("other", (2.0, 1.0)), ("q, late, hold", (1.0, 1.0))]


def test_rows_of_the_wrong_width_name_the_rows_a_unicycle_disc_robot_takes(repo_root, tmp_path, capsys):
    # a unicycle disc robot takes [t, x, y, heading]: the message said "disc robot: expected [t, x, y]"
    sc = load_scene(repo_root / "scenes" / "tb3-arena-unicycle.yaml")
    want = "expects [t, x, y, heading] for this disc robot (unicycle)"
    with pytest.raises(ValueError, match=re.escape(want)):
        R.as_waypoints([[0.0, 1.0, 1.0], [1.0, 1.2, 1.0]], sc)
    assert R.as_waypoints([[0.0, 1.0, 1.0, 0.0], [1.0, 1.2, 1.0, 0.0]], sc).shape == (2, 4)
    traj = _trajectory_file(tmp_path / "t.json", [[0.0, 1.0, 1.0], [1.0, 1.2, 1.0]], scene=sc.name)
    rc, _, err = _run(capsys, "check", repo_root / "scenes" / "tb3-arena-unicycle.yaml", traj)
    assert rc == 2 and f"{traj}: waypoints: rows of 3 numbers, but scene 'tb3-arena-unicycle' {want}" in err, err
