"""``gfuzzy map``: a scene around an occupancy-grid map, ready to plan on and to edit.

The scene has the map as its one obstacle (its path relative to the scene file), bounds
around the map's known cells (free or occupied; unknown margins left out), a robot, and
one query between two far-apart points of the largest region the robot fits in.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..typed import FloatArray
from .maps import UNKNOWN, MapObstacle, load_map
from .yamldoc import plain_name

__all__ = ["MapScene", "map_scene"]

DEFAULT_DISC = 0.2  # a small indoor robot's radius, metres
DEFAULT_VMAX = 0.5  # metres per second, a cautious indoor speed


@dataclass(frozen=True)
class MapScene:
    """A scene made by :func:`map_scene`.

    Attributes
    ----------
    text : str
        The scene file's YAML, with comments.
    bounds : (4,) tuple
    start, goal : tuple
        The sample query's poses (``None`` when the robot fits nowhere).
    """

    text: str
    bounds: tuple[float, float, float, float]
    start: tuple | None
    goal: tuple | None


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def _bounds(grid: MapObstacle) -> tuple[float, float, float, float]:
    """The known cells' bounding box (one cell of margin), inside the map's extent."""
    known = np.asarray(grid.values) != UNKNOWN
    x0, y0, x1, y1 = grid.extent
    if not known.any():
        return (x0, y0, x1, y1)
    h, _ = known.shape
    res = grid.resolution
    rows, cols = np.nonzero(known)
    ox, oy = grid.origin
    bx0 = max(x0, ox + (cols.min() - 1) * res)
    bx1 = min(x1, ox + (cols.max() + 2) * res)
    by0 = max(y0, oy + (h - 1 - rows.max() - 1) * res)
    by1 = min(y1, oy + (h - rows.min() + 1) * res)
    return (bx0, by0, bx1, by1)


def _far_apart(grid: MapObstacle, bounds, radius: float) -> tuple[FloatArray, FloatArray] | None:
    """Two far-apart cell centres of the largest region where a disc of ``radius`` fits."""
    from scipy import ndimage

    blocked = np.asarray(grid.blocked)
    res = grid.resolution
    # distance from a free cell's centre to the nearest blocked cell's centre, metres; the
    # nearest blocked point is at least that minus half a cell diagonal away
    dist = ndimage.distance_transform_edt(~blocked) * res - res * math.sqrt(0.5)
    centres = grid.free_centres()
    fits = np.zeros(blocked.shape, dtype=bool)
    i, j = np.nonzero(~blocked)
    xmin, ymin, xmax, ymax = bounds
    margin = radius * 1.1 + res
    inside = (
        (centres[:, 0] - xmin >= margin)
        & (xmax - centres[:, 0] >= margin)
        & (centres[:, 1] - ymin >= margin)
        & (ymax - centres[:, 1] >= margin)
    )
    fits[i, j] = inside & (dist[i, j] >= margin)
    labels, count = ndimage.label(fits)
    if count == 0:
        return None
    sizes = np.bincount(labels.ravel())[1:]
    keep = labels == (int(np.argmax(sizes)) + 1)
    h, _ = keep.shape
    ox, oy = grid.origin
    ki, kj = np.nonzero(keep)
    pts = np.stack([ox + (kj + 0.5) * res, oy + (h - 1 - ki + 0.5) * res], axis=1)
    a = pts[np.argmax(np.sum((pts - pts.mean(axis=0)) ** 2, axis=1))]
    b = pts[np.argmax(np.sum((pts - a) ** 2, axis=1))]
    a = pts[np.argmax(np.sum((pts - b) ** 2, axis=1))]
    return a, b


def map_scene(
    map_yaml: str | os.PathLike,
    scene_path: str | os.PathLike,
    robot_disc: float | None = None,
    robot_footprint: FloatArray | None = None,
    vmax: float = DEFAULT_VMAX,
    name: str | None = None,
    command: str = "",
) -> MapScene:
    """Write-ready scene text around a map.

    Parameters
    ----------
    map_yaml : path-like
        The map YAML file; it must lie inside the scene file's folder.
    scene_path : path-like
        Where the scene will be written (its folder anchors the map's relative path).
    robot_disc : float, optional
        A disc robot of this radius (default :data:`DEFAULT_DISC` without a footprint).
    robot_footprint : (n, 2) float, optional
        A footprint polygon in the robot's frame (poses then get a heading).
    vmax : float
    name : str, optional
        Scene name (default: the scene file's stem).
    command : str
        The command line, quoted in the file's first comment.

    Raises
    ------
    InputError
        A map outside the scene's folder, a bad robot.
    SceneError
        A bad map file.
    """
    scene_path = Path(scene_path)
    folder = scene_path.resolve().parent
    rel = os.path.relpath(Path(map_yaml).resolve(), folder)
    if rel.startswith(".."):
        raise InputError(
            f"{map_yaml}: the map must lie inside the scene file's folder ({folder}); "
            "write the scene beside the map or in a folder above it"
        )
    rel = Path(rel).as_posix()
    grid = load_map({"file": rel}, "map", str(map_yaml), folder)
    if robot_footprint is not None:
        fp = np.asarray(robot_footprint, dtype=float).reshape(-1, 2)
        radius = float(np.max(np.hypot(fp[:, 0], fp[:, 1])))
        pts = ", ".join(f"[{_fmt(x)}, {_fmt(y)}]" for x, y in fp)
        robot_line = f"  footprint: [{pts}]   # x forward, y left; poses are [x, y, heading]"
    else:
        radius = DEFAULT_DISC if robot_disc is None else float(robot_disc)
        if not (math.isfinite(radius) and radius > 0):
            raise InputError(f"--robot-disc must be a positive number, got {robot_disc!r}")
        robot_line = (
            f"  disc: {_fmt(radius)}   # or box: [length, width], or footprint: [[x, y], ...]"
        )
    bounds = _bounds(grid)
    pair = _far_apart(grid, bounds, radius)
    stem = name or re.sub(r"[^A-Za-z0-9_.-]", "-", scene_path.stem) or "map"
    lines = [
        f"# A scene around the map {rel} ({grid.shape[1]} x {grid.shape[0]} cells at {_fmt(grid.resolution)} m),",
        f"# written by: {command}" if command else "# written by gfuzzy map",
        "# Edit the robot, add movers, move the query; bounds keep the robot's whole body inside.",
        "version: 1",
        f"name: {plain_name(stem)}",
        "bounds: [" + ", ".join(_fmt(b) for b in bounds) + "]   # the map's known cells",
        "robot:",
        robot_line,
        f"  vmax: {_fmt(vmax)}",
        "obstacles:",
        f"  - map: {{file: {plain_name(rel, flow=True)}, unknown: blocked}}"
        "   # unknown cells block; 'free' to let them not",
    ]
    start = goal = None
    if pair is None:
        lines.append("# the robot fits nowhere on this map: no sample query")
    else:
        a, b = pair
        head = [0.0] if robot_footprint is not None else []
        start = tuple(float(v) for v in a) + tuple(head)
        goal = tuple(float(v) for v in b) + tuple(head)
        lines += [
            "queries:   # two far-apart points of the largest region the robot fits in",
            "  - name: across",
            "    start: [" + ", ".join(_fmt(v) for v in start) + "]",
            "    goal: [" + ", ".join(_fmt(v) for v in goal) + "]",
        ]
    return MapScene("\n".join(lines) + "\n", bounds, start, goal)
