"""Tests of the GA refinement (gfuzzy.ga): fitness against hand values, operators, determinism,
and refined paths checked for collisions independently with shapely."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import LineString, Point

from gfuzzy.ga import (
    REMOVED,
    GAOptions,
    Mutation,
    PathCoding,
    PathEvaluator,
    apply_mutation,
    crossover,
    fitness_parts,
    mutate,
    refine_path,
    roulette_select,
    smooth,
)

R_ROBOT = 0.25


def disc_clearance(center, radius, robot=R_ROBOT):
    c = np.asarray(center, dtype=float)
    return lambda xy: np.hypot(*(np.asarray(xy) - c).T) - radius - robot


def free_everywhere(xy):
    return np.full(len(xy), 10.0)


# --------------------------------------------------------------------------- fitness


def test_fitness_parts_hand_computed():
    # 3-4-5 triangle legs: length 10, chord 6, one turn of 2 * atan(4 / 3)
    path = np.array([[0.0, 0.0], [3.0, 4.0], [6.0, 0.0]])
    # the disc's nearest path point is the apex: clearance 2 - 0.5 - 0.25 = 1.25
    static = disc_clearance([3.0, 6.0], 0.5)
    opts = GAOptions(safe_clearance=2.0, w_length=1.0, w_security=2.0, w_smooth=0.5)
    fp = fitness_parts([path], R_ROBOT, static, options=opts)
    turn = 2 * math.atan(4 / 3)
    assert fp.length[0] == pytest.approx(10.0)
    assert fp.smoothness[0] == pytest.approx(turn)
    assert fp.min_clearance[0] == pytest.approx(1.25)
    assert fp.feasible[0]
    assert fp.fit_length[0] == pytest.approx(10 / 6)
    assert fp.fit_security[0] == pytest.approx(1 - 1.25 / 2.0)
    assert fp.fit_smooth[0] == pytest.approx(turn / math.pi)
    assert fp.cost[0] == pytest.approx(10 / 6 + 2.0 * 0.375 + 0.5 * turn / math.pi)


def test_fitness_parts_straight_and_saturated_security():
    path = np.array([[0.0, 0.0], [2.0, 0.0], [4.0, 0.0]])
    fp = fitness_parts([path], R_ROBOT, free_everywhere)
    assert fp.smoothness[0] == 0.0
    assert fp.fit_length[0] == pytest.approx(1.0)
    assert fp.fit_security[0] == 0.0  # clearance 10 >= safe (robot radius)
    assert fp.cost[0] == pytest.approx(1.0)


def test_infeasible_path_costs_inf():
    # the straight segment passes through the disc although both ends are free
    path = np.array([[0.0, 0.0], [6.0, 0.0]])
    fp = fitness_parts([path], R_ROBOT, disc_clearance([3.0, 0.0], 0.5))
    assert not fp.feasible[0]
    assert fp.cost[0] == math.inf
    assert fp.min_clearance[0] < 0


def test_segment_grazing_between_samples_is_caught():
    # Samples every 0.125 (robot radius / 2) at x = +-0.0625 from the disc's top: both read
    # +0.001, yet the segment dips into the disc between them. The Lipschitz bound sees it.
    r_tot = 0.8 + R_ROBOT
    y0 = math.sqrt((r_tot + 0.001) ** 2 - 0.0625**2)
    seg = np.array([[-1.0625, y0], [1.0625, y0]])
    fp = fitness_parts([seg], R_ROBOT, disc_clearance([0.0, 0.0], 0.8))
    assert fp.min_clearance[0] == pytest.approx(0.001, abs=1e-9)
    assert LineString(seg).distance(Point(0, 0)) < r_tot  # really colliding
    assert not fp.feasible[0]


def test_mover_times_follow_the_input_timing():
    # Waits and uneven speeds: the reference is at q(t); a "mover" whose clearance is
    # 1 - |xy - q(t)| reads 1 everywhere only if every sample is timed where the input is.
    ref = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 0.0], [2.0, 3.0]])
    t_ref = np.array([0.0, 1.0, 4.0, 5.0])  # fast, wait 3 s, slow

    def q(t):
        return np.column_stack([np.interp(t, t_ref, ref[:, 0]), np.interp(t, t_ref, ref[:, 1])])

    def mover(xy, t):
        return 1.0 - np.hypot(*(xy - q(t)).T)

    fp = fitness_parts(
        [ref], R_ROBOT, free_everywhere, mover, reference_path=ref, reference_times=t_ref
    )
    assert fp.min_clearance[0] == pytest.approx(1.0, abs=1e-9)

    # a mover that visits the wait point during the wait is seen, although no spatial
    # sample of the path is timed inside the wait
    def visitor(xy, t):
        at = np.column_stack([np.full_like(t, 2.0), np.where(np.abs(t - 2.5) < 0.2, 0.0, 50.0)])
        return np.hypot(*(xy - at).T) - 0.5

    fp = fitness_parts(
        [ref], R_ROBOT, free_everywhere, visitor, reference_path=ref, reference_times=t_ref
    )
    assert not fp.feasible[0]


def test_via_points_keep_their_knot_times():
    # Knot timing (refine_path's law): via-point k is reached when the input passed knot k,
    # and in between the robot moves as the input did, waits included. On a straight input
    # every decoded path lies on it, so a "mover" reading 1 - |xy - q(t)| stays at 1.
    ref = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 0.0], [10.0, 0.0]])
    t_ref = np.array([0.0, 2.0, 5.0, 6.0])  # slow, wait 3 s, fast

    def q(t):
        return np.column_stack([np.interp(t, t_ref, ref[:, 0]), np.interp(t, t_ref, ref[:, 1])])

    def mover(xy, t):
        return 1.0 - np.hypot(*(xy - q(t)).T)

    coding = PathCoding.from_path(ref, n_knots=5, levels=7, steps=0.3)
    m = coding.mid
    chroms = np.array(
        [[m] * 5, [m, REMOVED, m, REMOVED, REMOVED], [REMOVED] * 5, [m, m, m + 2, m, m]]
    )
    ev = PathEvaluator(R_ROBOT, free_everywhere, mover, ref, t_ref)
    out = ev.evaluate(*coding.decode(chroms), arc=coding.arc)
    np.testing.assert_allclose(out.min_clearance[:3], 1.0, atol=1e-9)
    assert out.min_clearance[3] < 0.9  # off the input's line: the check can tell
    # keep_speed: the bent candidate is longer than the input stretch it replaces
    assert out.feasible[:3].all() and not out.feasible[3]
    lax = PathEvaluator(R_ROBOT, free_everywhere, None, ref, t_ref, GAOptions(keep_speed=False))
    assert lax.evaluate(*coding.decode(chroms), arc=coding.arc).feasible.all()


def test_padded_batch_equals_single_paths():
    paths = [
        np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 0.0], [3.0, 1.0]]),
        np.array([[0.0, 0.0], [3.0, 1.0]]),
        np.array([[0.0, 0.0], [0.5, 0.2], [1.5, -0.4], [2.0, 0.3], [3.0, 1.0]]),
    ]
    static = disc_clearance([1.5, 2.0], 0.3)
    batch = fitness_parts(paths, R_ROBOT, static)
    for i, p in enumerate(paths):
        one = fitness_parts([p], R_ROBOT, static)
        for name in ("length", "smoothness", "min_clearance", "cost"):
            assert getattr(batch, name)[i] == pytest.approx(getattr(one, name)[0]), name


def _loop_length_turning(p):
    d = np.diff(p, axis=0)
    d = d[np.hypot(*d.T) > 1e-12]  # shorter segments count as repeated points
    length = float(np.sum(np.hypot(*d.T)))
    turn = 0.0
    for a, b in zip(d[:-1], d[1:], strict=True):
        turn += abs(math.atan2(a[0] * b[1] - a[1] * b[0], a @ b))
    return length, turn


@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(-3, 3), st.floats(-3, 3)),
        min_size=2,
        max_size=7,
    )
)
def test_batch_geometry_and_certified_clearance(points):
    """Cross-check: vectorised length / turning vs a plain loop; a path the evaluator calls
    feasible keeps its distance from the disc under shapely's exact distance."""
    p = np.array(points, dtype=float)
    center, radius = np.array([0.3, -0.2]), 0.8
    fp = fitness_parts([p], R_ROBOT, disc_clearance(center, radius))
    length, turn = _loop_length_turning(p)
    assert fp.length[0] == pytest.approx(length, abs=1e-9)
    assert fp.smoothness[0] == pytest.approx(turn, abs=1e-9)
    exact = (
        LineString(p).distance(Point(center)) if length > 0 else Point(p[0]).distance(Point(center))
    )
    # samples can only overestimate the true minimum
    assert fp.min_clearance[0] >= exact - radius - R_ROBOT - 1e-9
    if fp.feasible[0]:
        assert exact >= radius + R_ROBOT - 1e-9


# --------------------------------------------------------------------------- coding


def test_coding_knots_and_search_lines():
    path = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0]])
    coding = PathCoding.from_path(path, n_knots=3, levels=5, steps=0.5)
    # knots at arc length 2, 4, 6 of 8
    np.testing.assert_allclose(coding.knots, [[2.0, 0.0], [4.0, 0.0], [4.0, 2.0]], atol=1e-12)
    # search lines perpendicular to the path; at the corner, along the bisector
    np.testing.assert_allclose(np.abs(coding.normals[0]), [0.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(np.abs(coding.normals[2]), [1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(np.abs(coding.normals[1]), [math.sqrt(0.5)] * 2, atol=1e-12)
    mid = coding.mid
    pts, mask = coding.decode(np.array([[mid, mid + 2, REMOVED]]))
    assert pts.shape == (1, 5, 2) and mask.tolist() == [[True, True, True, False, True]]
    np.testing.assert_allclose(pts[0, 1], [2.0, 0.0])
    np.testing.assert_allclose(np.hypot(*(pts[0, 2] - [4.0, 0.0])), 1.0)  # 2 levels * 0.5
    np.testing.assert_allclose(
        coding.polyline([mid, mid, REMOVED]), [[0, 0], [2, 0], [4, 0], [4, 4]]
    )


# --------------------------------------------------------------------------- operators


def test_crossover_keeps_length_and_swaps_tails():
    rng = np.random.default_rng(3)
    a = np.arange(10, dtype=np.int16)
    b = np.arange(10, 20, dtype=np.int16)
    kids = crossover(np.stack([a, b, a, b]), rng, pc=1.0)
    assert kids.shape == (4, 10)
    for k in range(0, 4, 2):
        c1, c2 = kids[k], kids[k + 1]
        cut = int(np.argmax(c1 != a))
        assert 1 <= cut <= 9
        np.testing.assert_array_equal(c1, np.concatenate([a[:cut], b[cut:]]))
        np.testing.assert_array_equal(c2, np.concatenate([b[:cut], a[cut:]]))
    same = crossover(np.stack([a, b]), rng, pc=0.0)
    np.testing.assert_array_equal(same, np.stack([a, b]))


def test_each_mutation_kind():
    levels = 7
    pop = np.array([[3, 6, 0, REMOVED]], dtype=np.int16)
    rows = [0, 0, 0, 0]
    genes = [0, 1, 2, 3]
    up = apply_mutation(pop, rows, genes, [Mutation.UP] * 4, levels)
    np.testing.assert_array_equal(up, [[4, 6, 1, 3]])  # clamped at the top; removed -> middle
    down = apply_mutation(pop, rows, genes, [Mutation.DOWN] * 4, levels)
    np.testing.assert_array_equal(down, [[2, 5, 0, 3]])  # clamped at 0
    rem = apply_mutation(pop, rows, genes, [Mutation.REMOVE] * 4, levels)
    np.testing.assert_array_equal(rem, [[REMOVED] * 4])
    np.testing.assert_array_equal(pop, [[3, 6, 0, REMOVED]])  # input untouched


def test_mutate_rates():
    rng = np.random.default_rng(0)
    pop = np.full((50, 12), 7, dtype=np.int16)
    np.testing.assert_array_equal(mutate(pop, rng, 0.0, 15), pop)
    every = mutate(pop, rng, 1.0, 15)
    assert np.all(every != 7)  # up, down or removed: all differ from the middle
    assert set(np.unique(every)) == {REMOVED, 6, 8}
    rate = np.mean(mutate(pop, rng, 0.1, 15) != 7)
    assert 0.07 < rate < 0.13


def test_roulette_prefers_low_cost_and_never_picks_infeasible():
    rng = np.random.default_rng(1)
    costs = np.array([1.0, 2.0, np.inf, 1.5])
    picks = roulette_select(costs, rng, 4000)
    counts = np.bincount(picks, minlength=4)
    assert counts[2] == 0
    assert counts[0] > counts[3] > counts[1] > 0


def _corner_setup():
    # a V with its apex at the middle knot
    path = np.array([[0.0, 0.0], [5.0, 3.0], [10.0, 0.0]])
    coding = PathCoding.from_path(path, n_knots=5, levels=15, steps=0.2)
    chrom = np.full((1, 5), coding.mid, dtype=np.int16)
    return path, coding, chrom


def test_smooth_accepts_when_free_and_cuts_the_corner():
    path, coding, chrom = _corner_setup()
    ev = PathEvaluator(R_ROBOT, free_everywhere)
    new, ok = smooth(chrom, coding, ev, np.random.default_rng(0), p_smooth=1.0)
    assert ok.tolist() == [True]
    assert new.shape == chrom.shape
    before = fitness_parts([coding.polyline(chrom[0])], R_ROBOT, free_everywhere)
    after = fitness_parts([coding.polyline(new[0])], R_ROBOT, free_everywhere)
    assert after.length[0] < before.length[0]
    # the apex moved down towards the chord
    assert coding.polyline(new[0])[:, 1].max() < 3.0 - 1e-9


def test_smooth_refuses_segments_through_a_forbidden_region():
    path, coding, chrom = _corner_setup()

    def forbid_inside_corner(xy):
        # blocked: strictly under the V's legs (the input runs along them)
        x, y = xy[:, 0], xy[:, 1]
        inside = (y < 3.0 - 0.6 * np.abs(x - 5.0) - 0.05) & (y > 1.0)
        return np.where(inside, -1.0, 10.0)

    assert fitness_parts([path], R_ROBOT, forbid_inside_corner).feasible[0]
    free_ev = PathEvaluator(R_ROBOT, free_everywhere)
    blocked_ev = PathEvaluator(R_ROBOT, forbid_inside_corner)
    accepted_when_free = 0
    for seed in range(20):  # the same cut fractions with either callable
        _, ok = smooth(chrom, coding, free_ev, np.random.default_rng(seed), p_smooth=1.0)
        accepted_when_free += int(ok[0])
        new, ok = smooth(chrom, coding, blocked_ev, np.random.default_rng(seed), p_smooth=1.0)
        assert not ok.any()
        np.testing.assert_array_equal(new, chrom)
    assert accepted_when_free >= 10


def test_smooth_zero_probability_is_identity():
    _, coding, chrom = _corner_setup()
    ev = PathEvaluator(R_ROBOT, free_everywhere)
    new, ok = smooth(
        np.repeat(chrom, 4, axis=0), coding, ev, np.random.default_rng(0), p_smooth=0.0
    )
    assert not ok.any()
    np.testing.assert_array_equal(new, np.repeat(chrom, 4, axis=0))


# --------------------------------------------------------------------------- refine_path

DISC_C, DISC_R = np.array([5.0, 0.0]), 1.0
ZIGZAG = np.array(
    [(0, 0), (1.5, 1.0), (2.5, 0.2), (4, 2.2), (5, 1.6), (6, 2.4), (7.5, 0.8), (10, 0)], dtype=float
)
FAST = GAOptions(generations=300, patience=60)


def _shapely_clearance(path):
    return LineString(path).distance(Point(DISC_C)) - DISC_R - R_ROBOT


def test_zigzag_around_disc_gets_shorter_smoother_and_stays_free():
    static = disc_clearance(DISC_C, DISC_R)
    assert _shapely_clearance(ZIGZAG) > 0
    res = refine_path(ZIGZAG, None, R_ROBOT, static, None, FAST, seed=1)
    assert res.improved
    np.testing.assert_array_equal(res.path[0], ZIGZAG[0])
    np.testing.assert_array_equal(res.path[-1], ZIGZAG[-1])
    assert res.length_after < res.length_before
    assert res.smoothness_after < res.smoothness_before
    assert res.fitness_after < res.fitness_before
    assert res.fitness_history[-1] == pytest.approx(res.fitness_after)
    assert np.all(np.diff(res.fitness_history) <= 0)  # elitism
    # independent dense check: exact distance from the polyline to the disc
    assert _shapely_clearance(res.path) >= -1e-9
    # and the robot's swept footprint does not overlap the obstacle
    swept = LineString(res.path).buffer(R_ROBOT, quad_segs=64)
    assert (
        shapely.intersection(swept, Point(DISC_C).buffer(DISC_R * 0.999, quad_segs=64)).area == 0.0
    )


def test_a_passed_deadline_returns_the_input():
    static = disc_clearance(DISC_C, DISC_R)
    res = refine_path(ZIGZAG, None, R_ROBOT, static, None, FAST, seed=1, deadline=time.perf_counter() - 1.0)
    assert res.out_of_time and not res.improved and res.generations == 0
    np.testing.assert_array_equal(res.path, ZIGZAG)
    done = refine_path(ZIGZAG, None, R_ROBOT, static, None, FAST, seed=1, deadline=time.perf_counter() + 600)
    assert done.improved and not done.out_of_time and done.generations > 0


def test_same_seed_same_result_and_other_seed_runs():
    static = disc_clearance(DISC_C, DISC_R)
    a = refine_path(ZIGZAG, None, R_ROBOT, static, None, FAST, seed=7)
    b = refine_path(ZIGZAG, None, R_ROBOT, static, None, FAST, seed=np.random.default_rng(7))
    np.testing.assert_array_equal(a.path, b.path)
    np.testing.assert_array_equal(a.chromosome, b.chromosome)
    np.testing.assert_array_equal(a.fitness_history, b.fitness_history)
    c = refine_path(ZIGZAG, None, R_ROBOT, static, None, FAST, seed=8)
    assert c.improved


def test_no_feasible_individual_returns_input():
    res = refine_path(ZIGZAG, None, R_ROBOT, lambda xy: np.full(len(xy), -1.0), None, FAST, seed=0)
    assert not res.improved
    np.testing.assert_array_equal(res.path, ZIGZAG)
    assert math.isinf(res.fitness_before) and math.isinf(res.fitness_after)


def test_never_worse_than_input():
    # a straight input cannot be improved: the input comes back unchanged
    straight = np.array([[0.0, 0.0], [3.0, 0.0], [6.0, 0.0]])
    res = refine_path(straight, None, R_ROBOT, free_everywhere, None, FAST, seed=0)
    assert res.fitness_after <= res.fitness_before
    assert res.length_after == pytest.approx(6.0)


def test_mover_is_avoided_in_time():
    # The straight line is free of static obstacles, but a mover crosses it at the time the
    # input passes. The input detours around the crossing; the refinement must keep clear.
    r_m = 0.4

    def mover_at(t):
        t = np.asarray(t, dtype=float)
        return np.column_stack([np.full_like(t, 5.0), -3.0 + 1.0 * t])  # up x = 5 at speed 1

    def mover(xy, t):
        return np.hypot(*(xy - mover_at(t)).T) - r_m - R_ROBOT

    path = np.array([[0.0, 0.0], [2.0, 1.5], [4.0, 2.5], [6.0, 2.5], [8.0, 1.5], [10.0, 0.0]])
    times = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))]) * 0.5  # speed 2
    opts = GAOptions(generations=300, patience=80)
    res = refine_path(path, times, R_ROBOT, free_everywhere, mover, opts, seed=2)
    assert res.improved and res.trajectory is not None
    traj = res.trajectory
    assert traj[0, 0] == pytest.approx(times[0]) and traj[-1, 0] == pytest.approx(times[-1])
    np.testing.assert_allclose(traj[0, 1:], path[0])
    np.testing.assert_allclose(traj[-1, 1:], path[-1])
    assert np.all(np.diff(traj[:, 0]) >= 0)
    assert res.length_after <= res.length_before + 1e-9  # keep_speed
    # dense independent check along the timed trajectory (mover checks are sampled: allow
    # a small fraction of the sample spacing)
    tt = np.linspace(traj[0, 0], traj[-1, 0], 20001)
    xy = np.column_stack(
        [np.interp(tt, traj[:, 0], traj[:, 1]), np.interp(tt, traj[:, 0], traj[:, 2])]
    )
    gap = np.hypot(*(xy - mover_at(tt)).T) - r_m - R_ROBOT
    assert gap.min() >= -0.25 * R_ROBOT
    # and the straight line would have hit it: the check above can fail
    straight = np.column_stack([np.linspace(0, 10, 20001), np.zeros(20001)])
    t_line = np.linspace(times[0], times[-1], 20001)
    assert (np.hypot(*(straight - mover_at(t_line)).T) - r_m - R_ROBOT).min() < -0.25 * R_ROBOT


def test_trajectory_keeps_waits():
    path = np.array([[0.0, 0.0], [2.0, 1.0], [2.0, 1.0], [4.0, 0.0]])
    times = np.array([0.0, 1.0, 3.0, 4.0])
    res = refine_path(
        path, times, R_ROBOT, free_everywhere, lambda xy, t: np.full(len(t), 5.0), FAST, seed=0
    )
    traj = res.trajectory
    assert traj is not None
    dt_still = [
        b[0] - a[0] for a, b in zip(traj[:-1], traj[1:], strict=True) if np.all(a[1:] == b[1:])
    ]
    assert max(dt_still) == pytest.approx(2.0)  # the 2 s wait survives refinement


def test_zero_generations_and_tiny_options():
    static = disc_clearance(DISC_C, DISC_R)
    res = refine_path(ZIGZAG, None, R_ROBOT, static, None, GAOptions(generations=0), seed=0)
    assert res.generations == 0 and len(res.fitness_history) == 1
    res = refine_path(
        ZIGZAG,
        None,
        R_ROBOT,
        static,
        None,
        GAOptions(n_knots=1, population=2, generations=20),
        seed=0,
    )
    assert res.fitness_after <= res.fitness_before


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(pc=1.5),
        dict(pm=-0.1),
        dict(levels=14),
        dict(levels=1),
        dict(population=1),
        dict(n_knots=0),
        dict(step=0.0),
        dict(step=float("nan")),
        dict(patience=-1),
        dict(w_length=-1.0),
        dict(generations=2.5),
    ],
)
def test_bad_options_raise(kwargs):
    with pytest.raises(ValueError):
        GAOptions(**kwargs)


def test_bad_inputs_raise():
    static = disc_clearance(DISC_C, DISC_R)
    with pytest.raises(ValueError):
        refine_path(np.zeros((1, 2)), None, R_ROBOT, static)
    with pytest.raises(ValueError):
        refine_path(ZIGZAG, np.arange(3.0), R_ROBOT, static)
    with pytest.raises(ValueError):
        refine_path(ZIGZAG, np.arange(8.0)[::-1], R_ROBOT, static)
    with pytest.raises(ValueError):
        refine_path(ZIGZAG, None, 0.0, static)
    with pytest.raises(ValueError):
        refine_path(ZIGZAG, None, R_ROBOT, lambda xy: np.zeros(3), None, FAST)
    with pytest.raises(TypeError):
        refine_path(ZIGZAG, None, R_ROBOT, static, None, FAST, seed="x")


def test_static_segment_hook_decides_static_feasibility():
    """With a segment certifier, sampling the static clearance is not used for segments:
    a certifier that refuses everything leaves the input; one that accepts all refines."""
    path = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, -1.0], [3.0, 1.0], [4.0, 0.0]])

    def free(xy):
        return np.full(len(xy), 1.0)

    def refuse(a, b):
        return np.full(len(a), -1.0), np.full(len(a), -1.0)

    def accept(a, b):
        return np.zeros(len(a)), np.full(len(a), 1.0)

    opts = GAOptions(generations=60, patience=None, population=20)
    kept = refine_path(path, None, 0.2, free, None, opts, seed=1, static_segment=refuse)
    assert not kept.improved
    np.testing.assert_array_equal(kept.path, path)
    better = refine_path(path, None, 0.2, free, None, opts, seed=1, static_segment=accept)
    assert better.improved
    assert better.length_after < better.length_before


def _cache_case(seed):
    """A timed input with a wait at the start, a disc, a crossing mover and a random
    population of its coding (removed genes included)."""
    path = np.array([[0.0, 0.0], [0.0, 0.0], [2.0, 1.5], [4.0, 2.5], [6.0, 2.5], [8.0, 1.5], [10.0, 0.0]])
    times = np.array([0.0, 1.5, 4.0, 6.2, 8.2, 10.7, 13.2])

    def mover(xy, t):
        t = np.asarray(t, dtype=float)
        pos = np.column_stack([np.full_like(t, 5.0), -6.0 + 0.8 * t])
        return np.hypot(*(xy - pos).T) - 0.4 - R_ROBOT

    static = disc_clearance([3.0, 0.5], 0.5)
    coding = PathCoding.from_path(path, 8, 9, 0.3)
    rng = np.random.default_rng(seed)
    pop = rng.integers(2, 7, (60, 8))
    pop[rng.random(pop.shape) < 0.2] = REMOVED
    pop[0] = REMOVED  # the straight segment: slot 0 removed, start to goal
    pop[1] = 4  # the input resampled
    pts, mask = coding.decode(pop)
    return path, times, mover, static, coding, pop, pts, mask


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_segment_caches_give_the_uncached_evaluation(seed):
    # The GA's caches (static bound and mover grid per lattice node pair) must not change
    # one bit of the evaluation, over two rounds (the second one read from the caches).
    path, times, mover, static, coding, pop, pts, mask = _cache_case(seed)
    plain = PathEvaluator(R_ROBOT, static, mover, path, times)
    cached = PathEvaluator(R_ROBOT, static, mover, path, times)
    cached._enable_segment_cache(coding.n_knots * coding.levels + 2)
    want = plain.evaluate(pts, mask, None, coding.arc)
    assert not want.feasible.all() and want.feasible.any()
    for _ in range(2):
        got = cached.evaluate(pts, mask, coding.node_ids(pop), coding.arc)
        for name in ("length", "smoothness", "min_clearance", "segment_clearance", "feasible"):
            np.testing.assert_array_equal(getattr(got, name), getattr(want, name), err_msg=name)


def test_lazy_static_check_keeps_costs_and_marked_slots():
    # `exact`: rows ruled out by the movers or the speed rule skip the static check, except
    # on the marked slots; costs and the marked slots' clearances stay exact.
    path, times, mover, static, coding, pop, pts, mask = _cache_case(3)
    calls = []

    def counting(xy):
        calls.append(len(xy))
        return static(xy)

    full = PathEvaluator(R_ROBOT, counting, mover, path, times)
    want = full.evaluate(pts, mask, None, coding.arc)
    n_full = sum(calls)
    calls.clear()
    lazy = PathEvaluator(R_ROBOT, counting, mover, path, times)
    exact = np.zeros((len(pop), coding.n_knots + 1), dtype=bool)
    exact[::3, 2:5] = True
    got = lazy.evaluate(pts, mask, None, coding.arc, exact)
    assert sum(calls) < n_full  # some rows were ruled out before the static check
    np.testing.assert_array_equal(got.feasible, want.feasible)
    np.testing.assert_array_equal(full.fitness(got, 10.0).cost, full.fitness(want, 10.0).cost)
    np.testing.assert_array_equal(got.segment_clearance[exact], want.segment_clearance[exact])


def test_rows_blocked_by_a_cached_bound_skip_the_static_check():
    # A row with a segment whose cached static bound is below zero is infeasible whatever its
    # other segments hold: their static check is skipped unless a slot is marked exact.
    path, _, _, static, coding, pop, _, _ = _cache_case(4)
    calls = []

    def counting(xy):
        calls.append(len(xy))
        return static(xy)

    ev = PathEvaluator(R_ROBOT, counting)
    n_nodes = coding.n_knots * coding.levels + 2
    ev._enable_segment_cache(n_nodes)
    row = np.full((1, coding.n_knots), coding.mid)
    pts, mask = coding.decode(row)
    ids = coding.node_ids(row)
    ev._cache[:, ids[0, 0] * n_nodes + ids[0, 1]] = -1.0  # slot 0 known to be blocked
    none = np.zeros((1, coding.n_knots + 1), dtype=bool)
    got = ev.evaluate(pts, mask, ids, coding.arc, none)
    assert calls == [] and not got.feasible[0] and ev.fitness(got, 10.0).cost[0] == np.inf
    marked = none.copy()
    marked[0, 4] = True
    got = ev.evaluate(pts, mask, ids, coding.arc, marked)
    assert len(calls) == 1  # the marked slot only
    want = PathEvaluator(R_ROBOT, static).evaluate(pts, mask, None, coding.arc)
    assert got.segment_clearance[0, 4] == want.segment_clearance[0, 4]
    got = ev.evaluate(pts, mask, ids, coding.arc)  # exact=None: everything
    np.testing.assert_array_equal(got.segment_clearance[0, 1:], want.segment_clearance[0, 1:])
