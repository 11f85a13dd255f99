"""The navigator's predictions of the people it sees: how far each is kept (the inflation,
growing over the prediction), who may come within reach, and the movers the search
checks against (a base of :class:`gfuzzy.navigation.navigator.Navigator`, whose state,
options and clock it uses)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..collision.geometry import mover_distance
from ..scene.scene import Mover
from ..timespace.movers import MoverField
from ..typed import BoolArray, FloatArray
from .pathspace import STILL_SPEED
from .swerve import swerve_rates
from .timedfield import _TimedField
from .unknown import unknown_growth

__all__ = ["Prediction", "REACH_SAMPLES", "PERSON_DECAY", "prior_store"]

#: Samples of the look-ahead in the test of who may come within reach (:meth:`Prediction._may_reach`).
REACH_SAMPLES = 48
#: A call that does not run its search for want of the predictions' set-up time lowers the
#: navigator's estimate of it per person by this factor (:meth:`Prediction._affords`).
PERSON_DECAY = 0.8


def prior_store(safety: tuple | None, obs: FloatArray, infl: FloatArray, keep: BoolArray):
    """The interval store of an earlier search's field (``safety``: its store, people rows,
    inflation and relevant mask, :class:`~gfuzzy.navigation.navtypes._Searched`) when that
    field is at least as cautious as the one of ``obs[keep]`` inflated by ``infl``: the same
    people (``obs`` its first rows; a row without the columns ``appear``, ``vanish`` is the
    earlier row present from 0 to inf: the plain search after the one with the ghosts), each
    inflated at least as much at every slice, every one kept here kept there. Every step
    safe there is then safe here (the personal space, the ghosts only add to what is kept;
    up to the rounding of the margins' sums). Otherwise None (:attr:`IntervalStore.prior`)."""
    if safety is None:
        return None
    store, obs0, infl0, keep0 = safety
    k = len(obs)
    if not (store.pool and k <= len(obs0) and infl.shape[1:] == infl0.shape[1:] and obs.shape[1] <= obs0.shape[1]):
        return None
    head = obs0[:k]
    if obs.shape[1] < obs0.shape[1] and not ((head[:, 5] == 0.0).all() and np.isposinf(head[:, 6]).all()):
        return None
    same = np.array_equal(head[:, : obs.shape[1]], obs) and bool((infl <= infl0[:k]).all())
    return store if same and not (keep & ~keep0[:k]).any() else None


class Prediction:
    """The people predicted: the navigator's part that turns observations into the
    inflated, timed movers its searches and checks use."""

    def _inflation(self, pose: FloatArray, obs: FloatArray, relaxed: bool = False,
                   personal: bool = True) -> FloatArray:  # fmt: skip
        """(k, S) inflation (m) per person and prediction slice, shrunk near the robot.

        A person already closer than the full inflation (someone walked up to the robot)
        gets an inflation that starts just inside their present gap and recovers at the
        robot's speed, so that the robot, which stands where it stands, is not inside its
        own predictions and the search can move it away. The inflation never decreases
        from one slice to the next (both terms grow with the prediction time).
        """
        opts = self.options
        n_slices = int(math.ceil(opts.prediction_horizon / opts.slice - 1e-9))
        tau = np.arange(n_slices) * opts.slice
        speed = np.hypot(obs[:, 2], obs[:, 3])
        # uncertainty grows with how far a person may stray from the straight walk: with
        # their speed (someone standing is where they stand; a full-speed walker may turn)
        rate = self._growth_rate(speed) + swerve_rates(obs, opts.swerve_growth)
        space = opts.personal_space if personal else 0.0
        full = self.mover_clearance + opts.safety_buffer + space + rate[:, None] * tau[None, :]
        if relaxed:  # only what the contract asks: the robot's mover clearance
            full = np.full_like(full, self.mover_clearance)
        gap = self._gap(pose, obs)  # (k,) beyond the people's own radius
        allowed = np.maximum(gap - self._step_margin(speed) - 1e-6, 0.0)
        near = np.minimum(full, allowed[:, None] + self.vplan * tau[None, :])
        # people of unknown velocity may walk anywhere (the relaxed search takes the discs as they are)
        return near if relaxed else near + unknown_growth(self._unknown, obs, tau).T

    def _gap(self, pose: FloatArray, obs: FloatArray) -> FloatArray:
        if len(obs) == 0:
            return np.zeros(0)
        return mover_distance(self._pred_robot, pose[None, :], "disc", obs[:, 4], (0.0, 0.0), obs[:, :2])

    def _walks(self, obs: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Predicted velocity (k, 2) (zero for someone standing) and presence (k,) in seconds
        after ``t`` (the horizon; a person standing still is kept ``stationary_hold`` longer)."""
        opts = self.options
        still = np.hypot(obs[:, 2], obs[:, 3]) < STILL_SPEED
        vel = np.where(still[:, None], 0.0, obs[:, 2:4])
        hold = opts.stationary_hold if opts.stationary_hold > 0 else 0.0
        return vel, opts.prediction_horizon + np.where(still, hold, 0.0)

    def _may_reach(self, pose: FloatArray, xy: FloatArray, vel: FloatArray, walk: FloatArray,
                   look: FloatArray, reach: FloatArray) -> BoolArray:  # fmt: skip
        """(k,) False for each person who certainly stays farther than ``reach`` from the
        robot's reference point during the next ``look`` seconds, whatever the robot does.

        The person's centre walks at ``vel`` for ``walk`` seconds and then stands; the
        robot's reference point stays within ``vmax * tau`` of ``pose`` at time ``tau``
        (the speed bound every answer keeps). The distance between the two changes no faster
        than ``|vel| + vmax``, so its smallest value over samples ``h`` apart, minus that
        rate times ``h / 2``, bounds it from below on the whole interval.
        """
        k = len(xy)
        if k == 0:
            return np.zeros(0, dtype=bool)
        n = REACH_SAMPLES
        look = np.broadcast_to(np.asarray(look, dtype=float), (k,))
        tau = look[:, None] * np.linspace(0.0, 1.0, n)[None, :]  # (k, n)
        walked = np.minimum(tau, np.broadcast_to(np.asarray(walk, dtype=float), (k,))[:, None])
        centre = xy[:, None, :] + walked[..., None] * vel[:, None, :]
        vmax = float(self.robot.vmax)
        g = np.hypot(*(centre - pose[:2]).transpose(2, 0, 1)) - vmax * tau
        slack = (np.hypot(vel[:, 0], vel[:, 1]) + vmax) * look / (n - 1) / 2
        return g.min(axis=1) - slack <= reach

    def _relevant(self, pose: FloatArray, obs: FloatArray, infl: FloatArray, seconds: float) -> BoolArray:
        """(k,) the people whose prediction can make a robot pose unsafe within ``seconds``.

        A predicted person makes a point unsafe at a step only if the robot there is closer
        than their inflated radius plus the search's margin, and the robot is never farther
        than ``vmax * tau`` from where it is now at time ``tau``: a person who stays beyond
        that reach over their predicted presence (or the search's horizon) makes no pose
        the search can reach unsafe, and leaving them out changes no answer.
        """
        opts = self.options
        vel, presence = self._walks(obs)
        speed = np.hypot(vel[:, 0], vel[:, 1])
        reach = obs[:, 4] + infl.max(axis=1, initial=0.0) + self.robot.circumradius + (self.vplan + speed) * opts.dt
        look = np.minimum(presence, seconds) + opts.dt  # the field keeps a mover half a step longer
        return self._may_reach(pose, obs[:, :2], vel, opts.prediction_horizon, look, reach + 1e-6)

    def _near(self, pose: FloatArray, obs: FloatArray, look: float, gap: float) -> FloatArray:
        """The people (rows of ``obs``) who, walking on at constant velocity, may come within
        ``gap`` of the robot (beyond both radii and the mover clearance) within ``look``
        seconds; the fallbacks only look at them (the others cannot change their answers)."""
        if len(obs) == 0:
            return obs
        reach = obs[:, 4] + self.robot.circumradius + self.mover_clearance + gap + 1e-6
        return obs[self._may_reach(pose, obs[:, :2], obs[:, 2:4], math.inf, look, reach)]

    def _affords(self, now: float, detailed: int, deadline: float) -> bool:
        """Whether the predictions of ``detailed`` people can be set up from ``now`` before
        ``deadline``, at the navigator's measured cost per person (``_person_seconds``).
        When not, that estimate is lowered by ``PERSON_DECAY``: it is measured only when a
        search runs, so one slow measurement (a stall of the machine) used to keep every
        later search of the run from running (a whole crowd episode of evasive answers)."""
        if now + detailed * self._person_seconds <= deadline:
            return True
        self._person_seconds *= PERSON_DECAY
        return False

    def _field(self, t: float, obs: FloatArray, infl: FloatArray, steps: int, deadline: float = math.inf) -> MoverField:
        """The predicted people on the search's time grid: one trajectory mover per person.

        Person i walks on (or stands) as :meth:`_walks` says; the growing inflation goes
        into the field's margin step by step instead of into the disc. For a disc,
        inflating the radius by ``e`` and asking ``e`` more distance are the same test,
        so this field makes exactly the (point, step) pairs unsafe that a chain of one
        mover per prediction slice, each with its own inflated radius, would, with one
        mover per person instead of one per slice (the field's set-up costs per mover).
        Each mover's disc carries the inflation of the first step (the smallest: it never
        shrinks with time), so that the exact check of the first motions
        (:meth:`MoverField.motion_safe`) keeps it too. Rows of 7 columns (the ghosts of
        :meth:`_path_ghosts`) are present only from ``t + appear`` to ``t + vanish``.
        """
        opts = self.options
        k, n_s = infl.shape
        vel, presence = self._walks(obs)
        # the slice whose inflation holds at step n: the latest one present within half a step
        tau = (np.arange(steps + 1) + 0.5) * opts.dt
        s_of = np.minimum(np.floor(tau / opts.slice + 1e-9).astype(np.int64), n_s - 1)
        first = infl[:, s_of[0]]
        radius = obs[:, 4] + first
        appear = obs[:, 5] if obs.shape[1] > 5 else np.zeros(k)
        vanish = np.minimum(presence, obs[:, 6]) if obs.shape[1] > 6 else presence
        a = obs[:, :2] + vel * np.minimum(appear, opts.prediction_horizon)[:, None]
        b = obs[:, :2] + vel * np.minimum(vanish, opts.prediction_horizon)[:, None]
        movers = tuple(Mover(f"p{i}", "disc", float(radius[i]), (0.0, 0.0),
                             trajectory=np.array([[t + appear[i], a[i, 0], a[i, 1]], [t + vanish[i], b[i, 0], b[i, 1]]]))
                       for i in range(k))  # fmt: skip
        extra = float(np.max(infl - first[:, None], initial=0.0))  # the ghosts' is not monotone
        scene = replace(self.scene, robot=self._pred_robot, movers=movers)
        # built with the largest extra margin, so that its broad-phase boxes hold every
        # step's; then each step gets its own (the robot's clearance is in the radii: keep 0)
        field_ = _TimedField(scene, t, opts.dt, steps, self.vplan, clearance=extra)
        field_.deadline, field_.clock = deadline, self._clock
        field_.pace = self._pace  # the pieces' measured time, kept from call to call
        field_.keep = 0.0
        field_.margin += infl[:, s_of] - first[:, None] - extra
        field_.compiled = opts.backend == "compiled"
        return field_
