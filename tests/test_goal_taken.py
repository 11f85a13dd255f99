"""A query no horizon can answer: a mover comes to rest on its goal for ever (a ``once``
mover at its path's end, a path mover of speed 0). The ``no_path`` says so, instead of
"a longer horizon may find one" (``gfuzzy.planner.queries.goal_taken``)."""

from __future__ import annotations

import math

from gfuzzy.planner.planner import Planner, PlanOptions, Status
from gfuzzy.planner.queries import goal_taken
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
