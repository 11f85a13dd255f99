"""Looking where the robot has not looked: a disc robot's blind side (``NavOptions.fov``).

A holonomic robot whose sensor looks along its direction of motion (CrowdNav++'s
convention, CONTRACT.md section 7) sees nothing behind it while it drives on, and people
who do not see it either walk into it from there. A :class:`Lookout` remembers, per
direction about the robot, when it last looked that way (from the robot's own motion:
the view is centred on the last displacement, and kept while the robot stands). When a
side has gone unseen for ``NavOptions.look_after`` seconds, the navigator's answer is
replaced by a *look*: a short, slow motion toward that side, which turns the view there
for the next observation, and then standing (the navigator replans at its next call).
A side where only people seen standing are waits as long as an empty side does.
A look is taken only when it stays clear of everyone seen (walking on, un-inflated, over
``LOOK_CHECK`` seconds, or the navigator's ``cover`` if longer: the standing after the
look too) and of the static obstacles.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..trajectory import Trajectory
from ..typed import FloatArray
from . import sensing
from .navtypes import MOTION_SAMPLE
from .unknown import at_unknown

if TYPE_CHECKING:
    from .navigator import Navigator

__all__ = ["Lookout", "knowing_view", "SECTORS", "LOOK_TIME", "LOOK_SPEED", "LOOK_CHECK"]

#: Directions (equal sectors about the robot) whose last look is remembered.
SECTORS = 36
#: Seconds a look moves (then the robot stands until the navigator's next call).
LOOK_TIME = 0.25
#: Speed of a look, as a share of the robot's planning speed.
LOOK_SPEED = 0.2
#: Seconds over which a look must stay clear of everyone seen, walking on.
LOOK_CHECK = 1.0
#: A side where nobody known is goes unseen this many times ``look_after`` before a look.
EMPTY_FACTOR = 4.0
#: Seconds within which a person known on an unseen side could reach the robot for it to
#: look there after ``look_after``.
LOOK_REACH = 3.0
#: People seen standing (slower than this, m/s; not those seen once, whose velocity is
#: unknown) make their side stale only as an empty side does: they are not walking toward
#: the robot, and it drives where it looks (among people standing about, a 120-degree view
#: looked every other step: *The narrow noisy view on the square crossing*).
LOOK_STANDING = 0.25


class Lookout:
    """The directions a disc robot has looked at, and the look toward the stalest side.

    Parameters
    ----------
    fov : float
        The robot's field of view (degrees, < 360), centred on its direction of motion.
    look_after : float
        Seconds a side may go unseen before the robot looks there.
    goal : (2,) float
        Before the robot first moves, its view is centred on the direction to the goal.
    """

    def __init__(self, fov: float, look_after: float, goal: FloatArray):
        self.half = math.radians(fov) / 2
        self.look_after = look_after
        self.goal = np.asarray(goal, dtype=float)[:2]
        self.heading = 0.0
        self.centres = (np.arange(SECTORS) + 0.5) * (2 * math.pi / SECTORS)
        self.looked = np.full(SECTORS, -math.inf)  # when each direction was last in view
        self.pose: FloatArray | None = None

    def _in_view(self, heading: float) -> FloatArray:
        off = (self.centres - heading + math.pi) % (2 * math.pi) - math.pi
        return np.abs(off) <= self.half

    def observe(self, t: float, pose: FloatArray) -> None:
        """Record the view of the observation made at ``t`` from ``pose`` (2,): about the
        robot's displacement since the last call, or the last view when it stood."""
        xy = np.asarray(pose, dtype=float)[:2]
        d = xy - self.pose if self.pose is not None else self.goal - xy
        if math.hypot(*d) > 1e-9:
            self.heading = math.atan2(d[1], d[0])
        self.pose = xy.copy()
        self.looked[self._in_view(self.heading)] = t

    def stale(self, t: float, pose: FloatArray | None = None, obs: FloatArray | None = None,
              vmax: float = 1.0, unknown: FloatArray | None = None) -> np.ndarray:  # fmt: skip
        """(SECTORS,) bool: the stale sides. A side is stale when never seen, when unseen
        for ``look_after`` seconds while someone of ``obs`` (k, 5) (people seen before,
        walking on unseen) who is not standing (slower than ``LOOK_STANDING``; a person of
        unknown velocity, at one of the positions ``unknown`` (u, 2), counts as walking at
        ``UNKNOWN_GROWTH``) is there within ``LOOK_REACH`` seconds of the robot at ``pose``,
        or unseen for ``EMPTY_FACTOR * look_after`` seconds."""
        age = t - self.looked
        stale = age > EMPTY_FACTOR * self.look_after + 1e-9
        if pose is not None and obs is not None and len(obs):
            speed = np.hypot(obs[:, 2], obs[:, 3])
            if unknown is not None and len(unknown):  # reported standing, but may walk
                speed = np.where(at_unknown(unknown, obs), np.maximum(speed, sensing.UNKNOWN_GROWTH), speed)
            walk = speed >= LOOK_STANDING
            rel = obs[walk, :2] - np.asarray(pose, dtype=float)[None, :2]
            near = np.hypot(rel[:, 0], rel[:, 1]) - obs[walk, 4] <= (speed[walk] + vmax) * LOOK_REACH
            width = 2 * math.pi / SECTORS
            sector = (np.arctan2(rel[near, 1], rel[near, 0]) % (2 * math.pi) // width).astype(int) % SECTORS
            known = np.zeros(SECTORS, dtype=bool)
            known[sector] = True
            stale |= known & (age > self.look_after + 1e-9)
        return stale

    def direction(self, t: float, pose: FloatArray | None = None, obs: FloatArray | None = None,
                  vmax: float = 1.0, unknown: FloatArray | None = None) -> float | None:  # fmt: skip
        """The direction (radians) whose view takes in the most :meth:`stale` sides (the
        stalest first on ties); None when no side is stale."""
        stale = self.stale(t, pose, obs, vmax, unknown)
        if not stale.any():
            return None
        age = np.minimum(t - self.looked, 1e9)
        views = np.array([(stale & self._in_view(c)).sum() + 1e-12 * age[self._in_view(c)].sum() for c in self.centres])
        return float(self.centres[int(np.argmax(views))])

    def look(self, nav: Navigator, t: float, pose: FloatArray, obs: FloatArray, planned: Trajectory) -> Trajectory | None:
        """The look to take instead of ``planned``, or None (nothing stale, the plan
        already turns the view there, or the look is not clear)."""
        ang = self.direction(t, pose, obs, float(nav.vplan), nav._unknown)
        if ang is None:
            return None
        d = planned.at(t + LOOK_TIME)[:2] - pose[:2]
        if math.hypot(*d) > 1e-9 and self._in_view(math.atan2(d[1], d[0]))[int(ang // (2 * math.pi / SECTORS))]:
            return None  # the planned motion looks there itself
        step = np.array([math.cos(ang), math.sin(ang)]) * (LOOK_SPEED * nav.vplan * LOOK_TIME)
        end = pose.copy()
        end[:2] += step
        if nav.geometry.bounds_clearance(end[None])[0] < 0 or not nav.geometry.motion_free(pose, end):
            return None
        rows = np.array([[t, *pose], [t + LOOK_TIME, *end], [t + max(LOOK_CHECK, nav.options.cover), *end]])
        traj = Trajectory(rows, nav.robot.circumradius)
        span = traj.t_end - t  # the look and the standing after it, all of it checked
        near = nav._near(pose, obs, span, nav.options.safety_buffer + 0.5)
        if len(near):
            times = t + np.arange(0.0, span + 1e-9, MOTION_SAMPLE)
            pts = traj.at(times)[None]
            gap = nav._clearance_along(pts, times, near)
            if gap.min() <= nav.options.safety_buffer + nav._sample_gap(near):
                return None
        return traj


def knowing_view(options, fov: float):
    """``options`` (a ``NavOptions``) told the robot's field of view ``fov`` (degrees) when
    they leave it at its default (360): a navigator knows its own sensor."""
    from dataclasses import replace

    return replace(options, fov=fov) if options.fov >= 360 and fov < 360 else options
