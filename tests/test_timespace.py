"""The mover field of the time-space search (``gfuzzy.timespace.timespace.MoverField``): its margins
and its exact first motion."""

from __future__ import annotations

import numpy as np
from helpers import scene_of as _scene
from shared_scenes import CROSSING, PERSON

from gfuzzy.timespace.timespace import MoverField


def test_mover_clearance_is_in_the_margin_table():
    scene = _scene(CROSSING, mover_clearance=0.2)
    base = MoverField(scene.with_clearances(mover_clearance=0.0), 0.0, 0.07, 50, 1.0)
    kept = MoverField(scene, 0.0, 0.07, 50, 1.0)
    np.testing.assert_allclose(kept.margin - base.margin, 0.2)


def test_first_motion_is_decided_exactly():
    """motion_safe agrees with a dense sampling of the first step."""
    scene = _scene(PERSON)
    field_ = MoverField(scene, 2.0, 0.07, 4, 1.0)
    mv = scene.movers[0]
    rng = np.random.default_rng(3)
    agree = 0
    for _ in range(60):
        a = np.array([2.6, 1.5]) + rng.uniform(-0.15, 0.15, 2)
        step = rng.normal(size=2)
        b = a + step / np.linalg.norm(step) * rng.uniform(0, 0.07)
        ts = np.linspace(2.0, 2.07, 2001)
        f = (ts - 2.0) / 0.07
        p = a + f[:, None] * (b - a)
        xy, _ = mv.state(ts)
        dense = (np.hypot(*(xy - p).T) - 0.55).min()
        got = field_.motion_safe(a, b, 0)
        if dense < -1e-6:
            assert not got
        elif dense > 1e-4:
            assert got
        agree += 1
    assert agree == 60
