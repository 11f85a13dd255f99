"""The GA driver: the initial population, the generations with elitism and the early stop,
and the refined path with its timing (:func:`refine_path`).

The algorithm (paper sections 3.1, 3.3, 4.2)::

    code the path: knots at equal arc length, a search line at each, genes = levels
    population = [all genes at the middle level (the input resampled),
                  all genes removed (the straight start-goal segment),
                  random perturbations of the middle level]
    repeat up to `generations` times, or until the best stalls for `patience`:
        cost of every individual (cached by chromosome)
        keep the best (elitism)
        roulette-wheel selection of the others' parents
        single-point crossover (pc), mutation per gene (pm), smooth operator (p_smooth)
    return the best path if it is feasible and cheaper than the input, else the input
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, replace

import numpy as np

from ..rng import create_rng
from ..typed import ArrayLike, BoolArray, FloatArray, IntArray
from . import lattice
from .coding import PathCoding, _dedupe, _derive_steps
from .fitness import Evaluation, FitnessParts, PathEvaluator
from .operators import _free, _propose_smooth, crossover, mutate, roulette_select
from .options import (
    REMOVED,
    GAOptions,
    MoverClearance,
    StaticClearance,
    StaticSegment,
    _check_path,
    _check_times,
    _pos,
)

logger = logging.getLogger("gfuzzy.ga")


@dataclass(frozen=True, eq=False)
class GAResult:
    """Outcome of :func:`refine_path`.

    Attributes
    ----------
    path : (m, 2) float
        The refined path (start, kept via-points, goal), or the input path when
        ``improved`` is False.
    chromosome : (K,) int
        The best individual's genes (:data:`REMOVED` = -1 marks removed via-points).
    fitness_history : (g + 1,) float
        Best cost (lower is better) after each generation, generation 0 first; ``inf`` while
        no individual is feasible.
    generations : int
        Generations evolved (g).
    improved : bool
        True when the best individual is feasible and its cost is lower than the input's.
    fitness_before, fitness_after : float
        Cost of the input and of ``path``.
    length_before, length_after : float
        Path lengths.
    smoothness_before, smoothness_after : float
        Sums of absolute turning angles, radians.
    clearance_before, clearance_after : float
        Smallest sampled clearance (static and movers).
    trajectory : (q, 3) float or None
        With input ``times``: rows [t, x, y] of ``path`` timed as the mover checks assumed:
        each via-point at the time the input passed its knot, and in between as the input
        moved over the same stretch, waits included. Linear between rows.
    coding : PathCoding or None
        The knots, search lines and steps used (None if the path had zero length).
    out_of_time : bool
        The ``deadline`` passed before the generations ended: the input is returned
        (``improved`` False), whatever the generations so far had found.
    """

    path: FloatArray
    chromosome: IntArray
    fitness_history: FloatArray
    generations: int
    improved: bool
    fitness_before: float
    fitness_after: float
    length_before: float
    length_after: float
    smoothness_before: float
    smoothness_after: float
    clearance_before: float
    clearance_after: float
    trajectory: FloatArray | None
    coding: PathCoding | None
    out_of_time: bool = False


def refine_path(
    path_xy: ArrayLike,
    times: ArrayLike | None,
    robot_radius: float,
    static_clearance: StaticClearance,
    mover_clearance: MoverClearance | None = None,
    options: GAOptions | None = None,
    seed: int | np.random.Generator | None = None,
    static_segment: StaticSegment | None = None,
    deadline: float | None = None,
) -> GAResult:
    """Straighten and smooth a path's via-points with a genetic algorithm.

    The algorithm is in this module's docstring (paper sections 3.1, 3.3, 4.2).

    The clearance checks are sampled (certified for 1-Lipschitz static clearance, sampled in
    time for movers): the planner must still validate the final trajectory.

    Timing (with ``times``): a via-point is reached when the input reached its knot (the
    knot sits at a known arc length of the input, whose time is interpolated from ``times``);
    along a segment between two via-points the robot moves as the input moved over the
    stretch between their knots, waits included. A gene thus only changes the timing of its
    own two segments, which keeps the mover constraints local.

    Parameters
    ----------
    path_xy : (n, 2) float
        The input path, n >= 2.
    times : (n,) float or None
        Nondecreasing times of the input's points (a repeated point at a later time is a
        wait); see Timing above. None: candidates are timed at unit speed from t = 0 along
        themselves (and ``keep_speed`` does not apply).
    robot_radius : float
        Sets the sample spacing (radius / 2) and the safe clearance (radius) by default.
    static_clearance : callable
        ``static_clearance(xy (k, 2)) -> (k,)``: signed clearance of the robot centred at each
        point from static obstacles and bounds (the robot radius already subtracted), >= 0
        free. A signed distance (1-Lipschitz) makes the segment checks certified.
    mover_clearance : callable or None
        ``mover_clearance(xy (k, 2), t (k,)) -> (k,)``: clearance from the movers at times t
        (the sums of radii already subtracted), >= 0 free.
    options : GAOptions or None
        Defaults are the paper's.
    seed : int, numpy.random.Generator or None
        See :func:`gfuzzy.rng.create_rng`.
    static_segment : callable or None
        ``static_segment(a (k, 2), b (k, 2)) -> (bound, clearance)``: certifies whole
        segments instead of sampling ``static_clearance`` along them (the planner passes
        an exact sphere-tracing check, which also works in passages narrower than the
        sample spacing allows).
    deadline : float or None
        A :func:`time.perf_counter` time: once past it the generations stop and the input is
        returned, ``out_of_time`` set (never a partly evolved path: a refined answer is
        the whole GA's, whatever the machine's speed).

    Returns
    -------
    GAResult
        Never worse than the input under the fitness: the input is returned, with
        ``improved`` False, when no individual is feasible or none beats it.

    Raises
    ------
    ValueError
        On malformed inputs, options or clearance outputs.
    TypeError
        On a bad ``seed``.
    """
    opts, path, t_in = _checked(path_xy, times, robot_radius, options)
    rng = create_rng(seed)

    evaluator = PathEvaluator(
        robot_radius, static_clearance, mover_clearance, path, t_in, opts, static_segment
    )
    chord = float(np.hypot(*(path[-1] - path[0])))
    before = evaluator.fitness(
        evaluator.evaluate(path[None], np.ones((1, len(path)), dtype=bool)), chord
    )
    b = _scalars(before)

    geo = _dedupe(path)
    if len(geo) < 2:
        logger.info("refine_path: zero-length path, returned unchanged")
        return _unchanged(path, t_in, b, np.array([b[0]]), 0, None, opts)

    coding = _make_coding(geo, opts, robot_radius, evaluator, static_clearance)
    best, best_cost, history, gen = _evolve(coding, evaluator, chord, rng, opts, deadline)
    if gen < 0:  # the deadline passed
        logger.info("refine_path: the deadline passed after %d generations; input returned", -gen - 1)
        out = _unchanged(path, t_in, b, history, -gen - 1, coding, opts)
        return replace(out, out_of_time=True)

    if not (math.isfinite(best_cost) and best_cost < b[0] - 1e-12 * max(1.0, abs(best_cost))):
        if not math.isfinite(best_cost):
            logger.info(
                "refine_path: no feasible individual in %d generations; input returned", gen
            )
        return _unchanged(path, t_in, b, history, gen, coding, opts, best)
    return _improved(path, t_in, b, history, gen, coding, best, evaluator, chord)


def _checked(
    path_xy, times, robot_radius, options
) -> tuple[GAOptions, FloatArray, FloatArray | None]:
    """The options, path and times of :func:`refine_path`, checked."""
    opts = options or GAOptions()
    if not isinstance(opts, GAOptions):
        raise ValueError(f"options must be a GAOptions, not {type(opts).__name__}")
    path = _check_path(path_xy)
    t_in = None if times is None else _check_times(times, len(path))
    if not _pos(robot_radius):
        raise ValueError(f"robot_radius must be a finite number > 0, not {robot_radius!r}")
    return opts, path, t_in


def _make_coding(
    geo: FloatArray,
    opts: GAOptions,
    robot_radius: float,
    evaluator: PathEvaluator,
    static_clearance: StaticClearance,
) -> PathCoding:
    """The coding of the deduplicated input ``geo``, its steps derived when not given; turns
    on the evaluator's segment caches for its lattice."""
    if opts.step is None:
        proto = PathCoding.from_path(geo, opts.n_knots, opts.levels, 1.0)
        steps = _derive_steps(
            geo,
            proto.knots,
            proto.normals,
            opts.levels,
            robot_radius,
            evaluator.resolution,
            static_clearance,
        )
    else:
        steps = opts.step
    coding = PathCoding.from_path(geo, opts.n_knots, opts.levels, steps)
    evaluator._enable_segment_cache(opts.n_knots * opts.levels + 2)
    return coding


class _Costs:
    """The cost of every chromosome evaluated so far (the GA revisits many)."""

    def __init__(self, coding: PathCoding, evaluator: PathEvaluator, chord: float):
        self.coding, self.evaluator, self.chord = coding, evaluator, chord
        self.cache: dict[bytes, float] = {}
        self.compiled = lattice.supported(evaluator)

    def evaluate(self, batch: IntArray, exact: BoolArray | None = None) -> Evaluation:
        """Evaluate ``batch`` (P, K) and remember its costs; ``exact`` (P, K + 1): the slots
        whose segment clearance must be exact even in an infeasible row (see
        :meth:`PathEvaluator.evaluate`); None: none (the costs are exact anyway)."""
        coding = self.coding
        if self.compiled and len(batch):
            ev, cost = lattice.evaluate_genes(self.evaluator, coding, batch, exact, self.chord)
        else:
            pts, mask = coding.decode(batch)
            if exact is None:
                exact = np.zeros((len(batch), coding.n_knots + 1), dtype=bool)
            ev = self.evaluator.evaluate(pts, mask, coding.node_ids(batch), coding.arc, exact)
            cost = self.evaluator.fitness(ev, self.chord).cost
        self.cache.update(zip(_keys(batch), cost.tolist(), strict=True))
        return ev

    def missing(self, pop: IntArray) -> IntArray:
        """Rows of ``pop`` not evaluated yet, the first of each distinct chromosome."""
        seen: set[bytes] = set()
        rows = []
        cache = self.cache
        for i, key in enumerate(_keys(pop)):
            if key not in cache and key not in seen:
                seen.add(key)
                rows.append(i)
        return np.asarray(rows, dtype=np.int64)

    def of(self, pop: IntArray) -> FloatArray:
        """(P,) costs of evaluated chromosomes."""
        cache = self.cache
        return np.array([cache[key] for key in _keys(pop)], dtype=float)


def _keys(pop: IntArray) -> list[bytes]:
    """Each row's bytes (``row.tobytes()``), in one call."""
    pop = np.ascontiguousarray(pop)
    return pop.view(np.dtype((np.void, pop.shape[1] * pop.itemsize))).reshape(-1).tolist()


def _evolve(
    coding: PathCoding,
    evaluator: PathEvaluator,
    chord: float,
    rng: np.random.Generator,
    opts: GAOptions,
    deadline: float | None = None,
) -> tuple[IntArray, float, FloatArray, int]:
    """The generations: elitism, selection, crossover, mutation, smoothing, early stop;
    past ``deadline`` (a :func:`time.perf_counter` time) they stop, ``gen`` then -1 - the
    generations evolved.

    Returns
    -------
    best : (K,) int
    best_cost : float
    history : (gen + 1,) float
        Best cost after each generation.
    gen : int
        Generations evolved.
    """
    P, K = opts.population, opts.n_knots
    pop = _initial_population(rng, P, K, opts.levels)
    costs_of = _Costs(coding, evaluator, chord)
    costs_of.evaluate(pop[costs_of.missing(pop)])
    best_cost, best, stall = math.inf, pop[0].copy(), 0
    history = []
    patience = opts.patience or 0
    gen = 0
    while True:
        costs = costs_of.of(pop)
        i = int(np.argmin(costs))
        if costs[i] < best_cost - 1e-12 * max(
            1.0, abs(best_cost) if math.isfinite(best_cost) else 1.0
        ):
            best_cost, best, stall = float(costs[i]), pop[i].copy(), 0
        else:
            stall += 1
        history.append(best_cost)
        if gen >= opts.generations or (patience and stall >= patience):
            break
        if deadline is not None and time.perf_counter() > deadline:
            return best, best_cost, np.asarray(history), -1 - gen
        parents = roulette_select(costs, rng, P - 1)
        kids = crossover(pop[parents], rng, opts.pc)
        kids = mutate(kids, rng, opts.pm, opts.levels)
        # One batch evaluation per generation: the new children and the smooth candidates.
        rows, cand, new_slots = _propose_smooth(kids, coding, rng, opts.p_smooth)
        todo = kids[costs_of.missing(kids)]
        if len(todo) or len(rows):
            # the smooth candidates' new segments decide their acceptance: exact
            exact = np.concatenate([np.zeros((len(todo), K + 1), dtype=bool), new_slots])
            ev = costs_of.evaluate(np.concatenate([todo, cand]), exact)
            ok = _free(ev.segment_clearance[len(todo) :], new_slots)
            kids[rows[ok]] = cand[ok]
        pop = np.concatenate([best[None], kids])
        gen += 1
    logger.debug(
        "refine_path: %d generations, %d distinct individuals evaluated", gen, len(costs_of.cache)
    )
    return best, best_cost, np.asarray(history), gen


def _improved(path, t_in, b, history, gen, coding, best, evaluator, chord) -> GAResult:
    """The result with the best individual's path, figures and timing."""
    arc = coding.arc
    out = coding.polyline(best)
    pts, mask = coding.decode(best[None])
    after = _scalars(evaluator.fitness(evaluator.evaluate(pts, mask, None, arc), chord))
    traj = None if t_in is None else _timed(out, arc[mask[0]], path, t_in)
    logger.info(
        "refine_path: cost %.4g -> %.4g, length %.3f -> %.3f, turning %.3f -> %.3f rad, %d generations",
        b[0],
        after[0],
        b[1],
        after[1],
        b[2],
        after[2],
        gen,
    )
    return _result(out, best.astype(np.int64), history, gen, True, b, after, traj, coding)


def _scalars(fp: FitnessParts) -> tuple[float, float, float, float]:
    return (
        float(fp.cost[0]),
        float(fp.length[0]),
        float(fp.smoothness[0]),
        float(fp.min_clearance[0]),
    )


def _unchanged(path, t_in, b, history, gen, coding, opts, best=None) -> GAResult:
    chrom = (
        np.full(opts.n_knots, opts.levels // 2, dtype=np.int64)
        if best is None
        else best.astype(np.int64)
    )
    traj = None if t_in is None else np.column_stack([t_in, path])
    return _result(path.copy(), chrom, np.asarray(history, dtype=float), gen, False, b, b, traj, coding)


def _initial_population(rng: np.random.Generator, P: int, K: int, levels: int) -> IntArray:
    """The input resampled, the straight segment, and perturbations of growing spread."""
    mid = levels // 2
    pop = np.full((P, K), mid, dtype=np.int16)
    if P > 1:
        pop[1] = REMOVED
    if P > 2:
        spread = np.linspace(1.0, mid, P - 2)[:, None]
        g = np.clip(np.rint(mid + rng.normal(size=(P - 2, K)) * spread), 0, levels - 1).astype(
            np.int16
        )
        g[rng.random((P - 2, K)) < 0.1] = REMOVED
        pop[2:] = g
    return pop


def _timed(out: FloatArray, u_out: FloatArray, ref: FloatArray, t: FloatArray) -> FloatArray:
    """Rows [t, x, y] of the polyline ``out`` whose points stand for the input's arc-length
    fractions ``u_out``, timed as :meth:`PathEvaluator.evaluate` assumes: between two points
    the position is linear in the fraction, and the time is the input's at that fraction."""
    s_ref = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(ref, axis=0).T))])
    u_ref = s_ref / s_ref[-1]
    # the input's breakpoints keep its waits; the path's corners get their interpolated times
    u = np.concatenate([u_ref, u_out])
    tt = np.concatenate([t, np.interp(u_out, u_ref, t)])
    order = np.lexsort((u, tt))
    u, tt = u[order], tt[order]
    xy = np.column_stack([np.interp(u, u_out, out[:, 0]), np.interp(u, u_out, out[:, 1])])
    rows = np.column_stack([tt, xy])
    keep = np.ones(len(rows), dtype=bool)
    keep[1:] = np.any(np.abs(np.diff(rows, axis=0)) > 1e-12, axis=1)
    return rows[keep]


def _result(path, chromosome, history, gen, improved, b, after, traj, coding) -> GAResult:
    """A :class:`GAResult` from the before / after figures ``(cost, length, turning,
    clearance)``."""
    return GAResult(
        path=path,
        chromosome=chromosome,
        fitness_history=history,
        generations=gen,
        improved=improved,
        fitness_before=b[0],
        fitness_after=after[0],
        length_before=b[1],
        length_after=after[1],
        smoothness_before=b[2],
        smoothness_after=after[2],
        clearance_before=b[3],
        clearance_after=after[3],
        trajectory=traj,
        coding=coding,
    )


def warm() -> None:
    """Compile (or load from numba's on-disk cache) the GA's kernels with the argument types
    the GA passes them (``make warm`` runs this, so no GA pays a compile): a tiny refinement
    among a mover with the input's timing, and the operators on int16 and int64 genes."""
    path = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 0.0], [3.0, 1.0]])

    def free(xy):
        return np.ones(len(xy))

    opts = GAOptions(n_knots=4, levels=5, population=6, generations=3, patience=None, p_smooth=1.0)
    refine_path(path, np.arange(4.0), 0.1, free, lambda xy, t: free(xy), opts, seed=0)
    rng = np.random.default_rng(0)
    for dtype in (np.int16, np.int64):
        mutate(crossover(rng.integers(-1, 5, (6, 4)).astype(dtype), rng, 1.0), rng, 0.5, 5)


_warmed: list = []  # warm_if_cold ran in this process


def warm_if_cold() -> bool:
    """Compile the GA's kernels now (:func:`warm`), once per process, when numba's cache holds
    none of them (:func:`gfuzzy.timespace.jit.numba_cached`): a fresh ``pip
    install`` without ``make warm``. ``Planner.plan`` calls it before its clock starts with
    ``refine``: a cold ``--refine --time-limit 10`` on office-polygons answered ``solved``
    after 137 s, 136 of them compiling inside the GA, which no deadline stops. Whether it
    compiled them."""
    if _warmed:
        return False
    _warmed.append(True)
    import os

    from ..timespace.jit import numba_cached

    if numba_cached("kernels", os.path.dirname(os.path.abspath(__file__))):
        return False
    warm()
    return True
