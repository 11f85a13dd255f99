"""The GA's settings, gene constants, callable types and input checks (no other GA module
imported: every one of them imports this)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..typed import ArrayLike, FloatArray

REMOVED = -1
"""Gene value of a removed via-point."""

StaticClearance = Callable[[FloatArray], FloatArray]
MoverClearance = Callable[[FloatArray, FloatArray], FloatArray]
#: ``static_segment(a (k, 2), b (k, 2)) -> (bound (k,), clearance (k,))``: a lower bound on
#: the static clearance along each segment a-b (>= 0: the segment is free) and an estimate
#: of its smallest clearance.
StaticSegment = Callable[[FloatArray, FloatArray], "tuple[FloatArray, FloatArray]"]

_EPS = 1e-12


@dataclass(frozen=True)
class GAOptions:
    """Settings of the GA refinement; the defaults are the paper's values (section 5.3).

    Parameters
    ----------
    n_knots : int
        Chromosome length: knots at equal arc length along the input path (12).
    levels : int
        Integer levels per gene, odd so that level ``levels // 2`` is the knot itself (15).
    step : float or None
        Offset between two levels along a search line. None derives one step per knot from
        the free width of its search line (see ``docs/ga.md``).
    population : int
        Individuals per generation (50).
    generations : int
        Upper bound on generations (2000).
    pc : float
        Probability that a pair of parents is crossed (single point, 0.62).
    pm : float
        Probability that a gene mutates (0.1); the kind is drawn uniformly from
        :class:`Mutation`.
    p_smooth : float
        Probability that the smooth operator is tried on an individual (0.2).
    w_length, w_security, w_smooth : float
        Weights of the three fitness parts (1.0, 1.0, 0.5).
    patience : int or None
        Stop when the best cost has not improved for this many generations (200);
        None or 0 disables the early stop.
    safe_clearance : float or None
        Clearance at and beyond which the security part is zero; None: the robot radius.
    resolution : float or None
        Spacing of the clearance samples along each segment; None: robot radius / 2.
    time_resolution : float or None
        Spacing in time of extra mover-clearance samples that cover waits and slow stretches
        of the input timing; None: ``resolution`` divided by the input's mean speed.
    keep_speed : bool
        With input ``times``, a candidate is infeasible if any of its segments is longer than
        the stretch of the input whose time it takes, so the refined path is nowhere faster
        than the input and keeps the input's speed bound (True).

    Raises
    ------
    ValueError
        If a value is out of range.
    """

    n_knots: int = 12
    levels: int = 15
    step: float | None = None
    population: int = 50
    generations: int = 2000
    pc: float = 0.62
    pm: float = 0.1
    p_smooth: float = 0.2
    w_length: float = 1.0
    w_security: float = 1.0
    w_smooth: float = 0.5
    patience: int | None = 200
    safe_clearance: float | None = None
    resolution: float | None = None
    time_resolution: float | None = None
    keep_speed: bool = True

    def __post_init__(self):
        def need(ok: bool, what: str):
            if not ok:
                raise ValueError(f"GAOptions.{what}")

        need(
            _is_int(self.n_knots) and self.n_knots >= 1,
            f"n_knots must be an int >= 1, not {self.n_knots!r}",
        )
        need(
            _is_int(self.levels)
            and self.levels >= 3
            and self.levels % 2 == 1
            and self.levels <= 32767,
            f"levels must be an odd int in [3, 32767], not {self.levels!r}",
        )
        need(
            self.step is None or _pos(self.step),
            f"step must be None or a finite number > 0, not {self.step!r}",
        )
        need(
            _is_int(self.population) and self.population >= 2,
            f"population must be an int >= 2, not {self.population!r}",
        )
        need(
            _is_int(self.generations) and self.generations >= 0,
            f"generations must be an int >= 0, not {self.generations!r}",
        )
        for name in ("pc", "pm", "p_smooth"):
            v = getattr(self, name)
            need(
                _finite(v) and 0.0 <= v <= 1.0, f"{name} must be a probability in [0, 1], not {v!r}"
            )
        for name in ("w_length", "w_security", "w_smooth"):
            v = getattr(self, name)
            need(_finite(v) and v >= 0.0, f"{name} must be a finite weight >= 0, not {v!r}")
        need(
            self.patience is None or (_is_int(self.patience) and self.patience >= 0),
            f"patience must be None or an int >= 0, not {self.patience!r}",
        )
        for name in ("safe_clearance", "resolution", "time_resolution"):
            v = getattr(self, name)
            need(v is None or _pos(v), f"{name} must be None or a finite number > 0, not {v!r}")
        need(
            isinstance(self.keep_speed, bool), f"keep_speed must be a bool, not {self.keep_speed!r}"
        )


def _is_int(v) -> bool:
    return isinstance(v, (int, np.integer)) and not isinstance(v, bool)


def _finite(v) -> bool:
    return (
        isinstance(v, (int, float, np.integer, np.floating))
        and not isinstance(v, bool)
        and math.isfinite(v)
    )


def _pos(v) -> bool:
    return _finite(v) and v > 0


def _check_path(path_xy: ArrayLike) -> FloatArray:
    p = np.asarray(path_xy, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 2:
        raise ValueError(f"path_xy must have shape (n, 2) with n >= 2, not {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError("path_xy has non-finite values")
    return p


def _check_times(times: ArrayLike, n: int) -> FloatArray:
    t = np.asarray(times, dtype=float)
    if t.shape != (n,):
        raise ValueError(f"times must have shape ({n},), not {t.shape}")
    if not np.all(np.isfinite(t)):
        raise ValueError("times has non-finite values")
    if np.any(np.diff(t) < 0):
        raise ValueError("times must be nondecreasing")
    return t


def _call_static(fn: StaticClearance, xy: FloatArray) -> FloatArray:
    c = np.asarray(fn(xy), dtype=float)
    if c.shape != (len(xy),):
        raise ValueError(f"static_clearance returned shape {c.shape} for {len(xy)} points")
    return np.where(np.isnan(c), -np.inf, c)


def _call_mover(fn: MoverClearance, xy: FloatArray, t: FloatArray) -> FloatArray:
    c = np.asarray(fn(xy, t), dtype=float)
    if c.shape != (len(xy),):
        raise ValueError(f"mover_clearance returned shape {c.shape} for {len(xy)} points")
    return np.where(np.isnan(c), -np.inf, c)
