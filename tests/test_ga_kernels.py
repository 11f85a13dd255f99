"""The GA's compiled paths against the numpy code they replace: the operators' kernels, the
population evaluation (gfuzzy.ga.lattice), and the stages' clearance caches. Every check is
exact (bit for bit): same seed, same result."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gfuzzy.ga import (
    REMOVED,
    GAOptions,
    PathCoding,
    PathEvaluator,
    apply_mutation,
    crossover,
    lattice,
    mutate,
    refine_path,
)
from gfuzzy.ga.operators import _SMOOTH_FRACTION, _propose_smooth
from gfuzzy.ga.options import _EPS
from gfuzzy.ga.refine import _keys
from gfuzzy.typed import BoolArray, IntArray

ROOT = Path(__file__).resolve().parent.parent
R_ROBOT = 0.25


def _crossover_numpy(chromosomes, rng, pc):
    """The numpy crossover the kernel replaced."""
    pop = np.array(chromosomes, copy=True)
    P, K = pop.shape
    npairs = P // 2
    if K < 2 or npairs == 0:
        return pop
    do = rng.random(npairs) < pc
    cut = rng.integers(1, K, npairs)
    swap = do[:, None] & (np.arange(K)[None, :] >= cut[:, None])
    a, b = pop[0 : 2 * npairs : 2].copy(), pop[1 : 2 * npairs : 2].copy()
    pop[0 : 2 * npairs : 2] = np.where(swap, b, a)
    pop[1 : 2 * npairs : 2] = np.where(swap, a, b)
    return pop


def _propose_smooth_numpy(
    pop: IntArray, coding: PathCoding, rng: np.random.Generator, p_smooth: float
) -> tuple[IntArray, IntArray, BoolArray]:
    """The numpy operator the kernels replaced (gfuzzy/ga/operators.py before them)."""
    P, K = pop.shape
    tried = np.nonzero(rng.random(P) < p_smooth)[0]
    if len(tried) == 0:
        return tried, pop[:0], np.zeros((0, K + 1), dtype=bool)
    lam = rng.uniform(*_SMOOTH_FRACTION, len(tried))
    sub = pop[tried]
    pts, mask = coding.decode(sub)
    Q, M = mask.shape
    idx = np.arange(M)
    last = np.maximum.accumulate(np.where(mask, idx, -1), axis=1)
    first = np.minimum.accumulate(np.where(mask, idx, M)[:, ::-1], axis=1)[:, ::-1]
    prv, nxt = last[:, :-2], first[:, 2:]  # kept neighbours of points 1..M-2
    flat = pts.reshape(-1, 2)
    base = np.arange(Q)[:, None] * M
    inner = pts[:, 1:-1]
    din = inner - flat.take((base + prv).ravel(), axis=0).reshape(inner.shape)
    dout = flat.take((base + nxt).ravel(), axis=0).reshape(inner.shape) - inner
    cross = din[..., 0] * dout[..., 1] - din[..., 1] * dout[..., 0]
    dot = (din * dout).sum(-1)
    ang = np.where(mask[:, 1:-1], np.abs(np.arctan2(cross, dot)), 0.0)
    k = ang.argmax(axis=1)  # via index; point index k + 1
    valid = ang[np.arange(Q), k] > 1e-6
    r = np.arange(Q)
    iu, iw = prv[r, k], nxt[r, k]
    U, V, W = (
        flat.take(r * M + iu, axis=0),
        flat.take(r * M + k + 1, axis=0),
        flat.take(r * M + iw, axis=0),
    )
    A = V + lam[:, None] * (U - V)
    B = V + lam[:, None] * (W - V)
    C = 0.25 * A + 0.5 * V + 0.25 * B
    poly = np.stack([U, A, C, B, W], axis=1)  # (Q, 5, 2)
    p0, e = poly[:, :-1], np.diff(poly, axis=1)  # (Q, 4, 2)
    # intersect every knot line (p + s n) with every segment (p0 + tau e)
    rr = p0[:, None, :, :] - coding.knots[None, :, None, :]  # (Q, K, 4, 2)
    n = coding.normals[None, :, None, :]
    ee = e[:, None, :, :]
    den = n[..., 0] * ee[..., 1] - n[..., 1] * ee[..., 0]
    safe_den = np.where(np.abs(den) > _EPS, den, 1.0)
    s = (rr[..., 0] * ee[..., 1] - rr[..., 1] * ee[..., 0]) / safe_den
    tau = (rr[..., 0] * n[..., 1] - rr[..., 1] * n[..., 0]) / safe_den
    hits = (np.abs(den) > _EPS) & (tau >= -1e-9) & (tau <= 1 + 1e-9)
    cur = np.nan_to_num(coding.offsets(sub))  # removed genes: origin 0
    score = np.where(hits, np.abs(s - cur[..., None]), np.inf)
    j = score.reshape(-1, 4).argmin(axis=1) + 4 * np.arange(Q * K)
    s_best = s.take(j).reshape(Q, K)
    hit_any = np.isfinite(score.take(j)).reshape(Q, K)
    lvl = np.rint(s_best / coding.steps).astype(np.int64) + coding.mid
    in_range = hit_any & (lvl >= 0) & (lvl < coding.levels)
    new_genes = np.where(in_range, lvl, REMOVED)
    knot_pt = np.arange(K)[None, :] + 1
    region = (knot_pt > iu[:, None]) & (knot_pt < iw[:, None]) & valid[:, None]
    cand = np.where(region, new_genes, sub).astype(pop.dtype)
    changed = np.any(cand != sub, axis=1)
    slot_pt = np.arange(1, M)[None, :]
    new_slots = (slot_pt > iu[:, None]) & (slot_pt <= iw[:, None])
    return tried[changed], cand[changed], new_slots[changed]


# --------------------------------------------------------------------------- random cases


def _random_path(rng, n=None):
    """A zig-zag polyline (sometimes with a repeated point, a wait)."""
    n = n or int(rng.integers(3, 9))
    x = np.cumsum(rng.uniform(0.3, 2.0, n))
    y = rng.uniform(-1.5, 1.5, n)
    path = np.column_stack([x, y])
    if rng.random() < 0.5:
        i = int(rng.integers(0, n))
        path = np.insert(path, i, path[i], axis=0)
    return path


def _random_population(rng, P, K, levels, dtype):
    pop = rng.integers(0, levels, (P, K))
    pop[rng.random(pop.shape) < 0.25] = REMOVED
    pop[0] = REMOVED  # the straight segment
    pop[1] = levels // 2  # the input resampled
    if P > 2:
        pop[2, ::2] = REMOVED
    return pop.astype(dtype)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("dtype", [np.int16, np.int64])
def test_crossover_kernel_is_the_numpy_crossover(seed, dtype):
    rng = np.random.default_rng(seed)
    pop = _random_population(rng, int(rng.integers(2, 30)), int(rng.integers(1, 14)), 15, dtype)
    a, b = np.random.default_rng(seed + 100), np.random.default_rng(seed + 100)
    for pc in (0.0, 0.62, 1.0):
        got, want = crossover(pop, a, pc), _crossover_numpy(pop, b, pc)
        assert got.dtype == want.dtype
        np.testing.assert_array_equal(got, want)
    assert a.random() == b.random()  # the same draws were taken


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("dtype", [np.int16, np.int64])
def test_mutate_kernel_is_apply_mutation(seed, dtype):
    rng = np.random.default_rng(seed)
    levels = int(rng.choice([3, 5, 15]))
    pop = _random_population(rng, int(rng.integers(2, 30)), int(rng.integers(1, 14)), levels, dtype)
    a, b = np.random.default_rng(seed + 7), np.random.default_rng(seed + 7)
    got = mutate(pop, a, 0.4, levels)
    hit = b.random(pop.shape) < 0.4
    rows, genes = np.nonzero(hit)
    want = apply_mutation(pop, rows, genes, b.integers(0, 3, len(rows)), levels)
    assert got.dtype == want.dtype
    np.testing.assert_array_equal(got, want)
    assert a.random() == b.random()
    assert np.any(got != pop)  # the case mutates something


@pytest.mark.parametrize("seed", range(12))
def test_smooth_kernels_are_the_numpy_operator(seed):
    rng = np.random.default_rng(seed)
    K, levels = int(rng.integers(1, 14)), int(rng.choice([3, 7, 15]))
    coding = PathCoding.from_path(_random_path(rng), K, levels, float(rng.uniform(0.05, 0.5)))
    pop = _random_population(rng, 40, K, levels, np.int16 if seed % 2 else np.int64)
    changed = 0
    for p_smooth in (0.0, 0.3, 1.0):
        a, b = np.random.default_rng(seed), np.random.default_rng(seed)
        rows, cand, slots = _propose_smooth(pop, coding, a, p_smooth)
        w_rows, w_cand, w_slots = _propose_smooth_numpy(pop, coding, b, p_smooth)
        np.testing.assert_array_equal(rows, w_rows)
        np.testing.assert_array_equal(cand, w_cand)
        np.testing.assert_array_equal(slots, w_slots)
        assert cand.dtype == w_cand.dtype == pop.dtype
        assert a.random() == b.random()
        changed += len(rows)
    assert changed > 0 or K == 1


def test_keys_are_the_rows_bytes():
    pop = _random_population(np.random.default_rng(0), 20, 7, 15, np.int16)
    assert _keys(pop) == [row.tobytes() for row in pop]
    assert _keys(pop[::2]) == [row.tobytes() for row in pop[::2]]  # not contiguous


# --------------------------------------------------------------------------- evaluation


class _Recorder:
    """A clearance callable that logs its arguments (the compiled evaluation must call the
    callables exactly as the reference does)."""

    def __init__(self, fn):
        self.fn, self.calls = fn, []

    def __call__(self, *args):
        self.calls.append([np.array(a, copy=True) for a in args])
        return self.fn(*args)


def _evaluation_case(seed, kind):
    """(coding, evaluator factory, population, exact) for one configuration."""
    rng = np.random.default_rng(seed)
    path = _random_path(rng, 6)
    times = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T) / rng.uniform(0.5, 1.5))])
    if rng.random() < 0.5:
        times[1:] += 1.0  # a wait at the start
        path = np.insert(path, 0, path[0], axis=0)
        times = np.insert(times, 0, 0.0)
    centre = path[len(path) // 2] + rng.normal(0, 0.3, 2) + [0.0, 1.5 if kind in ("timed", "speed") else 0.6]

    def static(xy):
        return np.hypot(*(np.asarray(xy) - centre).T) - 0.4 - R_ROBOT

    def segment(a, b):
        mn = np.minimum(static(a), static(b))
        return np.where(mn > 0.3, mn - 0.3, -1.0), mn

    def mover(xy, t):
        pos = np.column_stack([np.full_like(t, path[:, 0].mean()), path[:, 1].min() - 2.0 + 0.5 * t])
        return np.hypot(*(xy - pos).T) - 0.3 - R_ROBOT

    K, levels = 8, 9
    coding = PathCoding.from_path(path, K, levels, 0.1)
    # weights that are not powers of two, so that every rounding of the cost shows
    weights = dict(w_length=1.3, w_security=0.7, w_smooth=0.37, safe_clearance=0.33)
    opts = GAOptions(n_knots=K, levels=levels, keep_speed=kind != "segment", **weights)

    def make():
        recs = {"static": _Recorder(static), "segment": _Recorder(segment), "mover": _Recorder(mover)}
        timed = kind != "static"  # "speed": the input's timing (the speed rule), no mover
        ev = PathEvaluator(
            R_ROBOT, recs["static"], recs["mover"] if timed and kind != "speed" else None, path if timed else None,
            times if timed else None, opts, recs["segment"] if kind == "segment" else None,
        )  # fmt: skip
        ev._enable_segment_cache(K * levels + 2)
        return ev, recs

    pop = _random_population(rng, 50, K, levels, np.int16)
    pop[3::2] = np.where(pop[3::2] == REMOVED, REMOVED, levels // 2 + rng.integers(-1, 2, pop[3::2].shape))
    exact = rng.random((len(pop), K + 1)) < 0.2
    return coding, make, pop, exact


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("kind", ["static", "timed", "segment", "speed"])
def test_compiled_evaluation_is_the_reference(seed, kind):
    coding, make, pop, exact = _evaluation_case(seed, kind)
    ref, ref_calls = make()
    fast, fast_calls = make()
    assert lattice.supported(fast)
    chord = float(np.hypot(*(coding.goal - coding.start)))
    feasible = []
    # three rounds over overlapping halves: the later ones read the node-pair caches
    for rows, marks in ((slice(0, 30), exact[:30]), (slice(20, 50), None), (slice(None), exact)):
        batch = pop[rows]
        pts, mask = coding.decode(batch)
        want_exact = np.zeros((len(batch), coding.n_knots + 1), dtype=bool) if marks is None else marks
        want = ref.evaluate(pts, mask, coding.node_ids(batch), coding.arc, want_exact)
        want_cost = ref.fitness(want, chord).cost
        got, cost = lattice.evaluate_genes(fast, coding, batch, marks, chord)
        for name in ("length", "smoothness", "min_clearance", "segment_clearance", "feasible"):
            np.testing.assert_array_equal(getattr(got, name), getattr(want, name), err_msg=name)
        np.testing.assert_array_equal(cost, want_cost)
        feasible.append(want.feasible)
    feasible = np.concatenate(feasible)
    assert feasible.any() and not feasible.all()  # both kinds of rows were compared
    for name in ("static", "segment", "mover"):
        assert len(fast_calls[name].calls) == len(ref_calls[name].calls), name
        for a, b in zip(fast_calls[name].calls, ref_calls[name].calls, strict=True):
            for x, y in zip(a, b, strict=True):
                np.testing.assert_array_equal(x, y)
    assert sum(len(r.calls) for r in fast_calls.values()) > 0


@pytest.mark.parametrize("seed", [0, 1])
def test_refine_path_compiled_equals_reference(seed, monkeypatch):
    # the whole GA, with and without the compiled evaluation: the same result, bit for bit
    coding, make, pop, _ = _evaluation_case(seed, "timed")
    path = coding.knots  # any polyline through the scene
    ev, recs = make()
    path = np.vstack([coding.start, coding.knots, coding.goal])
    times = np.linspace(0.0, 10.0, len(path))
    opts = GAOptions(n_knots=6, levels=7, generations=120, patience=None, population=16)
    args = (path, times, R_ROBOT, recs["static"].fn, recs["mover"].fn, opts)
    fast = refine_path(*args, seed=seed)
    monkeypatch.setattr(lattice, "supported", lambda evaluator: False)
    slow = refine_path(*args, seed=seed)
    for name in ("path", "chromosome", "fitness_history", "trajectory"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(slow, name), err_msg=name)
    for name in ("fitness_before", "fitness_after", "clearance_after", "smoothness_after", "improved"):
        assert getattr(fast, name) == getattr(slow, name), name


# --------------------------------------------------------------------------- stages' caches


@pytest.fixture(scope="module")
def building_floor():
    from gfuzzy.collision.geometry import StaticGeometry
    from gfuzzy.scene.scene import load_scene

    scene = load_scene(ROOT / "scenes" / "building-floor.yaml")
    return scene, StaticGeometry(scene)


def test_state_table_is_the_movers_states(building_floor):
    from gfuzzy.planner.stages import _StateTable

    scene, _ = building_floor
    table = _StateTable(scene.movers)
    rng = np.random.default_rng(0)
    grid = np.linspace(0.0, 30.0, 301)
    for i in range(6):
        t = rng.choice(grid, int(rng.integers(0, 60)))  # repeats, overlaps earlier calls
        if i == 3:
            t = np.append(t, [-0.0, 0.0, 1e-9])
        if i == 4:
            t = np.append(t, np.nan)  # not cached, still answered
        got = table(t)
        for mv, (pos, present) in zip(scene.movers, got, strict=True):
            want_pos, want_present = mv.state(t)
            np.testing.assert_array_equal(pos, want_pos)
            np.testing.assert_array_equal(present, want_present)
    for mv, (pos, present) in zip(scene.movers, table(2.5), strict=True):  # a scalar time
        want_pos, want_present = mv.state(2.5)
        np.testing.assert_array_equal(pos, want_pos)
        np.testing.assert_array_equal(present, want_present)
    assert 0 < len(table.times) < 301 + 4
    assert np.all(np.diff(table.times) > 0)


def test_traced_segments_are_motion_clearance(building_floor):
    from gfuzzy.planner.stages import _traced

    scene, geometry = building_floor
    rng = np.random.default_rng(1)
    nodes = np.column_stack([rng.uniform(0.2, 7.8, 30), rng.uniform(0.2, 4.8, 30), rng.uniform(-np.pi, np.pi, 30)])
    asked = []
    cache = {}

    def pose_clearance(pose):
        asked.append(tuple(pose))
        key = tuple(pose)
        if key not in cache:
            cache[key] = geometry.clearance1(pose)
        return cache[key]

    results = []
    for _ in range(120):
        i, j = rng.integers(0, len(nodes), 2)
        p, q = nodes[i].tolist(), nodes[j].tolist()
        got = _traced(geometry, p, q, pose_clearance)
        assert got == geometry.motion_clearance(p, q)
        results.append(got)
    results = np.array(results)
    assert (results < 0).any() and (results >= 0).any()
    assert len(cache) < len(asked)  # nodes were shared
