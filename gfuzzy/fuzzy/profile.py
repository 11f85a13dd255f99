"""One-dimensional speed profiles along a path: the acceleration bound and timing.

A profile is a speed bound ``v(s)`` sampled at increasing arc lengths ``s``. The fuzzy
speed layer (:mod:`gfuzzy.fuzzy.fuzzy`) makes one, the path-velocity re-timing
(:mod:`gfuzzy.planner.retime`) drives it, and the tracking simulation
(:mod:`gfuzzy.learning.tracking`) follows it; all three share these functions.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..typed import ArrayLike, FloatArray

__all__ = ["clean_path", "limit_acceleration", "profile_times"]


def clean_path(path_xy: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Path without repeated points, and its cumulative arc length."""
    p = np.asarray(path_xy, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 1:
        raise InputError(f"path_xy must have shape (n, 2) with n >= 1, got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise InputError("path_xy must be finite")
    seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
    keep = np.concatenate(([True], seg > 1e-12))
    p = p[keep]
    s = np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))))
    return p, s



def limit_acceleration(
    s: ArrayLike, v: ArrayLike, amax: float, v_start: float = 0.0, v_end: float = 0.0
) -> FloatArray:
    """Largest profile below ``v`` whose speed changes respect ``amax`` along ``s``.

    The forward-backward pass ``v[i+1]**2 <= v[i]**2 + 2 amax ds`` (forward, from
    ``v_start``) and the same backwards (from ``v_end``). Each pass is a running
    minimum: forward, ``v[i]**2 = 2 amax s[i] + min_{j<=i}(v[j]**2 - 2 amax s[j])``.

    Parameters
    ----------
    s : (k,) float
        Non-decreasing arc lengths.
    v : (k,) float
        Speed bound, non-negative.
    amax : float
        Acceleration bound, positive.
    v_start, v_end : float
        Speeds at the ends (0 = start and end at rest).

    Returns
    -------
    (k,) float
        The feasible profile, ``<= v`` everywhere.

    Raises
    ------
    ValueError
        If the shapes differ or ``amax`` is not positive.
    """
    s = np.asarray(s, dtype=float)
    u = np.array(v, dtype=float)
    if s.shape != u.shape or s.ndim != 1:
        raise InputError("s and v must be 1-D arrays of the same length")
    if not amax > 0:
        raise InputError(f"amax must be positive, got {amax}")
    if s.size == 0:
        return u
    u[0] = min(u[0], v_start)
    u[-1] = min(u[-1], v_end)
    sq = u**2
    idx = np.arange(s.size)
    # Running argmin j(i) of the key, then v[i]**2 = v[j]**2 + 2 amax |s[i] - s[j]|
    # computed directly (adding the key back would cancel digits near rest).
    key = sq - 2 * amax * s
    j = np.maximum.accumulate(np.where(key <= np.minimum.accumulate(key), idx, 0))
    fwd = sq[j] + 2 * amax * (s - s[j])
    key = (sq + 2 * amax * s)[::-1]
    j = np.maximum.accumulate(np.where(key <= np.minimum.accumulate(key), idx, 0))
    j = s.size - 1 - j[::-1]
    bwd = sq[j] + 2 * amax * (s[j] - s)
    return np.minimum(np.sqrt(np.minimum(fwd, bwd)), u)


def profile_times(s: ArrayLike, v: ArrayLike) -> FloatArray:
    """Times at the samples of a speed profile driven at its limit.

    Each interval is crossed at constant acceleration (``v**2`` linear in
    ``s``), taking ``2 ds / (v[i] + v[i+1])``.

    Parameters
    ----------
    s : (k,) float
        Increasing arc lengths.
    v : (k,) float
        Speeds; no two consecutive zeros.

    Returns
    -------
    (k,) float
        Times from 0.

    Raises
    ------
    ValueError
        If the shapes differ, or an interval of positive length has zero speed at
        both ends (it would never be crossed).
    """
    s = np.asarray(s, dtype=float)
    v = np.asarray(v, dtype=float)
    if s.shape != v.shape or s.ndim != 1:
        raise InputError("s and v must be 1-D arrays of the same length")
    ds = np.diff(s)
    vsum = v[:-1] + v[1:]
    if np.any((vsum <= 0) & (ds > 0)):
        raise ValueError("an interval has zero speed at both ends")
    dt = np.divide(2.0 * ds, vsum, out=np.zeros_like(ds), where=vsum > 0)
    return np.concatenate(([0.0], np.cumsum(dt)))


