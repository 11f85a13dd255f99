"""A differential drive tracking a timed plan: turns in place and straights, in time.

:func:`gfuzzy.learning.tracking.track` follows a holonomic plan's *path* by pure pursuit,
which cuts corners. A differential drive's plan (``kinematics: unicycle``) turns in place
at its corners, so it is followed as a *trajectory*: the reference pose and velocities at
each instant come from the plan's timed rows (linear between rows, a wait, a turn in place
or a straight), and the robot runs the tracking law of Kanayama et al.::

    e_x, e_y = the reference position in the robot's frame, e_h = wrap(h_ref - h)
    v = v_ref cos(e_h) + k_x e_x
    w = w_ref + v_ref (k_y e_y + k_h sin(e_h)) + k_turn sin(e_h)

(the last term turns the robot towards the reference heading where ``v_ref`` = 0, in a turn
in place or a wait), its commands saturated to the robot's bounds: ``0 <= v <= vmax``
(``-vmax`` with ``reverse``), ``|w| <= wmax``, ``|dv/dt| <= amax``, ``|dw/dt| <= alpha_max``.
A plan that the base can drive (the speed layer's: at rest at every corner, within amax)
is followed with errors of the time step's order; one that jumps between speeds (the
search's: full speed at once) is followed with the lag of the saturated commands.

References
----------
Y. Kanayama, Y. Kimura, F. Miyazaki, T. Noguchi, "A stable tracking control method for an
autonomous mobile robot", IEEE ICRA 1990, 384-389.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, check_number
from ..status import Status
from ..typed import FloatArray
from .tracking import UnicycleLimits, Violations

__all__ = ["DriveGains", "DriveTrackingResult", "track_drive", "reference_at", "HALF_ROW"]

#: Half the planner's time step (s): a row pair's speed holds from this after its start to
#: this before its end.
HALF_ROW = 0.035


@dataclass(frozen=True)
class DriveGains:
    """Gains of the tracking law and the simulation's settings.

    Attributes
    ----------
    kx : float
        Along-track gain, 1/s.
    ky : float
        Cross-track gain, 1/m^2.
    kh : float
        Heading gain while moving, 1/m.
    kturn : float
        Heading gain, 1/s (acts in turns in place and waits too).
    dt : float
        Simulation step, s.
    settle : float
        Seconds the simulation runs past the plan's end for the robot to settle.
    goal_tolerance : float
        The run counts as arrived (``Status.SOLVED``) once the robot is this close to the
        goal position (m) with its heading within ``heading_tolerance`` (rad).
    heading_tolerance : float
    violation_tolerance : float
        A command beyond its bound by more than this fraction counts as a violation.
    """

    kx: float = 3.0
    ky: float = 12.0
    kh: float = 5.0
    kturn: float = 5.0
    dt: float = 0.02
    settle: float = 3.0
    goal_tolerance: float = 0.02
    heading_tolerance: float = 0.05
    violation_tolerance: float = 0.05

    def __post_init__(self) -> None:
        for name in ("kx", "ky", "kh", "kturn", "dt", "goal_tolerance", "heading_tolerance"):
            check_number(f"DriveGains.{name}", getattr(self, name))
        for name in ("settle", "violation_tolerance"):
            check_number(f"DriveGains.{name}", getattr(self, name), strict=False)


@dataclass(frozen=True)
class DriveTrackingResult:
    """A differential drive's tracking run.

    Attributes
    ----------
    status : Status
        ``SOLVED`` when the robot arrived at the goal (see :class:`DriveGains`), else
        ``TIMEOUT``.
    t : (N,) float
    poses : (N, 3) float
        The robot's poses ``[x, y, heading]``.
    reference : (N, 3) float
        The plan's poses at the same times.
    v, omega : (N,) float
        Applied (saturated) commands.
    v_ref, omega_ref : (N,) float
        The plan's velocities.
    position_error : (N,) float
        Distance to the reference position, m.
    lateral_error : (N,) float
        Distance to the plan's path (its xy polyline), m: the holonomic tracker's figure.
    heading_error : (N,) float
        ``|wrap(h_ref - h)|``, rad.
    arrival_time : float
        Time the robot arrived (``nan`` when it did not), from the plan's start.
    max_position_error, max_lateral_error, mean_lateral_error, max_heading_error : float
    violations : Violations
        Steps whose commands exceeded a bound before saturation (a tracker riding a bound
        with its feedback on top counts too).
    plan_violations : Violations
        Steps where the plan's own velocities (``v_ref``, ``omega_ref``) exceed a bound: a
        plan the base can drive has none.
    """

    status: Status
    t: FloatArray
    poses: FloatArray
    reference: FloatArray
    v: FloatArray
    omega: FloatArray
    v_ref: FloatArray
    omega_ref: FloatArray
    position_error: FloatArray
    lateral_error: FloatArray
    heading_error: FloatArray
    arrival_time: float
    max_position_error: float
    max_lateral_error: float
    mean_lateral_error: float
    max_heading_error: float
    violations: Violations
    plan_violations: Violations


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def reference_at(rows: FloatArray, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The plan's pose and velocities at times ``t``.

    Parameters
    ----------
    rows : (n, 4) float
        ``[t, x, y, heading]``, t increasing; each pair a wait, a turn in place or a straight.
    t : (m,) float

    Returns
    -------
    poses : (m, 3) float
        Linear between rows (the heading along the shorter arc); the last row after the end.
    v, w : (m,) float
        Forward speed and turning rate: each row pair's mean, held from ``HALF_ROW`` after
        its start to ``HALF_ROW`` before its end (at its middle when it is shorter) and
        interpolated linearly in between (0 at the ends and during waits): on rows one time
        step apart the feed-forward changes within the acceleration bounds the rows keep.
    """
    rows = np.asarray(rows, dtype=float)
    t = np.asarray(t, dtype=float)
    dt = np.diff(rows[:, 0])
    d = np.diff(rows[:, 1:3], axis=0)
    dh = _wrap(np.diff(rows[:, 3]))
    fwd = (np.cos(rows[:-1, 3]) * d[:, 0] + np.sin(rows[:-1, 3]) * d[:, 1]) / dt
    k = np.clip(np.searchsorted(rows[:, 0], t, side="right") - 1, 0, len(rows) - 2)
    f = np.clip((t - rows[k, 0]) / dt[k], 0.0, 1.0)
    poses = np.column_stack([rows[k, 1:3] + f[:, None] * d[k], _wrap(rows[k, 3] + f * dh[k])])
    # a wait is two knots at rest (its ends), a motion one knot at its middle
    still = (np.abs(fwd) * dt <= 1e-12) & (np.abs(dh) <= 1e-12)
    kt, kv, kw = [rows[0, 0]], [0.0], [0.0]
    for a, b, vk, wk, rest in zip(rows[:-1, 0], rows[1:, 0], fwd, dh / dt, still, strict=True):
        if rest:
            kt += [a, b]
            kv += [0.0, 0.0]
            kw += [0.0, 0.0]
        else:  # constant inside a long row pair, changing within HALF_ROW of its ends
            h = min(0.5 * (b - a), HALF_ROW)
            kt += [a + h, b - h]
            kv += [vk, vk]
            kw += [wk, wk]
    kt.append(rows[-1, 0])
    kv.append(0.0)
    kw.append(0.0)
    return poses, np.interp(t, kt, kv, right=0.0), np.interp(t, kt, kw, right=0.0)


def _next_rest(rows: FloatArray) -> FloatArray:
    """For each row pair, the pose where the plan next comes to rest: the end of the run of
    row pairs of the same kind (a straight in a direction of travel, or a turn in a
    direction) it belongs to; (n-1, 3). A reversal of travel is a rest: the robot stops there."""
    d = np.diff(rows[:, 1:3], axis=0)
    dh = _wrap(np.diff(rows[:, 3]))
    along = np.cos(rows[:-1, 3]) * d[:, 0] + np.sin(rows[:-1, 3]) * d[:, 1]
    straight = np.hypot(d[:, 0], d[:, 1]) > 1e-12
    kind = np.where(straight, np.sign(along), np.where(np.abs(dh) > 1e-12, 2 * np.sign(dh), 0))
    out = np.empty((len(kind), 3))
    end = len(rows) - 1
    for k in range(len(kind) - 1, -1, -1):
        if k == len(kind) - 1 or kind[k] != kind[k + 1] or kind[k] == 0:
            end = k + 1
        out[k] = rows[end, 1:]
    return out


def _polyline_distance(xy: FloatArray, points: FloatArray) -> FloatArray:
    """Distance of each point to the polyline ``xy`` (repeated points allowed)."""
    a, b = xy[:-1], xy[1:]
    ab = b - a
    ab2 = np.einsum("ij,ij->i", ab, ab)
    out = np.full(len(points), np.inf)
    for i in range(len(a)):  # segments are few beside the samples
        u = points - a[i]
        f = np.clip(u @ ab[i] / ab2[i], 0.0, 1.0) if ab2[i] > 0 else np.zeros(len(points))
        out = np.minimum(out, np.hypot(*(u - f[:, None] * ab[i]).T))
    return out


def track_drive(
    rows: FloatArray, limits: UnicycleLimits, gains: DriveGains | None = None, reverse: bool = False
) -> DriveTrackingResult:
    """Simulate a differential drive tracking a timed plan.

    The robot starts at rest at the first row's pose; each step it reads the reference at
    the step's time, computes the tracking law's commands (module docstring), counts a
    violation where they exceed a bound, saturates them and integrates exactly over the
    step (an arc of constant v and w, the commands ramped within their rate bounds).

    Parameters
    ----------
    rows : (n, 4) float
        The plan's rows ``[t, x, y, heading]`` (``Trajectory.waypoints``), n >= 2.
    limits : UnicycleLimits
        ``vmax``, ``omega_max`` (the robot's wmax), ``amax``, ``alpha_max``.
    gains : DriveGains, optional
    reverse : bool
        May the robot drive backwards (``robot.reverse``).

    Returns
    -------
    DriveTrackingResult

    Raises
    ------
    InputError
        If ``rows`` is not (n >= 2, 4) with increasing times.
    """
    g = DriveGains() if gains is None else gains
    rows = np.asarray(rows, dtype=float)
    if rows.ndim != 2 or rows.shape[1] != 4 or len(rows) < 2 or np.any(np.diff(rows[:, 0]) <= 0):
        raise InputError("rows must be (n >= 2, 4) [t, x, y, heading] with increasing t")
    t0, T = rows[0, 0], rows[-1, 0] - rows[0, 0]
    n = int(math.ceil((T + g.settle) / g.dt)) + 1
    t = np.arange(n) * g.dt
    ref, v_ref, w_ref = reference_at(rows, t0 + t)
    rest = _next_rest(rows)[np.clip(np.searchsorted(rows[:, 0], t0 + t, side="right") - 1, 0, len(rows) - 2)]
    vmin = -limits.vmax if reverse else 0.0
    x, y, h = (float(c) for c in rows[0, 1:])
    v = w = 0.0
    out = np.empty((n, 5))
    counts = [0, 0, 0, 0, 0]
    tol = 1.0 + g.violation_tolerance
    goal = rows[-1, 1:]
    arrived = math.nan
    last = n
    for i in range(n):
        out[i] = (x, y, h, v, w)
        if t[i] >= T and math.hypot(x - goal[0], y - goal[1]) <= g.goal_tolerance and abs(
            _wrap(goal[2] - h)) <= g.heading_tolerance:  # fmt: skip
            arrived, last = float(t[i]), i + 1
            break
        if i == n - 1:
            break
        c, s = math.cos(h), math.sin(h)
        dx, dy = ref[i, 0] - x, ref[i, 1] - y
        ex, ey = c * dx + s * dy, -s * dx + c * dy
        eh = float(_wrap(ref[i, 2] - h))
        vc = v_ref[i] * math.cos(eh) + g.kx * ex
        # never faster than braking at amax to the plan's next rest allows (a robot that
        # cannot reverse must not overrun the corner it turns at; one that reverses stops
        # where its travel reverses), forwards or backwards
        ahead = (rest[i, 0] - x) * c + (rest[i, 1] - y) * s
        if vc > 0:
            vc = min(vc, math.sqrt(2.0 * limits.amax * max(ahead, 0.0)))
        elif vc < 0:
            vc = max(vc, -math.sqrt(2.0 * limits.amax * max(-ahead, 0.0)))
        wc = w_ref[i] + v_ref[i] * (g.ky * ey + g.kh * math.sin(eh)) + g.kturn * math.sin(eh)
        bad = (abs(vc) > limits.vmax * tol, abs(vc - v) > limits.amax * g.dt * tol,
               abs(wc) > limits.omega_max * tol, abs(wc - w) > limits.alpha_max * g.dt * tol)  # fmt: skip
        for k, b in enumerate(bad):
            counts[k] += b
        counts[4] += any(bad)
        v1 = min(max(vc, vmin), limits.vmax)
        v1 = v + max(-limits.amax * g.dt, min(limits.amax * g.dt, v1 - v))
        w1 = min(max(wc, -limits.omega_max), limits.omega_max)
        w1 = w + max(-limits.alpha_max * g.dt, min(limits.alpha_max * g.dt, w1 - w))
        vm, wm = 0.5 * (v + v1), 0.5 * (w + w1)  # the commands ramp within the step
        if abs(wm) > 1e-12:
            x += vm / wm * (math.sin(h + wm * g.dt) - math.sin(h))
            y -= vm / wm * (math.cos(h + wm * g.dt) - math.cos(h))
        else:
            x += vm * g.dt * c
            y += vm * g.dt * s
        h += wm * g.dt
        v, w = v1, w1
    out, t, ref, v_ref, w_ref = out[:last], t[:last], ref[:last], v_ref[:last], w_ref[:last]
    poses = out[:, :3]
    pos_err = np.hypot(*(ref[:, :2] - poses[:, :2]).T)
    lat = _polyline_distance(rows[:, 1:3], poses[:, :2])
    head = np.abs(_wrap(ref[:, 2] - poses[:, 2]))
    return DriveTrackingResult(
        status=Status.SOLVED if math.isfinite(arrived) else Status.TIMEOUT,
        t=t, poses=poses, reference=ref, v=out[:, 3], omega=out[:, 4], v_ref=v_ref, omega_ref=w_ref,
        position_error=pos_err, lateral_error=lat, heading_error=head, arrival_time=arrived,
        max_position_error=float(pos_err.max()), max_lateral_error=float(lat.max()),
        mean_lateral_error=float(lat.mean()), max_heading_error=float(head.max()),
        violations=Violations(*counts), plan_violations=_plan_violations(v_ref, w_ref, limits, g),
    )  # fmt: skip


def _plan_violations(v_ref, w_ref, limits: UnicycleLimits, g: DriveGains) -> Violations:
    tol = 1.0 + g.violation_tolerance
    dv, dw = np.abs(np.diff(v_ref, append=0.0)), np.abs(np.diff(w_ref, append=0.0))
    bad = [np.abs(v_ref) > limits.vmax * tol, dv > limits.amax * g.dt * tol,
           np.abs(w_ref) > limits.omega_max * tol, dw > limits.alpha_max * g.dt * tol]  # fmt: skip
    return Violations(*(int(b.sum()) for b in bad), int(np.any(bad, axis=0).sum()))
