"""Genetic-algorithm refinement of a roadmap path's via-points.

A path found on a probabilistic roadmap zig-zags between random vertices. This module
straightens and smooths it with a genetic algorithm while keeping it clear of the static
obstacles and of the moving ones, following the genetic-fuzzy planner's GA stage
(paper sections 3.1 coding, 3.3 fitness, 4.2 operators, 5.3 parameters):

* **Coding** ("reducing dimensions"): ``n_knots`` knots sit at equal arc length along the
  input path. At each knot a search line runs perpendicular to the path, its origin placed
  dynamically at the knot. A gene is an integer *level*; the via-point lies on the knot's
  search line at offset ``(level - levels // 2) * step``. The gene :data:`REMOVED` drops the
  via-point. The chromosome length is fixed; the decoded path is start, the kept via-points,
  goal.
* **Fitness** is a *cost*, lower is better: ``w_length * fit_length + w_security *
  fit_security + w_smooth * fit_smooth``, each part dimensionless (see :func:`fitness_parts`).
  An individual whose clearance bound falls below zero anywhere is infeasible (cost ``inf``).
* **Operators**: roulette-wheel selection with elitism, single-point crossover (Pc 0.62),
  mutation (Pm 0.1) in three kinds (:class:`Mutation`: shift up, shift down, remove), and the
  smooth operator (probability 0.2, :func:`smooth`), population 50, up to 2000 generations,
  early stop after ``patience`` generations without improvement.

The package is independent of the rest of the planner: it takes a polyline and two clearance
callables. See ``docs/ga.md`` for the design and its reasons. Its modules, each importing
only the ones before it: :mod:`.options` (settings, gene constants, input checks),
:mod:`.coding` (knots, search lines, steps), :mod:`.fitness` (batch evaluation and cost),
:mod:`.kernels` (numba kernels, bit for bit the numpy they replace), :mod:`.operators`
(selection, crossover, mutation, smooth), :mod:`.lattice` (the GA's compiled evaluation of a
population) and :mod:`.refine` (the driver).
"""

from .coding import PathCoding
from .fitness import Evaluation, FitnessParts, PathEvaluator, fitness_parts
from .operators import Mutation, apply_mutation, crossover, mutate, roulette_select, smooth
from .options import REMOVED, GAOptions
from .refine import GAResult, refine_path

__all__ = [
    "REMOVED",
    "GAOptions",
    "GAResult",
    "Mutation",
    "PathCoding",
    "PathEvaluator",
    "Evaluation",
    "FitnessParts",
    "refine_path",
    "fitness_parts",
    "roulette_select",
    "crossover",
    "apply_mutation",
    "mutate",
    "smooth",
]
