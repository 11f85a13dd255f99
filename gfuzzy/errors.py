"""Exception families.

Three kinds of failure, kept apart so that a bug is never blamed on the user:

* *bad input* raises :class:`InputError` (bad options, poses, command-line values) or
  its subclass :class:`SceneError` (a file, naming the file and the place in it);
* *a request beyond the memory bounds* (a time step far too fine for the scene) raises
  :class:`LimitError`;
* *no solution* is never an exception but a status on the result
  (:class:`gfuzzy.status.Status`).

Both exception families are ``ValueError`` subclasses, so code written against the
older API (``except ValueError``) still catches them. The command line turns these two
families, and only these, into one line on stderr and exit status 2; any other exception
is a bug and shows its traceback.
"""

from __future__ import annotations

import math
import numbers

from .settings import MAX_MAGNITUDE


class GfuzzyError(Exception):
    """Base class of every error gfuzzy raises on purpose."""


class InputError(GfuzzyError, ValueError):
    """Bad input that is not a file: an option, a pose, a value on the command line."""


class LimitError(GfuzzyError, ValueError):
    """A request the memory bounds refuse (:mod:`gfuzzy.settings` ``MAX_*``): a time step
    far too fine or a horizon far too long for the scene. The message says what to change."""


class SceneError(InputError):
    """Bad input: a file (scene, roadmap, trajectory, rule base) that cannot be used.

    Parameters
    ----------
    file : str
        The file the problem is in (``"<string>"`` when parsed from text).
    place : str
        Where in the file, e.g. ``"movers[2].path[1]"``; empty for the whole file.
    message : str
        What is wrong, one line.
    """

    def __init__(self, file: str, place: str, message: str):
        self.file = str(file)
        self.place = place
        self.message = " ".join(str(message).split())
        where = f"{self.file}: {place}" if place else self.file
        super().__init__(f"{where}: {self.message}")


def check_number(name: str, value, low: float = 0.0, *, strict: bool = True, finite: bool = True) -> None:
    """The one validation of a numeric option (``PlanOptions``, ``NavOptions``, ...).

    Raises :class:`InputError` naming ``name`` unless ``value`` is a real number above
    ``low`` (at least ``low`` when not ``strict``), finite and at most ``settings.MAX_MAGNITUDE``
    in magnitude unless ``finite`` is False.
    """
    ok = isinstance(value, numbers.Real) and not math.isnan(value) and (not finite or math.isfinite(value))
    if ok:
        ok = value > low if strict else value >= low
    if not ok:
        if strict and low == 0:
            want = "a positive number"
        else:
            want = f"a number {'>' if strict else '>='} {low:g}"
        raise InputError(f"{name} must be {want}, got {value!r}")
    if finite and abs(value) > MAX_MAGNITUDE:  # as a scene file's numbers: beyond, times stop resolving
        raise InputError(f"{name} must be at most {MAX_MAGNITUDE:g}, got {value:g}")
