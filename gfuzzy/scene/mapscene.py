"""``gfuzzy map``: a scene around an occupancy-grid map, ready to plan on and to edit.

The scene has the map as its one obstacle (its path relative to the scene file), bounds
around the map's known cells (free or occupied; unknown margins left out), a robot, and
one query between two far-apart points of the largest region the robot fits in.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError, check_number
from ..typed import FloatArray
from .maps import UNKNOWN, MapObstacle, load_map
from .yamldoc import NAME_RE, leaves_folder, name_from_stem, plain_name

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
    fit : str
        What had to fit for the query (e.g. "its footprint at heading 0").
    """

    text: str
    bounds: tuple[float, float, float, float]
    start: tuple | None
    goal: tuple | None
    fit: str = ""


def _fmt(x: float) -> str:
    """12 significant digits: a map far from the origin (UTM coordinates, 5,678,123.25 m)
    keeps its centimetres (6 digits wrote 5.67813e+06, ten metres off); no ``-0``."""
    return f"{x + 0.0:.12g}"


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


def _disc_fits(grid: MapObstacle, bounds, radius: float) -> np.ndarray:
    """(H, W) bool: free cells whose centre holds a disc of ``radius`` with a margin."""
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
    return fits


def _printable(text: str) -> str:
    """``text`` for a YAML comment: characters that would end the line or cannot be
    written (a line break, U+2028, DEL, an undecodable byte) written as escapes."""
    return "".join(c if c.isprintable() else ascii(c)[1:-1] for c in text)


def _box_fits(
    grid: MapObstacle, bounds, box: tuple[float, float, float, float], grow: float
) -> np.ndarray:
    """(H, W) bool: cells whose centre, as the robot's reference point at heading 0, keeps
    the box ``(x0, y0, x1, y1)`` of its footprint grown by ``grow`` clear of every blocked
    cell and inside ``bounds``.

    Every blocked cell the grown box could reach is counted (a window of cells at fixed
    offsets, summed with an integral image); cells beyond the grid count as blocked.
    """
    blocked = np.asarray(grid.blocked)
    h, w = blocked.shape
    res = grid.resolution
    x0, y0, x1, y1 = box
    # columns j + dj0 .. j + dj1 and rows (counted from the bottom) k + dk0 .. k + dk1
    dj0, dj1 = math.floor(0.5 + (x0 - grow) / res), math.floor(0.5 + (x1 + grow) / res)
    dk0, dk1 = math.floor(0.5 + (y0 - grow) / res), math.floor(0.5 + (y1 + grow) / res)
    if dj1 - dj0 >= w or dk1 - dk0 >= h:  # wider or taller than the whole grid
        return np.zeros((h, w), dtype=bool)
    up = blocked[::-1].astype(np.int32)  # row k from the bottom
    pl, pr, pb, pt = max(0, -dj0), max(0, dj1), max(0, -dk0), max(0, dk1)
    padded = np.pad(up, ((pb, pt), (pl, pr)), constant_values=1)
    s = np.zeros((padded.shape[0] + 1, padded.shape[1] + 1), dtype=np.int64)
    s[1:, 1:] = padded.cumsum(axis=0).cumsum(axis=1)
    k, j = np.arange(h)[:, None] + pb, np.arange(w)[None, :] + pl
    ka, kb, ja, jb = k + dk0, k + dk1 + 1, j + dj0, j + dj1 + 1
    count = s[kb, jb] - s[ka, jb] - s[kb, ja] + s[ka, ja]
    cx, cy = grid.centre_axes()
    cy = cy[::-1]  # rows from the bottom
    xmin, ymin, xmax, ymax = bounds
    in_x = (cx + x0 - grow >= xmin) & (cx + x1 + grow <= xmax)
    in_y = (cy + y0 - grow >= ymin) & (cy + y1 + grow <= ymax)
    fits_up = (count == 0) & in_y[:, None] & in_x[None, :]
    return fits_up[::-1]


def _far_apart(grid: MapObstacle, fits: np.ndarray) -> tuple[FloatArray, FloatArray] | None:
    """Two far-apart cell centres of the largest connected region of ``fits``."""
    from scipy import ndimage

    labels, count = ndimage.label(fits)
    if count == 0:
        return None
    sizes = np.bincount(labels.ravel())[1:]
    ki, kj = np.nonzero(labels == (int(np.argmax(sizes)) + 1))
    cx, cy = grid.centre_axes()
    pts = np.stack([cx[kj], cy[ki]], axis=1)
    a = pts[np.argmax(np.sum((pts - pts.mean(axis=0)) ** 2, axis=1))]
    b = pts[np.argmax(np.sum((pts - a) ** 2, axis=1))]
    a = pts[np.argmax(np.sum((pts - b) ** 2, axis=1))]
    return a, b


def _robot(robot_disc, robot_footprint) -> tuple[FloatArray | None, float, str]:
    """The footprint (or None), the circumscribed radius and the scene's robot line."""
    if robot_footprint is not None:
        fp = np.asarray(robot_footprint, dtype=float).reshape(-1, 2)
        radius = float(np.max(np.hypot(fp[:, 0], fp[:, 1])))
        pts = ", ".join(f"[{_fmt(x)}, {_fmt(y)}]" for x, y in fp)
        return fp, radius, f"  footprint: [{pts}]   # x forward, y left; poses are [x, y, heading]"
    radius = DEFAULT_DISC if robot_disc is None else float(robot_disc)
    if not (math.isfinite(radius) and radius > 0):
        raise InputError(f"--robot-disc must be a positive number, got {robot_disc!r}")
    return (
        None,
        radius,
        f"  disc: {_fmt(radius)}   # or box: [length, width], or footprint: [[x, y], ...]",
    )


def _fits(grid: MapObstacle, bounds, fp, radius: float, kinematics: str) -> tuple[np.ndarray, str]:
    """Where the sample query's robot fits (``map_scene``'s Notes), and what had to fit."""
    if fp is not None and kinematics == "holonomic":
        box = (*fp.min(axis=0), *fp.max(axis=0))
        return _box_fits(
            grid, bounds, box, grow=radius * 0.1 + grid.resolution
        ), "its footprint at heading 0"
    fits = _disc_fits(grid, bounds, radius)
    if fp is not None:
        return fits, f"its circumscribed disc, radius {radius:.4g}, to turn in place"
    return fits, f"a disc of radius {radius:.4g}"


def _kinematics_lines(kinematics: str, reverse: bool, wmax: float | None = None) -> list[str]:
    """The robot's ``kinematics``, ``wmax`` and ``reverse`` lines of a map's scene (none for a
    holonomic robot)."""
    if kinematics != "unicycle":
        return []
    drive = "  kinematics: unicycle   # a differential drive: turns in place, straight moves"
    turn = [] if wmax is None else [f"  wmax: {_fmt(wmax)}   # bound on its turning rate, rad/s"]
    if reverse:
        return [drive, *turn, "  reverse: true   # it may also drive backwards"]
    return [drive + ", forwards only (reverse: true to back up)", *turn]


def _check_drive(kinematics: str, reverse: bool, wmax: float | None) -> None:
    """The drive's options of :func:`map_scene`, refused (InputError) by the flags' names."""
    if kinematics not in ("holonomic", "unicycle"):
        raise InputError(f"--kinematics: expected holonomic or unicycle, got {kinematics!r}")
    if reverse and kinematics != "unicycle":  # as the scene file's own rule (and gfuzzy crowd's)
        raise InputError("--reverse needs --kinematics unicycle (only a differential drive drives backwards)")
    if wmax is not None:
        if kinematics != "unicycle":  # the scene file's rule, as --reverse's
            raise InputError("--wmax needs --kinematics unicycle (a turning-rate bound is a differential drive's)")
        check_number("--wmax", wmax)


def map_scene(
    map_yaml: str | os.PathLike,
    scene_path: str | os.PathLike,
    robot_disc: float | None = None,
    robot_footprint: FloatArray | None = None,
    vmax: float = DEFAULT_VMAX,
    name: str | None = None,
    command: str = "",
    kinematics: str = "holonomic",
    reverse: bool = False,
    wmax: float | None = None,
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
    kinematics : {"holonomic", "unicycle"}
        A differential drive gets ``kinematics: unicycle`` and poses with a heading (a disc
        included).
    reverse, wmax : bool, float or None
        The differential drive may also drive backwards (``reverse: true``); its bound on the
        turning rate (rad/s; default the scene file's, vmax / r). Only with ``kinematics="unicycle"``.

    Notes
    -----
    The sample query joins two far-apart points of the largest connected region of cells
    where the robot fits with a margin: a disc robot's disc; a footprint robot's footprint
    at heading 0, as the bounding box of the polygon (it can translate through that region
    without turning); a differential drive's circumscribed disc (it turns in place).

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
    if leaves_folder(rel):
        raise InputError(
            f"{map_yaml}: the map must lie inside the scene file's folder ({folder}); "
            "write the scene beside the map or in a folder above it"
        )
    rel = Path(rel).as_posix()
    _check_drive(kinematics, reverse, wmax)
    if name is not None and not NAME_RE.match(name):  # before the map is read, and as gfuzzy tracks says it
        raise InputError(f"name must be letters, digits, _ . - (got {name!r})")
    grid = load_map({"file": rel}, "map", str(map_yaml), folder)
    fp, radius, robot_line = _robot(robot_disc, robot_footprint)
    bounds = _bounds(grid)
    fits, fit = _fits(grid, bounds, fp, radius, kinematics)
    pair = _far_apart(grid, fits)
    stem = name or name_from_stem(scene_path.stem, "map")
    lines = [
        f"# A scene around the map {_printable(rel)} ({grid.shape[1]} x {grid.shape[0]} cells at {_fmt(grid.resolution)} m),",
        f"# written by: {_printable(command)}" if command else "# written by gfuzzy map",
        "# Edit the robot, add movers, move the query; bounds keep the robot's whole body inside.",
        "version: 1",
        f"name: {plain_name(stem)}",
        "bounds: [" + ", ".join(_fmt(b) for b in bounds) + "]   # the map's known cells",
        "robot:",
        robot_line,
        f"  vmax: {_fmt(vmax)}",
        *_kinematics_lines(kinematics, reverse, wmax),
        "obstacles:",
        f"  - map: {{file: {plain_name(rel, flow=True)}, unknown: blocked}}"
        "   # unknown cells block; 'free' to let them not",
    ]
    start = goal = None
    if pair is None:
        lines.append("# the robot fits nowhere on this map: no sample query")
    else:
        a, b = pair
        head = [0.0] if robot_footprint is not None or kinematics == "unicycle" else []
        start = tuple(float(v) for v in a) + tuple(head)
        goal = tuple(float(v) for v in b) + tuple(head)
        lines += [
            "queries:   # two far-apart points of the largest region the robot fits in",
            "  - name: across",
            "    start: [" + ", ".join(_fmt(v) for v in start) + "]",
            "    goal: [" + ", ".join(_fmt(v) for v in goal) + "]",
        ]
    return MapScene("\n".join(lines) + "\n", bounds, start, goal, fit)
