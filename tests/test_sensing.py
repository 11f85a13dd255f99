"""The robot's sensor (gfuzzy.navigation.sensing) and the social metrics (gfuzzy.navigation.socialmetrics):
each against a case whose answer is known by hand."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from helpers import main_completed, run_main

import gfuzzy
from gfuzzy.errors import InputError
from gfuzzy.navigation.sensing import Sensor, SensorOptions, Tracker, in_fov, line_of_sight
from gfuzzy.navigation.socialmetrics import social_metrics, step_gaps
from gfuzzy.scene.scene import Mover, parse_scene

ROOT = Path(__file__).resolve().parents[1]


def _scene(obstacles=()):
    return parse_scene({
        "version": 1, "name": "s", "bounds": [-10, -10, 10, 10], "robot": {"disc": 0.3, "vmax": 1.0},
        "obstacles": list(obstacles), "movers": [], "queries": [],
    })  # fmt: skip


def _walker(name, rows, r=0.3):
    return Mover(name, "disc", r, (0.0, 0.0), trajectory=np.asarray(rows, float))


# ------------------------------------------------------------------ velocity estimate


def test_tracker_velocity_is_the_difference_of_two_positions_one_period_apart():
    tr = Tracker()
    v = np.array([1.0, 0.5])
    first = tr.update(0.0, [[1.0, 2.0, 0.3]])
    assert first.shape == (1, 5)
    np.testing.assert_array_equal(first[0], [1.0, 2.0, 0.0, 0.0, 0.3])  # one sighting: no velocity yet
    for k in (1, 2, 3):
        out = tr.update(0.25 * k, [[1.0 + v[0] * 0.25 * k, 2.0 + v[1] * 0.25 * k, 0.3]])
        np.testing.assert_allclose(out[0, 2:4], v, atol=1e-12)
    # a turn: the estimate is the last period's displacement over the period (never the future)
    p = out[0, :2]
    out = tr.update(1.0, [[p[0], p[1] + 0.25, 0.3]])
    np.testing.assert_allclose(out[0, 2:4], [0.0, 1.0], atol=1e-12)


def test_tracker_associates_unlabelled_detections():
    tr = Tracker()
    a0, b0 = np.array([0.0, 0.0]), np.array([0.0, 1.5])
    va, vb = np.array([1.0, 0.0]), np.array([-1.0, 0.2])
    for k in range(4):
        t = 0.25 * k
        det = [[*(b0 + vb * t), 0.25], [*(a0 + va * t), 0.3]]
        if k % 2:
            det = det[::-1]  # detections come in no particular order
        out = tr.update(t, det)
    assert len(out) == 2
    by_radius = {round(r[4], 2): r for r in out}
    np.testing.assert_allclose(by_radius[0.3][2:4], va, atol=1e-12)
    np.testing.assert_allclose(by_radius[0.25][2:4], vb, atol=1e-12)


def test_a_person_seen_once_is_found_again_where_their_disc_grew_to():
    """Seen once (no velocity yet), then unseen for 2 s, then seen 1.8 m away: the same
    person (their reported disc grew at a walking pace, and so did the association gate),
    not a second track beside a phantom of the first."""
    tr = Tracker()
    tr.update(0.0, [[0.0, 0.0, 0.3]])
    for k in range(1, 8):
        grown = tr.update(0.25 * k, np.zeros((0, 3)))
    np.testing.assert_allclose(grown[0, 4], 0.3 + 1.0)  # grew at 1 m/s, capped at 1 m
    out = tr.update(2.0, [[1.8, 0.0, 0.3]])
    assert len(out) == 1
    np.testing.assert_allclose(out[0], [1.8, 0.0, 0.9, 0.0, 0.3])  # its velocity: 1.8 m over 2 s


def test_tracker_coasts_an_unseen_person_then_drops_them():
    tr = Tracker(coast=0.5)
    tr.update(0.0, [[0.0, 0.0, 0.3]])
    tr.update(0.25, [[0.25, 0.0, 0.3]])
    out = tr.update(0.5, np.zeros((0, 3)))  # unseen: walking on at the last velocity
    np.testing.assert_allclose(out[0, :4], [0.5, 0.0, 1.0, 0.0])
    assert len(tr.update(0.75, np.zeros((0, 3)))) == 1
    assert len(tr.update(1.0, np.zeros((0, 3)))) == 0  # 0.75 s unseen > coast


def test_noise_is_gaussian_with_the_given_sigma_and_seeded():
    truth = np.array([[2.0, 1.0, 0.0, 0.0, 0.3]])
    sensor = Sensor(_scene(), SensorOptions(velocity="exact", noise=0.1, seed=4))
    xy = np.array([sensor.observe(0.25 * k, np.zeros(2), 0.0, truth)[0, :2] for k in range(4000)])
    np.testing.assert_allclose(xy.mean(axis=0), [2.0, 1.0], atol=0.01)  # 4 sigma / sqrt(n) = 0.006
    np.testing.assert_allclose(xy.std(axis=0), [0.1, 0.1], rtol=0.05)
    again = Sensor(_scene(), SensorOptions(velocity="exact", noise=0.1, seed=4))
    np.testing.assert_array_equal(again.observe(0.0, np.zeros(2), 0.0, truth)[0, :2], xy[0])  # same seed
    other = Sensor(_scene(), SensorOptions(velocity="exact", noise=0.1, seed=5))
    assert not np.array_equal(other.observe(0.0, np.zeros(2), 0.0, truth)[0, :2], xy[0])


def test_estimated_velocity_under_noise_is_close_to_the_truth():
    sensor = Sensor(_scene(), SensorOptions(noise=0.05, seed=1))
    v = np.array([1.0, 0.0])
    est = []
    for k in range(200):
        t = 0.25 * k
        truth = np.array([[-5.0 + v[0] * t * 0.04, 0.0, 0.04, 0.0, 0.3]])  # slow, so it stays in view
        est.append(sensor.observe(t, np.zeros(2), math.pi, truth)[0, 2:4])
    est = np.array(est[20:])
    assert abs(est[:, 0].mean() - 0.04) < 0.03
    assert est[:, 0].std() < 0.25  # the raw difference would have 0.05 * sqrt(2) / 0.25 = 0.28


def test_field_of_view_is_a_cone_about_the_heading():
    pts = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 0.9], [1.0, 1.1], [-1.0, 0.0]])
    np.testing.assert_array_equal(in_fov(np.zeros(2), 0.0, pts, 90.0), [True, False, True, False, False])
    np.testing.assert_array_equal(in_fov(np.zeros(2), math.pi / 2, pts, 90.0), [False, True, False, True, False])
    assert in_fov(np.zeros(2), 0.0, pts, 360.0).all()
    # through the sensor: a person behind a robot heading +x is not seen with a 180 degree view
    s = Sensor(_scene(), SensorOptions(velocity="exact", fov=180.0))
    truth = np.array([[2.0, 0.5, 0, 0, 0.3], [-2.0, 0.0, 0, 0, 0.3]])
    np.testing.assert_array_equal(s.observe(0.0, np.zeros(2), 0.0, truth)[:, 0], [2.0])


def test_occlusion_by_a_static_obstacle_on_the_line_of_sight():
    scene = _scene([{"box": {"center": [2.0, 0.0], "size": [0.2, 2.0]}}])  # a wall, y in [-1, 1]
    pts = np.array([[4.0, 0.0], [4.0, 3.0], [1.0, 0.0]])
    # (4, 0): behind the wall; (4, 3): the line passes the wall's top at y = 1.5; (1, 0): in front
    np.testing.assert_array_equal(line_of_sight(scene, np.zeros(2), pts), [False, True, True])
    s = Sensor(scene, SensorOptions(velocity="exact", occlusion=True))
    truth = np.column_stack([pts, np.zeros((3, 2)), np.full(3, 0.3)])
    assert s.observe(0.0, np.zeros(2), 0.0, truth).shape == (2, 5)
    assert Sensor(scene, SensorOptions(velocity="exact")).observe(0.0, np.zeros(2), 0.0, truth).shape == (3, 5)


def test_occlusion_unites_the_obstacles_once_per_sensor(monkeypatch):
    # the obstacles' union was built again at every look: on a 4000 x 4000 SLAM map (9,000
    # cell rectangles) 0.3 s a look, 50 of the 75 s of a 45 s `gfuzzy navigate --occlusion`
    import shapely

    calls = []
    union_all = shapely.union_all
    monkeypatch.setattr(shapely, "union_all", lambda *a, **k: calls.append(1) or union_all(*a, **k))
    scene = _scene([{"box": {"center": [2.0, 0.0], "size": [0.2, 2.0]}}, {"disc": {"center": [0.0, 3.0], "radius": 0.5}}])
    s = Sensor(scene, SensorOptions(velocity="exact", occlusion=True))
    truth = np.array([[4.0, 0.0, 0, 0, 0.3], [4.0, 3.0, 0, 0, 0.3], [0.0, 5.0, 0, 0, 0.3]])
    for k in range(20):
        seen = s.observe(0.25 * k, np.zeros(2), 0.0, truth)
        assert seen[:, :2].tolist() == [[4.0, 3.0]]  # behind the wall and behind the disc: hidden
    assert len(calls) == 1
    # a sensor handed another scene looks through that scene's obstacles, not the first's
    s.scene = _scene([{"box": {"center": [2.0, 1.5], "size": [0.2, 0.4]}}])  # hides only (4, 3)
    seen = s.observe(5.0, np.zeros(2), 0.0, truth)
    assert sorted(seen[:, :2].tolist()) == [[0.0, 5.0], [4.0, 0.0]]


def test_line_of_sight_still_takes_a_list_of_shapes():
    # the fourth argument was a list of shapes; shapely would pair a list with the lines
    # one by one and answer wrongly
    import shapely

    scene = _scene([])
    wall = shapely.box(1.9, -1.0, 2.1, 1.0)
    pts = np.array([[4.0, 0.0], [4.0, 3.0]])
    for shapes in ([wall], [shapely.box(50, 50, 51, 51), wall]):
        np.testing.assert_array_equal(line_of_sight(scene, np.zeros(2), pts, shapes), [False, True])
        np.testing.assert_array_equal(line_of_sight(scene, np.zeros(2), pts[::-1], shapes), [True, False])


def test_sensor_options_refuse_bad_values():
    for kw in ({"velocity": "future"}, {"noise": -1.0}, {"fov": 0.0}, {"fov": 400.0}, {"sense": 0.0}):
        with pytest.raises(InputError):
            SensorOptions(**kw)


# ---------------------------------------------------------------------- social metrics


def test_discomfort_and_intrusion_by_hand():
    # the robot stands at the origin for 4 s (16 steps of 0.25 s); a person walks along
    # y = 0.5 from x = 4 to x = 0 at 1 m/s: the centre distance is hypot(4 - t, 0.5)
    robot = np.array([[0.0, 0.0, 0.0], [4.0, 0.0, 0.0]])
    walker = _walker("p", [[0.0, 4.0, 0.5], [4.0, 0.0, 0.5]])
    m = social_metrics(robot, 0.3, [walker], 0.25)
    assert m.steps == 16
    # gap < 0.2 <=> |4 - t| < sqrt(0.8^2 - 0.5^2) = 0.6245 <=> t > 3.3755: steps 13, 14, 15
    assert m.discomfort_steps == 3
    assert m.discomfort_frequency == pytest.approx(3 / 16)
    # centre within 0.6 <=> t > 4 - sqrt(0.6^2 - 0.5^2) = 3.6683 (while present, t <= 4):
    # the instants 3.75 and 4.0, seen from t_k = 3.75 - 0.25 j or 4.0 - 0.25 j (j = 1..5),
    # t_k in 2.5 .. 3.75: steps 10..15
    assert m.intrusion_steps == 6
    assert m.intrusion_ratio == pytest.approx(6 / 16)
    assert m.min_gap == pytest.approx(0.5 - 0.6)


def test_intrusion_looks_at_the_next_five_instants_only():
    # CrowdNav++'s test: the robot's centre now against the person's centre 0.25, 0.5, ...
    # 1.25 s later. A fast person passing 0.5 m from the standing robot between two of
    # those instants (centre abreast at t = 0.625: x = 4 t - 2.5) never intrudes: at
    # t = 0.5 and 0.75 the centre is hypot(0.5, 0.5) = 0.707 m away
    robot = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    fast = _walker("f", [[0.0, -2.5, 0.5], [2.0, 5.5, 0.5]])
    assert social_metrics(robot, 0.3, [fast], 0.25).intrusion_steps == 0
    # the same person 0.125 s later is abreast at t = 0.75, an instant seen from steps 0..2
    late = _walker("l", [[0.0, -3.0, 0.5], [2.0, 5.0, 0.5]])
    assert social_metrics(robot, 0.3, [late], 0.25).intrusion_steps == 3
    # someone close now but gone 0.25 s later is discomfort, not intrusion
    brief = _walker("b", [[0.0, 0.5, 0.0], [0.2, 0.5, 0.0]])
    m = social_metrics(robot, 0.3, [brief], 0.25)
    assert m.intrusion_steps == 0 and m.discomfort_steps == 1


def test_step_gaps_take_the_closest_instant_within_each_step():
    # a person passes the standing robot at t = 0.5, 0.7 m away: the closest instant is a
    # step boundary, the steps on either side both see it
    robot = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    walker = _walker("p", [[0.0, -2.0, 0.7], [1.0, 2.0, 0.7]])
    g = step_gaps(robot, 0.3, [walker], 0.25)
    np.testing.assert_allclose(g, [math.hypot(1.0, 0.7) - 0.6, 0.1, 0.1, math.hypot(1.0, 0.7) - 0.6])
    # the same person 0.2 s later: the closest instant is inside step 2 (t = 0.7)
    late = _walker("q", [[0.2, -2.0, 0.7], [1.2, 2.0, 0.7]])
    g = step_gaps(robot, 0.3, [late], 0.25)
    assert g[2] == pytest.approx(0.1)
    assert g[0] == pytest.approx(math.hypot(2.0 - 4 * 0.05, 0.7) - 0.6)  # present from t = 0.2 only
    assert social_metrics(robot, 0.3, [], 0.25).discomfort_steps == 0


# ----------------------------------------------------------------------- navigate


def _run(*args):
    return subprocess.run([sys.executable, "-m", "gfuzzy", *args], capture_output=True, text=True, cwd=ROOT)


@pytest.mark.parametrize("name", ["zara-crowd", "eth-crossing"])
def test_pedestrian_replays_with_estimated_velocities_reach_the_goal_and_check(tmp_path, name, capsys, monkeypatch):
    monkeypatch.chdir(ROOT)  # the scenes named as a user in the repository names them
    out = tmp_path / f"{name}.json"
    p = main_completed(capsys, "navigate", f"scenes/{name}.yaml", "-o", str(out))
    assert p.returncode == 0, p.stdout + p.stderr
    doc = json.loads(out.read_text())
    assert doc["status"] == "solved"
    assert doc["navigate"]["velocity"] == "estimated"
    assert 0.0 <= doc["discomfort_frequency"] <= 1.0 and 0.0 <= doc["intrusion_ratio"] <= 1.0
    c = main_completed(capsys, "check", f"scenes/{name}.yaml", str(out))
    assert c.returncode == 0, c.stdout + c.stderr


def test_navigate_with_a_narrow_noisy_view_stays_valid(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(ROOT)  # the scenes named as a user in the repository names them
    out = tmp_path / "z.json"
    p = main_completed(capsys, "navigate", "scenes/zara-crowd.yaml", "--noise", "0.05", "--fov", "180",
                       "--occlusion", "--seed", "3", "-o", str(out))  # fmt: skip
    assert p.returncode in (0, 1), p.stderr
    doc = json.loads(out.read_text())
    assert doc["navigate"]["noise"] == 0.05 and doc["navigate"]["fov"] == 180.0 and doc["navigate"]["occlusion"]
    scene = gfuzzy.load_scene(ROOT / "scenes" / "zara-crowd.yaml")
    rows = doc["waypoints"] if doc["status"] == "solved" else doc["executed"]
    assert gfuzzy.check_trajectory(scene, np.array(rows), None).valid


@pytest.mark.parametrize("flags", [["--noise", "-1"], ["--fov", "0"], ["--fov", "361"], ["--noise", "nan"],
                                   ["--velocity", "future"]])  # fmt: skip
def test_navigate_refuses_bad_sensor_flags_in_one_line(tmp_path, capsys, flags):
    # in this process (a traceback would be an exception here); one real process below
    out = tmp_path / "x.json"
    rc, stdout, stderr = run_main(capsys, "navigate", ROOT / "scenes" / "zara-crowd.yaml", *flags, "-o", out)
    assert rc == 2, stdout + stderr
    assert len(stderr.strip().splitlines()) == 1 and "Traceback" not in stderr
    assert not out.exists()


def test_navigate_refuses_a_bad_sensor_flag_from_a_real_process(tmp_path):
    out = tmp_path / "x.json"
    p = _run("navigate", "scenes/zara-crowd.yaml", "--noise", "nan", "-o", str(out))
    assert p.returncode == 2
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr
    assert not out.exists()


def test_a_map_wall_hides_a_mover(tmp_path):
    from PIL import Image

    img = np.full((40, 40), 254, np.uint8)  # 0.1 m cells over [-2, 2]^2; a wall at x in [0.9, 1.1]
    img[10:30, 29:31] = 0
    Image.fromarray(img).save(tmp_path / "m.pgm")
    (tmp_path / "m.yaml").write_text(
        "image: m.pgm\nresolution: 0.1\norigin: [-2.0, -2.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    (tmp_path / "s.yaml").write_text(
        "version: 1\nname: s\nrobot: {disc: 0.1, vmax: 1.0}\n"
        "obstacles: [{map: {file: m.yaml}}]\nmovers: []\nqueries: []\n"
    )
    scene = gfuzzy.load_scene(tmp_path / "s.yaml")
    pts = np.array([[1.8, 0.0], [1.5, 1.9], [0.5, 0.0]])
    # behind the wall (y in [-1, 1]); passing above its end (y 1.14 at x 0.9); in front of it
    np.testing.assert_array_equal(line_of_sight(scene, np.zeros(2), pts), [False, True, True])


def test_an_unseen_track_walks_on_less_certain_and_is_dropped_after_the_coast():
    from gfuzzy.navigation.sensing import Tracker

    tr = Tracker(noise=0.0, coast=4.0, gate=1.0, growth=0.2)
    tr.update(0.0, np.array([[0.0, 0.0, 0.3], [5.0, 5.0, 0.3]]))
    tr.update(0.25, np.array([[0.25, 0.0, 0.3]]))  # the first walks +x at 1 m/s; the second is lost
    out = tr.update(1.0, np.zeros((0, 3)))  # nobody seen
    walker = out[np.argmin(np.abs(out[:, 1]))]
    np.testing.assert_allclose(walker, [1.0, 0.0, 1.0, 0.0, 0.3 + 0.2 * 0.75])
    # seen once (velocity unknown), unseen for 1 s: it may be anywhere a walker gets in 1 s
    once = out[np.argmax(out[:, 1])]
    np.testing.assert_allclose(once, [5.0, 5.0, 0.0, 0.0, 0.3 + 1.0])
    # the gate grows with the time unseen before this update (0.75 s): 2 s later the walker
    # is taken up again 1.1 m off its prediction (gate 1 + 0.2 * 0.75 = 1.15)
    out = tr.update(3.0, np.array([[3.0, 1.1, 0.3]]))
    assert len(out) == 2 and np.any(np.all(np.isclose(out[:, :2], [3.0, 1.1]), axis=1))
    assert tr.update(4.3, np.zeros((0, 3))).shape[0] == 1  # the one seen once is gone (4 s)
    assert tr.update(7.1, np.zeros((0, 3))).shape[0] == 0


# ------------------------------------------------------------------ noisy first sightings


def test_noisy_first_sightings_give_the_least_squares_velocity():
    """With noise the filter's gains start as the expanding-memory filter's: at the n-th
    sighting (n <= 5, before the steady state) its velocity is the least-squares slope
    through the n noisy positions (numpy's polyfit as the oracle)."""
    rng = np.random.default_rng(3)
    tr = Tracker(noise=0.05)
    times = 0.25 * np.arange(5)
    z = np.column_stack([0.2 + 0.9 * times, -1.0 + 0.4 * times]) + rng.normal(0.0, 0.05, (5, 2))
    for n in range(1, 6):
        out = tr.update(times[n - 1], [[*z[n - 1], 0.3]])
        if n == 1:
            np.testing.assert_array_equal(out[0, 2:4], [0.0, 0.0])
            continue
        slope = [np.polyfit(times[:n], z[:n, c], 1)[0] for c in (0, 1)]
        np.testing.assert_allclose(out[0, 2:4], slope, atol=1e-9)


def test_velocity_sigma_matches_the_spread_of_the_estimates():
    """velocity_sigma is the estimates' standard deviation (Monte Carlo over 1000 walks),
    after 3 sightings and at the steady state (20 sightings). The walks are 100 people 10 m
    apart in each of 10 trackers (each detection its own track's: a track's filter is its
    own), not 1000 trackers of one person: 0.4 s, not 4.5."""
    rng = np.random.default_rng(7)
    lane = 10.0 * np.arange(100)
    for n in (3, 20):
        est, sig = [], []
        for _ in range(10):
            tr = Tracker(noise=0.05)
            for k in range(n):
                t = 0.25 * k
                seen = np.column_stack([t + rng.normal(0, 0.05, 100), lane + rng.normal(0, 0.05, 100), np.full(100, 0.3)])
                out = tr.update(t, seen)
            assert len(out) == 100 and np.all(np.abs(out[:, 1] - lane) < 1.0)  # one track per person, in order
            est.append(out[:, 2:4])
            sig.append(tr.velocity_sigma())
        est, sig = np.concatenate(est), np.concatenate(sig)
        assert np.ptp(sig) == 0.0
        sig = sig[0]
        np.testing.assert_allclose(est.mean(axis=0), [1.0, 0.0], atol=4 * sig / math.sqrt(1000) + 1e-3)
        np.testing.assert_allclose(est.std(axis=0), [sig, sig], rtol=0.08)


def test_an_unseen_noisy_track_grows_with_its_velocity_uncertainty():
    tr = Tracker(noise=0.05, growth=0.2)
    for k in range(3):
        tr.update(0.25 * k, [[0.25 * k, 0.0, 0.3]])
    sig = tr.velocity_sigma()[0]
    assert sig == pytest.approx(0.05 * math.sqrt(12 * 2 / (3 * 4)) / 0.5)  # least squares, 3 points over 0.5 s
    out = tr.update(1.0, np.zeros((0, 3)))  # 0.5 s unseen
    assert out[0, 4] == pytest.approx(0.3 + (0.2 + 3.0 * sig) * 0.5)
    clean = Tracker(noise=0.0, growth=0.2)
    for k in range(3):
        clean.update(0.25 * k, [[0.25 * k, 0.0, 0.3]])
    assert clean.velocity_sigma()[0] == 0.0
    assert clean.update(1.0, np.zeros((0, 3)))[0, 4] == pytest.approx(0.3 + 0.2 * 0.5)


def test_navigate_budget_on_cpu_time(tmp_path, capsys, monkeypatch):
    """`gfuzzy navigate --budget-clock cpu` (as `gfuzzy crowd` has) puts the replan budget on
    CPU time, so that a run does not depend on the machine's load; it was missing."""
    monkeypatch.chdir(ROOT)  # the scenes named as a user in the repository names them
    out = tmp_path / "z.json"
    p = main_completed(capsys, "navigate", "scenes/zara-crowd.yaml", "--budget-clock", "cpu", "-o", str(out))
    assert p.returncode == 0, p.stdout + p.stderr
    assert json.loads(out.read_text())["navigate"]["budget_clock"] == "cpu"
    p = main_completed(capsys, "navigate", "scenes/zara-crowd.yaml", "--budget-clock", "sundial", "-o", str(out))
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1


def test_navigate_file_says_how_the_navigator_searched(tmp_path, capsys, monkeypatch):
    """A run with ``--soft-search`` and one without wrote the same ``navigate`` settings: the
    file did not say that people's space had been priced, nor the search's step, budget or
    backend; every setting that changes the run is there now."""
    monkeypatch.chdir(ROOT)  # the scenes named as a user in the repository names them
    docs = {}
    # the first 2 s of the crossing: the file's settings are written whether or not the goal
    # was reached (the whole crossing cost 7 s a run, for the same settings)
    for name, flags in (("tiers", ()), ("priced", ("--soft-search", "--intrusion-cost", "3", "--dt", "0.2"))):
        out = tmp_path / f"{name}.json"
        p = main_completed(capsys, "navigate", "scenes/zara-crowd.yaml", "--budget-clock", "cpu", "--max-time", "2",
                           "--time-budget", "0.08", *flags, "-o", str(out))  # fmt: skip
        assert p.returncode in (0, 1), p.stdout + p.stderr
        docs[name] = json.loads(out.read_text())["navigate"]
    assert docs["tiers"]["soft_search"] is False and docs["tiers"]["intrusion_cost"] is None
    assert docs["priced"]["soft_search"] is True and docs["priced"]["intrusion_cost"] == 3.0
    assert docs["tiers"]["dt"] == 0.1 and docs["priced"]["dt"] == 0.2
    assert docs["priced"]["time_budget"] == 0.08 and docs["priced"]["backend"] == "compiled"
    assert docs["tiers"]["max_time"] == docs["priced"]["max_time"] == 2.0


def test_replan_times_are_on_the_budget_clock(monkeypatch):
    """The replan times a run reports are on the navigator's budget clock: with the budget
    on CPU time, a loaded machine does not make calls look over budget (they were always
    wall-clock time)."""
    import itertools

    from gfuzzy.navigation import navsim

    ticks = itertools.count(0.0, 7.0)
    monkeypatch.setattr(navsim, "BUDGET_CLOCKS", {"wall": time.perf_counter, "cpu": lambda: next(ticks)})
    scene = gfuzzy.load_scene(ROOT / "scenes" / "zara-crowd.yaml")
    rm = gfuzzy.build_roadmap(scene, gfuzzy.RoadmapOptions(vertices=60, seed=1))
    q = scene.queries[0]
    run = navsim.simulate(scene, rm, q.start, q.goal, max_time=1.0, options=gfuzzy.NavOptions(budget_clock="cpu"))
    assert run.replans >= 2 and np.all(run.replan_seconds == 7.0)


def test_navigate_says_when_the_run_went_on_after_every_mover(tmp_path, capsys):
    """``gfuzzy populate`` records 60 s by default; a crossing of the depot took 72 s, its
    last 12 s among nobody, and the run said "check valid" without a word. It says so now,
    and not when someone is there to the end."""
    from gfuzzy.cli import main

    def scene(until: float, cart: bool = False) -> Path:
        path = tmp_path / f"s{until:g}{cart}.yaml"
        path.write_text(
            "version: 1\nname: gone\nbounds: [0, 0, 10, 4]\nrobot: {disc: 0.2, vmax: 1.0}\n"
            f"movers:\n  - {{name: p, disc: 0.3, trajectory: [[0, 5, 3.5], [{until}, 5.5, 3.5]]}}\n"
            + ("  - {name: c, disc: 0.2, speed: 0.5, path: [[8, 3.6], [9, 3.6]], mode: bounce}\n" if cart else "")
            + "queries:\n  - {name: q, start: [1, 1], goal: [9, 1]}\n"
        )
        return path

    # a path mover (a cart on its loop) is there to the end: no note
    for until, cart, said in ((2.0, False, True), (60.0, False, False), (2.0, True, False)):
        out = tmp_path / f"r{until:g}{cart}.json"
        argv = ["navigate", str(scene(until, cart)), "-n", "60", "--budget-clock", "cpu", "-o", str(out)]
        assert main(argv) == 0
        err = capsys.readouterr().err
        assert ("every mover's recorded motion ends by t = 2 s and the robot drove on to" in err) == said, err
