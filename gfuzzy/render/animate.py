"""Animations (GIF): the robot and the movers over time, with an optional prediction overlay.

:func:`render_animation` draws the static scene once, then blits the moving artists
(movers, robot, trail, clock, the navigator's predictions) frame by frame; the frames
share one palette (:func:`_save_gif`).
"""

from __future__ import annotations

import logging
import math
import os

import numpy as np
from matplotlib import colormaps
from matplotlib.cm import ScalarMappable
from matplotlib.collections import LineCollection
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle

from ..atomic import write_atomic_with
from ..errors import InputError
from ..scene.scene import Scene
from ..typed import FloatArray
from .draw import (
    ANIMATION_SUFFIXES,
    GOAL_COLOR,
    ROBOT_COLOR,
    SPEED_CMAP,
    _clearance_outline,
    _draw_movers,
    _draw_obstacles,
    _figure,
    _footprint,
    _heading_tick,
    _inflated_xy,
    _move_patch,
    _mover_color,
    _mover_patch,
    _speed_values,
    _suffix,
    as_waypoints,
    poses_at_times,
)
from .span import default_span

__all__ = ["render_animation"]

log = logging.getLogger(__name__)
log.addHandler(logging.NullHandler())


def _to_image(fig: Figure, dpi: float | None = None):
    from PIL import Image

    if dpi is not None:
        fig.set_dpi(dpi)
    fig.canvas.draw()
    return Image.fromarray(np.asarray(fig.canvas.buffer_rgba())[..., :3].copy())


def _save_gif(frames, path: str, durations_ms) -> None:
    """Save RGB frames as a looping GIF with one shared palette (fast, no flicker).

    The palette is learnt from a few frames spread over the animation, so that a mover
    that appears late still finds its colour, plus exact white and black (a quantiser
    averages the background to an off-white otherwise).
    """
    from PIL import Image

    picks = np.unique(np.linspace(0, len(frames) - 1, min(len(frames), 8)).round().astype(int))
    sample = Image.fromarray(np.vstack([np.asarray(frames[i]) for i in picks]))
    learnt = sample.quantize(colors=254, method=Image.Quantize.FASTOCTREE).getpalette()
    learnt = np.asarray(learnt[: 3 * 254], dtype=np.uint8).reshape(-1, 3)
    # Pillow maps pixels through a coarse colour cache: near-whites would shadow white
    learnt = learnt[np.any(learnt < 244, axis=1) & np.any(learnt > 10, axis=1)]
    colors = np.vstack([[[255, 255, 255], [0, 0, 0]], learnt])
    palette = Image.new("P", (1, 1))
    palette.putpalette(colors.ravel().tolist())
    pal = [f.quantize(palette=palette, dither=Image.Dither.NONE) for f in frames]
    pal[0].save(
        path,
        format="GIF",
        save_all=True,
        append_images=pal[1:],
        duration=list(durations_ms),
        loop=0,
        disposal=1,
        optimize=False,
    )


def render_animation(
    scene: Scene,
    trajectory,
    out_path: str | os.PathLike,
    fps: float = 15.0,
    max_frames: int = 300,
    dpi: int = 80,
    duration: float | None = None,
    title: str | None = None,
    speed=None,
    predictions: list | None = None,
) -> int:
    """Animate the robot and the movers over the trajectory's time span, as a GIF.

    Each frame shows the static scene, the movers present at that time, the robot, its
    trail so far (and its remaining path, faint) and a clock. Playback runs in real time:
    when ``duration * fps`` exceeds ``max_frames`` the frames are spread evenly over the
    span and each is shown longer.

    Parameters
    ----------
    scene : Scene
    trajectory : (n, 3) or (n, 4) array, object with ``.waypoints``, or None
        None animates only the movers, over ``[0, duration]``.
    out_path : path-like
        ``.gif``; written atomically.
    fps : float
        Frames per second of playback.
    max_frames : int
        Upper bound on the number of frames.
    dpi : int
        Frame resolution; frames are about ``6.5 * dpi`` pixels wide.
    duration : float, optional
        Span to animate without a trajectory (default: the movers' longest period or
        last time, between 1 and 60 s; 10 s when they are all endless and aperiodic).
    title : str, optional
    speed : True, (n - 1,) or (n,) float, optional
        Colour the robot's trail by speed, as :func:`render_scene` does, with a colour bar.
    predictions : list of dict, optional
        A ``gfuzzy navigate`` file's ``replan_log``: each frame also shows what the robot
        predicted at the latest logged replan (dashed discs walking on at constant
        velocity, inflated as the navigator saw them) and the plan it made then (dotted).

    Returns
    -------
    int
        Number of frames written.

    Raises
    ------
    ValueError
        An unsupported suffix (nothing is written), a malformed trajectory, or
        ``fps`` / ``max_frames`` / ``duration`` not positive.
    """
    _suffix(out_path, ANIMATION_SUFFIXES, "an animation")
    _check_timing(fps, max_frames, duration)
    wp = None if trajectory is None else as_waypoints(trajectory, scene)
    times, frame_ms = _frame_times(scene, wp, fps, max_frames, duration)
    t0, t1 = float(times[0]), float(times[-1])

    with_speed = wp is not None and speed is not None and speed is not False and len(wp) >= 2
    speeds = _speed_values(speed, wp, scene) if with_speed else None
    fig, ax = _figure(scene, 6.5, speeds is not None, 0)
    fig.set_dpi(dpi)
    _draw_obstacles(ax, scene)
    _draw_movers(ax, scene, marker=False)
    ax.set_title(scene.name if title is None else title, fontsize=10)

    mover_xy, present = scene.mover_states(times)
    mover_patches = _mover_patches(ax, scene, mover_xy)
    dynamic = list(mover_patches)
    robot = _RobotArtists(ax, fig, scene, wp, times, speeds) if wp is not None else None
    if robot is not None:
        dynamic += robot.artists
    clock = _clock(ax)
    dynamic.append(clock)
    overlay = _PredictionOverlay(ax, predictions) if predictions else None
    if overlay is not None:
        dynamic += overlay.artists

    def update(k: int, t: float) -> None:
        for i, p in enumerate(mover_patches):
            _move_patch(p, scene.movers[i], mover_xy[i, k])
            p.set_visible(bool(present[i, k]))
        if robot is not None:
            robot.update(k, t)
        clock.set_text(_clock_text(t))
        if overlay is not None:
            overlay.update(t)

    frames = _blit_frames(fig, ax, times, dynamic, update)
    durations = _gif_durations(len(frames), frame_ms)

    def write(tmp: str) -> None:
        _save_gif(frames, tmp, durations)

    write_atomic_with(out_path, write)
    log.info("wrote %s (%d frames over %.2f s)", out_path, len(frames), t1 - t0)
    return len(frames)


def _mover_patches(ax, scene: Scene, mover_xy: FloatArray) -> list:
    """One animated patch per mover, at its first frame's place."""
    patches = []
    for i, m in enumerate(scene.movers):
        p = _mover_patch(m, mover_xy[i, 0], _mover_color(i), alpha=0.75, lw=1.0, zorder=4)
        p.set_animated(True)
        ax.add_patch(p)
        patches.append(p)
    return patches


def _clock(ax):
    """The animated clock text, top left."""
    return ax.text(
        0.02,
        0.97,
        "",
        transform=ax.transAxes,
        ha="left",
        va="top",
        fontsize=10,
        zorder=8,
        family="monospace",
        animated=True,
        bbox=dict(boxstyle="round,pad=0.25", fc="white", ec="0.5", alpha=0.85),
    )


def _blit_frames(fig, ax, times: FloatArray, dynamic: list, update) -> list:
    """RGB frames: the static figure drawn once; per frame ``update(k, t)``, then the
    ``dynamic`` artists drawn over a copy of it (blitting: fast)."""
    canvas = fig.canvas
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)
    from PIL import Image

    frames = []
    for k, t in enumerate(times):
        canvas.restore_region(background)
        update(k, t)
        for artist in dynamic:
            ax.draw_artist(artist)
        frames.append(Image.fromarray(np.asarray(canvas.buffer_rgba())[..., :3].copy()))
    return frames


def _check_timing(fps, max_frames, duration) -> None:
    """InputError unless the animation's timing arguments are usable."""
    if not (fps > 0 and math.isfinite(fps)):
        raise InputError(f"fps must be positive, got {fps}")
    if int(max_frames) < 1:
        raise InputError(f"max_frames must be at least 1, got {max_frames}")
    if duration is not None and not (duration > 0 and math.isfinite(duration)):
        raise InputError(f"duration must be positive, got {duration}")


def _frame_times(scene: Scene, wp, fps: float, max_frames: int, duration) -> tuple[FloatArray, float]:
    """(frame times (n,), milliseconds between two frames) of an animation."""
    if wp is not None:
        t0, t1 = float(wp[0, 0]), float(wp[-1, 0])
    else:
        t0, t1 = 0.0, default_span(scene) if duration is None else float(duration)
    n = max(1, min(int(max_frames), math.floor((t1 - t0) * fps + 1e-9) + 1))
    if t1 > t0:
        n = max(n, 2)
    times = np.linspace(t0, t1, n)
    frame_ms = 1000.0 * (t1 - t0) / (n - 1) if n > 1 else 1000.0
    return times, frame_ms


#: The longest delay a GIF frame can have, in centiseconds (a 16-bit field).
GIF_MAX_DELAY_CS = 65535


def _gif_durations(count: int, frame_ms: float) -> list:
    """Each frame's delay in ms. GIF delays are whole centiseconds: round the running
    clock, not each frame, so that playback keeps real time, up to the longest delay a
    frame can have (:data:`GIF_MAX_DELAY_CS`: a trajectory of days plays faster)."""
    step = min(frame_ms / 10.0, GIF_MAX_DELAY_CS)
    ticks = np.round(np.arange(count + 1) * step).astype(np.int64)
    return (10 * np.clip(np.diff(ticks), 1, GIF_MAX_DELAY_CS)).tolist()


def _clock_text(t: float) -> str:
    """A frame's clock: hundredths of a second, or 6 digits past a million seconds (the
    hundredths of t = 1e300 are 300 digits, drawn in every frame)."""
    return f"t = {t:6.2f} s" if abs(t) < 1e6 else f"t = {t:.6g} s"


class _RobotArtists:
    """The robot's moving artists: trail (by speed, over a black edge, when ``speeds``),
    footprint, clearance outline, heading tick; static: its faint path and the goal."""

    def __init__(self, ax, fig, scene: Scene, wp: FloatArray, times: FloatArray, speeds):
        self.scene, self.wp, self.speeds = scene, wp, speeds
        self.edge = self.tick = None
        ax.plot(wp[:, 1], wp[:, 2], color=ROBOT_COLOR, lw=1.0, alpha=0.25, zorder=4.5)
        ax.plot(*wp[-1, 1:3], marker="*", ms=11, mfc=GOAL_COLOR, mec="black", mew=0.8, zorder=4.6)
        self.poses = poses_at_times(wp, times)
        self.artists = []
        if speeds is None:
            self.trail = Line2D([], [], color=ROBOT_COLOR, lw=2.0, zorder=5, animated=True)
            ax.add_line(self.trail)
        else:  # the driven part coloured by speed, over a black edge, as in the picture
            norm = Normalize(0.0, max(scene.robot.vmax, float(np.max(speeds))))
            self.edge = LineCollection([], colors="black", linewidths=3.4, zorder=4.9, animated=True)
            self.trail = LineCollection([], cmap=colormaps[SPEED_CMAP], norm=norm, linewidths=2.2, zorder=5,
                                        capstyle="round", animated=True)  # fmt: skip
            ax.add_collection(self.edge)
            ax.add_collection(self.trail)
            self.artists.append(self.edge)
            fig.colorbar(ScalarMappable(norm, colormaps[SPEED_CMAP]), ax=ax, shrink=0.8, pad=0.02,
                         label="robot speed [m/s]")  # fmt: skip
        self.robot = _footprint(scene, self.poses[0], fc=ROBOT_COLOR, ec="black", alpha=0.85, lw=1.0, zorder=6)
        self.robot.set_animated(True)
        ax.add_patch(self.robot)
        self.artists += [self.trail, self.robot]
        # the larger clearance kept, as a dashed outline that moves with the robot
        self.keep = max(scene.robot.clearance, scene.robot.mover_clearance)
        self.ring = _clearance_outline(scene, self.poses[0], self.keep, ec="black", zorder=6)
        if self.ring is not None:
            self.ring.set_animated(True)
            ax.add_patch(self.ring)
            self.artists.append(self.ring)
        if scene.robot.dof == 3:  # a box, a footprint, or any unicycle: its heading
            self.tick = Line2D([], [], color="white", lw=1.5, zorder=6.1, animated=True)
            ax.add_line(self.tick)
            self.artists.append(self.tick)

    def update(self, k: int, t: float) -> None:
        """Move the artists to frame ``k`` (time ``t``)."""
        scene, wp, pose, ring = self.scene, self.wp, self.poses[k], self.ring
        done = wp[wp[:, 0] < t]
        if self.speeds is None:
            self.trail.set_data(np.append(done[:, 1], pose[0]), np.append(done[:, 2], pose[1]))
        else:  # the segment under way keeps its own speed
            pts = np.vstack([done[:, 1:3], pose[None, :2]])
            segs = np.stack([pts[:-1], pts[1:]], axis=1)
            self.edge.set_segments(segs)
            self.trail.set_segments(segs)
            self.trail.set_array(self.speeds[: len(segs)])
        if scene.robot.shape == "disc":
            self.robot.set_center(pose[:2])
        else:
            self.robot.set_xy(scene.robot.corners(pose[None, :3])[0])
        if scene.robot.dof == 3:
            self.tick.set_data(*_heading_tick(scene, pose).T)
        if ring is not None and scene.robot.shape == "disc":
            ring.set_center(pose[:2])
        elif ring is not None:
            ring.set_xy(_inflated_xy(scene, pose, self.keep))


class _PredictionOverlay:
    """Dashed predicted discs and the dotted plan of the latest logged replan."""

    def __init__(self, ax, log: list, max_discs: int = 40):
        from ..trajectory import replan_entries

        self.log = replan_entries(list(log), "predictions")  # a SceneError (InputError) names a broken entry
        self.times = np.array([float(e["t"]) for e in self.log])
        self.discs = []
        for _ in range(max_discs):
            c = Circle((0.0, 0.0), 0.1, fill=False, ls="--", lw=0.9, ec="0.35", zorder=4.2, animated=True)
            c.set_visible(False)
            ax.add_patch(c)
            self.discs.append(c)
        self.plan = Line2D([], [], color=ROBOT_COLOR, lw=1.0, ls=":", zorder=4.4, animated=True)
        ax.add_line(self.plan)
        self.artists = [*self.discs, self.plan]

    def update(self, t: float) -> None:
        k = int(np.searchsorted(self.times, t, side="right")) - 1
        entry = self.log[k] if k >= 0 else None
        pred = np.asarray(entry.get("predicted", []) if entry else [], dtype=float).reshape(-1, 5)
        age = t - float(entry["t"]) if entry else 0.0
        for i, c in enumerate(self.discs):
            if i < len(pred):
                x, y, vx, vy, r = pred[i]
                c.set_center((x + vx * age, y + vy * age))
                c.set_radius(max(r, 1e-3))
                c.set_visible(True)
            else:
                c.set_visible(False)
        plan = np.asarray(entry.get("plan", []) if entry else [], dtype=float)
        if plan.ndim == 2 and len(plan) and plan.shape[1] >= 3:
            self.plan.set_data(plan[:, 1], plan[:, 2])
        else:
            self.plan.set_data([], [])
