"""A box drive's way through a curved gap with half a centimetre per side: a chain of small
turns no roadmap vertex offers, found by the repair (:mod:`gfuzzy.timespace.unirepair`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gfuzzy.check.check import check_trajectory
from gfuzzy.planner.planner import Planner, PlanOptions
from gfuzzy.roadmap.roadmap import Roadmap
from gfuzzy.scene.scene import parse_scene
from gfuzzy.timespace import unirepair

R = 0.6  # the gap's middle line: a quarter circle round the origin
H = math.pi / 2


def arc_scene(reverse: bool = True):
    """A 0.6 x 0.2 box drive (reverse) round a post through a quarter-circle gap as wide as
    the band it sweeps driving tangent to the circle plus 1 cm; a room before it (below the
    x axis) and one after it (left of the y axis), the rest blocked."""
    rin, rout = R - 0.1 - 0.005, math.hypot(R + 0.1, 0.3) + 0.005
    t = np.linspace(0.0, math.pi / 2, 48)
    outer = [[float(rout * math.cos(a)), float(rout * math.sin(a))] for a in t] + [[0.0, 1.5], [1.5, 1.5], [1.5, 0.0]]
    return parse_scene({
        "version": 1, "name": "arc-gap", "bounds": [-1.5, -1.5, 1.5, 1.5],
        "robot": {"box": [0.6, 0.2], "vmax": 0.5, "kinematics": "unicycle", "reverse": reverse},
        "obstacles": [{"disc": {"center": [0.0, 0.0], "radius": rin}}, {"polygon": outer},
                      {"box": {"center": [-0.75, -0.75], "size": [1.5, 1.5]}}],
    })  # fmt: skip


def arc_roadmap(sc, cut: bool = False):
    """Three vertices in each room, one at each mouth of the gap, and one in its middle
    (the roadmap's holonomic way round): no lane at a held heading passes the gap. ``cut``:
    no edge into the middle one (the roadmap leaves the rooms apart)."""
    m = R / math.sqrt(2.0)
    v = np.array([[R, 0.0, H], [R, -0.6, H], [R, -1.0, H], [0.0, R, math.pi], [-0.6, R, math.pi],
                  [-1.0, R, math.pi], [m, m, 3 * math.pi / 4]])  # fmt: skip
    e = np.array([[0, 1], [1, 2], [0, 2], [3, 4], [4, 5], [3, 5], [0, 6], [6, 3]])[: 6 if cut else 8]
    return Roadmap(v, e, np.hypot(*(v[e[:, 1], :2] - v[e[:, 0], :2]).T), sc.name, sc.static_hash, sc.robot.circumradius)


@pytest.fixture(scope="module")
def arc():
    sc = arc_scene()
    return sc, arc_roadmap(sc)


def test_a_drive_rounds_a_curved_gap_by_small_turns(arc, monkeypatch):
    """Without the repair ``no_path`` (its lanes prove the ends apart: no straight lane
    passes the gap, and turns happen only at vertices); the repair, on by default (off
    by default before session 38: this fails there), joins the rooms' pieces by a chain of
    2 cm drives and 0.01 rad turns, and the answer passes the check. Its A*'s moves are
    certified from clearances kept per pose (a drive or turn whose ends' clearances add up
    to its length needs no further query), a target's turns from the arc traced once: the
    chains ask 21,843 FCL queries, 29,361 before session 38 (each move traced afresh, each
    finishing turn and drive onto every target copy too)."""
    sc, rm = arc
    start, goal = [R, -0.6, H], [-0.6, R, math.pi]
    off = Planner(sc, arc_roadmap(sc)).plan(start, goal, 0.0, PlanOptions(time_limit=1e6, drive_repair=False))
    assert off.status.value == "no_path"  # --no-drive-repair: as before, at once
    res, calls, _ = _chain_calls(sc, rm, monkeypatch)
    assert 0 < calls < 25_000
    assert res.solved, res.message
    rep = check_trajectory(sc, res.trajectory.waypoints)
    assert rep.valid, rep.reason
    wp = res.trajectory.waypoints
    angles = np.arctan2(wp[:, 2], wp[:, 1])
    assert angles.min() < 0.0 and angles.max() > math.pi / 2  # round the post, not elsewhere
    assert np.all(np.hypot(wp[:, 1], wp[:, 2]) > R - 0.1)  # (the post's edge)


def test_the_repair_is_kept_on_the_roadmap_and_changes_no_solved_answer(arc):
    """A query the graph joins without it never builds the repair (the same answer as
    before it): one inside the room before the gap."""
    sc, rm = arc
    rm2 = arc_roadmap(sc)
    res = Planner(sc, rm2).plan([R, -0.6, H], [R, -1.0, H], 0.0, PlanOptions(time_limit=1e6, drive_repair=True))
    assert res.solved, res.message
    assert not any(k[0] in ("unicycle-chains", "unicycle-repaired") for k in rm2._derived)
    res = Planner(sc, rm).plan([R, -0.6, H], [-0.6, R, math.pi], 0.0, PlanOptions(time_limit=1e6, drive_repair=True))
    assert res.solved
    assert any(k[0] == "unicycle-chains" for k in rm._derived)


@pytest.mark.parametrize("command", ["plan", "regress", "batch"])
def test_the_command_line_turns_the_repair_off(command):
    """The repair is on by default; ``--no-drive-repair`` reaches ``PlanOptions.drive_repair``
    (and ``--drive-repair``, the flag before session 38, still parses)."""
    from gfuzzy.cli.common import _plan_options
    from gfuzzy.cli.main import _parser

    words = {"plan": ["plan", "s.yaml"], "regress": ["regress", "s.yaml"], "batch": ["batch", "s.yaml", "-o", "x.csv"]}
    assert _plan_options(_parser().parse_args([*words[command], "--drive-repair"])).drive_repair
    assert _plan_options(_parser().parse_args(words[command])).drive_repair
    assert PlanOptions().drive_repair
    assert not _plan_options(_parser().parse_args([*words[command], "--no-drive-repair"])).drive_repair


@pytest.mark.parametrize("reverse", [True, False])
def test_the_message_says_the_roadmap_joins_the_ends_the_drive_cannot(reverse):
    """The arc's roadmap joins the rooms (its vertex in the gap); the drive without the
    repair has no way: the ``no_path`` message says the roadmap joins them and names what
    may help (before: "not connected on the roadmap (sealed off, or the roadmap missed a
    passage ...)", untrue). Backing up is named only for a robot that may not; cut the
    roadmap's way through the gap and the roadmap's own message comes back."""
    sc = arc_scene(reverse)
    no = PlanOptions(time_limit=1e6, drive_repair=False)
    res = Planner(sc, arc_roadmap(sc)).plan([R, -0.6, H], [-0.6, R, math.pi], 0.0, no)
    assert res.status.value == "no_path"
    assert res.message.startswith("start and goal are joined on the roadmap, but the differential drive"), res.message
    assert "\n" not in res.message and "more vertices (-n)" in res.message and "drop --no-drive-repair" in res.message
    assert ("robot.reverse: true" in res.message) is (not reverse)
    planner = Planner(sc, arc_roadmap(sc))  # a kept goal (replanning) says the same
    kept = planner.plan_from(planner.prepare([-0.6, R, math.pi], no), [R, -0.6, H])
    assert kept.status.value == "no_path" and kept.message == res.message, kept.message
    res = Planner(sc, arc_roadmap(sc, cut=True)).plan([R, -0.6, H], [-0.6, R, math.pi], 0.0, no)
    assert res.status.value == "no_path" and "not connected on the roadmap" in res.message, res.message


def _chain_calls(sc, rm, monkeypatch) -> tuple:
    """(answer, FCL queries asked inside :func:`unirepair.drive_chain`, A* expansions) of the
    arc's query on roadmap ``rm`` (the default options)."""
    seen = {"calls": 0, "certs": []}
    chain, cert = unirepair.drive_chain, unirepair._Cert

    def counted(geo, *args, **kwargs):
        c0 = geo.calls
        try:
            return chain(geo, *args, **kwargs)
        finally:
            seen["calls"] += geo.calls - c0

    class Kept(cert):
        def __init__(self, geo):
            super().__init__(geo)
            seen["certs"].append(self)

    monkeypatch.setattr(unirepair, "drive_chain", counted)
    monkeypatch.setattr(unirepair, "_Cert", Kept)
    res = Planner(sc, rm).plan([R, -0.6, H], [-0.6, R, math.pi], 0.0, PlanOptions(time_limit=1e6))
    return res, seen["calls"], sum(unirepair.TOTAL - c.budget for c in seen["certs"])


def test_the_repair_stops_at_its_total_of_expansions(arc, monkeypatch):
    """Where no way is found the repair's attempts stop at ``TOTAL`` expansions in all (an
    unsolvable query pays at most that): with a total of 200 the arc is not rounded,
    ``no_path``, every expansion of the 200 spent (before session 38: 6 attempts of up to
    1500 expansions each; this fails there, no ``_Cert``)."""
    monkeypatch.setattr(unirepair, "TOTAL", 200)
    sc = arc[0]
    res, _, spent = _chain_calls(sc, arc_roadmap(sc), monkeypatch)
    assert res.status.value == "no_path"
    assert spent == 200
    assert "the drive repair found no chain of small turns" in res.message, res.message
