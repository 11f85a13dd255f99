"""tools/bench_unseen_drives.py: generated drive cases load and hold valid queries, their
walls hold no line of zero width, the outcomes are classified against the oracle, and a
dumped case reloads with its maps."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest
import shapely
from conftest import ROOT

sys.path.insert(0, str(ROOT))

from gfuzzy.collision.geometry import StaticGeometry  # noqa: E402
from gfuzzy.planner.planner import query_problem  # noqa: E402
from gfuzzy.scene.scene import Polygon, load_scene  # noqa: E402
from tools.bench_unseen_drives import SCENARIOS, band, dump, make_case, make_drive, outcome  # noqa: E402


def _flat_triangles(scene) -> int:
    """Triangles of zero area but length in the scene's polygons (a wall of zero width)."""
    n = 0
    for ob in scene.obstacles:
        if not isinstance(ob, Polygon):
            continue
        for t in shapely.get_parts(shapely.constrained_delaunay_triangles(shapely.Polygon(ob.points))):
            p = np.asarray(t.exterior.coords)[:3]
            area2 = (p[1, 0] - p[0, 0]) * (p[2, 1] - p[0, 1]) - (p[2, 0] - p[0, 0]) * (p[1, 1] - p[0, 1])
            n += abs(area2) < 1e-14 and np.ptp(p, axis=0).max() > 1e-6
    return n


@pytest.mark.parametrize("scenario", list(SCENARIOS))
def test_every_scenario_gives_a_drive_with_a_valid_query_and_walls_without_cracks(scenario):
    for index in (0, 3):
        case = make_case(1, index, scenarios=(scenario,))
        scene, q = case["scene"], case["query"]
        assert scene.robot.kinematics == "unicycle" and case["scenario"] == scenario
        assert query_problem(StaticGeometry(scene), q.start, q.goal) == ""
        assert _flat_triangles(scene) == 0, (scenario, index)


def test_seed_1_case_0_the_arc_that_had_a_zero_width_wall():
    """Before the walls were cut from the free space grown by 0.1 um, this curved gap's
    rooms met it along a line and left a wall of zero width across the way (two flat
    triangles), which the check blocks and FCL did not see."""
    case = make_case(1, 0)
    assert (case["body"], case["scenario"]) == ("disc", "arc")
    assert _flat_triangles(case["scene"]) == 0


def test_the_same_seed_gives_the_same_case_and_another_seed_another():
    a, b, c = make_case(3, 5), make_case(3, 5), make_case(4, 5)
    assert a["doc"] == b["doc"] and a["roadmap_seed"] == b["roadmap_seed"]
    assert a["doc"] != c["doc"]


def test_the_band_of_a_disc_and_of_a_long_box_round_a_circle():
    rng = np.random.default_rng(0)
    disc = make_drive(rng, "disc")
    r = disc.spec["disc"]
    assert band(disc, 1.5) == pytest.approx((1.5 - r, 1.5 + r))
    box = make_drive(rng, "box")
    length, width = box.spec["box"]
    lo, hi = band(box, 1.5)
    assert lo == pytest.approx(1.5 - width / 2, abs=1e-5)  # the inner side's middle touches the circle (sampled every 5 mm)
    assert hi == pytest.approx(math.hypot(1.5 + width / 2, length / 2), abs=1e-3)  # the outer corners


def test_outcomes_against_the_oracle():
    row = lambda g, o: {"gfuzzy": g, "oracle": o}  # noqa: E731
    assert outcome(row("solved", "proved")) == "both"
    assert outcome(row("solved", "not_found")) == "gfuzzy-only"
    assert outcome(row("unsolved", "proved")) == "missed"
    assert outcome(row("unsolved", "not_found")) == "neither"
    assert outcome(row("check_reject", "proved")) == "check_reject"
    assert outcome(row("unsolved", "")) == "unsolved"


def test_a_dumped_crop_reloads_with_its_map(tmp_path):
    case = make_case(1, 9)
    assert case["scenario"] == "crop"
    path = dump(tmp_path, 1, case, {"outcome": "missed", "message": "", "roadmap_seed": 5}, (200, 400))
    scene = load_scene(path)
    assert scene.bounds == case["scene"].bounds and scene.static_hash == case["scene"].static_hash
    assert "-n 200 --seed 5" in path.read_text()


def test_a_plan_budget_reaches_the_planner():
    """``--time-limit``: each plan's budget (the planner's 60 s wall clock made a loaded
    machine's hard cases timeouts)."""
    from tools.bench_unseen_drives import plan_case

    got = plan_case(make_case(1, 0, scenarios=("door",)), vertices=(12,), time_limit=1e-9)
    assert got["gfuzzy"] == "unsolved" and got["status"] == "timeout"
