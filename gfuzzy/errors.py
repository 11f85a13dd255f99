"""Exception families.

Two kinds of failure, two families: *bad input* raises :class:`SceneError` (a
``ValueError``) naming the file and the place in it; *no solution* is never an
exception but a status on the result (see :class:`gfuzzy.timespace.Status`).
"""

from __future__ import annotations


class GfuzzyError(Exception):
    """Base class of every error gfuzzy raises on purpose."""


class SceneError(GfuzzyError, ValueError):
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
