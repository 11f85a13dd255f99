"""The robot policies of the crowd benchmarks (:mod:`gfuzzy.navigation.crowd`): each is called with
``(t, pose, observations)`` every step and answers with a trajectory from ``[t, *pose]``
that the robot follows for one step. ``c`` is the protocol's constants
(:data:`gfuzzy.navigation.crowd.CROWD`: time step, robot radius and speed, ORCA parameters)."""

from __future__ import annotations

import numpy as np

from ..trajectory import Trajectory
from ..typed import FloatArray
from .humans import _rvo

__all__ = ["OrcaPolicy", "SocialForcePolicy", "NavigatorPolicy", "OraclePolicy", "piece_of"]


class OrcaPolicy:
    """CrowdNav's ORCA robot: its ORCA velocity among the observed humans, who it assumes
    take half of the avoidance, held for one step."""

    def __init__(self, goal, c: dict):
        self.goal = np.asarray(goal, float)
        self.vel = np.zeros(2)
        self.c = c

    def __call__(self, t, pose, obs) -> Trajectory:
        pyrvo = _rvo()
        c, dt = self.c, self.c["time_step"]
        sim = pyrvo.RVOSimulator(dt, c["neighbor_dist"], c["max_neighbors"], c["time_horizon"],
                                 c["time_horizon_obst"], c["robot_radius"] + 0.01, c["robot_vmax"])  # fmt: skip
        me = sim.add_agent((float(pose[0]), float(pose[1])))
        sim.set_agent_velocity(me, (float(self.vel[0]), float(self.vel[1])))
        pref = _toward(pose, self.goal, c["robot_vmax"])
        sim.set_agent_pref_velocity(me, (float(pref[0]), float(pref[1])))
        for x, y, vx, vy, r in obs:
            h = sim.add_agent((float(x), float(y)), c["neighbor_dist"], c["max_neighbors"], c["time_horizon"],
                              c["time_horizon_obst"], float(r) + 0.01, c["v_pref"], (float(vx), float(vy)))  # fmt: skip
            sim.set_agent_pref_velocity(h, (float(vx), float(vy)))
        sim.do_step()
        v = sim.get_agent_velocity(me)
        self.vel = _capped(np.array([v.x, v.y]), c["robot_vmax"])
        p = np.asarray(pose, float)[:2]
        return Trajectory(np.array([[t, *p], [t + dt, *(p + self.vel * dt)]]), c["robot_radius"])


class SocialForcePolicy:
    """A social-force robot: the model of :mod:`gfuzzy.navigation.humans` for the robot, pushed away
    from the observed humans (walking on at their observed velocity), held for one step."""

    def __init__(self, goal, c: dict):
        self.goal = np.asarray(goal, float)
        self.vel = np.zeros(2)
        self.c = c

    def __call__(self, t, pose, obs) -> Trajectory:
        from .humans import SF, social_force_velocity

        c, dt = self.c, self.c["time_step"]
        n_sub = max(1, int(round(dt / SF["substep"])))
        h = dt / n_sub
        p = np.asarray(pose, float)[:2].copy()
        v = self.vel.copy()
        rows = [[t, *p]]
        for j in range(n_sub):
            others = obs[:, :2] + obs[:, 2:4] * (j * h)
            v = social_force_velocity(p[None], v[None], self.goal[None], others, np.array([c["robot_radius"]]),
                                      obs[:, 4], c["robot_vmax"], h)[0]  # fmt: skip
            v = _capped(v, c["robot_vmax"])
            p = p + v * h
            rows.append([t + (j + 1) * h, *p])
        self.vel = (p - np.asarray(pose, float)[:2]) / dt
        return Trajectory(np.array(rows), c["robot_radius"])


class NavigatorPolicy:
    def __init__(self, nav):
        self.nav = nav

    def __call__(self, t, pose, obs, unknown=None) -> Trajectory:
        return self.nav.step(t, pose, obs, unknown)


class OraclePolicy:
    """The plan told the humans' true future (they ignore the robot): followed as planned."""

    def __init__(self, traj: Trajectory | None, radius: float):
        self.traj = traj
        self.radius = radius

    def __call__(self, t, pose, obs) -> Trajectory:
        if self.traj is None:  # no plan: stand
            return Trajectory(np.array([[t, *pose], [t + 1.0, *pose]]), self.radius)
        return Trajectory(_rows_from(self.traj, t), self.radius)


def _toward(pose, goal, vmax) -> FloatArray:
    d = np.asarray(goal, float)[:2] - np.asarray(pose, float)[:2]
    n = float(np.hypot(*d))
    return d / n * vmax if n > 1.0 else d * vmax


def _capped(v: FloatArray, vmax: float) -> FloatArray:
    s = float(np.hypot(*v))
    return v * (vmax / s * (1 - 1e-9)) if s > vmax * (1 - 1e-9) else v


def _rows_from(traj: Trajectory, t: float) -> FloatArray:
    """Rows of ``traj`` from ``t`` on (standing at its end for a second after it)."""
    w = traj.waypoints
    if t >= w[-1, 0] - 1e-9:
        return np.array([[t, *w[-1, 1:]], [t + 1.0, *w[-1, 1:]]])
    inner = w[w[:, 0] > t + 1e-9]
    return np.vstack([np.array([t, *traj.at(t)])[None], inner])


def piece_of(traj: Trajectory, ta: float, tb: float) -> FloatArray:
    """Rows of the motion along ``traj`` from ``ta`` to ``tb`` (standing after its end)."""
    w = traj.waypoints
    inner = w[(w[:, 0] > ta + 1e-9) & (w[:, 0] < tb - 1e-9)]
    end = traj.at(min(tb, w[-1, 0]))
    return np.vstack([np.array([ta, *traj.at(ta)])[None], inner, np.array([tb, *end])[None]])
