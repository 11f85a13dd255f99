"""A differential drive's end that can neither turn round nor drive out: the no_path
message says so (more vertices cannot help), measured on a slot barely wider than the body."""

from __future__ import annotations

import pytest

from gfuzzy.collision.geometry import StaticGeometry
from gfuzzy.planner.hemmed import hemmed_note
from gfuzzy.planner.planner import Planner
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap
from gfuzzy.scene.scene import parse_scene

# a slot 0.42 wide from x = 4 to the bounds at x = 6; the 0.6 x 0.4 body inside it cannot turn
SLOT = [
    {"box": {"center": [5.0, 2.26], "size": [2.0, 0.1]}},
    {"box": {"center": [5.0, 1.74], "size": [2.0, 0.1]}},
]
DEEP = [5.69, 2.0, 0.0]  # its nose 0.01 m from the end of the slot


def slot_scene(reverse: bool, start=DEEP, goal=(1.0, 2.0, 0.0)):
    return parse_scene({
        "version": 1, "name": "slot", "bounds": [0, 0, 6, 4],
        "robot": {"box": [0.6, 0.4], "vmax": 1.0, "kinematics": "unicycle", "reverse": reverse},
        "obstacles": SLOT,
        "queries": [{"name": "out", "start": list(start), "goal": list(goal)}],
    })  # fmt: skip


def test_an_end_hemmed_in_is_named_with_what_it_can_do():
    geo = StaticGeometry(slot_scene(False))
    note = hemmed_note(geo, DEEP, "start")
    assert note.startswith("the start is hemmed in: it turns in place at most")
    assert "forwards" in note and "robot.reverse: true allows it" in note
    # the same pose as a goal is entered forwards from behind it: free, no note
    assert hemmed_note(geo, DEEP, "goal") == ""
    # facing out of the slot, the goal is entered only from the slot's end
    assert hemmed_note(geo, [5.69, 2.0, 3.14159265], "goal").startswith("the goal is hemmed in")
    # in the open, or a robot that may reverse out: nothing to say
    assert hemmed_note(geo, [1.0, 2.0, 0.5], "start") == ""
    assert hemmed_note(StaticGeometry(slot_scene(True)), DEEP, "start") == ""


@pytest.fixture(scope="module")
def roadmap():
    return build_roadmap(slot_scene(False), RoadmapOptions(vertices=120, seed=1))


def test_no_path_from_a_hemmed_start_says_why_and_reversing_solves_it(roadmap):
    sc = slot_scene(False)
    q = sc.queries[0]
    res = Planner(sc, roadmap).plan(q.start, q.goal)
    assert res.status == "no_path"
    assert "the start is hemmed in" in res.message and "-n" not in res.message
    rev = slot_scene(True)
    assert Planner(rev, roadmap).plan(q.start, q.goal).status == "solved"


@pytest.mark.parametrize("half_width, hemmed", [(0.215, True), (0.25, False)])
def test_a_part_turn_that_clears_the_way_is_no_hemming(half_width, hemmed):
    # a pointed nose 5 mm from a post, walls on both sides: straight ahead is blocked at once,
    # but where the walls leave 17 degrees of turn, the straight at the turn's limit drives
    # 0.08 m past the post (the review: an end that can turn part way and drive out was called
    # hemmed in); with 4 degrees it cannot
    fp = [[0.3, 0.0], [0.1, 0.2], [-0.2, 0.2], [-0.2, -0.2], [0.1, -0.2]]
    scene = parse_scene({
        "version": 1, "name": "post", "bounds": [-2, -2, 2, 2],
        "robot": {"footprint": fp, "vmax": 1.0, "kinematics": "unicycle"},
        "obstacles": [{"disc": {"center": [0.325, 0.0], "radius": 0.02}},
                      {"box": {"center": [0.0, half_width + 0.05], "size": [0.8, 0.1]}},
                      {"box": {"center": [0.0, -half_width - 0.05], "size": [0.8, 0.1]}}],
    })  # fmt: skip
    note = hemmed_note(StaticGeometry(scene), [0.0, 0.0, 0.0], "start")
    assert note.startswith("the start is hemmed in") if hemmed else note == ""
