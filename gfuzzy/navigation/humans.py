"""Simulated people: ORCA and social-force crowds, with or without the robot among them.

* :class:`OrcaCrowd`: the humans of CrowdNav (Chen et al. 2019): ORCA (van den Berg et
  al. 2011, the RVO2 library through ``pyrvo``) with CrowdNav's parameters (neighbour
  distance 10 m, 10 neighbours, time horizons 5 s, radius + 0.01, maximum speed v_pref,
  preferred velocity toward the goal, unit length farther than 1 m away). When the robot
  is *visible* it is one more ORCA agent, placed every step where the robot is and moving
  with the velocity it last had, so the humans take their share of the avoidance (as
  CrowdNav's ``robot.visible``); when it is not, the humans ignore it.
* :class:`SocialForceCrowd`: the social force model (Helbing & Molnar 1995; the
  anisotropic form of Helbing et al. 2000): each person relaxes toward their preferred
  velocity in ``tau`` seconds and is pushed away from every other person (and the
  visible robot) by ``A exp(-gap / B)``, weighted by ``lam + (1 - lam)(1 + cos phi) / 2``
  (people ahead matter more than people behind); integrated in sub-steps of 0.05 s,
  the speed capped at v_pref. Our own implementation (pysocialforce's import writes a
  log file into the working folder and turns the root logger to DEBUG).

Both advance by :meth:`step` over one time step; their positions at the step ends are
the people's true motion (linear in between, as a scene's ``trajectory`` mover).
"""

from __future__ import annotations

import math

import numpy as np

from ..typed import FloatArray

__all__ = ["ORCA", "OrcaCrowd", "SocialForceCrowd", "social_force_velocity", "preferred_velocity"]

#: CrowdNav's ORCA parameters (crowd_sim/envs/policy/orca.py).
ORCA = {"neighbor_dist": 10.0, "max_neighbors": 10, "time_horizon": 5.0, "time_horizon_obst": 5.0}
#: Social force parameters: relaxation time (s), repulsion strength (m/s^2) and range (m),
#: anisotropy, integration sub-step (s).
SF = {"tau": 0.5, "A": 10.0, "B": 0.2, "lam": 0.35, "substep": 0.05}


def _rvo():
    try:
        import pyrvo
    except ImportError as exc:  # an optional dependency: say which extra brings it
        raise ImportError("ORCA humans need pyrvo (pip install 'gfuzzy[crowd]')") from exc
    return pyrvo


def preferred_velocity(pos: FloatArray, goals: FloatArray, v_pref: float) -> FloatArray:
    """(K, 2) velocity toward the goals: ``v_pref`` long farther than 1 m (CrowdNav), the
    remaining vector scaled by ``v_pref`` nearer (so a person stops on the goal)."""
    d = np.asarray(goals, float) - np.asarray(pos, float)
    n = np.hypot(d[:, 0], d[:, 1])
    scale = np.where(n > 1.0, v_pref / np.maximum(n, 1e-12), v_pref)
    return d * scale[:, None]


class OrcaCrowd:
    """K ORCA humans.

    Parameters
    ----------
    starts, goals : (K, 2) float
    radius, v_pref : float
    dt : float
        Time step (s).
    visible : bool
        The robot is an agent the humans avoid.
    robot_radius : float
    """

    def __init__(self, starts, goals, radius=0.3, v_pref=1.0, dt=0.25, visible=False, robot_radius=0.3):
        pyrvo = _rvo()
        self.pos = np.array(starts, dtype=float).reshape(-1, 2)
        self.goals = np.array(goals, dtype=float).reshape(-1, 2)
        self.vel = np.zeros_like(self.pos)
        self.radius, self.v_pref, self.dt, self.visible = radius, v_pref, dt, visible
        o = ORCA
        self._sim = pyrvo.RVOSimulator(dt, o["neighbor_dist"], o["max_neighbors"], o["time_horizon"],
                                       o["time_horizon_obst"], radius + 0.01, v_pref)  # fmt: skip
        self._ids = [self._sim.add_agent((float(x), float(y))) for x, y in self.pos]
        self._robot = None
        if visible:
            # far away until the first step places it; its speed bound: the robot's vmax
            self._robot = self._sim.add_agent((1e6, 1e6), o["neighbor_dist"], o["max_neighbors"], o["time_horizon"],
                                              o["time_horizon_obst"], robot_radius + 0.01, 10.0, (0.0, 0.0))  # fmt: skip

    def step(self, robot_xy: FloatArray | None = None, robot_vel: FloatArray | None = None) -> None:
        """Advance one time step; the robot (when visible) is at ``robot_xy`` moving with ``robot_vel``."""
        pref = preferred_velocity(self.pos, self.goals, self.v_pref)
        for i, a in enumerate(self._ids):
            self._sim.set_agent_pref_velocity(a, (float(pref[i, 0]), float(pref[i, 1])))
        if self._robot is not None and robot_xy is not None:
            v = (0.0, 0.0) if robot_vel is None else (float(robot_vel[0]), float(robot_vel[1]))
            self._sim.set_agent_position(self._robot, (float(robot_xy[0]), float(robot_xy[1])))
            self._sim.set_agent_velocity(self._robot, v)
            self._sim.set_agent_pref_velocity(self._robot, v)
        self._sim.do_step()
        for i, a in enumerate(self._ids):
            p, v = self._sim.get_agent_position(a), self._sim.get_agent_velocity(a)
            self.pos[i] = (p.x, p.y)
            self.vel[i] = (v.x, v.y)


def social_force_velocity(pos: FloatArray, vel: FloatArray, goals: FloatArray, others: FloatArray,
                          radii: FloatArray, others_radii: FloatArray, v_pref: float, h: float,
                          self_index: np.ndarray | None = None) -> FloatArray:  # fmt: skip
    """(K, 2) velocities after one sub-step ``h`` of the social force model.

    Parameters
    ----------
    pos, vel, goals : (K, 2) float
        The people moved.
    others : (M, 2) float
        Everyone who repels them (may include themselves: ``self_index`` (K,) gives the
        row of ``others`` that is person k, skipped).
    radii : (K,) float
    others_radii : (M,) float
    v_pref : float
    h : float
    """
    s = SF
    desired = preferred_velocity(pos, goals, v_pref)
    force = (desired - vel) / s["tau"]
    if len(others):
        d = pos[:, None, :] - others[None, :, :]  # (K, M, 2) from the other to me
        dist = np.maximum(np.hypot(d[..., 0], d[..., 1]), 1e-9)
        n = d / dist[..., None]
        gap = dist - radii[:, None] - others_radii[None, :]
        speed = np.hypot(vel[:, 0], vel[:, 1])
        e = np.where(speed[:, None] > 1e-9, vel / np.maximum(speed, 1e-9)[:, None], desired / np.maximum(
            np.hypot(desired[:, 0], desired[:, 1]), 1e-9)[:, None])  # fmt: skip
        cos_phi = -np.einsum("kmj,kj->km", n, e)
        w = s["lam"] + (1 - s["lam"]) * (1 + cos_phi) / 2
        mag = s["A"] * np.exp(-gap / s["B"]) * w
        if self_index is not None:
            mag[np.arange(len(pos)), self_index] = 0.0
        force = force + np.einsum("km,kmj->kj", mag, n)
    v = vel + force * h
    sp = np.hypot(v[:, 0], v[:, 1])
    over = sp > v_pref
    v[over] *= (v_pref / sp[over])[:, None]
    return v


class SocialForceCrowd:
    """K social-force humans (see the module's notes); the same interface as :class:`OrcaCrowd`."""

    def __init__(self, starts, goals, radius=0.3, v_pref=1.0, dt=0.25, visible=False, robot_radius=0.3):
        self.pos = np.array(starts, dtype=float).reshape(-1, 2)
        self.goals = np.array(goals, dtype=float).reshape(-1, 2)
        self.vel = np.zeros_like(self.pos)
        self.radius, self.v_pref, self.dt, self.visible = radius, v_pref, dt, visible
        self.robot_radius = robot_radius

    def step(self, robot_xy: FloatArray | None = None, robot_vel: FloatArray | None = None) -> None:
        k = len(self.pos)
        n_sub = max(1, int(round(self.dt / SF["substep"])))
        h = self.dt / n_sub
        radii = np.full(k, self.radius)
        start = self.pos.copy()
        for j in range(n_sub):
            others, o_r = self.pos, radii
            if self.visible and robot_xy is not None:
                rv = np.zeros(2) if robot_vel is None else np.asarray(robot_vel, float)
                r_now = np.asarray(robot_xy, float)[:2] + rv * (j * h)
                others = np.vstack([self.pos, r_now[None]])
                o_r = np.append(radii, self.robot_radius)
            self.vel = social_force_velocity(self.pos, self.vel, self.goals, others, radii, o_r, self.v_pref, h,
                                             np.arange(k))  # fmt: skip
            self.pos = self.pos + self.vel * h
        # the velocity a sensor would report: the step's mean (positions are what is seen)
        self.vel = (self.pos - start) / self.dt if self.dt > 0 else self.vel
        if not math.isfinite(float(np.sum(self.pos))):
            raise FloatingPointError("social force crowd diverged")
