"""The fuzzy speed layer: inference, rule files, the speed profile, rule learning."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gfuzzy.errors import SceneError
from gfuzzy.fuzzy import fuzzy
from gfuzzy.fuzzy.fuzzy import FuzzyOptions, Partition, RuleBase
from gfuzzy.learning import learn

P3 = Partition.uniform(3)

# A 3 x 3 rule base small enough to evaluate by hand (rows curve, columns distance).
HAND = RuleBase.from_matrix(
    [
        [2, 3, 3],  # curve L:  dist L -> Z, Z -> H, H -> H
        [1, 2, 3],  # curve Z:  L, Z, H
        [1, 1, 2],  # curve H:  L, L, Z
    ],
    P3,
    P3,
    P3,
)


def skfuzzy_output(rb: RuleBase, curve, dist, n: int = 601):
    """The same controller built with scikit-fuzzy's control API."""
    skfuzzy = pytest.importorskip("skfuzzy")
    from skfuzzy import control as ctrl

    u = np.linspace(0.0, 1.0, n)
    c = ctrl.Antecedent(u, "curve")
    d = ctrl.Antecedent(u, "distance")
    v = ctrl.Consequent(u, "speed", defuzzify_method="centroid")
    for var, part in ((c, rb.curve), (d, rb.distance), (v, rb.speed)):
        for label, tri in zip(part.labels, part.triangles, strict=True):
            var[label] = skfuzzy.trimf(u, list(tri))
    rules = []
    m = rb.matrix
    for i, lc in enumerate(rb.curve.labels):
        for j, ld in enumerate(rb.distance.labels):
            if m[i, j]:
                rules.append(ctrl.Rule(c[lc] & d[ld], v[rb.speed.labels[m[i, j] - 1]]))
    sim = ctrl.ControlSystemSimulation(ctrl.ControlSystem(rules), cache=False)
    sim.input["curve"] = np.asarray(curve, dtype=float)
    sim.input["distance"] = np.asarray(dist, dtype=float)
    sim.compute()
    return np.asarray(sim.output["speed"])


def _grid(n=11, extra=40, seed=3):
    g = np.linspace(0.0, 1.0, n)
    cc, dd = (a.ravel() for a in np.meshgrid(g, g, indexing="ij"))
    rng = np.random.default_rng(seed)
    return np.concatenate([cc, rng.random(extra)]), np.concatenate([dd, rng.random(extra)])


@pytest.mark.parametrize(
    "rb",
    [
        fuzzy.expert_rules(),
        RuleBase(
            tuple(np.random.default_rng(1).integers(1, 8, size=21)),
            Partition.unequal(7),
            Partition.uniform(3),
            Partition.unequal(7),
        ),
        RuleBase(
            tuple(np.random.default_rng(2).integers(1, 6, size=25)),
            Partition.unequal(5),
            Partition.unequal(5),
            Partition.uniform(5),
        ),
        HAND,
    ],
    ids=["expert-7x5", "unequal7x3", "unequal5x5", "hand-3x3"],
)
@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # inside skfuzzy, numpy 2
def test_exact_inference_matches_skfuzzy(rb):
    curve, dist = _grid()
    ours = fuzzy.infer_exact(curve, dist, rb, FuzzyOptions(output_resolution=601))
    ref = skfuzzy_output(rb, curve, dist, n=601)
    np.testing.assert_allclose(ours, ref, atol=1e-6, rtol=0)


def test_hand_computed_values():
    # Partitions L, Z, H with peaks 0, 0.5, 1 (triangles of half-width 0.5).
    # (curve 0.25, dist 0.5): curve is L 0.5 and Z 0.5, dist is Z 1.
    #   Rules (L, Z) -> H and (Z, Z) -> Z both fire at 0.5.
    #   Aggregate: Z clipped at 0.5 (rises 2x on [0, .25], then 0.5) and H clipped at
    #   0.5 (0.5 on [.75, 1]) -> f = 2x on [0, .25], 0.5 on [.25, 1].
    #   Area = .25 * .5 / 2 + .75 * .5 = 0.4375.
    #   Moment = int_0^.25 2x^2 dx + .5 (1 - .0625) / 2 = 1/96 + 15/64 = 47/192.
    #   Centroid = (47/192) / (7/16) = 47/84 = 0.559524...
    # (curve 0, dist 1): only (L, H) -> H fires, at 1: f = 2(x - .5) on [.5, 1],
    #   a right triangle whose centroid is .5 + (2/3) .5 = 5/6.
    out = fuzzy.infer_exact([0.25, 0.0], [0.5, 1.0], HAND)
    np.testing.assert_allclose(out, [47 / 84, 5 / 6], atol=1e-12)


def test_no_rule_fires_gives_min_speed():
    rb = RuleBase.from_matrix([[0, 0, 3], [0, 0, 0], [0, 0, 0]], P3, P3, P3)
    opt = FuzzyOptions(min_speed=0.2)
    out = fuzzy.infer_exact([1.0, 0.0, 0.0], [0.0, 1.0, 0.6], rb, opt)
    assert out[0] == pytest.approx(0.2)  # nothing fires: the documented fallback
    assert out[1] == pytest.approx(5 / 6)
    assert 0.5 < out[2] < 1.0  # the one rule fires at 0.2


def test_surface_interpolation_close_to_exact():
    ctl = fuzzy.SpeedController()
    curve, dist = _grid(n=7, extra=300, seed=5)
    np.testing.assert_allclose(ctl.infer(curve, dist), ctl.infer_exact(curve, dist), atol=0.02)
    # On the grid nodes the surface is exact.
    axis = np.linspace(0, 1, ctl.options.surface_resolution)[::6]
    cc, dd = (a.ravel() for a in np.meshgrid(axis, axis, indexing="ij"))
    np.testing.assert_allclose(ctl.infer(cc, dd), ctl.infer_exact(cc, dd), atol=1e-12)


def test_expert_surface_is_monotone():
    ctl = fuzzy.SpeedController()
    surf = ctl.surface
    # At the peaks one rule fires alone, and the expert table is monotone there:
    # a sharper bend is never faster, a farther one never slower.
    n = surf.shape[0]
    ci = np.round(np.asarray(ctl.rulebase.curve.peaks) * (n - 1)).astype(int)
    di = np.round(np.asarray(ctl.rulebase.distance.peaks) * (n - 1)).astype(int)
    nodes = surf[np.ix_(ci, di)]
    assert np.all(np.diff(nodes, axis=0) <= 1e-9)
    assert np.all(np.diff(nodes, axis=1) >= -1e-9)
    # In between, clipping makes max-centroid inference wiggle, but only a little.
    assert np.all(np.diff(surf, axis=0) <= 0.01)
    assert np.all(np.diff(surf, axis=1) >= -0.01)
    assert surf[-1, 0] < 0.1 < 0.9 < surf[0, -1]


def test_speed_fraction_spans_zero_one():
    ctl = fuzzy.SpeedController(options=FuzzyOptions(min_speed=0.05))
    frac = ctl.speed_fraction([0.0, 1.0], [1.0, 0.0])
    np.testing.assert_allclose(frac, [1.0, 0.05], atol=1e-9)


def test_partition_is_ruspini():
    x = np.linspace(0, 1, 101)
    for part in (
        Partition.uniform(3),
        Partition.uniform(7),
        Partition.unequal(5),
        Partition.unequal(7),
    ):
        mu = part.membership(x)
        np.testing.assert_allclose(mu.sum(axis=1), 1.0, atol=1e-12)
        np.testing.assert_allclose(part.membership(part.peaks), np.eye(part.size), atol=1e-12)


@pytest.mark.parametrize(
    "peaks", [(0, 1), (0, 0.5, 0.5, 0.7, 1), (0.1, 0.5, 1), (0, 0.5, 1, 1.2, 2)]
)
def test_bad_partition(peaks):
    with pytest.raises(ValueError):
        Partition(peaks)


# --------------------------------------------------------------------- path features


def test_curve_ahead_single_corner():
    path = np.array([[0.0, 0.0], [5.0, 0.0], [5.0, 5.0]])
    s = np.array([0.0, 3.0, 3.4, 4.0, 4.8, 5.0, 5.5, 8.0])
    curve, dist = fuzzy.curve_ahead(path, s, lookahead=1.5)
    # The 90 degree turn is spread evenly over [4.85, 5.15] (0.1 look-ahead each
    # side). The window [3.4, 4.9] holds 0.05 m of it, a sixth, whose middle is
    # at 4.875; [4.0, 5.5] and [4.8, 6.3] hold all of it, middle 5.0;
    # [5.0, 6.5] holds the second half, middle 5.075.
    np.testing.assert_allclose(curve, [0, 0, 0.5 / 6, 0.5, 0.5, 0.25, 0, 0], atol=1e-12)
    np.testing.assert_allclose(
        dist, [1, 1, (4.875 - 3.4) / 1.5, 1 / 1.5, 0.2 / 1.5, 0.075 / 1.5, 1, 1], atol=1e-12
    )


def test_curve_ahead_accumulates_a_sampled_arc():
    phi = np.linspace(0, np.pi / 2, 31)
    path = np.stack([np.sin(phi), 1 - np.cos(phi)], axis=1)  # quarter circle, radius 1
    curve, _ = fuzzy.curve_ahead(path, [0.0], lookahead=10.0)
    # The 30 chords turn from heading pi/120 to pi/2 - pi/120: 29 pi / 60 in all.
    assert curve[0] == pytest.approx(29 / 60, abs=1e-9)


def test_speed_lower_at_sharp_bends_than_on_straights():
    path = np.array([[0.0, 0.0], [6.0, 0.0], [6.0, 0.5], [12.0, 0.5]])  # two sharp corners
    s, v = fuzzy.speed_limit(path, vmax=1.0, amax=1.0)
    at_bend = v[np.argmin(np.abs(s - 6.0))]
    straight = v[np.argmin(np.abs(s - 3.0))]
    assert straight == pytest.approx(1.0)
    assert at_bend < 0.5 * straight
    gentle = np.array([[0.0, 0.0], [6.0, 0.0], [12.0, 1.0]])  # one 9.5 degree bend
    s2, v2 = fuzzy.speed_limit(gentle, vmax=1.0, amax=1.0)
    assert v2[np.argmin(np.abs(s2 - 6.0))] > at_bend


def _check_profile(s, v, vmax, amax):
    assert np.all(np.diff(s) > 0)
    assert v[0] == 0 and v[-1] == 0
    assert np.all(v[1:-1] > 0)
    assert np.all(v <= vmax + 1e-12)
    dv2 = np.abs(np.diff(v**2))
    assert np.all(dv2 <= 2 * amax * np.diff(s) * (1 + 1e-9) + 1e-12)


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.tuples(st.floats(-10, 10), st.floats(-10, 10)), min_size=2, max_size=8),
    st.floats(0.2, 3.0),
    st.floats(0.2, 4.0),
)
def test_speed_limit_feasible(points, vmax, amax):
    path = np.array(points)
    s, v = fuzzy.speed_limit(path, vmax, amax)
    if s.size == 1:  # a path of zero length
        assert v[0] == 0
        return
    length = np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1))
    assert s[0] == 0 and s[-1] == pytest.approx(length)
    _check_profile(s, v, vmax, amax)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(0.0, 5.0), min_size=2, max_size=40), st.floats(0.1, 5.0))
def test_forward_backward_pass(vs, amax):
    v = np.array(vs)
    s = np.cumsum(np.linspace(0.05, 0.3, v.size)) - 0.05
    out = fuzzy.limit_acceleration(s, v, amax)
    assert np.all(out <= v + 1e-12)
    assert out[0] == 0 and out[-1] == 0
    dv2 = np.abs(np.diff(out**2))
    assert np.all(dv2 <= 2 * amax * np.diff(s) * (1 + 1e-9) + 1e-12)
    # The same as the sequential two-pass loop.
    ref = v.copy()
    ref[0] = ref[-1] = 0.0
    for i in range(1, v.size):
        ref[i] = min(ref[i], math.sqrt(ref[i - 1] ** 2 + 2 * amax * (s[i] - s[i - 1])))
    for i in range(v.size - 2, -1, -1):
        ref[i] = min(ref[i], math.sqrt(ref[i + 1] ** 2 + 2 * amax * (s[i + 1] - s[i])))
    np.testing.assert_allclose(out, ref, atol=1e-9)


def test_speed_limit_bad_input():
    with pytest.raises(ValueError):
        fuzzy.speed_limit(np.zeros((3, 3)), 1.0, 1.0)
    with pytest.raises(ValueError):
        fuzzy.speed_limit([[0, 0], [1, np.nan]], 1.0, 1.0)
    with pytest.raises(ValueError):
        fuzzy.speed_limit([[0, 0], [1, 0]], 0.0, 1.0)


# ------------------------------------------------------------------------ rule files


@pytest.mark.parametrize("rb", [fuzzy.expert_rules(), fuzzy.learned_rules(), HAND])
def test_rule_file_round_trip(rb, tmp_path):
    path = tmp_path / "rules.txt"
    fuzzy.save_rules(rb, path, comment="a test\nof two lines")
    assert fuzzy.load_rules(path) == rb


def test_table_is_readable():
    table = fuzzy.expert_rules().table().splitlines()
    assert table[0].split() == ["curve\\dist", "VL", "L", "Z", "H", "VH"]
    assert table[1].split() == ["VVL", "VVH", "VVH", "VVH", "VVH", "VVH"]
    assert len(table) == 8
    assert "-" in HAND.__class__.from_matrix(np.zeros((3, 3), int), P3, P3, P3).table()


@settings(max_examples=40, deadline=None)
@given(
    st.sampled_from([3, 5, 7]),
    st.sampled_from([3, 5, 7]),
    st.sampled_from([3, 5, 7]),
    st.booleans(),
    st.data(),
)
def test_rule_file_round_trip_random(nc, nd, ns, unequal, data):
    make = Partition.unequal if unequal else Partition.uniform
    genes = data.draw(st.lists(st.integers(0, ns), min_size=nc * nd, max_size=nc * nd))
    rb = RuleBase(tuple(genes), make(nc), Partition.uniform(nd), make(ns))
    assert fuzzy.parse_rules(fuzzy.format_rules(rb)) == rb


def test_custom_peaks_round_trip():
    rb = RuleBase((1, 2, 3) * 3, Partition((0.0, 0.123456789, 1.0)), P3, P3)
    text = fuzzy.format_rules(rb)
    assert "peaks 0.0 0.123456789 1.0" in text
    assert fuzzy.parse_rules(text) == rb


GOOD = fuzzy.format_rules(HAND)


def _replace_line(text, number, new):
    lines = text.splitlines()
    lines[number - 1] = new
    return "\n".join(lines)


def _line_of(text, start):
    return next(i for i, line in enumerate(text.splitlines(), 1) if line.startswith(start))


@pytest.mark.parametrize(
    ("mutate", "place", "words"),
    [
        (lambda t: t.replace("speed: uniform 3", "speed: uniform 4"), "line", "3, 5 or 7"),
        (
            lambda t: t.replace("curve: uniform 3", "curve: triangle 3"),
            "line",
            "expected 'uniform N'",
        ),
        (
            lambda t: t.replace("curve: uniform 3", "curve: peaks 0 0.7 0.5 0.8 1"),
            "line",
            "increasing",
        ),
        (lambda t: t.replace("distance: uniform 3\n", ""), "", "missing 'distance:'"),
        (lambda t: t.replace("rules:\n", ""), "line", "expected 'key: value'"),
        (
            lambda t: t.replace("speed: uniform 3", "speed: uniform 3\nspeed: uniform 3"),
            "line",
            "duplicate",
        ),
        (lambda t: t.replace("speed: uniform 3", "colour: red"), "line", "unknown key"),
        (lambda t: t.replace("Z   H   H", "Z   H   XX"), "column 3", "unknown speed label 'XX'"),
        (lambda t: t.replace("Z   H   H", "Z   H"), "line", "expected 3 entries"),
        (lambda t: t.replace("\nH          L   L   Z", ""), "line", "expected 3 rows"),
        (
            lambda t: t.replace("\nH          L   L   Z", "\nX          L   L   Z"),
            "line",
            "curve set 'H'",
        ),
        (
            lambda t: t.replace("curve\\dist L   Z   H", "curve\\dist L   H   Z"),
            "line",
            "table header",
        ),
        (lambda t: t.split("rules:")[0] + "rules:\n", "line", "empty rule table"),
        (lambda t: t.replace("rules:", "rules: now"), "line", "nothing may follow"),
    ],
)
def test_bad_rule_files(mutate, place, words, tmp_path):
    text = mutate(GOOD)
    assert text != GOOD
    path = tmp_path / "bad.txt"
    path.write_text(text)
    with pytest.raises(SceneError) as info:
        fuzzy.load_rules(path)
    err = info.value
    assert err.file == str(path)
    assert place in err.place
    assert words in err.message


def test_bad_rule_file_names_the_line():
    number = _line_of(GOOD, "Z ")
    text = _replace_line(GOOD, number, "Z L Z HH")
    with pytest.raises(SceneError) as info:
        fuzzy.parse_rules(text, "mine.txt")
    assert info.value.place == f"line {number}, column 3"
    assert str(info.value).startswith(f"mine.txt: line {number}, column 3:")


def test_missing_rule_file(tmp_path):
    with pytest.raises(SceneError, match="cannot read"):
        fuzzy.load_rules(tmp_path / "nope.txt")


@settings(max_examples=80, deadline=None)
@given(
    st.text(
        alphabet=st.sampled_from(list("curvedistancspd:rules\\LZHV-0123457.# \n")), max_size=200
    )
)
def test_parser_raises_only_scene_errors(text):
    try:
        rb = fuzzy.parse_rules(text)
    except SceneError:
        return
    assert isinstance(rb, RuleBase)


# ------------------------------------------------------------------------- learning


def _tiny_learning(seed):
    opts = learn.LearnOptions(
        population=4,
        generations=(1, 2, 1),
        curve=Partition.uniform(3),
        distance=Partition.uniform(3),
        speed=Partition.uniform(5),
        fuzzy=FuzzyOptions(output_resolution=61, ds=0.1),
    )
    paths = [np.array([[0.0, 0.0], [2.5, 0.0], [2.5, 2.5]])]
    near = [np.array([[0.0, 0.0], [2.0, 0.0], [4.0, 0.3]])]
    return learn.learn_rules(paths, set_point_paths=near, options=opts, seed=seed)


def test_learning_is_reproducible():
    a, b = _tiny_learning(7), _tiny_learning(7)
    assert a.rulebase == b.rulebase
    assert a.cost == b.cost and a.history == b.history
    assert len(a.history) == 3 and [len(h) for h in a.history] == [2, 3, 2]
    assert a.rulebase.curve.size == 3 and a.rulebase.speed.size == 5
    # Elitism: the best cost of a stage never gets worse.
    for hist in a.history:
        assert all(y <= x + 1e-12 for x, y in zip(hist, hist[1:], strict=False))
    rng = np.random.default_rng(7)
    assert _tiny_learning(rng).rulebase == a.rulebase


def test_learned_rules_ship():
    rb = fuzzy.learned_rules()
    assert rb.n_rules > 0
    s, v = fuzzy.speed_limit(np.array([[0.0, 0.0], [5.0, 0.0], [5.0, 5.0]]), 1.0, 1.0, rb)
    _check_profile(s, v, 1.0, 1.0)


def test_profile_times_of_a_trapezoid():
    # 10 m at vmax 1 with amax 1, from and to rest: each 1 s ramp covers 0.5 m,
    # so the cruise is 9 m: 1 + 9 + 1 = 11 s.
    s, v = fuzzy.speed_limit(np.array([[0.0, 0.0], [10.0, 0.0]]), 1.0, 1.0)
    t = fuzzy.profile_times(s, v)
    assert t[0] == 0 and np.all(np.diff(t) > 0)
    assert t[-1] == pytest.approx(11.0, abs=1e-9)
    with pytest.raises(ValueError):
        fuzzy.profile_times([0.0, 1.0], [0.0, 0.0])
