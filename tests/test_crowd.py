"""The crowd benchmarks (gfuzzy.navigation.crowd, gfuzzy.navigation.humans, ``gfuzzy crowd``)."""

from __future__ import annotations

import csv
import math
import re
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pyrvo")

from helpers import main_completed, run_main  # noqa: E402

from gfuzzy.errors import InputError  # noqa: E402
from gfuzzy.navigation import crowd as C  # noqa: E402
from gfuzzy.navigation.crowdsummary import summarize  # noqa: E402
from gfuzzy.navigation.humans import OrcaCrowd, SocialForceCrowd  # noqa: E402
from gfuzzy.navigation.sensing import SensorOptions  # noqa: E402
from gfuzzy.navigation.socialmetrics import SocialMetrics  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def _run(*args):
    return subprocess.run([sys.executable, "-m", "gfuzzy", *args], capture_output=True, text=True, cwd=ROOT)


# ------------------------------------------------------------------------ protocols


def test_circle_layout_is_crowdnavs():
    s = C.CrowdSetting("circle", humans=8)
    lay = C.layout(s, np.random.default_rng(3))
    np.testing.assert_array_equal(lay.start, [0, -4])
    np.testing.assert_array_equal(lay.goal, [0, 4])
    r = np.hypot(*lay.human_starts.T)
    assert np.all((r > 4 - 0.71) & (r < 4 + 0.71))  # radius 4, U[-0.5, 0.5) per coordinate
    np.testing.assert_array_equal(lay.human_goals, -lay.human_starts)
    agents = np.vstack([lay.start, lay.human_starts])
    d = np.hypot(*(agents[:, None] - agents[None]).transpose(2, 0, 1)) + np.eye(len(agents)) * 9
    assert d.min() >= 0.3 + 0.3 + 0.2  # no two agents start within the discomfort distance
    again = C.layout(s, np.random.default_rng(3))
    np.testing.assert_array_equal(again.human_starts, lay.human_starts)


def test_a_jammed_circle_placement_starts_over():
    # 20 humans on the circle of radius 4: seed [2, 75] places some humans that leave the
    # rest no room (the old code gave up after 100 000 draws); the placement starts over
    s = C.CrowdSetting("circle", humans=20)
    lay = C.layout(s, np.random.default_rng([2, 75]))
    assert len(lay.human_starts) == 20
    for ends, robot in ((lay.human_starts, lay.start), (lay.human_goals, lay.goal)):
        agents = np.vstack([robot, ends])
        d = np.hypot(*(agents[:, None] - agents[None]).transpose(2, 0, 1)) + np.eye(len(agents)) * 9
        assert d.min() >= 0.3 + 0.3 + 0.2


def test_square_and_arena_layouts():
    sq = C.layout(C.CrowdSetting("square", humans=10), np.random.default_rng(1))
    assert np.all(np.abs(sq.human_starts) <= 5) and np.all(np.abs(sq.human_goals) <= 5)
    # each human crosses from one side of x = 0 to the other
    assert np.all(np.sign(sq.human_starts[:, 0]) == -np.sign(sq.human_goals[:, 0]))
    for seed in range(5):
        ar = C.layout(C.CrowdSetting("arena", humans=20), np.random.default_rng(seed))
        assert np.all(np.abs(ar.start) <= 6) and np.all(np.abs(ar.goal) <= 6)
        assert np.hypot(*(ar.start - ar.goal)) >= 8
        r = np.hypot(*ar.human_starts.T)
        assert np.all(np.abs(r - 6 * math.sqrt(2)) < 2 * math.sqrt(2))  # the circle, U[0, 2) per coordinate


def _one_at_a_time(scenario, K, rng, restart_every=None):
    """CrowdNav's placement as the one-draw-at-a-time loop (the reference), starting over
    every ``restart_every`` draws of a start (None: never)."""
    start, goal = np.array([0.0, -4.0]), np.array([0.0, 4.0])
    if scenario == "arena":
        while True:
            p = rng.uniform(-6.0, 6.0, 4)
            if math.hypot(p[0] - p[2], p[1] - p[3]) >= 8.0:
                break
        start, goal = p[:2], p[2:]
    agents = [(start, goal, 0.3)]

    def far(p, which):
        return all(np.hypot(*(p - a[which])) >= 0.3 + a[2] + 0.2 for a in agents)

    tries = 0
    while len(agents) <= K:
        tries += 1
        if restart_every and tries % restart_every == 0:
            del agents[1:]
        if scenario == "square":
            sign = -1.0 if rng.random() > 0.5 else 1.0
            p = np.array([rng.random() * 10.0 * 0.5 * sign, (rng.random() - 0.5) * 10.0])
            if not far(p, 0):
                continue
            while True:
                g = np.array([rng.random() * 10.0 * 0.5 * -sign, (rng.random() - 0.5) * 10.0])
                if far(g, 1):
                    break
        else:
            angle = rng.random() * 2 * math.pi
            R, noise = (6 * math.sqrt(2), rng.uniform(0.0, 2.0, 2)) if scenario == "arena" else (4.0, rng.random(2) - 0.5)
            p = np.array([R * math.cos(angle), R * math.sin(angle)]) + noise
            g = -p
            if not (far(p, 0) and far(p, 1)):
                continue
        agents.append((p, g, 0.3))
    return np.array([a[0] for a in agents[1:]]).reshape(-1, 2), np.array([a[1] for a in agents[1:]]).reshape(-1, 2)


@pytest.mark.parametrize("scenario,K", [("circle", 12), ("circle", 20), ("square", 30), ("arena", 40)])
def test_layouts_are_the_one_at_a_time_protocols(scenario, K):
    # the block-wise placement reads the generator as CrowdNav's loop does: the same episodes
    for seed in range(6):
        lay = C.layout(C.CrowdSetting(scenario, humans=K), np.random.default_rng([seed, 3]))
        starts, goals = _one_at_a_time(scenario, K, np.random.default_rng([seed, 3]))
        np.testing.assert_array_equal(lay.human_starts, starts)
        np.testing.assert_array_equal(lay.human_goals, goals)


@pytest.mark.parametrize("scenario,K", [("square", 50), ("circle", 14)])
def test_restarts_count_the_starts_drawn_as_the_loop_does(scenario, K, monkeypatch):
    # a jammed placement starts over after the same draws as CrowdNav's loop with its
    # restart (the square's goals drawn again do not count: counting them moved the
    # restarts and changed dense square episodes), and leaves a caller's generator where
    # that loop leaves it
    from gfuzzy.navigation import crowdlayout

    monkeypatch.setattr(crowdlayout, "RESTART_EVERY", 101)
    restarted = 0
    for seed in range(4):
        rng, ref = np.random.default_rng([seed, 7]), np.random.default_rng([seed, 7])
        lay = C.layout(C.CrowdSetting(scenario, humans=K), rng)
        starts, goals = _one_at_a_time(scenario, K, ref, restart_every=101)
        np.testing.assert_array_equal(lay.human_starts, starts)
        np.testing.assert_array_equal(lay.human_goals, goals)
        assert rng.random() == ref.random()
        once = _one_at_a_time(scenario, K, np.random.default_rng([seed, 7]))[0]
        restarted += not np.array_equal(once, starts)
    assert restarted  # the case restarts


@pytest.mark.parametrize("scenario,K", [("circle", 30), ("square", 200), ("arena", 200)])
def test_a_crowd_that_does_not_fit_is_refused_after_a_bounded_number_of_draws(scenario, K, monkeypatch):
    # CrowdNav's loop never ends when the humans do not fit (the square's goals looped
    # forever here, and the circle took a million draws one at a time, about 40 s):
    # the draws are bounded, and the refusal says what fitted
    from gfuzzy.navigation import crowdlayout

    monkeypatch.setattr(crowdlayout, "RESTART_EVERY", 7_001)
    monkeypatch.setattr(crowdlayout, "DRAW_BUDGET", 21_000)
    with pytest.raises(InputError, match=rf"cannot place {K} humans in the {scenario} scenario: .* 3 attempts ") as err:
        C.layout(C.CrowdSetting(scenario, humans=K), np.random.default_rng(1))
    best = int(re.search(r"placed at most (\d+)", str(err.value)).group(1))
    assert 0 < best < K


def test_setting_refuses_bad_values():
    for kw in ({"scenario": "hall"}, {"crowd": "boids"}, {"kinematics": "legs"}, {"humans": -1}):
        with pytest.raises(InputError):
            C.CrowdSetting(**kw)


# ------------------------------------------------------------------------ crowds


@pytest.mark.parametrize("model", [OrcaCrowd, SocialForceCrowd])
def test_visible_humans_avoid_the_robot_invisible_ones_do_not(model):
    # one human walks from (0.1, -3) to (0.1, 3) through a robot standing at the origin
    # (0.1 m off the axis: head-on symmetry is a standstill for ORCA)
    def closest(visible):
        crowd = model([[0.1, -3.0]], [[0.1, 3.0]], visible=visible)
        d = []
        for _ in range(40):
            crowd.step(np.zeros(2), np.zeros(2))
            d.append(float(np.hypot(*crowd.pos[0])))
        return min(d), crowd.pos[0]

    blind, end = closest(False)
    assert blind < 0.3  # walks straight through where the robot stands
    seeing, end = closest(True)
    assert seeing >= 0.6 - 0.05  # keeps (about) the two radii away
    assert end[1] > 2.0  # and still gets on toward its goal


def test_arena_humans_change_goals():
    s = C.CrowdSetting("arena", humans=20)
    lay = C.layout(s, np.random.default_rng(0))
    world = C._World(s, lay, np.random.default_rng(1), False)
    first = world.crowd.goals.copy()
    for _ in range(20):  # 5 s: every human draws a new goal with chance 0.5
        world.step()
    changed = np.any(world.crowd.goals != first, axis=1).sum()
    assert 3 <= changed <= 17  # binomial(20, 0.5): outside this with probability < 0.003


# ------------------------------------------------------------------------ episodes


@pytest.fixture(scope="module")
def roadmap():
    return C.crowd_roadmap(C.CrowdSetting())


def test_episodes_are_seeded_and_policies_share_the_walk(roadmap):
    s = C.CrowdSetting(humans=4)
    pol = ["orca", "social-force", "oracle"]
    a = C.run_episode(s, roadmap, 5, 2, pol)
    b = C.run_episode(s, roadmap, 5, 2, pol)
    assert [e.policy for e in a] == pol
    for x, y in zip(a, b, strict=True):
        assert x.outcome == y.outcome and x.min_separation == y.min_separation and x.social == y.social
        assert (x.time == y.time) or (math.isnan(x.time) and math.isnan(y.time))
    other = C.run_episode(s, roadmap, 5, 3, pol)
    assert [e.min_separation for e in other] != [e.min_separation for e in a]
    oracle = a[2]
    assert oracle.reached and oracle.min_separation >= -1e-9  # told the true future: never collides


def test_an_episode_ends_at_a_collision_and_the_row_keeps_the_file_format(roadmap):
    s = C.CrowdSetting(humans=10)
    eps = [e for i in range(6) for e in C.run_episode(s, roadmap, 1, i, ["orca"])]
    # CrowdNav's ORCA robot assumes people yield; they do not: it collides in some episodes
    assert any(e.collision for e in eps)
    for e in eps:
        if e.collision:
            assert e.min_separation < 0 and math.isnan(e.time)
        row = e.row(s)
        assert tuple(row) == C.CSV_COLUMNS
        assert row["outcome"] == str(e.outcome) and row["steps"] == e.social.steps


def test_navigator_episode_succeeds_among_a_few_people(roadmap):
    s = C.CrowdSetting(humans=3, visible=True)
    ep = C.run_episode(s, roadmap, 1, 0, ["navigator"])[0]
    assert ep.reached and ep.min_separation >= 0
    assert ep.time <= 25 and dict(ep.modes).get("plan", 0) > 0
    assert len(ep.replan_seconds) == ep.social.steps


def test_replan_times_are_on_the_budget_clock(roadmap, monkeypatch):
    """With ``--budget-clock cpu`` the episode's replan times are the navigator's CPU
    times, as ``gfuzzy navigate`` reports them (they were wall-clock; a review found it):
    a fake CPU clock that advances 1 ms per reading gives every call a whole number of ms."""
    from gfuzzy.navigation import navigator as N

    ticks = [0.0]

    def fake():
        ticks[0] += 0.001
        return ticks[0]

    monkeypatch.setitem(N.BUDGET_CLOCKS, "cpu", fake)
    s = C.CrowdSetting(humans=0)
    ep = C.run_episode(s, roadmap, 1, 0, ["navigator"], N.NavOptions(budget_clock="cpu"))[0]
    ms = np.asarray(ep.replan_seconds) * 1000.0
    assert len(ms) and np.allclose(ms, np.round(ms)) and ms.min() >= 1.0


def test_a_unicycle_robot_turns_toward_its_way_and_arrives(roadmap):
    s = C.CrowdSetting(humans=2, kinematics="unicycle")
    ep = C.run_episode(s, roadmap, 1, 0, ["navigator"])[0]
    assert ep.reached and ep.min_separation >= 0
    scene = C.crowd_scene(s, C.layout(s, np.random.default_rng([1, 0])))
    assert scene.robot.kinematics == "unicycle" and len(scene.queries[0].start) == 3


def test_a_robot_that_may_reverse_is_a_unicycle_one(roadmap):
    with pytest.raises(InputError):
        C.CrowdSetting(humans=2, reverse=True)
    s = C.CrowdSetting(humans=2, kinematics="unicycle", reverse=True)
    assert C.crowd_scene(s).robot.reverse and not C.crowd_scene(replace(s, reverse=False)).robot.reverse
    ep = C.run_episode(s, roadmap, 1, 0, ["navigator"])[0]
    assert ep.reached and ep.min_separation >= 0
    assert ep.row(s)["reverse"] == 1 and ep.row(replace(s, reverse=False))["reverse"] == 0


def test_summary_by_hand():
    def ep(outcome, time, steps, disc, intr, sep, lat):
        return C.Episode("p", 0, outcome, time, sep, SocialMetrics(steps, disc, intr), np.array(lat))

    runs = [[ep(C.Outcome.SUCCESS, 10.0, 40, 4, 2, 0.1, [0.01, 0.02])],
            [ep(C.Outcome.COLLISION, math.nan, 20, 0, 1, -0.2, [0.03])],
            [ep(C.Outcome.SUCCESS, 12.0, 40, 2, 0, 0.4, [0.04])]]  # fmt: skip
    s = summarize(runs, "p")
    assert s.episodes == 3
    assert s.success == pytest.approx(2 / 3) and s.collision == pytest.approx(1 / 3) and s.timeout == 0
    assert s.time == pytest.approx(11.0)
    # discomfort pooled over all steps (CrowdNav); intrusion the mean of the episodes'
    # ratios, each over its steps plus the one that finds the episode over (CrowdNav++)
    assert s.discomfort == pytest.approx(6 / 100) and s.intrusion == pytest.approx((2 / 41 + 1 / 21 + 0 / 41) / 3)
    assert s.min_separation == pytest.approx(0.1)
    assert s.replan_p50 == pytest.approx(0.025)


def test_the_oracle_drives_a_unicycle_as_it_may(roadmap):
    """The oracle of a differential drive plans on the heading graph from the posed start:
    its plan obeys the row rule, arrives, and is never sooner than the holonomic oracle's
    on the same episode (every drive's path is one a holonomic robot may take)."""
    from gfuzzy import check_trajectory, plan

    s = C.CrowdSetting(humans=3, kinematics="unicycle")
    drive, holo = (C.run_episode(k, roadmap, 1, 2, ["oracle"])[0] for k in (s, replace(s, kinematics="holonomic")))
    assert drive.reached and holo.reached and drive.min_separation >= 0
    assert drive.time >= holo.time - 1e-9
    lay = C.layout(s, np.random.default_rng([1, 2]))
    scene = C.crowd_scene(s, lay)
    res = plan(scene, roadmap, *C._poses(s, lay), 0.0)
    assert res.trajectory.waypoints.shape[1] == 4
    assert check_trajectory(scene, res.trajectory.waypoints, scene.queries[0]).valid


def test_oracle_with_visible_humans_and_other_policies_for_a_unicycle_are_refused(roadmap):
    with pytest.raises(InputError):
        C.run_episode(C.CrowdSetting(humans=2, visible=True), roadmap, 1, 0, ["oracle"])
    with pytest.raises(InputError):
        C.run_episode(C.CrowdSetting(humans=2, kinematics="unicycle"), roadmap, 1, 0, ["orca"])


# ------------------------------------------------------------------------ command


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


TIMING = ("replan_p50_ms", "replan_p95_ms", "replan_max_ms")


def test_crowd_command_end_to_end_same_seed_same_csv(tmp_path, capsys):
    # the same seed in a real process and in this one (another process, imports a second
    # apart); the other seed in this one too (a real process costs a second of imports)
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    args = ["crowd", "--scenario", "square", "--humans", "3", "--episodes", "2", "--seed", "4",
            "--policy", "orca", "social-force", "oracle"]  # fmt: skip
    p = _run(*args, "-o", str(a))
    assert p.returncode == 0, p.stderr
    assert "square, 3 humans" in p.stdout and "social-force" in p.stdout
    q = main_completed(capsys, *args, "-o", str(b))
    assert q.returncode == 0 and q.stdout.splitlines()[0] == p.stdout.splitlines()[0], q.stdout + q.stderr
    ra, rb = _rows(a), _rows(b)
    assert len(ra) == 6 and list(ra[0]) == list(C.CSV_COLUMNS)
    strip = [{k: v for k, v in r.items() if k not in TIMING} for r in ra]
    assert strip == [{k: v for k, v in r.items() if k not in TIMING} for r in rb]
    c = tmp_path / "c.csv"
    other = ["crowd", "--scenario", "square", "--humans", "3", "--episodes", "2", "--seed", "5", "--policy", "orca"]
    assert main_completed(capsys, *other, "-o", str(c)).returncode == 0
    assert [r["min_separation"] for r in _rows(c)] != [r["min_separation"] for r in ra if r["policy"] == "orca"]
    # each row says the run it came from: its seed and how the robot sensed
    assert {(r["seed"], r["velocity"], r["noise"], r["fov"], r["sense"]) for r in ra} == {("4", "estimated", "0.0", "360.0", "")}
    assert {r["seed"] for r in _rows(c)} == {"5"}


def test_a_row_names_the_sensing_and_the_arena_range():
    ep = C.Episode("navigator", 3, C.Outcome.SUCCESS, 9.0, 0.4, SocialMetrics(10, 1, 0), np.array([0.01]))
    s = C.CrowdSetting(scenario="arena", humans=20, sensor=SensorOptions(noise=0.05, fov=180.0, occlusion=True))
    row = ep.row(s, 7)
    assert (row["seed"], row["episode"], row["noise"], row["fov"], row["occlusion"]) == (7, 3, 0.05, 180.0, 1)
    assert row["sense"] == C.ARENA["sense"]  # the scenario's range when the sensor sets none
    assert ep.row(C.CrowdSetting())["sense"] == "" and ep.row(C.CrowdSetting())["seed"] == ""
    assert row["goal_changes"] == 1 and ep.row(replace(s, goal_changes=False))["goal_changes"] == 0


@pytest.mark.parametrize("workers", [pytest.param(["--workers", "2"], marks=pytest.mark.slow), []])
def test_crowd_command_navigator_visible(tmp_path, workers, capsys):
    out = tmp_path / "n.csv"
    p = main_completed(capsys, "crowd", "--humans", "3", "--visible", "--episodes", "2", "--policy", "navigator",
                       "orca", *workers, "-o", str(out))  # fmt: skip
    assert p.returncode == 0, p.stderr
    rows = _rows(out)
    assert [(r["policy"], r["episode"]) for r in rows] == [("navigator", "0"), ("orca", "0"), ("navigator", "1"), ("orca", "1")]
    assert all(r["visible"] == "1" for r in rows)
    assert "plan:" in rows[0]["modes"]


@pytest.mark.parametrize("flags", [
    ["--humans", "-1"], ["--episodes", "0"], ["--kinematics", "unicycle", "--policy", "orca"],
    ["--visible", "--policy", "oracle"],
    ["--scenario", "hall"], ["--fov", "0"], ["--noise", "-0.1"], ["--workers", "-1"], ["--time-budget", "0"],
    ["--path-space", "-1"], ["--path-space", "nan"], ["--personal-space", "inf"], ["--reverse"], ["--dt", "0"],
    ["--dt", "nan"], ["--dt", "100"],  # a step longer than the prediction: every episode ran to its limit
    ["--seed", "-1"], ["--noise", "1e300"],  # a traceback each: numpy's seed, a 146 GiB array of ghosts
    ["--soft-search", "--intrusion-cost", "-1"], ["--soft-search", "--intrusion-cost", "nan"],
    ["--soft-search", "--intrusion-cost", "1e308"],  # named NavOptions' intrusion_cost, not the flag
    ["--intrusion-cost", "3"],  # silently ignored without --soft-search
    ["--scenario", "square", "--steady-goals"],  # silently ignored outside the arena
])  # fmt: skip
def test_crowd_command_refuses_bad_arguments_in_one_line(tmp_path, capsys, flags):
    # in this process (a traceback would be an exception here); one real process below
    out = tmp_path / "x.csv"
    rc, stdout, stderr = run_main(capsys, "crowd", *flags, "--episodes" if "--episodes" not in flags else "--seed", "1",
                                  "-o", out)  # fmt: skip
    assert rc == 2, stdout + stderr
    assert len(stderr.strip().splitlines()) == 1 and "Traceback" not in stderr
    assert not out.exists()
    named = [f for f in flags if f in ("--fov", "--noise", "--intrusion-cost")]
    if named and "1e300" not in flags:  # named as the user typed it, as navigate does
        assert stderr.startswith(f"gfuzzy crowd: {named[0]} ")


def test_crowd_command_refuses_bad_arguments_from_a_real_process(tmp_path):
    out = tmp_path / "x.csv"
    p = _run("crowd", "--noise", "1e300", "--episodes", "1", "-o", str(out))
    assert p.returncode == 2, p.stdout + p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr
    assert not out.exists()


def test_crowd_command_refuses_humans_that_do_not_fit_before_any_episode(tmp_path, capsys, caplog):
    # every episode's layout is drawn first: the refusal names the episode and what fitted
    # (in this process: the real process's one line is test_crowd_command_refuses_bad_arguments_from_a_real_process's)
    out = tmp_path / "x.csv"
    p = main_completed(capsys, "crowd", "--humans", "30", "--episodes", "3", "--policy", "orca", "-o", str(out))
    assert p.returncode == 2, p.stdout + p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr
    assert "episode 0: cannot place 30 humans in the circle scenario" in p.stderr and "placed at most" in p.stderr
    assert not out.exists() and p.stdout == ""
    # 25 humans fit in episode 0 of --seed 4 but not in episode 1: refused before episode 0 runs
    p = main_completed(capsys, "crowd", "--humans", "25", "--seed", "4", "--episodes", "2", "--policy", "orca", "-o", str(out))
    assert p.returncode == 2, p.stdout + p.stderr
    assert p.stderr.startswith("gfuzzy crowd: episode 1: cannot place 25 humans") and p.stdout == ""
    assert not out.exists()
    assert [r.getMessage() for r in caplog.records if r.levelno >= 30] == []  # a real process's stderr: one line


def test_crowd_command_takes_the_navigators_full_speed_option():
    import argparse

    from gfuzzy.cli.crowds import _setting, add_crowd

    parser = argparse.ArgumentParser()
    add_crowd(parser.add_subparsers())
    off = _setting(parser.parse_args(["crowd", "--humans", "2"]))[1]
    on = _setting(parser.parse_args(["crowd", "--humans", "2", "--full-speed"]))[1]
    assert not off.full_speed and on.full_speed


def test_crowd_command_takes_the_navigators_priced_search():
    import argparse

    from gfuzzy.cli.crowds import _setting, add_crowd

    parser = argparse.ArgumentParser()
    add_crowd(parser.add_subparsers())
    off = _setting(parser.parse_args(["crowd", "--humans", "2"]))[1]
    on = _setting(parser.parse_args(["crowd", "--humans", "2", "--soft-search", "--intrusion-cost", "4"]))[1]
    assert not off.soft_search and off.intrusion_cost == 2.0
    assert on.soft_search and on.intrusion_cost == 4.0


def test_crowd_command_takes_the_navigators_time_step():
    import argparse

    from gfuzzy.cli.crowds import _setting, add_crowd

    parser = argparse.ArgumentParser()
    add_crowd(parser.add_subparsers())
    assert _setting(parser.parse_args(["crowd", "--humans", "2"]))[1].dt == 0.1
    assert _setting(parser.parse_args(["crowd", "--humans", "2", "--dt", "0.05"]))[1].dt == 0.05


def test_the_oracle_plans_on_the_time_step_it_is_given(roadmap, monkeypatch):
    import gfuzzy.planner.planner as planner

    seen, real = [], planner.plan

    def recording(scene, rm, start, goal, t0, options):
        seen.append(options.dt)
        return real(scene, rm, start, goal, t0, options)

    monkeypatch.setattr(planner, "plan", recording)
    s = C.CrowdSetting(humans=2, kinematics="unicycle")
    fine = C.run_episode(s, roadmap, 1, 0, ["oracle"], oracle_dt=0.05)[0]
    C.run_episode(s, roadmap, 1, 0, ["oracle"])
    assert seen == [0.05, planner.PlanOptions().dt] and fine.reached


# ------------------------------------------------------------------------ Ctrl-C


def _ctrl_c() -> None:
    """What a SIGINT does at this point: the handler in force runs (no real signal)."""
    import signal

    signal.getsignal(signal.SIGINT)(signal.SIGINT, None)


def _dropped_ctrl_c() -> None:
    """A SIGINT that a callback from native code printed and dropped."""
    try:
        _ctrl_c()
    except KeyboardInterrupt:
        pass


def test_an_episode_stops_at_the_step_after_a_dropped_interrupt(roadmap, monkeypatch):
    from gfuzzy.errors import interrupt_handling

    real = C.Sensor.observe
    calls = []

    def observe(self, *args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            _dropped_ctrl_c()
        return real(self, *args, **kwargs)

    monkeypatch.setattr(C.Sensor, "observe", observe)
    with interrupt_handling(), pytest.raises(KeyboardInterrupt):
        C.run_episode(C.CrowdSetting(humans=3), roadmap, 1, 0, ["orca"])
    assert len(calls) == 2


def _crowd_on_one_worker(monkeypatch, at_start=None, at_progress=None):
    """``gfuzzy crowd --workers 1 --episodes 3 --policy orca`` in-process: (status, the
    progress counts seen)."""
    import distributed

    import gfuzzy.cli.crowds as crowds
    from gfuzzy.cli import main

    real = distributed.LocalCluster
    seen = []

    def starting(*args, **kwargs):
        if at_start:
            at_start()
        return real(*args, **kwargs)

    def bar(label):
        def cb(done, total):
            seen.append(done)
            if done == 1 and at_progress:
                at_progress()

        return cb

    monkeypatch.setattr(distributed, "LocalCluster", starting)
    monkeypatch.setattr(crowds, "_progress_bar", bar)
    code = main(["crowd", "--workers", "1", "--episodes", "3", "--humans", "3", "--policy", "orca"])
    return code, seen


def test_crowd_stops_as_its_cluster_has_started_on_a_ctrl_c_meanwhile(monkeypatch, capsys):
    # the Ctrl-C was held until the first episode had run
    code, seen = _crowd_on_one_worker(monkeypatch, at_start=_ctrl_c)
    assert code == 130 and capsys.readouterr().err.strip() == "interrupted"
    assert [d for d in seen if d] == []


def test_crowd_stops_between_episodes_after_a_dropped_interrupt(monkeypatch, capsys):
    code, seen = _crowd_on_one_worker(monkeypatch, at_progress=_dropped_ctrl_c)
    assert code == 130 and capsys.readouterr().err.strip() == "interrupted"
    assert [d for d in seen if d] == [1]


def test_an_oracle_without_a_plan_says_so_beside_its_outcome():
    """The unicycle oracle of the arena (20 humans, seed 1, episode 0) finds no plan and
    stands at its start until someone walks into it: the table said only "collide 1.000",
    as if it had driven into them. Its modes say ``no_plan`` now; an oracle that planned has none."""
    s = C.CrowdSetting("arena", humans=20, kinematics="unicycle")
    (ep,) = C.run_episode(s, C.crowd_roadmap(s), 1, 0, ["oracle"])
    assert ep.outcome == C.Outcome.COLLISION and ep.path_length == 0.0
    assert dict(ep.modes) == {C.NO_PLAN: 1}
    h = replace(s, kinematics="holonomic")
    (ok,) = C.run_episode(h, C.crowd_roadmap(h), 1, 0, ["oracle"])
    assert ok.outcome == C.Outcome.SUCCESS and ok.modes == ()
