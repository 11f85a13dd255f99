"""Drawing helpers of the pictures and animations (:mod:`gfuzzy.render.render`, :mod:`gfuzzy.render.animate`).

The colours, the figure, and one function per layer: obstacles, roadmap, movers, queries,
the robot's trajectory (path, footprints, time stamps, waits), a violation, the legend;
and the small trajectory helpers they share (:func:`as_waypoints`, :func:`poses_at_times`,
:func:`segment_speeds`, :func:`wait_intervals`). Matplotlib through
:class:`matplotlib.figure.Figure` and the Agg canvas only, never ``pyplot``.
"""

from __future__ import annotations

import logging
import math
import os
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib import colormaps
from matplotlib.artist import Artist
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.patches import Circle, PathPatch, Rectangle
from matplotlib.patches import Polygon as PolygonPatch
from matplotlib.path import Path as MplPath

from ..errors import InputError
from ..poses import row_words, wrap_angle
from ..scene.scene import Box, Disc, MapObstacle, Mover, Polygon, Scene
from ..trajectory import Trajectory
from ..typed import FloatArray

__all__ = ["as_waypoints", "poses_at_times", "segment_speeds", "wait_intervals"]

log = logging.getLogger(__name__)
log.addHandler(logging.NullHandler())

#: Suffixes each renderer writes (lower case).
PICTURE_SUFFIXES = (".png", ".gif")
ANIMATION_SUFFIXES = (".gif",)

OBSTACLE_FACE = "#8c8c8c"
OBSTACLE_EDGE = "#4d4d4d"
ROADMAP_COLOR = "#9ecae1"
ROBOT_COLOR = "#1f3b73"
START_COLOR = "#2bb24c"
GOAL_COLOR = "#ffcc00"
WAIT_COLOR = "#d62728"
#: The first violation of the guarantees of a drawn, invalid trajectory.
VIOLATION_COLOR = "#ff00ff"
#: Mover colours: tab10 without its blue (the robot's hue), grey (the obstacles') and red
#: (the waits').
MOVER_COLORS = ("#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#bcbd22", "#17becf")
SPEED_CMAP = "RdYlGn"
#: Movers beyond this count are grouped into one legend entry per kind.
MAX_LEGEND_MOVERS = 8
#: Pose tolerance under which two consecutive rows count as a wait.
WAIT_TOL = 1e-9


# --------------------------------------------------------------------------- trajectories


def as_waypoints(trajectory: Any, scene: Scene | None = None) -> FloatArray:
    """The waypoint array of a trajectory.

    Parameters
    ----------
    trajectory : array-like, object with ``.waypoints``, or mapping with ``"waypoints"``
        Rows ``[t, x, y]`` (holonomic disc robot) or ``[t, x, y, heading]`` (any other robot),
        t strictly increasing (docs/formats.md section 2).
    scene : Scene, optional
        When given, the row length must match its robot.

    Returns
    -------
    (n, 3) or (n, 4) float

    Raises
    ------
    ValueError
        Not a list of rows of 3 or 4 finite numbers, no rows, t not strictly increasing,
        or a row length that does not fit the scene's robot.
    """
    if isinstance(trajectory, dict):
        if "waypoints" not in trajectory:
            raise InputError("trajectory has no 'waypoints'")
        trajectory = trajectory["waypoints"]
    elif hasattr(trajectory, "waypoints"):
        trajectory = trajectory.waypoints
    try:
        wp = np.asarray(trajectory, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"trajectory waypoints are not a table of numbers ({exc})") from None
    if wp.ndim != 2 or wp.shape[1] not in (3, 4):
        raise InputError(
            f"trajectory waypoints must be rows [t, x, y] or [t, x, y, heading], got shape {wp.shape}"
        )
    if len(wp) == 0:
        raise InputError("trajectory has no waypoints (only a solved trajectory can be drawn)")
    if not np.all(np.isfinite(wp)):
        raise InputError("trajectory waypoints contain a non-finite number")
    bad = np.nonzero(np.diff(wp[:, 0]) <= 0)[0]
    if bad.size:
        j = int(bad[0]) + 1
        raise InputError(f"trajectory waypoints[{j}]: t={wp[j, 0]:g} does not increase")
    if scene is not None and wp.shape[1] != scene.robot.dof + 1:
        raise InputError(
            f"trajectory rows have {wp.shape[1]} numbers but scene {scene.name!r} expects "
            f"{row_words(scene.robot.dof, scene.robot)}"
        )
    return wp


def poses_at_times(waypoints: FloatArray, times: FloatArray) -> FloatArray:
    """Robot poses at ``times`` (clamped to the trajectory): :meth:`Trajectory.at`.

    Returns
    -------
    (k, 2) or (k, 3) float
    """
    return Trajectory(np.asarray(waypoints, dtype=float)).at(np.atleast_1d(np.asarray(times, dtype=float)))


def segment_speeds(waypoints: FloatArray, circumradius: float = 0.0) -> FloatArray:
    """Configuration speed of every segment (docs/formats.md section 3): :meth:`Trajectory.speeds`."""
    return Trajectory(np.asarray(waypoints, dtype=float), circumradius).speeds()


def wait_intervals(
    waypoints: FloatArray, tol: float = WAIT_TOL
) -> list[tuple[float, float, FloatArray]]:
    """Where the robot waits: runs of consecutive rows with the same pose.

    Returns
    -------
    list of (t_begin, t_end, pose)
        ``pose`` is ``[x, y(, heading)]``.
    """
    wp = np.asarray(waypoints, dtype=float)
    if len(wp) < 2:
        return []
    d = np.abs(np.diff(wp[:, 1:], axis=0))
    if wp.shape[1] == 4:
        d[:, 2] = np.abs(wrap_angle(d[:, 2]))
    still = np.all(d <= tol, axis=1)
    out = []
    i = 0
    while i < len(still):
        if still[i]:
            j = i
            while j + 1 < len(still) and still[j + 1]:
                j += 1
            out.append((float(wp[i, 0]), float(wp[j + 1, 0]), wp[i, 1:].copy()))
            i = j + 1
        else:
            i += 1
    return out


# --------------------------------------------------------------------------- output files


def _suffix(out_path: str | os.PathLike, allowed: tuple[str, ...], what: str) -> str:
    suffix = Path(out_path).suffix.lower()
    if suffix not in allowed:
        raise InputError(
            f"{out_path}: cannot write {what} as {suffix or 'a file without suffix'!r}; "
            f"use {' or '.join(allowed)}"
        )
    return suffix


# --------------------------------------------------------------------------- drawing


def _figure(scene: Scene, width: float, colorbar: bool, legend_rows: int) -> tuple[Figure, Any]:
    """A figure whose axes fit the scene's aspect, with room for labels and a legend."""
    xmin, ymin, xmax, ymax = scene.bounds
    aspect = (ymax - ymin) / (xmax - xmin)
    ax_w = width - 0.9 - (1.1 if colorbar else 0.0)
    ax_h = ax_w * aspect
    if ax_h > 1.4 * width:  # a tall scene: cap the height, narrow the axes
        ax_h = 1.4 * width
    fig_h = max(ax_h, 1.5) + 1.0 + 0.3 * legend_rows
    fig = Figure(figsize=(width, fig_h), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    # "datalim": the axes fill the space the layout gives them and the view widens in one
    # direction instead, so an estimate of the margins above never clips the title or legend.
    ax.set_aspect("equal", adjustable="datalim")
    # No fixed limits (they would fight "datalim"): the view autoscales to the bounds
    # rectangle, which _draw_obstacles adds first, and to anything drawn beyond it.
    ax.margins(0.03)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    return fig, ax


def _ring(points: FloatArray, ccw: bool) -> FloatArray:
    pts = np.asarray(points, dtype=float)
    area = 0.5 * np.sum(pts[:, 0] * np.roll(pts[:, 1], -1) - np.roll(pts[:, 0], -1) * pts[:, 1])
    return pts if (area > 0) == ccw else pts[::-1]


def _polygon_patch(poly: Polygon, **kw) -> PathPatch:
    """A patch of a polygon with holes (holes wound against the exterior)."""
    verts, codes = [], []
    for ring in [_ring(poly.points, True)] + [_ring(h, False) for h in poly.holes]:
        verts.extend(ring.tolist() + [ring[0].tolist()])
        codes.extend([MplPath.MOVETO] + [MplPath.LINETO] * (len(ring) - 1) + [MplPath.CLOSEPOLY])
    return PathPatch(MplPath(verts, codes), **kw)


def _draw_obstacles(ax, scene: Scene) -> None:
    xmin, ymin, xmax, ymax = scene.bounds
    ax.add_patch(
        Rectangle((xmin, ymin), xmax - xmin, ymax - ymin, fill=False, ec="black", lw=1.5, zorder=1)
    )
    style = dict(fc=OBSTACLE_FACE, ec=OBSTACLE_EDGE, lw=0.8, zorder=2)
    for k, ob in enumerate(scene.obstacles):
        label = "static obstacle" if k == 0 else None
        if isinstance(ob, Disc):
            ax.add_patch(Circle(ob.center, ob.radius, label=label, **style))
        elif isinstance(ob, Box):
            ax.add_patch(PolygonPatch(ob.vertices(), closed=True, label=label, **style))
        elif isinstance(ob, Polygon):
            ax.add_patch(_polygon_patch(ob, label=label, **style))
        elif isinstance(ob, MapObstacle):
            _draw_map(ax, ob, scene.bounds)


MAP_OCCUPIED = (0.30, 0.30, 0.30, 1.0)  # OBSTACLE_EDGE
MAP_UNKNOWN = (0.72, 0.72, 0.72, 1.0)  # blocking unknown cells; free unknown ones are paler
MAP_UNKNOWN_FREE = (0.72, 0.72, 0.72, 0.35)


def _draw_map(ax, grid: MapObstacle, bounds) -> None:
    """The grid's cells that meet the bounds, at their true extent: occupied dark,
    unknown gray, costs (scale / raw modes) a transparent gray by value, free cells
    transparent."""
    h, w = grid.shape
    ox, oy = grid.origin
    res = grid.resolution
    c0 = max(0, math.floor((bounds[0] - ox) / res))
    c1 = min(w, math.ceil((bounds[2] - ox) / res))
    k0 = max(0, math.floor((bounds[1] - oy) / res))  # rows counted from the bottom
    k1 = min(h, math.ceil((bounds[3] - oy) / res))
    if c0 >= c1 or k0 >= k1:
        return
    values = np.asarray(grid.values)[h - k1 : h - k0, c0:c1]
    rgba = np.zeros(values.shape + (4,), dtype=np.float32)  # half the bytes of a big map
    cost = (values > 0) & (values < 100)
    rgba[cost] = (0.3, 0.3, 0.3, 0.0)
    rgba[cost, 3] = 0.6 * values[cost] / 100.0
    rgba[values == 100] = MAP_OCCUPIED
    rgba[values == -1] = MAP_UNKNOWN_FREE if grid.unknown_free else MAP_UNKNOWN
    extent = (ox + c0 * res, ox + c1 * res, oy + k0 * res, oy + k1 * res)
    ax.imshow(rgba, extent=extent, origin="upper", interpolation="nearest", zorder=1.8)


def _draw_roadmap(ax, roadmap) -> None:
    v = np.asarray(roadmap.vertices, dtype=float)[:, :2]
    e = np.asarray(roadmap.edges, dtype=np.int64).reshape(-1, 2)
    if len(e):
        ax.add_collection(
            LineCollection(v[e], colors=ROADMAP_COLOR, linewidths=0.5, alpha=0.8, zorder=1.5)
        )
    ax.scatter(
        v[:, 0],
        v[:, 1],
        s=3,
        color=ROADMAP_COLOR,
        edgecolors="none",
        zorder=1.6,
        label=f"roadmap ({len(v)} vertices, {len(e)} edges)",
    )


def _mover_patch(mover: Mover, xy, color: str, **kw):
    if mover.shape == "disc":
        return Circle(xy, mover.radius, fc=color, ec=color, **kw)
    w, h = mover.size
    return Rectangle((xy[0] - w / 2, xy[1] - h / 2), w, h, fc=color, ec=color, **kw)


def _move_patch(patch, mover: Mover, xy) -> None:
    if mover.shape == "disc":
        patch.set_center(xy)
    else:
        patch.set_xy((xy[0] - mover.size[0] / 2, xy[1] - mover.size[1] / 2))


def _mover_color(i: int) -> str:
    return MOVER_COLORS[i % len(MOVER_COLORS)]


def _draw_movers(ax, scene: Scene, marker: bool = True) -> None:
    """Movers' paths, direction arrows and their shape at t = 0 (or first row)."""
    many = len(scene.movers) > MAX_LEGEND_MOVERS
    n_path = sum(m.trajectory is None for m in scene.movers)
    n_timed = len(scene.movers) - n_path
    first_path = first_timed = True
    for i, m in enumerate(scene.movers):
        color = _mover_color(i)
        if m.trajectory is None:
            label = f"mover {m.name} ({m.mode}, {m.speed:g} m/s)"
            if many:
                label = f"path movers ({n_path})" if first_path else None
                first_path = False
            pts = m._polyline
            ax.plot(pts[:, 0], pts[:, 1], ls="--", lw=1.2, color=color, zorder=3, label=label)
            _draw_arrows(ax, pts, color, both=m.mode == "bounce")
            xy0 = m.state([0.0])[0][0]
        else:
            label = f"mover {m.name} (t {m.time_range[0]:g} to {m.time_range[1]:g} s)"
            if many:
                label = f"timed movers ({n_timed})" if first_timed else None
                first_timed = False
            tr = m.trajectory
            ax.plot(
                tr[:, 1], tr[:, 2], ls="-", lw=0.7, color=color, alpha=0.8, zorder=3, label=label
            )
            if len(tr) >= 2:
                _draw_arrows(ax, tr[:, 1:], color, both=False, max_arrows=1)
            xy0 = tr[0, 1:]
        if marker:
            ax.add_patch(_mover_patch(m, xy0, color, alpha=0.35, lw=1.0, zorder=3.1))
            ax.plot(*xy0, marker="o", ms=3, color=color, zorder=3.2)


def _draw_arrows(ax, pts: FloatArray, color: str, both: bool, max_arrows: int = 6) -> None:
    """Arrows at the middle of the longest segments, pointing along the polyline."""
    seg = np.diff(pts, axis=0)
    length = np.hypot(seg[:, 0], seg[:, 1])
    if not np.any(length > 0):
        return
    order = np.argsort(-length, kind="stable")[:max_arrows]
    for k in sorted(order):
        if length[k] <= 0:
            continue
        mid = pts[k] + 0.5 * seg[k]
        u = seg[k] / length[k] * min(0.2 * length[k], 0.15)
        ax.annotate(
            "",
            xy=mid + u,
            xytext=mid - u,
            zorder=3.2,
            arrowprops=dict(
                arrowstyle="<|-|>" if both else "-|>",
                color=color,
                lw=1.2,
                mutation_scale=10,
                shrinkA=0,
                shrinkB=0,
            ),
        )


def _footprint(scene: Scene, pose, **kw):
    """A patch of the robot at ``pose`` (a box or footprint robot turned by its heading)."""
    if scene.robot.shape == "disc":
        return Circle(pose[:2], scene.robot.radius, **kw)
    return PolygonPatch(scene.robot.corners(np.asarray(pose)[None, :3])[0], closed=True, **kw)


def _inflated_xy(scene: Scene, pose, margin: float) -> FloatArray:
    """(k, 2): outline of the robot at ``pose`` grown by ``margin`` (rounded corners)."""
    import shapely

    corners = scene.robot.corners(np.asarray(pose)[None, :3])[0]
    return np.asarray(shapely.Polygon(corners).buffer(margin, quad_segs=4).exterior.coords)


def _clearance_outline(scene: Scene, pose, margin: float, **kw):
    """A dashed-outline patch of the robot grown by a clearance (None when it is 0)."""
    if margin <= 0:
        return None
    kw = {"fill": False, "ls": "--", "lw": 0.8, **kw}
    if scene.robot.shape == "disc":
        return Circle(pose[:2], scene.robot.radius + margin, **kw)
    return PolygonPatch(_inflated_xy(scene, pose, margin), closed=True, **kw)


def _heading_tick(scene: Scene, pose) -> FloatArray:
    """(2, 2): reference point to the front of a robot with a heading (a box; a footprint:
    its farthest vertex along the heading, the circumradius when none is ahead; a unicycle
    disc: to its rim)."""
    if scene.robot.shape == "footprint":
        half = max(x for x, _ in scene.robot.footprint)
        half = half if half > 0 else scene.robot.circumradius
    else:
        half = scene.robot.radius if scene.robot.shape == "disc" else 0.5 * scene.robot.size[0]
    front = [pose[0] + half * math.cos(pose[2]), pose[1] + half * math.sin(pose[2])]
    return np.array([pose[:2], front])


def _draw_queries(ax, scene: Scene) -> None:
    for k, q in enumerate(scene.queries):
        for pose, color, mk, what in (
            (q.start, START_COLOR, "o", "start"),
            (q.goal, GOAL_COLOR, "*", "goal"),
        ):
            ax.add_patch(_footprint(scene, pose, fill=False, ec=color, lw=1.0, ls=":", zorder=4))
            if scene.robot.dof == 3:  # a box, a footprint, or any unicycle: its heading
                tick = _heading_tick(scene, pose)
                ax.plot(tick[:, 0], tick[:, 1], color=color, lw=1.0, zorder=4)
            ax.plot(
                pose[0],
                pose[1],
                marker=mk,
                ms=11 if mk == "*" else 8,
                mfc=color,
                mec="black",
                mew=0.8,
                ls="none",
                zorder=6,
                label=what if k == 0 else None,
            )
    if len(scene.queries) > 1:  # one label per start: names of queries leaving one place were printed over each other
        at: dict = {}
        for q in scene.queries:
            at.setdefault(tuple(q.start[:2]), []).append(q.name)
        for xy, names in at.items():
            ax.annotate(", ".join(names), xy, xytext=(4, 4), textcoords="offset points", fontsize=7, zorder=6)


def _nice_step(duration: float, target: int = 8) -> float:
    """A round time step giving about ``target`` stamps over ``duration``."""
    if duration <= 0:
        return 1.0
    raw = duration / target
    mag = 10 ** math.floor(math.log10(raw))
    for f in (1, 2, 2.5, 5, 10):
        if f * mag >= raw:
            return f * mag
    return 10 * mag


def _fmt_time(t: float) -> str:
    if abs(t) >= 1e6:  # '.2f' wrote 1e300 as 301 digits: the title squeezed the axes to nothing
        return f"{t:.3g}"
    return f"{t:.2f}".rstrip("0").rstrip(".")


def _speed_values(speed, wp: FloatArray, scene: Scene) -> FloatArray:
    """Per-segment speeds from ``speed``: True, (n - 1,) per segment or (n,) per waypoint."""
    n = len(wp)
    if speed is True:
        return segment_speeds(wp, scene.robot.circumradius)
    v = np.asarray(speed, dtype=float).ravel()
    if v.size == n - 1:
        return v
    if v.size == n:
        return 0.5 * (v[:-1] + v[1:])
    raise InputError(
        f"speed has {v.size} values; the trajectory has {n} waypoints ({n - 1} segments)"
    )


def _draw_trajectory(ax, fig, scene: Scene, wp: FloatArray, speed, footprints: int) -> None:
    """The robot's trajectory in layers: path, footprints, time stamps, waits."""
    _draw_path(ax, fig, scene, wp, speed)
    _draw_footprints(ax, scene, wp, footprints)
    waits = wait_intervals(wp)
    _draw_stamps(ax, wp, waits)
    _draw_waits(ax, scene, waits)


def _draw_path(ax, fig, scene: Scene, wp: FloatArray, speed) -> None:
    """The path, coloured by speed (with a colour bar) when ``speed`` is given."""
    t0, t1 = float(wp[0, 0]), float(wp[-1, 0])
    xy = wp[:, 1:3]
    label = f"robot path ({_fmt_time(t1 - t0)} s)"
    if speed is not None and speed is not False and len(wp) >= 2:
        v = _speed_values(speed, wp, scene)
        vmax = max(scene.robot.vmax, float(np.max(v)) if v.size else 0.0)
        segs = np.stack([xy[:-1], xy[1:]], axis=1)
        ax.add_collection(LineCollection(segs, colors="black", linewidths=3.6, zorder=4.9))
        lc = LineCollection(
            segs,
            cmap=colormaps[SPEED_CMAP],
            norm=Normalize(0.0, vmax),
            linewidths=2.4,
            zorder=5,
            capstyle="round",
        )
        lc.set_array(v)
        ax.add_collection(lc)
        fig.colorbar(lc, ax=ax, shrink=0.8, pad=0.02, label="robot speed [m/s]")
        ax.plot(
            [], [], color=colormaps[SPEED_CMAP](0.85), lw=2.4, label=label + ", coloured by speed"
        )
    else:
        ax.plot(xy[:, 0], xy[:, 1], color=ROBOT_COLOR, lw=2.0, zorder=5, label=label)


def _draw_footprints(ax, scene: Scene, wp: FloatArray, footprints: int) -> None:
    """``footprints`` robot outlines along the trajectory, with the clearances kept."""
    t0, t1 = float(wp[0, 0]), float(wp[-1, 0])
    # footprints, evenly spaced in time, start and end included
    times = np.linspace(t0, t1, max(2, footprints)) if t1 > t0 else np.array([t0])
    poses = poses_at_times(wp, times)
    for k, pose in enumerate(poses):
        ax.add_patch(
            _footprint(
                scene,
                pose,
                fc=ROBOT_COLOR,
                ec=ROBOT_COLOR,
                alpha=0.18,
                lw=1.0,
                zorder=4.5,
                label="robot footprint" if k == 0 else None,
            )
        )
        if scene.robot.dof == 3:
            tick = _heading_tick(scene, pose)
            ax.plot(tick[:, 0], tick[:, 1], color=ROBOT_COLOR, lw=1.0, zorder=4.6)
        # the clearances kept: from static obstacles (dashed), from movers (dotted)
        for margin, ls, what in ((scene.robot.clearance, "--", "static"), (scene.robot.mover_clearance, ":", "mover")):
            ring = _clearance_outline(scene, pose, margin, ec=ROBOT_COLOR, ls=ls, zorder=4.5,
                                      label=f"{what} clearance {margin:g} m" if k == 0 else None)  # fmt: skip
            if ring is not None:
                ax.add_patch(ring)


def _draw_stamps(ax, wp: FloatArray, waits) -> None:
    """Time stamps along the path, none inside a wait (its label gives its times)."""
    t0, t1 = float(wp[0, 0]), float(wp[-1, 0])
    # time stamps every `step` seconds
    step = _nice_step(t1 - t0)
    stamps = np.arange(math.ceil(t0 / step - 1e-9) * step, t1 + 1e-9, step)
    if t1 > t0 and (not stamps.size or t1 - stamps[-1] > 0.3 * step):
        stamps = np.append(stamps, t1)
    for ta, tb, _ in waits:  # the wait's own label gives its times; stamps there would pile up
        stamps = stamps[(stamps <= ta) | (stamps > tb)]
    spos = poses_at_times(wp, stamps)
    ax.plot(
        spos[:, 0],
        spos[:, 1],
        ls="none",
        marker="o",
        ms=3.5,
        mfc="white",
        mec="black",
        mew=0.7,
        zorder=6,
    )
    for t, p in zip(stamps, spos, strict=True):
        ax.annotate(
            f"t={_fmt_time(t)}",
            p[:2],
            xytext=(4, -10),
            textcoords="offset points",
            fontsize=7,
            zorder=7,
            bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.75),
        )


def _draw_waits(ax, scene: Scene, waits) -> None:
    """A marker per wait, and a label per group of waits close together."""
    # waits: a marker each; one label per group of waits close together (the short stops
    # of a dodge), placed clear of the other texts and markers when the figure is drawn
    for k, (_, _, pose) in enumerate(waits):
        ax.plot(
            pose[0],
            pose[1],
            marker="H",
            ms=WAIT_MARKER_SIZE,
            mfc="none",
            mec=WAIT_COLOR,
            mew=1.8,
            ls="none",
            zorder=6.5,
            label="wait" if k == 0 else None,
        )
    xmin, ymin, xmax, ymax = scene.bounds
    labels = []
    for group in _wait_groups(waits, WAIT_GROUP_SPAN * max(xmax - xmin, ymax - ymin)):
        anchor = np.mean([waits[k][2][:2] for k in group], axis=0)
        label = ax.annotate(
            "\n".join(
                f"wait {_fmt_time(waits[k][1] - waits[k][0])} s (t={_fmt_time(waits[k][0])} to {_fmt_time(waits[k][1])})"
                for k in group
            ),
            anchor,
            xytext=WAIT_LABEL_PLACES[0][:2],  # up-left: the time stamps sit down-right
            textcoords="offset points",
            ha=WAIT_LABEL_PLACES[0][2],
            va=WAIT_LABEL_PLACES[0][3],
            fontsize=7,
            color=WAIT_COLOR,
            zorder=7,
            bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.75),
            # a leader line, shown only when the label had to move away from its waits
            arrowprops=dict(arrowstyle="-", color=WAIT_COLOR, lw=0.6, shrinkA=0, shrinkB=WAIT_MARKER_SIZE / 2),
        )
        label.arrow_patch.set_visible(False)
        labels.append(label)
    if labels:
        ax.add_artist(_LabelLayout(labels, [w[2][:2] for w in waits]))


#: Marker size (points) of a wait.
WAIT_MARKER_SIZE = 12
#: Waits closer than this fraction of the scene's larger side share one label.
WAIT_GROUP_SPAN = 0.04
#: Places tried for a wait label, in order: (dx, dy) in points from its wait, horizontal and
#: vertical alignment. Beside the wait first, then further above and below.
WAIT_LABEL_PLACES = [
    (dx, sign * (4 + 11 * k), ha, "bottom" if sign > 0 else "top")
    for k in range(9)
    for sign in (1, -1)
    for dx, ha in ((-8, "right"), (8, "left"))
]


def _wait_groups(waits, radius: float) -> list[list[int]]:
    """Indices of the waits grouped by proximity (single linkage: a wait within ``radius``
    of any member joins the group), each group in time order, groups by first wait."""
    parent = list(range(len(waits)))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(len(waits)):
        for j in range(i):
            if np.hypot(*(waits[i][2][:2] - waits[j][2][:2])) <= radius:
                parent[root(i)] = root(j)
    groups: dict = {}
    for i in range(len(waits)):
        groups.setdefault(root(i), []).append(i)
    return sorted(groups.values(), key=lambda g: g[0])


class _LabelLayout(Artist):
    """Places the wait labels when the figure is drawn, once its layout is final.

    Each label, in time order, takes the first of :data:`WAIT_LABEL_PLACES` that overlaps
    no other text of the axes (time stamps, labels placed before it) nor a wait's marker,
    and stays in view; a label moved off its wait gets a leader line.
    """

    def __init__(self, labels, markers):
        super().__init__()
        self.labels = labels
        self.markers = np.asarray(markers, dtype=float).reshape(-1, 2)
        self.set_zorder(6.99)  # drawn (laid out) just before the texts, at zorder 7
        self.set_in_layout(False)  # it draws nothing itself

    def draw(self, renderer) -> None:
        from matplotlib.text import Text
        from matplotlib.transforms import Bbox

        ax = self.axes
        view = ax.bbox
        half = renderer.points_to_pixels(WAIT_MARKER_SIZE / 2)
        placed = [
            Bbox.from_extents(x - half, y - half, x + half, y + half)
            for x, y in ax.transData.transform(self.markers)
        ]
        placed += [
            Text.get_window_extent(t, renderer).padded(2)
            for t in ax.texts
            if t not in self.labels and t.get_visible() and t.get_text()
        ]
        for label in self.labels:
            best = None
            for rank, place in enumerate(WAIT_LABEL_PLACES):
                dx, dy, ha, va = place
                label.xyann = (dx, dy)
                label.set_ha(ha)
                label.set_va(va)
                label.update_positions(renderer)
                box = Text.get_window_extent(label, renderer)
                hits = sum(box.overlaps(other) for other in placed)
                inside = view.x0 <= box.x0 and box.x1 <= view.x1 and view.y0 <= box.y0 and box.y1 <= view.y1
                score = (hits, not inside, rank)
                if best is None or score < best[0]:
                    best = (score, place, box)
                if hits == 0 and inside:
                    break
            _, (dx, dy, ha, va), box = best
            label.xyann = (dx, dy)
            label.set_ha(ha)
            label.set_va(va)
            label.arrow_patch.set_visible(abs(dy) > 4)
            placed.append(box.padded(2))
        self.stale = False


def _draw_violation(ax, scene: Scene, wp: FloatArray, t: float, reason: str) -> None:
    """The robot where a check found the first violation, crossed out."""
    pose = poses_at_times(wp, [t])[0]
    ax.add_patch(_footprint(scene, pose, fc="none", ec=VIOLATION_COLOR, lw=2.0, zorder=8))
    ax.plot(
        pose[0],
        pose[1],
        marker="X",
        ms=11,
        mfc=VIOLATION_COLOR,
        mec="white",
        mew=0.8,
        ls="none",
        zorder=8.1,
        label="first violation of the guarantees",
    )
    ax.annotate(
        textwrap.fill(reason, 48),
        pose[:2],
        xytext=(10, -10),
        textcoords="offset points",
        va="top",
        fontsize=7,
        color=VIOLATION_COLOR,
        zorder=8.2,
        bbox=dict(boxstyle="round,pad=0.2", fc="white", ec=VIOLATION_COLOR, lw=0.6, alpha=0.9),
    )


def _legend(fig, ax) -> None:
    """One legend below the axes; the constrained layout makes room for it."""
    handles, labels = ax.get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=7, frameon=False)


def _legend_rows(scene: Scene, roadmap, wp) -> int:
    movers = len(scene.movers) if len(scene.movers) <= MAX_LEGEND_MOVERS else 2
    n = 1 + movers + (1 if roadmap is not None else 0) + (2 if scene.queries else 0)
    n += 3 if wp is not None else 0
    if wp is not None:  # the clearance outlines
        n += (scene.robot.clearance > 0) + (scene.robot.mover_clearance > 0)
    return math.ceil(n / 3)
