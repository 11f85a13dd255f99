"""Who is about to swerve (gfuzzy/navigation/swerve.py), and the navigator's use of it."""

from __future__ import annotations

import numpy as np
import pytest

import gfuzzy
from gfuzzy.errors import InputError
from gfuzzy.navigation.swerve import meeting, swerve_rates
from gfuzzy.scene.scene import parse_scene


@pytest.fixture(scope="module")
def crowd_nav_parts():
    doc = {"version": 1, "name": "swerve", "bounds": [-6, -6, 6, 6], "robot": {"disc": 0.3, "vmax": 1.0},
           "obstacles": [], "movers": [], "queries": [{"name": "q", "start": [0, -5], "goal": [0, 5]}]}
    scene = parse_scene(doc)
    return scene, gfuzzy.build_roadmap(scene, gfuzzy.RoadmapOptions(vertices=60, seed=1))


def _sampled_meeting(obs, look, gap, n=20001):
    """Oracle: the first sampled instant at which a pair's centres come within both radii
    plus ``gap`` (a fine grid of times, no algebra)."""
    s = np.linspace(0.0, look, n)
    out = np.full(len(obs), np.inf)
    for i in range(len(obs)):
        for j in range(len(obs)):
            if i == j:
                continue
            pi = obs[i, :2] + s[:, None] * obs[i, 2:4]
            pj = obs[j, :2] + s[:, None] * obs[j, 2:4]
            d = np.hypot(*(pi - pj).T) - obs[i, 4] - obs[j, 4]
            hit = np.nonzero(d <= gap)[0]
            if len(hit):
                out[i] = min(out[i], s[hit[0]])
    return out


def test_head_on_pair_meets_at_the_hand_computed_time():
    # 4 m apart centre to centre, closing at 2 m/s, radii 0.3 + 0.3 + gap 0.3: within 0.9 m
    # after (4 - 0.9) / 2 = 1.55 s; the third person stands far away and meets nobody
    obs = np.array([[0.0, 0.0, 1.0, 0.0, 0.3], [4.0, 0.0, -1.0, 0.0, 0.3], [0.0, 8.0, 0.0, 0.0, 0.3]])
    when = meeting(obs, look=3.0, gap=0.3)
    assert when[0] == pytest.approx(1.55)
    assert when[1] == pytest.approx(1.55)
    assert np.isinf(when[2])
    assert meeting(obs, look=1.5, gap=0.3).tolist() == [np.inf] * 3  # too late for a 1.5 s look
    assert swerve_rates(obs, 0.3, look=3.0, gap=0.3).tolist() == [0.3, 0.3, 0.0]
    assert swerve_rates(obs, 0.0, look=3.0, gap=0.3).tolist() == [0.0, 0.0, 0.0]


def test_meeting_agrees_with_a_sampled_oracle():
    rng = np.random.default_rng(7)
    for _ in range(20):
        k = int(rng.integers(2, 8))
        obs = np.column_stack([rng.uniform(-4, 4, (k, 2)), rng.uniform(-1, 1, (k, 2)), rng.uniform(0.2, 0.4, k)])
        got = meeting(obs, look=3.0, gap=0.3)
        want = _sampled_meeting(obs, 3.0, 0.3)
        assert np.array_equal(np.isfinite(got), np.isfinite(want))
        both = np.isfinite(got) & np.isfinite(want)
        assert np.allclose(got[both], want[both], atol=3.0 / 20000 + 1e-9)


def test_people_already_close_or_walking_together_or_apart():
    # side by side 0.7 m apart (gap 0.1 < 0.3): already within the gap at time 0
    together = np.array([[0.0, 0.0, 1.0, 0.0, 0.3], [0.0, 0.7, 1.0, 0.0, 0.3]])
    assert meeting(together, 2.0, 0.3).tolist() == [0.0, 0.0]
    # 2 m apart, walking apart: never
    apart = np.array([[0.0, 0.0, -1.0, 0.0, 0.3], [2.0, 0.0, 1.0, 0.0, 0.3]])
    assert np.isinf(meeting(apart, 2.0, 0.3)).all()
    # the same velocity, 2 m apart: never (no relative motion)
    parallel = np.array([[0.0, 0.0, 1.0, 0.0, 0.3], [0.0, 2.0, 1.0, 0.0, 0.3]])
    assert np.isinf(meeting(parallel, 2.0, 0.3)).all()
    assert meeting(np.zeros((0, 5)), 2.0, 0.3).shape == (0,)
    assert swerve_rates(np.zeros((1, 5)), 0.3).tolist() == [0.0]


def test_navigator_grows_only_the_swerving_peoples_discs(crowd_nav_parts):
    from gfuzzy.navigation.navigator import Navigator, NavOptions

    scene, roadmap = crowd_nav_parts
    far_pose = np.array([0.0, -5.0])
    # two people walking at each other 3 m north of the robot, one walking alone
    obs = np.array([[-1.5, 3.0, 1.0, 0.0, 0.3], [1.5, 3.0, -1.0, 0.0, 0.3], [-4.0, -1.0, 0.0, 1.0, 0.3]])
    plain = Navigator(scene, roadmap, np.array([0.0, 5.0]), NavOptions(swerve_growth=0.0))
    swerve = Navigator(scene, roadmap, np.array([0.0, 5.0]), NavOptions(swerve_growth=0.3))
    a = plain._inflation(far_pose, obs)
    b = swerve._inflation(far_pose, obs)
    tau = np.arange(a.shape[1]) * plain.options.slice
    assert np.allclose(b[:2] - a[:2], 0.3 * tau[None, :])
    assert np.allclose(b[2], a[2])
    with pytest.raises(InputError):
        NavOptions(swerve_growth=-0.1)
