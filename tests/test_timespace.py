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


def test_points_on_a_segment_but_not_evenly_spaced_are_all_examined():
    """A group whose points lie on its segment but bunch up (a re-timed chain that
    accelerates) is judged point by point: the shortcut that examines only the points
    within reach of a mover's projection holds for evenly spaced points only. Oracle:
    the distance of the two discs' centres from the mover's own state."""
    scene = _scene(PERSON)
    mv = scene.movers[0]
    xs = np.array([0.0, 0.01, 0.02, 0.03, 2.35, 2.45, 2.55, 2.65, 2.75, 6.0])  # on y = 1, bunched
    poses = np.column_stack([xs, np.full(len(xs), 1.0)])
    steps = 10
    t = 2.0 + 0.07 * np.arange(steps)
    xy, _ = mv.state(t)
    gap = np.hypot(xs[:, None] - xy[None, :, 0], 1.0 - xy[None, :, 1]) - 0.55  # (points, steps)
    for compiled in (False, True):
        field_ = MoverField(scene, 2.0, 0.07, steps, 1.0)
        field_.compiled = compiled
        margin = field_.margin[0, :steps]  # the motion between two steps' allowance
        assert np.abs(gap - margin).min() > 1e-6  # no pair on the boundary
        want = {(int(n), int(s)) for n, s in zip(*np.nonzero(gap < margin), strict=True)}
        assert len(want) > 10
        node, step = field_.unsafe_pairs(poses, np.array([0, len(xs)]), np.array([0]), np.array([steps - 1]))
        assert set(zip(node.tolist(), step.tolist(), strict=True)) == want, compiled


def _crowd_scene(rng, people: int = 40) -> str:
    """People walking straight lines over a 20 m square, some appearing or leaving inside a step."""
    rows = []
    for i in range(people):
        t0 = float(rng.choice([0.0, 1.03, 2.51]))
        t1 = float(rng.choice([6.0, 3.97, 10.0]))
        p = rng.uniform(1, 19, 2)
        v = rng.uniform(-1.4, 1.4, 2)
        q = p + v * (t1 - t0)
        rows.append(f"  - {{name: p{i}, disc: 0.25, trajectory: [[{t0}, {p[0]:.3f}, {p[1]:.3f}], [{t1}, {q[0]:.3f}, {q[1]:.3f}]]}}")
    return "version: 1\nname: crowd\nbounds: [-20, -20, 40, 40]\nrobot: {disc: 0.25, vmax: 1.5}\nmovers:\n" + "\n".join(rows) + "\n"


def test_first_motion_examines_only_the_people_within_reach(monkeypatch):
    """motion_safe decides a motion among 40 people from those whose broad-phase boxes
    meet it (on a pedestrian replay, 56 first motions among 48 people cost 170 ms of CPU
    in one call, over the navigator's 100 ms budget), and answers as the check of every
    person does (the boxes opened to the whole plane)."""
    import gfuzzy.timespace.movers as movers_mod

    rng = np.random.default_rng(7)
    scene = _scene(_crowd_scene(rng))
    dt, steps = 0.1, 60
    field_ = MoverField(scene, 0.0, dt, steps, 1.5)
    every = MoverField(scene, 0.0, dt, steps, 1.5)
    every.bbox[..., :2], every.bbox[..., 2:] = -np.inf, np.inf
    calls = {"n": 0}
    exact = movers_mod.mover_distance

    def counted(*args, **kwargs):
        calls["n"] += 1
        return exact(*args, **kwargs)

    answers = {True: 0, False: 0}
    filtered = examined = 0
    for _ in range(300):
        step = int(rng.integers(0, steps))
        mv = scene.movers[int(rng.integers(0, len(scene.movers)))]
        xy, _ = mv.state(np.array([step * dt]))
        a = xy[0] + rng.uniform(-0.9, 0.9, 2)
        d = rng.normal(size=2)
        b = a + d / np.linalg.norm(d) * rng.uniform(0, 1.5 * dt)
        want = every.motion_safe(a, b, step)
        monkeypatch.setattr(movers_mod, "mover_distance", counted)
        calls["n"] = 0
        got = field_.motion_safe(a, b, step)
        filtered += calls["n"]
        calls["n"] = 0
        every.motion_safe(a, b, step)
        examined += calls["n"]
        monkeypatch.setattr(movers_mod, "mover_distance", exact)
        assert got == want
        answers[got] += 1
    assert answers[True] > 30 and answers[False] > 30
    assert filtered < examined / 5


def test_straight_movers_are_sampled_as_the_loop_samples_them(monkeypatch):
    """People walking straight from one row to the next (a navigator's predictions, some
    appearing late or vanishing early, some standing) sampled at once: the field's samples,
    presence, margins and boxes are the loop's to the bit."""
    from dataclasses import replace

    import gfuzzy.timespace.movers as movers_mod
    from gfuzzy.scene.scene import Mover

    rng = np.random.default_rng(5)
    rows = []
    for i in range(9):
        t0 = 0.3 + rng.uniform(-1.0, 2.0)
        a, b = rng.uniform(0.0, 4.0, 2), rng.uniform(0.0, 4.0, 2) if i % 4 else None
        rows.append(np.array([[t0, *a], [t0 + rng.uniform(0.05, 6.0), *(a if b is None else b)]]))
    times = 0.3 + 0.1 * np.arange(71)  # the field's times: one appears, one vanishes half a step off a sample
    rows[0][:, 0] += times[5] + 0.05 - rows[0][0, 0]
    rows[1][:, 0] += times[40] - 0.05 - rows[1][1, 0]
    scene = _scene(PERSON)
    scene = replace(scene, movers=tuple(Mover(f"p{i}", "disc", 0.3, (0.0, 0.0), trajectory=r) for i, r in enumerate(rows)))
    fast = MoverField(scene, 0.3, 0.1, 70, 1.0)
    monkeypatch.setattr(movers_mod, "_straight_samples", lambda *a: None)
    loop = MoverField(scene, 0.3, 0.1, 70, 1.0)
    for name in ("xy", "present", "margin", "bbox"):
        x, y = getattr(fast, name), getattr(loop, name)
        assert x.dtype == y.dtype and x.shape == y.shape and np.array_equal(x, y), name
    assert not fast.present.all() and fast.present.any()
