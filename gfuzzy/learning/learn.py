"""Learning a rule base: self-organising GA rule generation in three stages (SOGARG).

The cost of a rule base is measured by simulating a unicycle robot that tracks training
paths under the speed profile the rule base gives (:mod:`gfuzzy.learning.tracking`).
``tools/learn_rules.py`` runs it and writes ``gfuzzy/data/rules_learned.txt``. Planning
never imports this subpackage.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..fuzzy.fuzzy import FuzzyOptions, SpeedController, _samples, curve_ahead
from ..fuzzy.profile import clean_path as _clean_path
from ..fuzzy.profile import limit_acceleration
from ..fuzzy.rules import _UNIFORM5, _UNIFORM7, Partition, RuleBase
from ..rng import create_rng
from ..status import Status
from ..typed import ArrayLike, FloatArray
from . import tracking

logger = logging.getLogger(__name__)
logger.addHandler(logging.NullHandler())

__all__ = ["LearnOptions", "LearnResult", "learn_rules"]

# --------------------------------------------------------------------------
# Learning the rule base: self-organising GA rule generation in three stages
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class LearnOptions:
    """Settings of :func:`learn_rules`.

    Attributes
    ----------
    population : int
        Individuals per generation.
    generations : (int, int, int)
        Generations of stages 1, 2 and 3.
    crossover_rate : float
        Probability that two parents are crossed (two-point, on the flat
        chromosome); the paper's Pc.
    mutation_rate : float
        Per-allele mutation probability in stages 1 and 2 (stage 3 uses half).
    tournament : int
        Tournament size for selection.
    elite : int
        Best individuals copied unchanged to the next generation.
    set_point_curve : float
        Stage 1 learns the curve sets whose peak is at most this (near-straight).
    time_weight, error_weight, max_error_weight, violation_weight : float
        Objective weights: traversal time over the time at vmax; mean and max
        lateral error over ``error_scale``; fraction of time steps with a bound
        violation.
    error_scale : float
        Lateral error (metres) that costs as much as doubling the traversal time.
    rule_penalty : float
        Stage 3 cost per rule, so redundant rules are deleted.
    consistency_weight : float
        Stages 2 and 3 cost per pair of neighbouring rules that contradict the
        domain's monotonicity (a sharper bend never allows more speed, a farther
        one never less). Cells that seldom fire on the training paths get little
        say from the simulations; this keeps them in line with their neighbours.
    curve, distance, speed : Partition
        Partitions of the learned rule base.
    fuzzy : FuzzyOptions
        Speed-layer settings used in the objective. While learning, inference
        is always ``exact`` on the training samples; the default coarse output
        grid (61 points, still through every peak) makes it cheap.
    """

    population: int = 20
    generations: tuple[int, int, int] = (8, 32, 16)
    crossover_rate: float = 0.62
    mutation_rate: float = 0.1
    tournament: int = 2
    elite: int = 2
    set_point_curve: float = 0.2
    time_weight: float = 1.0
    error_weight: float = 1.0
    max_error_weight: float = 0.25
    violation_weight: float = 10.0
    error_scale: float = 0.1
    rule_penalty: float = 0.002
    consistency_weight: float = 0.01
    curve: Partition = _UNIFORM7
    distance: Partition = _UNIFORM5
    speed: Partition = _UNIFORM7
    fuzzy: FuzzyOptions = field(default_factory=lambda: FuzzyOptions(output_resolution=61))

    def __post_init__(self) -> None:
        if self.population < 2 or self.elite < 0 or self.elite >= self.population:
            raise InputError("need population >= 2 and 0 <= elite < population")
        if len(self.generations) != 3 or min(self.generations) < 0:
            raise InputError("generations must be three non-negative ints")
        if self.tournament < 1:
            raise InputError("tournament must be >= 1")


@dataclass(frozen=True)
class LearnResult:
    """Outcome of :func:`learn_rules`.

    Attributes
    ----------
    rulebase : RuleBase
        Best rule base of stage 3.
    cost : float
        Its stage-3 cost.
    history : tuple of tuple of float
        Best cost per generation, one tuple per stage.
    evaluations : int
        Distinct (stage, chromosome) simulations run.
    """

    rulebase: RuleBase
    cost: float
    history: tuple[tuple[float, ...], ...]
    evaluations: int


class _Objective:
    """Cost of a chromosome from tracking simulations on fixed training paths."""

    def __init__(self, paths, lopt: LearnOptions, limits, tracking_options):
        self.lopt = lopt
        self.limits = tracking.UnicycleLimits() if limits is None else limits
        self.topt = tracking.TrackingOptions() if tracking_options is None else tracking_options
        self.fopt = dataclasses.replace(lopt.fuzzy, exact=True)
        self.cases = []
        for path in paths:
            p, sp = _clean_path(path)
            if sp[-1] <= 0:
                continue
            s = _samples(sp, self.fopt.ds)
            curve, dist = curve_ahead(p, s, self.fopt.lookahead, self.fopt.max_turn)
            self.cases.append((p, s, curve, dist, sp[-1] / self.limits.vmax))
        if not self.cases:
            raise InputError("no training path of positive length")
        # One inference call for all paths' distinct samples (straights repeat).
        pairs = np.stack(
            [
                np.concatenate([case[2] for case in self.cases]),
                np.concatenate([case[3] for case in self.cases]),
            ],
            axis=1,
        )
        pairs, self.inverse = np.unique(pairs, axis=0, return_inverse=True)
        self.inverse = self.inverse.reshape(-1)
        self.curve, self.dist = pairs[:, 0], pairs[:, 1]
        self.splits = np.cumsum([case[1].size for case in self.cases])[:-1]

    def __call__(self, genes: tuple[int, ...], with_violations: bool) -> float:
        lopt = self.lopt
        rb = RuleBase(genes, lopt.curve, lopt.distance, lopt.speed)
        frac = SpeedController(rb, self.fopt).speed_fraction(self.curve, self.dist)
        frac = np.split(frac[self.inverse], self.splits)
        total = 0.0
        for (p, s, _, _, t_min), f in zip(self.cases, frac, strict=True):
            v = limit_acceleration(s, self.limits.vmax * f, self.limits.amax)
            res = tracking.track(p, (s, v), self.limits, self.topt)
            t = res.traversal_time if res.status is Status.SOLVED else 10 * t_min
            cost = lopt.time_weight * t / t_min
            cost += lopt.error_weight * res.mean_lateral_error / lopt.error_scale
            cost += lopt.max_error_weight * res.max_lateral_error / lopt.error_scale
            if with_violations:
                cost += lopt.violation_weight * res.violations.steps / max(1, res.t.size)
            total += cost
        return total / len(self.cases)


def _default_set_point_paths() -> list[FloatArray]:
    x = np.linspace(0.0, 8.0, 33)
    gentle = np.stack([x, 0.25 * np.sin(x * 2 * math.pi / 8.0)], axis=1)
    kinks = np.array([[0, 0], [2, 0], [4, 0.35], [6, 0.35], [8, 0.0]], dtype=float)
    return [np.array([[0.0, 0.0], [6.0, 0.0]]), gentle, kinks]


def learn_rules(
    paths: Sequence[ArrayLike],
    *,
    set_point_paths: Sequence[ArrayLike] | None = None,
    options: LearnOptions | None = None,
    limits=None,
    tracking_options=None,
    seed: int | np.random.Generator | None = None,
    map_fn: Callable | None = None,
) -> LearnResult:
    """Learn a rule base with a self-organising GA in three stages (SOGARG).

    Every chromosome is scored by simulating a unicycle tracking the training
    paths under the speed bound it produces (:func:`gfuzzy.learning.tracking.track`).

    1. **Set point.** Only the alleles of the near-straight curve sets (peak <=
       ``set_point_curve``) are learned, on near-straight paths; every allele
       must be a rule (mutation: reset to a random label or step +-1). Cost:
       traversal time and lateral error.
    2. **Whole input space.** All alleles, on the training paths plus the
       set-point paths. Stage-1 alleles start from stage 1's best; the others
       grow out of them row by row (a neighbour's label plus a random step), and
       mutation (reset or step +-1) may also remove a rule. Cost: stage 1's plus the fraction of steps that violate a
       bound of the robot and ``consistency_weight`` per inconsistent pair of
       neighbouring rules.
    3. **Fine tuning.** From stage 2's population, with mutations that *modify*
       (step +-1), *delete* or *add* (copy a neighbour's label) one rule. Cost:
       stage 2's plus ``rule_penalty`` per rule, so redundant rules go.

    Each generation: keep the ``elite`` best, fill with children of tournament
    parents by two-point crossover (probability ``crossover_rate``) and the
    stage's mutation.

    Parameters
    ----------
    paths : sequence of (n, 2) float
        Training paths.
    set_point_paths : sequence of (n, 2) float, optional
        Near-straight paths for stage 1 (default: a straight line, a gentle wave
        and a gentle double kink).
    options : LearnOptions, optional
    limits : gfuzzy.learning.tracking.UnicycleLimits, optional
    tracking_options : gfuzzy.learning.tracking.TrackingOptions, optional
    seed : int or numpy.random.Generator, optional
        Same seed, same rule base.
    map_fn : callable, optional
        ``map``-like ``map_fn(f, iterable)`` used to score new chromosomes (for
        instance a process pool's ``map``); it must keep the order. Default: the
        built-in ``map``.

    Returns
    -------
    LearnResult

    Notes
    -----
    The stages follow the self-organising GA rule generation (SOGARG) scheme
    the project's source paper uses to learn its fuzzy layer; the chromosome
    (one allele per pair of input sets, 0 = no rule) is the paper's. The
    consistency term is this implementation's addition.
    """
    lopt = LearnOptions() if options is None else options
    near = _default_set_point_paths() if set_point_paths is None else list(set_point_paths)
    obj_near = _Objective(near, lopt, limits, tracking_options)
    # Stages 2 and 3 keep the set-point paths, so the set-point rules stay earned.
    obj_all = _Objective(list(paths) + near, lopt, limits, tracking_options)
    run = _Sogarg(lopt, create_rng(seed), map if map_fn is None else map_fn, obj_near, obj_all)
    g1, g2, g3 = lopt.generations
    pop = run.evolve(1, run.stage1_population(), g1, run.mutate1)
    pop = run.evolve(2, run.stage2_population(pop), g2, run.mutate2)
    # Stage 3: fine tuning of stage 2's population.
    pop = run.evolve(3, [p.copy() for p in pop], g3, run.mutate3)
    best = pop[0]
    rb = RuleBase(tuple(int(x) for x in best), lopt.curve, lopt.distance, lopt.speed)
    cost = run.cache[(3, tuple(int(x) for x in best))]
    return LearnResult(rb, cost, tuple(run.history), len(run.cache))


class _Sogarg:
    """The state of one :func:`learn_rules` run: the random generator (one stream, used
    in a fixed order, so the same seed gives the same rule base), the cost cache, the
    set-point region of the chromosome, and each stage's operators."""

    def __init__(self, lopt: LearnOptions, rng: np.random.Generator, mapper, obj_near, obj_all):
        self.lopt, self.rng, self.mapper = lopt, rng, mapper
        self.obj_near, self.obj_all = obj_near, obj_all
        nc, nd, k = lopt.curve.size, lopt.distance.size, lopt.speed.size
        self.nc, self.nd, self.k = nc, nd, k
        region = np.zeros((nc, nd), dtype=bool)
        region[np.asarray(lopt.curve.peaks) <= lopt.set_point_curve + 1e-12, :] = True
        region = region.reshape(-1)
        if not region.any():
            region[:nd] = True
        self.region = region
        self.grid = np.arange(nc * nd).reshape(nc, nd)
        self.cache: dict[tuple[int, tuple[int, ...]], float] = {}
        self.history: list[tuple[float, ...]] = []

    def score(self, stage: int, pop: list[np.ndarray]) -> np.ndarray:
        cache = self.cache
        keys = [tuple(int(g) for g in ind) for ind in pop]
        new = list(dict.fromkeys(key for key in keys if (stage, key) not in cache))
        if new:
            fn = _StageCost(stage, self.obj_near if stage == 1 else self.obj_all, self.lopt)
            for key, cost in zip(new, self.mapper(fn, new), strict=True):
                cache[(stage, key)] = float(cost)
        return np.array([cache[(stage, key)] for key in keys])

    def evolve(self, stage: int, pop: list[np.ndarray], gens: int, mutate) -> list[np.ndarray]:
        lopt, rng = self.lopt, self.rng
        costs = self.score(stage, pop)
        best = [float(costs.min())]
        for _ in range(gens):
            order = np.argsort(costs, kind="stable")
            nxt = [pop[i].copy() for i in order[: lopt.elite]]
            while len(nxt) < lopt.population:
                a = pop[_tournament(rng, costs, lopt.tournament)]
                b = pop[_tournament(rng, costs, lopt.tournament)]
                if rng.random() < lopt.crossover_rate:
                    i, j = np.sort(rng.choice(a.size + 1, size=2, replace=False))
                    c1, c2 = a.copy(), b.copy()
                    c1[i:j], c2[i:j] = b[i:j], a[i:j]
                else:
                    c1, c2 = a.copy(), b.copy()
                for child in (c1, c2):
                    if len(nxt) < lopt.population:
                        nxt.append(mutate(child))
            pop = nxt
            costs = self.score(stage, pop)
            best.append(float(costs.min()))
        self.history.append(tuple(best))
        order = np.argsort(costs, kind="stable")
        logger.info("SOGARG stage %d: best cost %.4f", stage, costs[order[0]])
        return [pop[i] for i in order]

    def stage1_population(self) -> list[np.ndarray]:
        """Stage 1: the set-point region only; the rest stays "no rule" (min speed)."""
        nc, nd, k, region, rng = self.nc, self.nd, self.k, self.region, self.rng
        pop = []
        for _ in range(self.lopt.population):
            g = np.zeros(nc * nd, dtype=np.int64)
            g[region] = rng.integers(1, k + 1, size=int(region.sum()))
            pop.append(g)
        return pop

    def stage2_population(self, stage1: list[np.ndarray]) -> list[np.ndarray]:
        """Stage 2: keep the set-point rules and grow the rest out of them: each new rule
        takes its lower-curve neighbour's label plus a random step in {-2, -1, 0, +1} (a
        random walk, not a fixed table)."""
        nc, nd, k, rng, lopt = self.nc, self.nd, self.k, self.rng, self.lopt
        seeds = stage1[: max(1, lopt.population // 4)]
        pop = []
        rows = self.region.reshape(nc, nd).any(axis=1)
        for idx in range(lopt.population):
            g = seeds[idx % len(seeds)].reshape(nc, nd).copy()
            for r in range(nc):
                if not rows[r]:
                    above = g[r - 1] if r > 0 else rng.integers(1, k + 1, size=nd)
                    g[r] = np.clip(np.maximum(above, 1) + rng.integers(-2, 2, size=nd), 1, k)
            pop.append(g.reshape(-1))
        return pop

    def mutate1(self, g: np.ndarray) -> np.ndarray:
        """Stage 1: reset or step +-1, set-point alleles only, always a rule."""
        rng, k, region, pm = self.rng, self.k, self.region, self.lopt.mutation_rate
        hit = region & (rng.random(g.size) < pm)
        step = rng.random(g.size) < 0.5
        delta = rng.choice([-1, 1], size=g.size)
        reset = rng.integers(1, k + 1, size=g.size)
        g[hit] = np.where(step[hit], np.clip(g[hit] + delta[hit], 1, k), reset[hit])
        return g

    def mutate2(self, g: np.ndarray) -> np.ndarray:
        """Stage 2: reset (possibly to no rule) or step +-1, set-point alleles at half rate."""
        rng, k, region, pm = self.rng, self.k, self.region, self.lopt.mutation_rate
        rate = np.where(region, pm / 2, pm)
        hit = rng.random(g.size) < rate
        step = rng.random(g.size) < 0.5
        delta = rng.choice([-1, 1], size=g.size)
        reset = np.where(rng.random(g.size) < 0.05, 0, rng.integers(1, k + 1, size=g.size))
        g[hit] = np.where(step[hit] & (g[hit] > 0), np.clip(g[hit] + delta[hit], 1, k), reset[hit])
        return g

    def mutate3(self, g: np.ndarray) -> np.ndarray:
        """Stage 3: add (copy a neighbour's label), delete or modify (step +-1) a rule."""
        rng, k, nc, nd, grid, pm = self.rng, self.k, self.nc, self.nd, self.grid, self.lopt.mutation_rate
        for i in np.flatnonzero(rng.random(g.size) < pm / 2):
            r, c = divmod(int(i), nd)
            if g[i] == 0:  # add: copy a neighbouring rule's label
                nb = [
                    grid[rr, cc]
                    for rr, cc in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1))
                    if 0 <= rr < nc and 0 <= cc < nd and g[grid[rr, cc]] > 0
                ]
                g[i] = g[nb[int(rng.integers(len(nb)))]] if nb else int(rng.integers(1, k + 1))
            elif rng.random() < 0.25:  # delete
                g[i] = 0
            else:  # modify
                g[i] = int(np.clip(g[i] + rng.choice([-1, 1]), 1, k))
        return g


def _tournament(rng: np.random.Generator, costs: np.ndarray, size: int) -> int:
    idx = rng.integers(0, costs.size, size=size)
    return int(idx[np.argmin(costs[idx])])


def _inconsistencies(m: np.ndarray) -> int:
    """Neighbouring rule pairs whose speed rises with curve or falls with distance."""
    down = (m[1:, :] > m[:-1, :]) & (m[1:, :] > 0) & (m[:-1, :] > 0)
    right = (m[:, 1:] < m[:, :-1]) & (m[:, 1:] > 0) & (m[:, :-1] > 0)
    return int(down.sum() + right.sum())


class _StageCost:
    """Picklable cost of one stage (so a process pool can run it)."""

    def __init__(self, stage: int, objective: _Objective, lopt: LearnOptions):
        self.stage = stage
        self.objective = objective
        self.rule_penalty = lopt.rule_penalty
        self.consistency_weight = lopt.consistency_weight
        self.shape = (lopt.curve.size, lopt.distance.size)

    def __call__(self, genes: tuple[int, ...]) -> float:
        cost = self.objective(genes, with_violations=self.stage >= 2)
        if self.stage == 3:
            cost += self.rule_penalty * sum(1 for g in genes if g)
        if self.stage >= 2 and self.consistency_weight:
            cost += self.consistency_weight * _inconsistencies(np.reshape(genes, self.shape))
        return cost

