"""Who is about to swerve: people whose walks are about to meet.

A person walking straight at another one does not walk through them: they turn or slow
down (ORCA people do so at once, at any rate), and the constant-velocity prediction of
both is wrong from then on. :func:`swerve_rates` picks the people whose predicted walks
come within :data:`SWERVE_GAP` of someone else's within :data:`SWERVE_LOOK` seconds, so
that the navigator grows their predicted disc faster than a free walker's: the robot
keeps more room around those who are about to deviate, and no more around the others.
"""

from __future__ import annotations

import numpy as np

from ..typed import FloatArray

__all__ = ["SWERVE_GAP", "SWERVE_LOOK", "meeting", "swerve_rates"]

#: Seconds ahead in which two people's straight walks must meet for them to swerve.
SWERVE_LOOK = 3.0
#: Gap (m, beyond both radii) under which two people's straight walks count as meeting.
SWERVE_GAP = 0.3


def meeting(obs: FloatArray, look: float = SWERVE_LOOK, gap: float = SWERVE_GAP) -> FloatArray:
    """(k,) the earliest time (s, in [0, look]) at which each person's straight walk comes
    within ``gap`` of another person's; ``inf`` for someone who meets nobody within ``look``.

    Parameters
    ----------
    obs : (k, >=5) float
        ``[x, y, vx, vy, radius, ...]`` per person.
    look, gap : float

    Notes
    -----
    Two discs walking at constant velocity are at ``|p + w s| - r_i - r_j`` at time ``s``
    (``p``, ``w``: relative position and velocity): the time they first come within
    ``gap`` is the smaller root of a quadratic, clipped to ``[0, look]``.
    """
    k = len(obs)
    out = np.full(k, np.inf)
    if k < 2:
        return out
    p = obs[None, :, :2] - obs[:, None, :2]  # (k, k, 2): j relative to i
    w = obs[None, :, 2:4] - obs[:, None, 2:4]
    reach = obs[:, None, 4] + obs[None, :, 4] + gap
    a = np.einsum("ijk,ijk->ij", w, w)
    b = 2.0 * np.einsum("ijk,ijk->ij", p, w)
    c = np.einsum("ijk,ijk->ij", p, p) - reach**2
    disc = b * b - 4.0 * a * c
    with np.errstate(divide="ignore", invalid="ignore"):
        first = (-b - np.sqrt(np.maximum(disc, 0.0))) / (2.0 * a)
    first = np.where(c <= 0.0, 0.0, first)  # already within the gap
    hit = (c <= 0.0) | ((a > 0.0) & (disc >= 0.0) & (first >= 0.0) & (first <= look))
    np.fill_diagonal(hit, False)
    when = np.where(hit, first, np.inf)
    return when.min(axis=1)


def swerve_rates(obs: FloatArray, growth: float, look: float = SWERVE_LOOK, gap: float = SWERVE_GAP) -> FloatArray:
    """(k,) extra growth (m per s of prediction) of each person's predicted disc: ``growth``
    for the people whose walks meet someone else's within ``look`` (:func:`meeting`), 0
    for the others."""
    if growth <= 0 or len(obs) < 2:
        return np.zeros(len(obs))
    return np.where(np.isfinite(meeting(obs, look, gap)), float(growth), 0.0)
