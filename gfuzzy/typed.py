"""Shared type aliases (array shapes are in the docstrings that use them)."""

from __future__ import annotations

from os import PathLike
from typing import Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]
PathType = Union[str, "PathLike[str]"]

__all__ = ["ArrayLike", "FloatArray", "IntArray", "BoolArray", "PathType"]
