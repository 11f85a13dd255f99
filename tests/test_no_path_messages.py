"""``no_path`` messages that say what would help, or that nothing would.

A query no horizon can answer: a mover comes to rest on its goal for ever (a ``once``
mover at its path's end, a path mover of speed 0); the message says so, instead of "a
longer horizon may find one" (``gfuzzy.planner.queries.goal_taken``). A robot fast for
the time step, whose movers are kept far off between two samples: a smaller dt may help
(``first_motion_hint``)."""

from __future__ import annotations

import math

from gfuzzy.planner.planner import Planner, PlanOptions, Status
from gfuzzy.planner.queries import first_motion_hint, goal_taken
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap
from gfuzzy.scene.scene import parse_scene

PARKED = {
    "version": 1, "name": "parked", "bounds": [0, 0, 6, 2], "robot": {"disc": 0.2, "vmax": 1.0},
    "movers": [{"name": "cart", "disc": 0.3, "speed": 1.0, "path": [[5, 1.8], [5, 1]], "mode": "once"},
               {"name": "post", "disc": 0.2, "speed": 0, "path": [[2, 0.3], [3, 0.3]], "mode": "loop"}],
}  # fmt: skip


def test_a_goal_a_mover_comes_to_rest_on_says_no_horizon_helps():
    # a `once` cart parks on the goal at t = 0.8 s; the robot needs 4.5 s: the answer said
    # "the horizon cut the search: a longer one (--horizon) may find one" (found by s39-newuser)
    scene = parse_scene(PARKED)
    planner = Planner(scene, build_roadmap(scene, RoadmapOptions(vertices=40, seed=1)))
    res = planner.plan([0.5, 1.0], [5.0, 1.0], 0.0)
    assert res.status is Status.NO_PATH and res.message == (
        "the goal is taken for ever from t=0.8 s: mover 'cart' comes to rest there (mode once), "
        "so no horizon finds a trajectory"
    ), res.message
    # a mover of speed 0 (the post) is at rest for ever from the start
    res = planner.plan([0.5, 1.0], [2.0, 0.5], 0.0)
    assert res.status is Status.NO_PATH and "mover 'post' comes to rest there (speed 0)" in res.message
    # a horizon that ends before the cart parks proves nothing: a longer one may help
    res = planner.plan([0.5, 1.0], [5.0, 1.0], 0.0, PlanOptions(horizon=0.5))
    assert res.status is Status.NO_PATH and "the goal is taken" not in res.message, res.message


def test_a_goal_touching_the_parked_mover_is_not_taken():
    # touching is allowed: the robot may park against the cart (0.2 + 0.3 from its centre)
    scene = parse_scene(PARKED)
    assert goal_taken(scene, [5.5, 1.0], math.inf) == ""
    assert goal_taken(scene, [5.49, 1.0], math.inf).startswith("the goal is taken for ever from t=0.8 s")
    kept = parse_scene({**PARKED, "robot": {**PARKED["robot"], "mover_clearance": 0.05}})
    assert "mover 'cart'" in goal_taken(kept, [5.5, 1.0], math.inf)  # closer than mover_clearance
    assert goal_taken(kept, [5.5, 1.0], 0.7) == ""  # the search ended before the cart parked


def test_a_robot_fast_for_the_time_step_is_told_a_smaller_dt_may_help():
    # vmax 200 m/s at dt 0.07 kept every mover 7 m off: in a 5 m room "no first motion ...
    # (the start is too close to a mover at t0)" of a start 3 m from the only mover, with
    # no word of dt; dt 0.001 solves it (found by s39-newuser)
    doc = {"version": 1, "name": "fast", "bounds": [0, 0, 5, 5], "robot": {"disc": 0.2, "vmax": 200.0},
           "movers": [{"name": "a", "disc": 0.2, "speed": 1, "path": [[1, 1], [4, 1]], "mode": "bounce"}]}
    scene = parse_scene(doc)
    planner = Planner(scene, build_roadmap(scene, RoadmapOptions(vertices=30, seed=1)))
    res = planner.plan([0.5, 4.0], [4.5, 4.0], 0.0)
    assert res.status is Status.NO_PATH and res.message.endswith(
        "; a step of 0.07 s moves this robot up to 14 m, and the movers are kept 7 m farther off for it: "
        "a smaller --dt (PlanOptions.dt) may find one"
    ), res.message
    assert planner.plan([0.5, 4.0], [4.5, 4.0], 0.0, PlanOptions(dt=0.001)).status is Status.SOLVED
    # half a step within the robot's body: the margin is not the news
    assert first_motion_hint(parse_scene({**doc, "robot": {"disc": 0.2, "vmax": 1.0}}).robot, 0.07) == ""
    assert first_motion_hint(scene.robot, 0.002) == ""  # 0.4 m a step: half of it is the radius
    assert first_motion_hint(scene.robot, 0.07, "the goal is not reachable on the roadmap") == ""
