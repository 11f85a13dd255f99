"""People whose velocity is not known yet: walkers of unknown direction.

A tracker that has seen a person once has their position, not their velocity: it
reports them standing (``Sensor.unknown`` marks them). With a narrow view about the
robot's motion this is the person seen once by the look back at the start, beside or
behind the robot, who then walks its way unseen while the robot plans around a disc
standing where they were (*The noisy half view, fourth round*, navigator-experiments.md).
:meth:`gfuzzy.Navigator.step` told who they are predicts each as a disc that grows at a
walking pace (``UNKNOWN_GROWTH``, up to ``UNKNOWN_CAP`` more) over the prediction: in the
search's inflation and in every check of a motion against the people walking on (the
fallbacks, the evasive motion, the look), so the robot keeps away from where they may walk.
"""

from __future__ import annotations

import numpy as np

from ..typed import FloatArray
from . import sensing

__all__ = ["unknown_positions", "at_unknown", "unknown_growth"]


def unknown_positions(obs: FloatArray, unknown) -> FloatArray:
    """(u, 2) positions of the rows of ``obs`` (k, 5) marked by ``unknown`` (k,) bool (None:
    nobody) that are reported standing (a person of unknown velocity)."""
    if unknown is None or not len(obs):
        return np.zeros((0, 2))
    unknown = np.asarray(unknown, dtype=bool).reshape(-1)
    if unknown.shape != (len(obs),):
        raise ValueError(f"unknown must be one flag per observation ({len(obs)}), got {unknown.shape}")
    still = np.all(obs[:, 2:4] == 0.0, axis=1)
    return obs[unknown & still, :2].copy()


def at_unknown(known: FloatArray, obs: FloatArray) -> np.ndarray:
    """(k,) True for each row of ``obs`` (k, >=2) standing at one of the positions ``known``
    (u, 2) of people of unknown velocity (callers pass subsets of the observations: the
    position, not the row's index, names the person)."""
    if not len(known) or not len(obs):
        return np.zeros(len(obs), dtype=bool)
    return np.all(obs[:, None, :2] == np.asarray(known)[None, :, :2], axis=2).any(axis=1)


def unknown_growth(known: FloatArray, obs: FloatArray, tau: FloatArray) -> FloatArray:
    """(T, k) growth (m) at the times ``tau`` (T,) after now of the discs of ``obs`` (k, >=5)
    that stand at one of the positions ``known`` (u, 2) of people of unknown velocity
    (0 for everyone else): a walking pace, capped."""
    tau = np.asarray(tau, dtype=float).reshape(-1)
    if not len(known) or not len(obs):
        return np.zeros((len(tau), len(obs)))
    same = at_unknown(known, obs) & np.all(obs[:, 2:4] == 0.0, axis=1)
    # read at call time: the constants live in one place (sensing), where a script may set them
    growth, cap = sensing.UNKNOWN_GROWTH, sensing.UNKNOWN_CAP
    return np.minimum(np.maximum(tau, 0.0)[:, None] * (growth * same)[None, :], cap)
