"""What a caller hands :class:`~gfuzzy.navigation.navigator.Navigator`, checked: the goal,
each step's time and pose, and the observations. Malformed input is an
:class:`~gfuzzy.errors.InputError` (a ``ValueError``) naming what is wrong; it never reaches
the searches.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..planner.planner import check_pose
from ..poses import as_number, number_array
from ..typed import FloatArray

__all__ = ["observation_rows", "checked_pose", "flat_pose"]


def observation_rows(observations) -> np.ndarray:
    """``Navigator.step``'s observations as a (k, 5) array: rows ``[x, y, vx, vy, radius]``, or one
    such row alone; any other shape (a transposed array, a row of 4) is refused, never reshaped,
    and so is a row that is not finite or has a negative radius, by its index."""
    obs = np.asarray(observations, dtype=float)
    if obs.size == 0:
        return np.zeros((0, 5))
    if obs.shape == (5,):
        obs = obs[None, :]
    if obs.ndim != 2 or obs.shape[1] != 5:
        raise InputError(f"observations must be an array of shape (k, 5), rows [x, y, vx, vy, radius]; got shape {obs.shape}")
    bad = np.flatnonzero(~np.all(np.isfinite(obs), axis=1) | ~(obs[:, 4] >= 0))
    if len(bad):  # a tracker's NaN row among fifty: say which, and what is in it
        i = int(bad[0])
        more = f" (and {len(bad) - 1} more)" if len(bad) > 1 else ""
        raise InputError(f"observations[{i}] = {obs[i].tolist()}{more}: rows must be finite [x, y, vx, vy, radius >= 0] "
                         "(drop a track the tracker has no estimate for)")
    return obs


def checked_pose(pose, robot, t, t_last=-math.inf) -> FloatArray:
    """``pose`` as a (dof,) float array (:func:`flat_pose`); InputError also when ``t`` is no
    finite number (:func:`gfuzzy.poses.as_number`: not a boolean or a string) or is before
    ``t_last``, the last call's (its predictions, look-outs and kept plans are of that later time)."""
    number = as_number(t)
    if number is None or not math.isfinite(number):
        raise InputError(f"t: expected a finite number, got {t!r}")
    if number < t_last:
        raise InputError(f"t: {number!r} is before the last call's t = {t_last!r} (a new run needs a new Navigator)")
    return flat_pose(pose, robot, "pose")


def flat_pose(pose, robot, label: str) -> FloatArray:
    """A goal or a pose as a (dof,) float array (``[[x, y]]`` serves as ``[x, y]``, as
    ``traj.at([t])`` gives it); InputError naming ``label`` when it is not ``dof`` finite
    numbers (a string or a boolean, even among numbers, is none, as in a scene file; beyond
    ``MAX_MAGNITUDE`` too, as :func:`gfuzzy.plan`'s)."""
    arr = number_array(pose)
    return check_pose(pose if arr is None else arr.reshape(-1), robot.dof, label, robot)
