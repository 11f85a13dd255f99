"""Predictions in which people avoid each other (NavOptions.interaction, navigation/rollout.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import gfuzzy
from gfuzzy.navigation.navigator import Navigator, NavOptions
from gfuzzy.navigation.rollout import ROLL_STEP, rollout
from gfuzzy.scene.scene import parse_scene


@pytest.fixture(scope="module")
def open_square():
    scene = parse_scene({"version": 1, "name": "roll", "bounds": [-5, -5, 5, 5], "robot": {"disc": 0.3, "vmax": 1.0},
                         "obstacles": [], "movers": [], "queries": [{"name": "q", "start": [0, -4], "goal": [0, 4]}]})  # fmt: skip
    return scene, gfuzzy.build_roadmap(scene, gfuzzy.RoadmapOptions(vertices=150, seed=3))


def test_two_people_walking_at_each_other_part():
    xy = np.array([[-3.0, 0.05], [3.0, -0.05]])
    vel = np.array([[1.0, 0.0], [-1.0, 0.0]])
    paths = rollout(xy, vel, np.array([0.3, 0.3]), 5.0)
    assert paths.shape == (int(round(5.0 / ROLL_STEP)) + 1, 2, 2)
    straight = xy[None] + (ROLL_STEP * np.arange(len(paths)))[:, None, None] * vel[None]
    assert np.hypot(*(straight[:, 0] - straight[:, 1]).T).min() < 0.6  # walking on, they would collide
    assert np.hypot(*(paths[:, 0] - paths[:, 1]).T).min() > 0.6  # they pass each other
    assert paths[-1, 0, 1] > 0.2 and paths[-1, 1, 1] < -0.2  # each to their own side


def test_someone_walking_alone_walks_on_straight():
    paths = rollout(np.array([[1.0, 2.0], [4.0, -4.0]]), np.array([[0.5, -0.5], [0.0, 0.0]]), np.array([0.3, 0.3]), 3.0)
    np.testing.assert_allclose(paths[-1], [[2.5, 0.5], [4.0, -4.0]])


def test_the_search_keeps_off_the_rolled_paths_and_leaves_out_only_who_cannot_matter(open_square):
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(backend="reference", interaction=True))
    pose = np.array([0.0, -3.0])
    rng = np.random.default_rng(5)
    obs = np.column_stack([rng.uniform(-4.5, 4.5, (30, 2)), rng.uniform(-1.0, 1.0, (30, 2)), np.full(30, 0.3)])
    obs[:3, 2:4] = 0.0  # some stand
    nav._roll(obs)
    infl = nav._inflation(pose, obs)
    steps = 60
    field_ = nav._field(0.0, obs, infl, steps, rows=np.arange(len(obs)))
    n = int(round(2.0 / nav.options.dt))  # 2 s: a vertex of the rolled paths
    np.testing.assert_allclose(field_.xy[:, n], nav._paths[int(round(2.0 / ROLL_STEP))], atol=1e-9)
    keep = nav._relevant(pose, obs, infl, steps * nav.options.dt)
    assert keep.any() and not keep.all()
    some = nav._field(0.0, obs[keep], infl[keep], steps, rows=np.flatnonzero(keep))
    # every point the robot can reach at step n (within vplan * n * dt of its pose)
    n_in = rng.integers(0, steps + 1, 4000)
    a_in = rng.uniform(0, 2 * math.pi, 4000)
    r_in = np.sqrt(rng.uniform(0, 1, 4000)) * nav.vplan * n_in * nav.options.dt
    pts = pose + np.column_stack([r_in * np.cos(a_in), r_in * np.sin(a_in)])
    i = np.arange(len(pts))
    full, part = field_.unsafe(pts)[i, n_in], some.unsafe(pts)[i, n_in]
    assert full.any()
    np.testing.assert_array_equal(full, part)


def test_interaction_is_off_by_default_and_straight_walks_are_predicted(open_square):
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0))
    obs = np.array([[-3.0, 0.05, 1.0, 0.0, 0.3], [3.0, -0.05, -1.0, 0.0, 0.3]])
    nav.step(0.0, np.array([0.0, -4.0]), obs)
    assert nav._paths is None
    field_ = nav._field(0.0, obs, nav._inflation(np.array([0.0, -4.0]), obs), 40, rows=np.arange(2))
    np.testing.assert_allclose(field_.xy[0, 30], [0.0, 0.05])
