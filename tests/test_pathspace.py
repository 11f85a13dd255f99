"""Keeping off the way people are about to walk: the ghosts of gfuzzy.navigation.pathspace."""

from __future__ import annotations

import math

import numpy as np
import pytest

import gfuzzy
from gfuzzy.navigation.navigator import Navigator, NavOptions
from gfuzzy.navigation.pathspace import MAX_GHOSTS, WallCheck, ghost_window, path_ghosts, walled_off
from gfuzzy.scene.scene import parse_scene


def _scene(obstacles=()):
    return parse_scene(
        {
            "version": 1, "name": "ps-test", "bounds": [-5.0, -5.0, 5.0, 5.0],
            "robot": {"disc": 0.3, "vmax": 1.0}, "obstacles": list(obstacles), "movers": [],
            "queries": [{"name": "q", "start": [0.0, -3.0], "goal": [0.0, 3.0]}],
        }
    )  # fmt: skip


@pytest.fixture(scope="module")
def open_square():
    scene = _scene()
    return scene, gfuzzy.build_roadmap(scene, gfuzzy.RoadmapOptions(vertices=300, seed=4))


def test_ghosts_by_hand():
    # a person at the origin walking +x at 1 m/s, one standing at (3, 3)
    obs = np.array([[0.0, 0.0, 1.0, 0.0, 0.3], [3.0, 3.0, 0.0, 0.0, 0.3]])
    g = path_ghosts(obs, 1.25, 0.3, 0.05, 0.1)
    # ceil(1.25 / 0.7) = 2 ghosts, 0.625 s and 1.25 s ahead; none for the one standing
    np.testing.assert_allclose(g.shift, [0.625, 1.25])
    np.testing.assert_allclose(g.obs[:, :2], [[0.625, 0.0], [1.25, 0.0]])
    np.testing.assert_array_equal(g.owner, [0, 0])
    # half spacing 0.3125: sqrt(0.65^2 + 0.3125^2) - 0.6
    np.testing.assert_allclose(g.cover, math.sqrt(0.65**2 + 0.3125**2) - 0.6)
    assert len(path_ghosts(obs, 0.0, 0.3, 0.05, 0.1)) == 0


@pytest.mark.parametrize("speed", [0.4, 1.0, 1.7])
def test_ghost_zones_cover_the_band_the_person_sweeps(speed):
    # every robot centre within 0.3 + 0.3 + buffer of the person's path from the first
    # ghost to the last is within some ghost's zone (its radius plus cover, plus the robot's)
    obs = np.array([[1.0, -2.0, 0.0, speed, 0.3]])
    g = path_ghosts(obs, 1.25, 0.3, 0.05, 0.1)
    rng = np.random.default_rng(3)
    along = rng.uniform(g.shift.min() * speed, 1.25 * speed, 4000)
    side = rng.uniform(-0.65, 0.65, 4000)
    pts = np.column_stack([1.0 + side, -2.0 + along])
    d = np.hypot(*(pts[:, None, :] - g.obs[None, :, :2]).transpose(2, 0, 1))
    assert np.all(np.min(d - (0.3 + g.obs[:, 4] + g.cover)[None, :], axis=1) <= 1e-9)


@pytest.mark.parametrize(("speed", "look"), [(1e9, 1.25), (1.0, 1e9)])
def test_an_absurd_velocity_or_look_gets_at_most_max_ghosts_still_covering(speed, look):
    # `navigate --noise 1e9` estimated such velocities and path_ghosts asked for an array of
    # 146 GiB; `crowd --path-space 1e9` had the process killed for its memory
    obs = np.array([[1.0, -2.0, 0.0, speed, 0.3]])
    g = path_ghosts(obs, look, 0.3, 0.05, 0.1)
    assert len(g) == MAX_GHOSTS
    rng = np.random.default_rng(5)
    along = rng.uniform(g.shift.min() * speed, look * speed, 4000)
    side = rng.uniform(-0.65, 0.65, 4000)
    pts = np.column_stack([1.0 + side, -2.0 + along])
    d = np.hypot(*(pts[:, None, :] - g.obs[None, :, :2]).transpose(2, 0, 1))
    assert np.all(np.min(d - (0.3 + g.obs[:, 4] + g.cover)[None, :], axis=1) <= 1e-6)


def test_a_robot_in_the_way_gets_time_to_step_aside():
    obs = np.array([[0.0, 0.0, 1.0, 0.0, 0.3]])
    g = path_ghosts(obs, 1.25, 0.3, 0.05, 0.1)
    margin0 = np.full(len(g), 0.1)
    ahead, _ = ghost_window(g, obs, np.array([1.5, 0.0]), 0.3, margin0, 1.0, 0.1, 4.0)
    aside, vanish = ghost_window(g, obs, np.array([1.5, 2.0]), 0.3, margin0, 1.0, 0.1, 4.0)
    behind, _ = ghost_window(g, obs, np.array([-1.5, 0.0]), 0.3, margin0, 1.0, 0.1, 4.0)
    assert np.all(ahead > 0.1) and np.all(aside == 0) and np.all(behind == 0)
    np.testing.assert_allclose(vanish, 4.0)


def test_no_ghost_the_search_keeps_from_the_start_covers_the_robot(open_square):
    # a ghost's zone in the search is its band's cover plus the uncertainty of the
    # prediction that far ahead; a robot inside it (e.g. 0.86 m beside a walker's line:
    # outside the cover alone, inside with the uncertainty) must get time to step out,
    # or the search with the ghosts starts inside one and finds nothing
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 3.0), NavOptions())
    obs = np.array([[0.0, 0.0, 1.0, 0.0, 0.3], [0.5, -1.5, -0.3, 0.9, 0.3]])
    rng = np.random.default_rng(5)
    poses = np.vstack([[[1.5, 0.86]], rng.uniform(-2.5, 2.5, (300, 2))])
    for pose in poses:
        rows, infl = nav._path_ghosts(pose, obs)
        speed = np.hypot(rows[:, 2], rows[:, 3])
        zone = nav.robot.circumradius + rows[:, 4] + infl[:, 0] + nav._step_margin(speed)
        covers = np.hypot(*(rows[:, :2] - pose).T) < zone
        assert np.all(rows[covers, 5] > 0), pose


def test_no_ghost_through_a_wall_or_in_a_passage():
    wall = {"box": {"center": [1.0, 0.0], "size": [0.2, 4.0]}}
    walls = WallCheck(_scene([wall]))
    obs = np.array([[0.0, 0.0, 1.0, 0.0, 0.3], [0.0, 4.0, 0.0, -1.0, 0.3]])
    g = path_ghosts(obs, 1.25, 0.3, 0.05, 0.1)
    off = walled_off(g, obs, walls, np.full(len(g), 0.7))
    # the first walks into the wall (its ghosts: 0.6 m from it, then behind it); the
    # second walks down beside it, clear of it
    np.testing.assert_array_equal(off, [True, True, False, False])
    assert not walled_off(g, obs, WallCheck(_scene()), np.full(len(g), 0.7)).any()


def _intrusions(traj, person, t0, steps=8):
    """Steps (0.25 s) of the plan's first two seconds at whose start the robot's centre is
    within 0.6 m of the person (walking on at constant velocity) 0.25 .. 1.25 s later."""
    count = 0
    for k in range(steps):
        t = t0 + 0.25 * k
        p = traj.at(min(t, traj.t_end))[:2]
        for j in range(1, 6):
            q = person[:2] + person[2:4] * (t - t0 + 0.25 * j)
            if math.hypot(*(p - q)) < 0.6:
                count += 1
                break
    return count


def test_the_navigator_does_not_cut_in_front_of_a_walker(open_square):
    scene, rm = open_square
    # the robot goes up the y axis; a person crosses it from the left, 1 m/s, 1 m ahead,
    # due at its straight way in 2.5 s
    pose = np.array([0.0, -3.0])
    person = np.array([-2.5, -2.0, 1.0, 0.0, 0.3])
    ways, ends = {}, {}
    for ps, cost in ((0.0, 0.0), (1.25, 10.0), (1.25, 1.0)):
        opts = NavOptions(path_space=ps, path_space_cost=cost, personal_space=0.0, time_budget=5.0)
        nav = Navigator(scene, rm, (0.0, 3.0), opts)
        traj = nav.step(0.0, pose, person[None])
        assert nav.last.mode == "plan"
        ways[ps, cost], ends[ps, cost] = _intrusions(traj, person, 0.0), traj.t_end
    assert ways[0.0, 0.0] > 0  # without the path space it crosses just in front of them
    assert ways[1.25, 10.0] == 0  # with it, it lets them pass
    # a soft cost: letting them pass takes more than a second longer here, so by default
    # the robot crosses (the plan without the path space)
    assert ends[1.25, 10.0] > ends[0.0, 0.0] + 1.0
    assert ways[1.25, 1.0] == ways[0.0, 0.0] and ends[1.25, 1.0] == ends[0.0, 0.0]

