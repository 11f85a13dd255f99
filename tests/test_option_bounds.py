"""The numeric options of ``navigate``, ``crowd`` and ``populate`` under one rule: each is
checked by ``gfuzzy.errors.check_number`` under its flag's own name (a number above zero, or
at least zero, and at most 1e9 in magnitude, as a scene file's numbers), and a run that
cannot finish is refused before it starts (``navsim.check_run``: a period of at least 1 ms,
at most ``settings.MAX_RUN_STEPS`` replans; ``crowd --episodes`` at most ``MAX_EPISODES``).

Every case is refused before any roadmap, episode or walk: in this process, cheap.
"""

from __future__ import annotations

import re

import pytest
from conftest import ROOT
from helpers import run_main

from gfuzzy.errors import InputError

SCENE = ROOT / "scenes" / "sim-4s1m.yaml"
ROADMAP = ROOT / "roadmaps" / "sim-4s1m.json"


def _refused(capsys, *argv) -> str:
    rc, out, err = run_main(capsys, *argv)
    assert rc == 2, out + err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.mark.parametrize(
    ("flags", "expect"),
    [
        # accepted before: ran to the goal (exit 0), while --noise 1e300 was refused "at most 1e+09"
        (["--max-time", "1e300"], "--max-time must be at most 1e+09, got 1e+300"),
        (["--sense", "1e300"], "--sense must be at most 1e+09, got 1e+300"),
        (["--period", "1e300"], "--period must be at most 1e+09, got 1e+300"),  # one replan, an invalid run
        (["--log-every", str(10**20)], "--log-every must be at most 1e+09, got 1e+20"),
        # refused before, but named after NavOptions' and SensorOptions' fields, not the flags
        (["--noise", "1e300"], "--noise must be at most 1e+09, got 1e+300"),
        (["--time-budget", "1e300"], "--time-budget must be at most 1e+09, got 1e+300"),
        (["--personal-space", "1e300"], "--personal-space must be at most 1e+09, got 1e+300"),
        (["--path-space", "1e300"], "--path-space must be at most 1e+09, got 1e+300"),
    ],
)
def test_navigate_bounds_every_number_by_its_flag(tmp_path, capsys, flags, expect):
    out = tmp_path / "o.json"
    line = _refused(capsys, "navigate", SCENE, "--roadmap", ROADMAP, "--budget-clock", "cpu", *flags, "-o", out)
    assert line == f"gfuzzy navigate: {expect}"
    assert not out.exists()


def test_navigate_refuses_a_period_below_a_millisecond(tmp_path, capsys):
    # --period 1e-9 asked for 1.2e11 replans: still running after minutes, a practical hang;
    # this one (20 replans of 0.5 ms) ran, exit 0
    out = tmp_path / "o.json"
    line = _refused(capsys, "navigate", SCENE, "--roadmap", ROADMAP, "--period", "0.0005", "--max-time", "0.01",
                    "-o", out)  # fmt: skip
    assert line == "gfuzzy navigate: --period must be at least 0.001 s (a replan every millisecond), got 0.0005"
    assert not out.exists()


def test_navigate_refuses_more_replans_than_a_run_may_make(tmp_path, capsys, monkeypatch):
    from gfuzzy.navigation import navsim

    monkeypatch.setattr(navsim, "MAX_RUN_STEPS", 10)  # 20 replans: refused before the run
    out = tmp_path / "o.json"
    line = _refused(capsys, "navigate", SCENE, "--roadmap", ROADMAP, "--max-time", "5", "-o", out)
    assert line == ("gfuzzy navigate: --max-time 5 s / --period 0.25 s is 20 replans, more than 10 a run may make: "
                    "give a larger --period or a smaller --max-time")  # fmt: skip
    assert not out.exists()


def test_check_run_is_the_one_bound_of_a_simulated_run():
    from gfuzzy.navigation.navsim import check_run
    from gfuzzy.settings import MAX_RUN_STEPS

    check_run(0.25, MAX_RUN_STEPS * 0.25)  # exactly the bound: a run of 100000 replans is allowed
    check_run(0.001, 1.0)
    for period, max_time, words in [(0.25, MAX_RUN_STEPS * 0.25 + 1, "replans, more than 100,000"),
                                    (1e-9, 120.0, "period must be at least 0.001 s"),
                                    (0.25, 1e300, "max_time must be at most 1e+09"),
                                    (0.25, 0.0, "max_time must be a positive number")]:  # fmt: skip
        with pytest.raises(InputError, match=re.escape(words)):
            check_run(period, max_time)


@pytest.mark.parametrize(
    ("flags", "expect"),
    [
        (["--sense", "1e300"], "--sense must be at most 1e+09, got 1e+300"),  # ran its episodes before
        (["--noise", "1e300"], "--noise must be at most 1e+09, got 1e+300"),  # was named "noise"
        (["--time-budget", "1e300"], "--time-budget must be at most 1e+09, got 1e+300"),  # "time_budget"
        (["--personal-space", "1e300"], "--personal-space must be at most 1e+09, got 1e+300"),
        (["--dt", "1e300"], "--dt must be at most 1e+09, got 1e+300"),
        # drew 1e9 layouts (3-10 ms each) before the first episode, saying nothing
        (["--episodes", "1000000000"], "--episodes must be between 1 and 10000, got 1000000000"),
    ],
)
def test_crowd_bounds_every_number_by_its_flag(tmp_path, capsys, monkeypatch, flags, expect):
    from gfuzzy.navigation import crowd

    def no_layout(*args, **kwargs):  # refused before any: the old code fails here, not after days
        raise AssertionError("an episode's layout was drawn")

    monkeypatch.setattr(crowd, "episode_layout", no_layout)
    out = tmp_path / "c.csv"
    line = _refused(capsys, "crowd", *flags, *(["--episodes", "1"] if "--episodes" not in flags else []), "-o", out)
    assert line == f"gfuzzy crowd: {expect}"
    assert not out.exists()


def test_crowd_episodes_are_bounded_in_the_library_too():
    from gfuzzy.navigation.crowd import MAX_EPISODES, CrowdSetting, episodes

    with pytest.raises(InputError, match=f"episodes must be between 1 and {MAX_EPISODES}"):
        episodes(CrowdSetting("circle", 5), None, 1, MAX_EPISODES + 1, ["orca"])


@pytest.mark.parametrize(
    ("flags", "expect"),
    [
        (["--duration", "1e300"], "--duration must be at most 1e+09, got 1e+300"),  # was "duration must ..."
        (["--speed", "1e20"], "--speed must be at most 1e+09, got 1e+20"),
        (["--radius", "nan"], "--radius must be a positive number, got nan"),
        # PopulateOptions' own bounds, said of the flags (they were "people ...", "duration ...")
        (["--people", "600"], "--people must be between 1 and 500, got 600"),
        (["--duration", "1e6"], "--duration must be at most 25000 s (100000 steps of 0.25 s), got 1e+06"),
    ],
)
def test_populate_bounds_every_number_by_its_flag(tmp_path, capsys, flags, expect):
    out = tmp_path / "p.yaml"
    line = _refused(capsys, "populate", SCENE, *(["--people", "2"] if "--people" not in flags else []), *flags, "-o", out)
    assert line == f"gfuzzy populate: {expect}"
    assert not out.exists()


@pytest.mark.parametrize(
    ("argv", "expect"),
    [
        (["batch", SCENE, "--workers", "100000", "-o", "{tmp}/rows.csv"],
         "gfuzzy batch: --workers must be at most 256 (local worker processes), got 100000"),
        (["crowd", "--workers", "100000", "--episodes", "1", "-o", "{tmp}/rows.csv"],
         "gfuzzy crowd: --workers must be between 0 and 256, got 100000"),
    ],
)  # fmt: skip
def test_a_local_cluster_of_more_workers_than_a_machine_holds_is_refused_first(tmp_path, capsys, monkeypatch, argv,
                                                                               expect):  # fmt: skip
    # both set about starting 100000 worker processes (after building the roadmaps): here
    # the cluster would fail the test, not the machine
    from gfuzzy.runs import batch

    def no_cluster(*args, **kwargs):
        raise AssertionError("a local cluster was started")

    monkeypatch.setattr(batch, "local_cluster", no_cluster)
    line = _refused(capsys, *(str(a).format(tmp=tmp_path) for a in argv))
    assert line == expect
    assert not (tmp_path / "rows.csv").exists()


def test_local_cluster_refuses_more_workers_before_starting_any():
    from gfuzzy.runs.batch import MAX_LOCAL_WORKERS, local_cluster

    with pytest.raises(InputError, match=f"workers must be between 1 and {MAX_LOCAL_WORKERS}, got 100000"):
        with local_cluster(100_000):
            pass


def test_navigate_says_when_its_period_leaves_one_plan_for_the_whole_run(tmp_path, capsys):
    # --period 200 with --max-time 120 (or --period 1e300) replanned once and drove that
    # plan blind, into a mover here (exit 1, check INVALID), without a word on why
    out = tmp_path / "o.json"
    rc, _, err = run_main(capsys, "navigate", SCENE, "--roadmap", ROADMAP, "--budget-clock", "cpu", "--period", "10",
                          "--max-time", "8", "-o", out)  # fmt: skip
    assert rc == 1 and out.exists()
    note = ("note: --period 10 s is not shorter than --max-time 8 s: the robot observes and plans once, at the start, "
            "and follows that plan without looking again")  # fmt: skip
    assert note in err.splitlines()
    rc, _, err = run_main(capsys, "navigate", SCENE, "--roadmap", ROADMAP, "--budget-clock", "cpu", "--period", "7.9",
                          "--max-time", "8", "-o", out)  # fmt: skip
    assert "--period" not in err  # it looks again at 7.9 s
