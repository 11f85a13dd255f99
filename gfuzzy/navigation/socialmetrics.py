"""How social a robot's motion among people was (CONTRACT.md section 7).

* **Discomfort frequency** (CrowdNav, Chen et al. 2019): the share of time steps in which
  the gap between the robot's and a person's bodies falls below 0.2 m at some instant of
  the step (CrowdNav takes the closest distance over the step, not at its end).
* **Intrusion ratio** (CrowdNav++, Liu et al. 2023): the share of time steps at whose
  start the robot's centre lies closer than 0.6 m (the two radii, 0.3 + 0.3) to where a
  person's centre really is at one of the next five instants 0.25 s apart (1.25 s ahead:
  CrowdNav++'s ``calc_reward`` with ``danger_zone="future"``, its ground-truth future
  positions at ``t + 0.25 j``, j = 1..5; the person's position at ``t`` itself does not
  count).

The discomfort gaps are computed exactly for motions that are linear between rows (the
robot's executed waypoints, ``trajectory`` movers); a ``path`` mover is sampled every
0.02 s. The robot and the movers count as discs (their circumscribed ones when they are
not).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..scene.scene import Mover
from ..typed import FloatArray

__all__ = ["DISCOMFORT_GAP", "INTRUSION_DISTANCE", "INTRUSION_HORIZON", "INTRUSION_SAMPLE", "SocialMetrics", "social_metrics", "step_gaps"]

DISCOMFORT_GAP = 0.2
INTRUSION_DISTANCE = 0.6
INTRUSION_HORIZON = 1.25
#: CrowdNav++'s prediction step (s): the intrusion test looks at the instants
#: ``t + INTRUSION_SAMPLE * j``, j = 1 .. INTRUSION_HORIZON / INTRUSION_SAMPLE.
INTRUSION_SAMPLE = 0.25
#: Sampling (s) of movers that are not given by rows.
PATH_SAMPLE = 0.02


@dataclass(frozen=True)
class SocialMetrics:
    """Counts over the time steps of one run.

    Attributes
    ----------
    steps : int
        Time steps of the run (``ceil(duration / dt)``).
    discomfort_steps : int
        Steps with a gap below ``DISCOMFORT_GAP``.
    intrusion_steps : int
        Steps at whose start the robot intrudes (``INTRUSION_DISTANCE``, ``INTRUSION_HORIZON``).
    min_gap : float
        Smallest gap over the run (inf without people).
    """

    steps: int
    discomfort_steps: int
    intrusion_steps: int
    min_gap: float = math.inf

    @property
    def discomfort_frequency(self) -> float:
        return self.discomfort_steps / self.steps if self.steps else 0.0

    @property
    def intrusion_ratio(self) -> float:
        """Intrusion steps over the run's steps (``gfuzzy navigate``, ``gfuzzy experiments``).
        An episode of ``gfuzzy crowd`` divides by one step more, as CrowdNav++'s evaluation
        does (:attr:`gfuzzy.navigation.crowd.Episode.intrusion_ratio`)."""
        return self.intrusion_steps / self.steps if self.steps else 0.0


def _positions(rows: FloatArray, times: FloatArray) -> FloatArray:
    return np.column_stack([np.interp(times, rows[:, 0], rows[:, 1]), np.interp(times, rows[:, 0], rows[:, 2])])


def _mover_rows(mv: Mover, lo: float, hi: float) -> FloatArray | None:
    """``[t, x, y]`` rows of the mover over [lo, hi] (only where present), None if never."""
    if mv.trajectory is not None:
        tr = np.asarray(mv.trajectory, dtype=float)
        return tr if tr[-1, 0] >= lo and tr[0, 0] <= hi else None
    times = np.unique(np.concatenate([np.arange(lo, hi, PATH_SAMPLE), [hi]]))
    xy, present = mv.state(times)
    if not present.any():
        return None
    return np.column_stack([times[present], xy[present]])  # a path mover is always present


def _segment_min(a: FloatArray, b: FloatArray) -> FloatArray:
    """(n,) smallest norm of ``a + s (b - a)`` over s in [0, 1], row by row."""
    d = b - a
    dd = np.einsum("ij,ij->i", d, d)
    s = np.clip(-np.einsum("ij,ij->i", a, d) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    c = a + s[:, None] * d
    return np.hypot(c[:, 0], c[:, 1])


def step_gaps(waypoints: FloatArray, robot_radius: float, movers, dt: float = 0.25) -> FloatArray:
    """(n_steps,) smallest gap between the robot and any mover during each time step.

    Parameters
    ----------
    waypoints : (n, d + 1) float
        The robot's executed rows ``[t, x, y, ...]`` (linear between rows).
    robot_radius : float
    movers : sequence of Mover
    dt : float
        Length of a time step; step k is ``[t0 + k dt, t0 + (k + 1) dt]``.

    Returns
    -------
    (n_steps,) float
        inf for a step in which no mover is present.
    """
    w = np.asarray(waypoints, dtype=float)
    t0, t1 = float(w[0, 0]), float(w[-1, 0])
    n = int(math.ceil((t1 - t0) / dt - 1e-9))
    out = np.full(n, math.inf)
    if n == 0:
        return out
    bounds = t0 + np.arange(n + 1) * dt
    for mv in movers:
        rows = _mover_rows(mv, t0, t1)
        if rows is None:
            continue
        lo, hi = max(t0, rows[0, 0]), min(t1, rows[-1, 0])
        if lo > hi:
            continue
        g = np.concatenate([w[:, 0], rows[:, 0], bounds, [lo, hi]])
        g = np.unique(g[(g >= lo) & (g <= hi)])
        rel = _positions(rows, g) - _positions(w[:, :3], g)
        radii = robot_radius + mv.extent
        if len(g) == 1:
            k = min(int((g[0] - t0) // dt), n - 1)
            out[k] = min(out[k], float(np.hypot(*rel[0])) - radii)
            continue
        gap = _segment_min(rel[:-1], rel[1:]) - radii
        mid = 0.5 * (g[:-1] + g[1:])
        k = np.minimum(((mid - t0) // dt).astype(np.int64), n - 1)
        np.minimum.at(out, k, gap)
    return out


def _intrusion(w: FloatArray, movers, dt: float, n: int, distance: float, horizon: float) -> np.ndarray:
    """(n,) True for each step at whose start the robot's centre is closer than
    ``distance`` to a present mover's centre at one of the instants
    ``INTRUSION_SAMPLE * j`` (j = 1..) later, up to ``horizon``."""
    starts = float(w[0, 0]) + np.arange(n) * dt
    robot = _positions(w[:, :3], starts)  # (n, 2)
    ahead = INTRUSION_SAMPLE * np.arange(1, int(round(horizon / INTRUSION_SAMPLE)) + 1)
    times = starts[:, None] + ahead[None, :]  # (n, J)
    hit = np.zeros(n, dtype=bool)
    for mv in movers:
        xy, present = mv.state(times.ravel())
        d = np.hypot(*(xy.reshape(n, -1, 2) - robot[:, None, :]).transpose(2, 0, 1))
        hit |= np.any(present.reshape(n, -1) & (d < distance), axis=1)
    return hit


def social_metrics(waypoints: FloatArray, robot_radius: float, movers, dt: float = 0.25,
                   discomfort: float = DISCOMFORT_GAP, distance: float = INTRUSION_DISTANCE,
                   horizon: float = INTRUSION_HORIZON) -> SocialMetrics:  # fmt: skip
    """Discomfort and intrusion counts of the robot's run among ``movers``.

    Parameters
    ----------
    waypoints : (n, d + 1) float
        The executed rows, from the run's start to its end.
    robot_radius : float
    movers : sequence of Mover
        The people as they really moved (their rows may run past the robot's end: the
        intrusion test looks ``horizon`` seconds ahead).
    dt : float
        Time step (s).

    Returns
    -------
    SocialMetrics
    """
    w = np.asarray(waypoints, dtype=float)
    gaps = step_gaps(w, robot_radius, movers, dt)
    n = len(gaps)
    hit = _intrusion(w, movers, dt, n, distance, horizon) if n else np.zeros(0, dtype=bool)
    return SocialMetrics(n, int(np.sum(gaps < discomfort)), int(hit.sum()), float(np.min(gaps, initial=math.inf)))
