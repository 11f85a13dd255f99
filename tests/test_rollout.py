"""Predictions in which people avoid each other (NavOptions.interaction, navigation/rollout.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gfuzzy.errors import InputError
from gfuzzy.navigation.drivenav import _if_safe
from gfuzzy.navigation.navigator import Navigator, NavOptions
from gfuzzy.navigation.rollout import ROLL_STEP, orca_rollout, rollout
from gfuzzy.trajectory import Trajectory

#: Two people walking at each other along y = 0 (0.1 m apart sideways), 6 m apart at 1 m/s.
HEAD_ON = np.array([[-3.0, 0.05, 1.0, 0.0, 0.3], [3.0, -0.05, -1.0, 0.0, 0.3]])


@pytest.mark.parametrize("roll", [rollout, orca_rollout])
def test_two_people_walking_at_each_other_part(roll):
    xy, vel = HEAD_ON[:, :2], HEAD_ON[:, 2:4]
    paths = roll(xy, vel, np.array([0.3, 0.3]), 5.0)
    assert paths.shape == (int(round(5.0 / ROLL_STEP)) + 1, 2, 2)
    straight = xy[None] + (ROLL_STEP * np.arange(len(paths)))[:, None, None] * vel[None]
    assert np.hypot(*(straight[:, 0] - straight[:, 1]).T).min() < 0.6  # walking on, they would collide
    assert np.hypot(*(paths[:, 0] - paths[:, 1]).T).min() > 0.6  # they pass each other
    assert paths[-1, 0, 1] > 0.2 and paths[-1, 1, 1] < -0.2  # each to their own side
    speed = np.hypot(*np.diff(paths, axis=0).transpose(2, 0, 1)) / ROLL_STEP
    assert speed.max() <= 1.0 + 1e-6  # nobody faster than seen


@pytest.mark.parametrize("roll", [rollout, orca_rollout])
def test_someone_walking_alone_walks_on_straight(roll):
    paths = roll(np.array([[1.0, 2.0], [4.0, -4.0]]), np.array([[0.5, -0.5], [0.0, 0.0]]), np.array([0.3, 0.3]), 3.0)
    np.testing.assert_allclose(paths[-1], [[2.5, 0.5], [4.0, -4.0]], atol=1e-6)


def test_an_unknown_crowd_model_is_refused():
    with pytest.raises(InputError):
        NavOptions(interaction="social")


@pytest.mark.parametrize("model", ["ttc", "orca"])
def test_the_search_keeps_off_the_rolled_paths_and_leaves_out_only_who_cannot_matter(open_square, model):
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(backend="reference", interaction=model))
    pose = np.array([0.0, -3.0])
    rng = np.random.default_rng(5)
    obs = np.column_stack([rng.uniform(-4.5, 4.5, (30, 2)), rng.uniform(-1.0, 1.0, (30, 2)), np.full(30, 0.3)])
    obs[:3, 2:4] = 0.0  # some stand
    nav._roll(obs)
    infl = nav._inflation(pose, obs)
    steps = 60
    field_ = nav._field(0.0, obs, infl, steps)
    n = int(round(2.0 / nav.options.dt))  # 2 s: a vertex of the rolled paths
    np.testing.assert_allclose(field_.xy[:, n], nav._paths[int(round(2.0 / ROLL_STEP))], atol=1e-9)
    keep = nav._relevant(pose, obs, infl, steps * nav.options.dt)
    assert keep.any() and not keep.all()
    some = nav._field(0.0, obs[keep], infl[keep], steps)
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
    nav.step(0.0, np.array([0.0, -4.0]), HEAD_ON)
    assert nav._paths is None
    field_ = nav._field(0.0, HEAD_ON, nav._inflation(np.array([0.0, -4.0]), HEAD_ON), 40)
    np.testing.assert_allclose(field_.xy[0, 30], [0.0, 0.05])


@pytest.mark.parametrize("model", ["ttc", "orca"])
def test_the_checks_of_a_kept_plan_and_of_the_evasions_see_the_rolled_paths(open_square, model):
    """The robot stands 1.2 m beside where the two people would meet walking on: their
    straight walks pass it with room to spare, but parting, one of them comes closer; the
    gaps of the checks (a kept plan's, the evasions') are measured to the rolled paths."""
    scene, rm = open_square
    pose = np.array([0.0, 1.2])
    prev = Trajectory(np.array([[0.0, *pose], [6.0, *pose]]), 0.3)
    infl = np.full((2, 10), 0.3)
    times = np.arange(0.0, 5.0, 0.05)
    verdicts = {}
    for m in ("none", model):
        nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(interaction=m))
        nav._roll(HEAD_ON)
        nav._previous = prev
        verdicts[m] = _if_safe(nav, prev, 0.0, pose, HEAD_ON, infl) is not None
        gap = nav._clearance_along(np.repeat(pose[None], len(times), axis=0), times, HEAD_ON)
        if m == model:
            pos = nav._paths[np.minimum(np.round(times / ROLL_STEP).astype(int), len(nav._paths) - 1)]
            on_path = np.isclose(times / ROLL_STEP, np.round(times / ROLL_STEP))
            expect = np.hypot(*(pos - pose).transpose(2, 0, 1)) - 0.6 - nav.mover_clearance
            np.testing.assert_allclose(gap[on_path], expect[on_path], atol=1e-9)
        assert len(nav._near(pose, HEAD_ON, 5.0, 0.3)) == 2
    assert verdicts == {"none": True, model: False}
