"""tools/nav_contacts.py: who walked into whom, and whether the robot could see them."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest
from conftest import ROOT

sys.path.insert(0, str(ROOT))

from gfuzzy.scene.scene import parse_scene  # noqa: E402
from tools.nav_contacts import contacts  # noqa: E402

# a person walks south down x = 0 at 1 m/s; the box robot slides north up x = 0 at 0.5 m/s
SCENE = {
    "version": 1, "name": "slide", "bounds": [-3.0, -3.0, 3.0, 5.0],
    "robot": {"box": [0.4, 0.3], "vmax": 1.0}, "obstacles": [],
    "movers": [{"name": "walker", "disc": 0.3, "trajectory": [[0.0, 0.0, 4.0], [6.0, 0.0, -2.0]]}],
}  # fmt: skip


@pytest.mark.parametrize(("heading", "seen", "blind"), [(0.0, False, 1.0), (math.pi / 2, True, 0.0)])
def test_a_robot_sliding_sideways_into_someone_did_not_see_them(heading, seen, blind):
    scene = parse_scene(SCENE)
    t = np.linspace(0.0, 4.0, 9)
    rows = np.column_stack([t, np.zeros_like(t), -2.0 + 0.5 * t, np.full_like(t, heading)])
    share, found = contacts(scene, rows, fov=90.0)
    assert share == pytest.approx(blind)  # facing east, it moved north: all of it outside a 90-degree view
    (c,) = found
    assert c["mover"] == "walker" and c["seen"] is seen and c["deepest"] < 0
    assert c["robot_closing"] == pytest.approx(0.5, abs=1e-6) and c["mover_closing"] == pytest.approx(1.0, abs=1e-6)
    # they meet when 1.5 t = 6 - (0.3 + 0.15): the robot's half-length ahead and the person's radius
    assert c["t"] == pytest.approx((6.0 - 0.45) / 1.5, abs=0.05)
