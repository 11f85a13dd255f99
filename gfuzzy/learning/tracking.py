"""Unicycle path tracking under a speed-limit profile.

A differential-drive robot (unicycle: state ``x, y, theta``, inputs ``v, omega``)
with bounds on ``v``, ``omega``, linear and angular acceleration follows a
polyline. The speed reference is a profile ``v(s)`` along the path (the fuzzy
speed layer's :func:`gfuzzy.fuzzy.fuzzy.speed_limit`, or :func:`constant_profile`);
steering is adaptive pure pursuit: the look-ahead grows with speed, so a robot
slowed for a bend also cuts it less.

The simulation is a fixed-step time loop (pure Python on floats, which beats
small numpy calls at this size); commands are checked against the bounds
*before* saturation, and the checks are counted as violations.
"""

from __future__ import annotations

import logging
import math
from bisect import bisect_right
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..fuzzy.profile import clean_path, limit_acceleration
from ..status import Status
from ..typed import ArrayLike, FloatArray

logger = logging.getLogger(__name__)
logger.addHandler(logging.NullHandler())

__all__ = [
    "UnicycleLimits",
    "TrackingOptions",
    "TrackStatus",
    "Violations",
    "TrackingResult",
    "track",
    "constant_profile",
    "synthetic_paths",
]


@dataclass(frozen=True)
class UnicycleLimits:
    """Bounds of the differential-drive robot.

    Attributes
    ----------
    vmax : float
        Largest forward speed, m/s (the robot never reverses).
    omega_max : float
        Largest ``|omega|``, rad/s.
    amax : float
        Largest ``|dv/dt|``, m/s^2.
    alpha_max : float
        Largest ``|d omega/dt|``, rad/s^2.
    """

    vmax: float = 1.0
    omega_max: float = 1.5
    amax: float = 1.0
    alpha_max: float = 4.0

    def __post_init__(self) -> None:
        for name in ("vmax", "omega_max", "amax", "alpha_max"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise InputError(f"{name} must be positive and finite, got {value}")


@dataclass(frozen=True)
class TrackingOptions:
    """Settings of the tracking simulation.

    Attributes
    ----------
    dt : float
        Time step, s.
    lookahead_min, lookahead_gain : float
        Pure-pursuit look-ahead ``lookahead_min + lookahead_gain * v`` (m, s).
    goal_tolerance : float
        The run ends when the closest path point is this close (arc length, m)
        to the path's end.
    creep_fraction : float
        Smallest speed command, as a fraction of vmax (and at most ``amax dt``),
        so the robot reaches the end even where the profile is 0.
    timeout_factor : float
        The run times out after ``timeout_factor * length / vmax + 5`` s.
    violation_tolerance : float
        A command counts as a violation when it exceeds its bound by more than
        this fraction (absorbs the time discretisation).
    """

    dt: float = 0.02
    lookahead_min: float = 0.2
    lookahead_gain: float = 0.6
    goal_tolerance: float = 0.02
    creep_fraction: float = 0.05
    timeout_factor: float = 20.0
    violation_tolerance: float = 0.05

    def __post_init__(self) -> None:
        if not (self.dt > 0 and self.lookahead_min > 0 and self.lookahead_gain >= 0):
            raise InputError("dt and lookahead_min must be positive, lookahead_gain non-negative")
        if not (self.goal_tolerance > 0 and 0 < self.creep_fraction <= 1):
            raise InputError("goal_tolerance must be positive and creep_fraction in (0, 1]")
        if not (self.timeout_factor > 0 and self.violation_tolerance >= 0):
            raise InputError("timeout_factor must be positive, violation_tolerance non-negative")


#: How a tracking run ends: ``Status.SOLVED`` (the end of the path was reached) or
#: ``Status.TIMEOUT``. The old name, kept for the learning code's readers.
TrackStatus = Status


@dataclass(frozen=True)
class Violations:
    """Time steps whose command exceeded a bound before saturation.

    Attributes
    ----------
    speed, acceleration, omega, angular_acceleration : int
        Steps violating each bound.
    steps : int
        Steps violating at least one bound.
    """

    speed: int = 0
    acceleration: int = 0
    omega: int = 0
    angular_acceleration: int = 0
    steps: int = 0

    @property
    def total(self) -> int:
        """Sum over the four bounds."""
        return self.speed + self.acceleration + self.omega + self.angular_acceleration


@dataclass(frozen=True)
class TrackingResult:
    """A tracking run: time series and statistics.

    Attributes
    ----------
    status : Status
    t : (N,) float
        Times, s, every ``dt`` from 0.
    xy : (N, 2) float
        Positions.
    theta : (N,) float
        Headings, rad (not wrapped).
    v, omega : (N,) float
        Applied (saturated) speed and turn rate at each time.
    omega_cmd : (N,) float
        Commanded turn rate before saturation (0 at the last sample).
    v_ref : (N,) float
        Speed reference read from the profile (0 at the last sample).
    s : (N,) float
        Arc length of the closest path point.
    lateral_error : (N,) float
        Distance from the robot to the path, m.
    traversal_time : float
        Time of the last sample, s (the end is reached there if ``status`` is
        ``SOLVED``).
    max_lateral_error, mean_lateral_error : float
        Over the samples, m.
    max_abs_omega : float
        Largest applied ``|omega|``.
    max_abs_omega_cmd : float
        Largest commanded ``|omega|`` before saturation.
    violations : Violations
    """

    status: Status
    t: FloatArray
    xy: FloatArray
    theta: FloatArray
    v: FloatArray
    omega: FloatArray
    omega_cmd: FloatArray
    v_ref: FloatArray
    s: FloatArray
    lateral_error: FloatArray
    traversal_time: float
    max_lateral_error: float
    mean_lateral_error: float
    max_abs_omega: float
    max_abs_omega_cmd: float
    violations: Violations


def _polyline(path_xy: ArrayLike) -> tuple[FloatArray, FloatArray]:
    return clean_path(path_xy)


def constant_profile(
    path_xy: ArrayLike, vmax: float, amax: float, ds: float = 0.05
) -> tuple[FloatArray, FloatArray]:
    """The constant-vmax speed profile, with acceleration ramps at both ends.

    Parameters
    ----------
    path_xy : (n, 2) float
    vmax, amax : float
        Speed and acceleration bounds.
    ds : float
        Arc-length step, m.

    Returns
    -------
    s : (k,) float
    v : (k,) float
        ``vmax`` except for the ramps from and to rest.
    """
    _, sp = _polyline(path_xy)
    length = float(sp[-1])
    if length <= 0:
        return np.zeros(1), np.zeros(1)
    s = np.linspace(0.0, length, max(2, int(math.ceil(length / ds)) + 1))
    return s, limit_acceleration(s, np.full_like(s, vmax), amax)


def track(
    path_xy: ArrayLike,
    profile: tuple[ArrayLike, ArrayLike] | None = None,
    limits: UnicycleLimits | None = None,
    options: TrackingOptions | None = None,
) -> TrackingResult:
    """Simulate a unicycle tracking ``path_xy`` with adaptive pure pursuit.

    The robot starts at rest on the first point, heading along the first
    segment. At each step it projects itself onto the path (searching forward
    from the last closest segment, within reach of one look-ahead, so it never
    jumps to a nearby later leg), reads the speed limit ``v(s)`` at the
    position it will pass mid-step (``v**2`` is interpolated linearly in ``s``,
    so the profile's acceleration ramps are followed exactly), commands
    ``min(v(s), v + amax dt)`` (a limit is not a demand: only braking harder
    than ``amax`` counts as a violation), and steers toward the path point one look-ahead
    ``L = lookahead_min + lookahead_gain * v`` further on with
    ``omega = 2 v sin(alpha) / d`` (``alpha`` the bearing of that point, ``d``
    its distance). The commands are then checked against the bounds, saturated
    (speed, turn rate, then their rates of change) and integrated with the
    step's mean inputs (midpoint heading).

    Parameters
    ----------
    path_xy : (n, 2) float
        Polyline to follow, metres.
    profile : ((k,) float, (k,) float), optional
        Speed reference: arc lengths ``s`` (increasing) and speeds ``v``,
        linearly interpolated. Default :func:`constant_profile` at ``limits.vmax``.
    limits : UnicycleLimits, optional
    options : TrackingOptions, optional

    Returns
    -------
    TrackingResult

    Raises
    ------
    ValueError
        If the path or the profile is malformed.

    References
    ----------
    R. C. Coulter, "Implementation of the pure pursuit path tracking
    algorithm", CMU-RI-TR-92-01, 1992.
    """
    lim = UnicycleLimits() if limits is None else limits
    opt = TrackingOptions() if options is None else options
    p, sp = _polyline(path_xy)
    length = float(sp[-1])
    if profile is None:
        profile = constant_profile(p, lim.vmax, lim.amax)
    ps, pv = _checked_profile(profile)
    if p.shape[0] < 2 or length <= opt.goal_tolerance:
        heading = 0.0 if p.shape[0] < 2 else math.atan2(p[1, 1] - p[0, 1], p[1, 0] - p[0, 0])
        return _at_rest(float(p[0, 0]), float(p[0, 1]), heading)
    status, rows, wc, vr, counts = _simulate(p, sp, ps, pv, lim, opt)
    if status is Status.TIMEOUT:
        logger.info("tracking timed out after %.1f s at s = %.2f of %.2f m", rows[-1][0], rows[-1][6], length)
    T, X, Y, TH, V, W, SC, E = (list(c) for c in zip(*rows, strict=True))
    return _result(status, (T, X, Y, TH, V, W, wc, vr, SC, E), Violations(*counts))


def _simulate(p: FloatArray, sp: FloatArray, ps: FloatArray, pv: FloatArray, lim, opt):
    """The per-step loop of :func:`track` (one function: a call per step costs ~5 %). Returns
    (status, rows of (t, x, y, heading, v, omega, s, lateral error), commanded omegas,
    speed references, violation counts (speed, acceleration, omega, alpha, any))."""
    dt, length = opt.dt, float(sp[-1])
    x, y = float(p[0, 0]), float(p[0, 1])
    px, py, ux, uy, seg_len, S, PS, Q = _as_lists(p, sp, ps, pv)
    nseg, last_p = len(seg_len), len(PS) - 1
    vmax, wmax, amax, alpha_max = lim.vmax, lim.omega_max, lim.amax, lim.alpha_max
    tol = 1.0 + opt.violation_tolerance
    lmin, gain = opt.lookahead_min, opt.lookahead_gain
    creep = min(opt.creep_fraction * vmax, amax * dt)
    lim_dv, lim_dw = amax * dt, alpha_max * dt  # the largest change of v and w in a step
    v_bad, dv_bad, w_bad, dw_bad = vmax * tol, lim_dv * tol, wmax * tol, lim_dw * tol  # violations
    reach = lmin + gain * vmax + vmax * dt + 0.05
    n_max = int((opt.timeout_factor * length / vmax + 5.0) / dt) + 1
    th = math.atan2(uy[0], ux[0])
    v = w = sc = 0.0
    k = 0
    rows, WC, VR = [], [], []
    n_v = n_a = n_w = n_al = n_any = 0
    sin, cos, atan2, hypot, pi = math.sin, math.cos, math.atan2, math.hypot, math.pi
    for step in range(n_max):
        # Closest point, searching forward from the last segment within reach.
        best, kk, limit_s = math.inf, k, sc + reach
        while kk < nseg and S[kk] <= limit_s:
            rx, ry = x - px[kk], y - py[kk]
            u = rx * ux[kk] + ry * uy[kk]
            if u < 0.0:
                u = 0.0
            elif u > seg_len[kk]:
                u = seg_len[kk]
            ex, ey = rx - u * ux[kk], ry - u * uy[kk]
            d2 = ex * ex + ey * ey
            if d2 < best:
                best, k_best, u_best = d2, kk, u
            kk += 1
        k = k_best
        sc = S[k] + u_best
        rows.append((step * dt, x, y, th, v, w, sc, math.sqrt(best)))
        if length - sc <= opt.goal_tolerance:
            WC.append(0.0)
            VR.append(0.0)
            return Status.SOLVED, rows, WC, VR, (n_v, n_a, n_w, n_al, n_any)
        # Speed reference at the mid-step position s + (v + v_cmd) dt / 2, solved
        # by fixed-point iteration from v + amax dt: exact on the profile's
        # constant-acceleration ramps (v**2 linear in s, interpolated as such).
        v_ref = v + lim_dv
        for _ in range(3):
            sq = sc + 0.5 * (v + v_ref) * dt
            i = bisect_right(PS, sq) - 1
            if i < 0:
                q = Q[0]
            elif i >= last_p:
                q = Q[last_p]
            else:
                q = Q[i] + (sq - PS[i]) * (Q[i + 1] - Q[i]) / (PS[i + 1] - PS[i])
            v_ref = math.sqrt(q) if q > 0.0 else 0.0
        # The profile is a limit, not a demand: never ask for more speed than the robot
        # can reach this step. Braking beyond amax is still a violation.
        v_cmd = v_ref if v_ref > creep else creep
        if v_cmd > v + lim_dv:
            v_cmd = v + lim_dv
        # Pure pursuit toward the point one look-ahead further along the path.
        st = sc + lmin + gain * v_cmd
        if st >= length:
            tx, ty = px[-1], py[-1]
        else:
            j = bisect_right(S, st) - 1
            if j >= nseg:
                j = nseg - 1
            r = st - S[j]
            tx, ty = px[j] + r * ux[j], py[j] + r * uy[j]
        dx, dy = tx - x, ty - y
        dist = hypot(dx, dy)
        alpha = (atan2(dy, dx) - th + pi) % (2 * pi) - pi
        w_cmd = 2.0 * v_cmd * sin(alpha) / (dist if dist > 1e-6 else 1e-6)
        WC.append(w_cmd)
        VR.append(v_ref)
        # Bounds, checked before saturation.
        w_sat = w_cmd if -wmax <= w_cmd <= wmax else math.copysign(wmax, w_cmd)
        if v_cmd > v_bad or abs(v_cmd - v) > dv_bad or abs(w_cmd) > w_bad or abs(w_sat - w) > dw_bad:
            n_v, n_a = n_v + (v_cmd > v_bad), n_a + (abs(v_cmd - v) > dv_bad)
            n_w, n_al = n_w + (abs(w_cmd) > w_bad), n_al + (abs(w_sat - w) > dw_bad)
            n_any += 1
        # Saturate, then integrate with the step's mean speed and turn rate
        # (the inputs ramp linearly within a step under the rate bounds).
        v0, w0 = v, w
        dv = (v_cmd if v_cmd < vmax else vmax) - v
        v += lim_dv if dv > lim_dv else (-lim_dv if dv < -lim_dv else dv)
        dw = w_sat - w
        w += lim_dw if dw > lim_dw else (-lim_dw if dw < -lim_dw else dw)
        ds_step, dth = 0.5 * (v0 + v) * dt, 0.5 * (w0 + w) * dt
        mid = th + 0.5 * dth
        x += ds_step * cos(mid)
        y += ds_step * sin(mid)
        th += dth
    return Status.TIMEOUT, rows, WC, VR, (n_v, n_a, n_w, n_al, n_any)


def _as_lists(p: FloatArray, sp: FloatArray, ps: FloatArray, pv: FloatArray) -> tuple[list, ...]:
    """The path and the profile as plain lists for :func:`_simulate`'s loop (numpy scalar
    indexing costs ~10x more): x, y, unit directions, segment lengths, arc lengths of
    the path; arc lengths and squared speeds of the profile."""
    d = np.diff(p, axis=0)
    seg_len = np.linalg.norm(d, axis=1)
    ux, uy = (d[:, 0] / seg_len).tolist(), (d[:, 1] / seg_len).tolist()
    return p[:, 0].tolist(), p[:, 1].tolist(), ux, uy, seg_len.tolist(), sp.tolist(), ps.tolist(), (pv * pv).tolist()


def _checked_profile(profile) -> tuple[FloatArray, FloatArray]:
    ps = np.asarray(profile[0], dtype=float)
    pv = np.asarray(profile[1], dtype=float)
    if ps.ndim != 1 or ps.shape != pv.shape or ps.size < 1:
        raise InputError("profile must be two 1-D arrays of the same, positive length")
    if ps.size > 1 and np.any(np.diff(ps) <= 0):
        raise InputError("profile arc lengths must be increasing")
    if not (np.all(np.isfinite(pv)) and np.all(pv >= 0)):
        raise InputError("profile speeds must be finite and non-negative")
    return ps, pv


def _at_rest(x: float, y: float, heading: float) -> TrackingResult:
    """The result of a path too short to move along: there already."""
    one = np.zeros(1)
    return TrackingResult(
        Status.SOLVED, one, np.array([[x, y]]), np.array([heading]), one, one, one, one, one, one,
        0.0, 0.0, 0.0, 0.0, 0.0, Violations(),
    )  # fmt: skip


def _result(status: Status, series, violations: Violations) -> TrackingResult:
    T, X, Y, TH, V, W, WC, VR, SC, E = series
    err = np.asarray(E)
    w_arr = np.asarray(W)
    wc_arr = np.asarray(WC)
    return TrackingResult(
        status=status,
        t=np.asarray(T),
        xy=np.stack([X, Y], axis=1),
        theta=np.asarray(TH),
        v=np.asarray(V),
        omega=w_arr,
        omega_cmd=wc_arr,
        v_ref=np.asarray(VR),
        s=np.asarray(SC),
        lateral_error=err,
        traversal_time=float(T[-1]),
        max_lateral_error=float(err.max()),
        mean_lateral_error=float(err.mean()),
        max_abs_omega=float(np.abs(w_arr).max()),
        max_abs_omega_cmd=float(np.abs(wc_arr).max()),
        violations=violations,
    )


def _arc(start: FloatArray, heading: float, radius: float, angle: float, step: float) -> FloatArray:
    """Points of a circular arc (left turn for ``angle > 0``), excluding the start."""
    n = max(2, int(math.ceil(abs(angle) * radius / step)))
    sign = 1.0 if angle > 0 else -1.0
    centre = start + radius * np.array([-math.sin(heading), math.cos(heading)]) * sign
    phi0 = heading - sign * math.pi / 2
    phi = phi0 + np.linspace(0.0, angle, n + 1)[1:]
    return centre + radius * np.stack([np.cos(phi), np.sin(phi)], axis=1)


def synthetic_paths() -> dict[str, FloatArray]:
    """Named test paths (metres), each an ``(n, 2) float`` polyline.

    * ``straight``: 10 m line.
    * ``s_curve``: 3 m straight, 90 deg left and 90 deg right arcs of radius
      1.5 m sampled every 0.1 m, 3 m straight.
    * ``zigzag``: sharp corners of 45 and 90 degrees.
    * ``corner``: one 90 degree corner.
    * ``hairpin``: two 90 degree corners 1.2 m apart.
    * ``arc``: 270 degree arc of radius 2 m sampled every 0.1 m, between straights
      of 3 m and 1.5 m.
    """
    paths: dict[str, FloatArray] = {}
    paths["straight"] = np.array([[0.0, 0.0], [10.0, 0.0]])
    pts = [np.array([[0.0, 0.0], [3.0, 0.0]])]
    a1 = _arc(np.array([3.0, 0.0]), 0.0, 1.5, math.pi / 2, 0.1)
    a2 = _arc(a1[-1], math.pi / 2, 1.5, -math.pi / 2, 0.1)
    end = a2[-1] + np.array([3.0, 0.0])
    paths["s_curve"] = np.concatenate(pts + [a1, a2, end[None]])
    paths["zigzag"] = np.array(
        [[0, 0], [3, 0], [5, 2], [7, 0], [9, 2], [11, 0], [14, 0]], dtype=float
    )
    paths["corner"] = np.array([[0.0, 0.0], [5.0, 0.0], [5.0, 5.0]])
    paths["hairpin"] = np.array([[0.0, 0.0], [5.0, 0.0], [5.0, 1.2], [0.0, 1.2]])
    a3 = _arc(np.array([3.0, 0.0]), 0.0, 2.0, 1.5 * math.pi, 0.1)
    tail = a3[-1] + np.array([0.0, -1.5])
    paths["arc"] = np.concatenate([[[0.0, 0.0]], a3, tail[None]])
    return paths
