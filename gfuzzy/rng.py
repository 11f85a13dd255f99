"""One place that turns a ``seed`` argument into a generator (after networkx's
``create_random_state``). Library code never touches global random state."""

from __future__ import annotations

import numpy as np

from .errors import InputError

Seed = "int | np.random.Generator | None"


def create_rng(seed: int | np.random.Generator | None = None) -> np.random.Generator:
    """Return a ``numpy.random.Generator`` for ``seed``.

    Parameters
    ----------
    seed : int, Generator or None
        An int seeds a new PCG64 generator; a Generator is returned unchanged;
        None gives the fixed default seed 0 (same call, same result).

    Raises
    ------
    TypeError
        If ``seed`` is of another type.
    InputError
        If ``seed`` is a negative int.
    """
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is None:
        return np.random.default_rng(0)
    if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
        if seed < 0:  # numpy's ValueError, raised where the seed is first used, was a traceback
            raise InputError(f"seed must be a whole number >= 0, got {seed}")
        return np.random.default_rng(int(seed))
    raise TypeError(f"seed must be an int or numpy.random.Generator, not {type(seed).__name__}")
