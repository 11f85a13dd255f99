"""Pictures and animations of scenes, roadmaps and trajectories.

:func:`render_scene` draws a still picture (PNG): the bounds, the static obstacles, an
optional roadmap, the movers' paths, the queries and, when given, the robot's trajectory
with footprints, time stamps, waits and, optionally, its speed as a colour.
:func:`render_animation` animates the robot and the movers over the trajectory's time
span (GIF). :func:`render` picks one of them from the output's suffix.

Matplotlib is used through :class:`matplotlib.figure.Figure` and the Agg canvas only, never
through ``pyplot``, so rendering selects no global backend and leaves no figures open.
Every output is written atomically: to a temporary file in the same folder, then renamed.
"""

from __future__ import annotations

import logging
import os

from ..atomic import write_atomic_with
from ..scene.scene import Scene
from .animate import _save_gif, _to_image, render_animation
from .draw import (  # noqa: F401  (re-exported: callers and tests reach them as render.X)
    ANIMATION_SUFFIXES,
    GOAL_COLOR,
    MOVER_COLORS,
    OBSTACLE_EDGE,
    OBSTACLE_FACE,
    PICTURE_SUFFIXES,
    ROADMAP_COLOR,
    ROBOT_COLOR,
    SPEED_CMAP,
    START_COLOR,
    VIOLATION_COLOR,
    WAIT_COLOR,
    _clearance_outline,
    _draw_movers,
    _draw_obstacles,
    _draw_queries,
    _draw_roadmap,
    _draw_trajectory,
    _draw_violation,
    _figure,
    _fmt_time,
    _legend,
    _legend_rows,
    _suffix,
    as_waypoints,
    colormaps,
    poses_at_times,
    segment_speeds,
    wait_intervals,
)

__all__ = [
    "render",
    "render_scene",
    "render_animation",
    "as_waypoints",
    "poses_at_times",
    "segment_speeds",
    "wait_intervals",
]

log = logging.getLogger(__name__)
log.addHandler(logging.NullHandler())


# --------------------------------------------------------------------------- public API


def render_scene(
    scene: Scene,
    out_path: str | os.PathLike,
    roadmap=None,
    trajectory=None,
    speed=None,
    title: str | None = None,
    dpi: int = 120,
    footprints: int = 6,
    violation: tuple[float, str] | None = None,
) -> None:
    """Draw the scene, and optionally a roadmap and a trajectory, as a still picture.

    Parameters
    ----------
    scene : Scene
    out_path : path-like
        ``.png`` (or ``.gif`` for a one-frame GIF); written atomically.
    roadmap : Roadmap, optional
        Anything with ``vertices`` (V, d) and ``edges`` (E, 2).
    trajectory : (n, 3) or (n, 4) array, or object with ``.waypoints``, optional
        The robot's trajectory (docs/formats.md section 2).
    speed : True, (n - 1,) or (n,) float, optional
        Colour the robot's path by speed: ``True`` derives each segment's configuration
        speed from the trajectory; an array gives a speed per segment (n - 1) or per
        waypoint (n, each segment takes the mean of its ends).
    title : str, optional
        Default: the scene's name, and the trajectory's duration.
    dpi : int
        Picture resolution; the picture is about ``8 * dpi`` pixels wide.
    footprints : int
        Number of robot footprints drawn along the trajectory, start and end included.
    violation : (float, str), optional
        Time and text of the trajectory's first violation of the guarantees (see
        :attr:`gfuzzy.check.check.CheckReport.time`): the robot is drawn there, crossed out in
        magenta, with the text below the picture.

    Raises
    ------
    ValueError
        An unsupported suffix (nothing is written), a malformed trajectory, or a speed
        array of the wrong length.
    """
    suffix = _suffix(out_path, PICTURE_SUFFIXES, "a picture")
    wp = None if trajectory is None else as_waypoints(trajectory, scene)
    with_speed = wp is not None and speed is not None and speed is not False
    fig, ax = _figure(scene, 8.0, with_speed, _legend_rows(scene, roadmap, wp) + (violation is not None))
    _draw_obstacles(ax, scene)
    if roadmap is not None:
        _draw_roadmap(ax, roadmap)
    _draw_movers(ax, scene)
    _draw_queries(ax, scene)
    if wp is not None:
        _draw_trajectory(ax, fig, scene, wp, speed if with_speed else None, footprints)
        if violation is not None:
            _draw_violation(ax, scene, wp, *violation)
    if title is None:
        title = scene.name
        if wp is not None:
            title += f": trajectory of {_fmt_time(wp[-1, 0] - wp[0, 0])} s"
    ax.set_title(title)
    _legend(fig, ax)

    def write(tmp: str) -> None:
        if suffix == ".png":
            fig.savefig(tmp, dpi=dpi, format="png")
        else:
            _save_gif([_to_image(fig, dpi)], tmp, [1000])

    write_atomic_with(out_path, write)
    log.info("wrote %s", out_path)


def render(
    scene: Scene,
    out_path: str | os.PathLike,
    trajectory=None,
    roadmap=None,
    **options,
) -> None:
    """Picture or animation, chosen from ``out_path``'s suffix.

    ``.png`` calls :func:`render_scene`, ``.gif`` :func:`render_animation` (which also
    animates the movers alone when ``trajectory`` is None); ``options`` go to the one
    called.

    Raises
    ------
    ValueError
        Any other suffix (nothing is written), or what the renderer raises.
    """
    suffix = _suffix(out_path, (".png", ".gif"), "a picture or an animation")
    if suffix == ".png":
        render_scene(scene, out_path, roadmap=roadmap, trajectory=trajectory, **options)
    else:
        render_animation(scene, trajectory, out_path, **options)
