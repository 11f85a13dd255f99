"""Crowd episodes: the CrowdNav circle-crossing protocol as scenes, and its ORCA robot.

After Chen, Liu, Kreiss & Alahi, "Crowd-Robot Interaction: Crowd-aware Robot Navigation
with Attention-based Deep Reinforcement Learning" (ICRA 2019) and its CrowdNav code:

* K humans, discs of radius 0.3 with a preferred speed of 1 m/s, start on a circle of
  radius 4 about the origin at a uniformly random angle, each coordinate perturbed by a
  uniform noise in [-0.5, 0.5) m (``(random - 0.5) * v_pref``), and walk to the opposite
  point ``(-x, -y)``. A draw is rejected when the new human's start lies within
  ``0.3 + r + 0.2`` m (the discomfort distance) of an earlier agent's start or goal,
  the robot's included.
* The humans are moved by ORCA (van den Berg et al., the RVO2 library through ``pyrvo``)
  with CrowdNav's parameters: neighbour distance 10 m, 10 neighbours, time horizons 5 s,
  radius 0.3 + 0.01, maximum speed 1, preferred velocity toward the goal (unit length
  farther than 1 m away, the remaining vector nearer). They do not see the robot. Once at
  their goal they stay there (still ORCA agents for the others).
* Time step 0.25 s; the humans' positions are sampled at every step and move linearly in
  between, which is exactly how a scene's ``trajectory`` mover moves, so collisions are
  decided exactly between samples.
* The robot is a disc of radius 0.3, vmax 1, from (0, -4) to (0, 4) within 25 s.

``pyrvo`` is an optional dependency (the ``test`` and ``bench`` extras).
"""

from __future__ import annotations

import math

import numpy as np

from .rng import create_rng
from .scene import Scene, parse_scene
from .typing import FloatArray

__all__ = ["CROWD", "circle_crossing", "simulate_humans", "orca_robot", "run_episode", "episodes"]

#: The protocol's constants.
CROWD = {
    "human_radius": 0.3,
    "v_pref": 1.0,
    "circle_radius": 4.0,
    "discomfort": 0.2,
    "robot_radius": 0.3,
    "robot_vmax": 1.0,
    "start": (0.0, -4.0),
    "goal": (0.0, 4.0),
    "time_limit": 25.0,
    "time_step": 0.25,
    "bounds": (-6.0, -6.0, 6.0, 6.0),
    # ORCA (CrowdNav's policy/orca.py)
    "neighbor_dist": 10.0,
    "max_neighbors": 10,
    "time_horizon": 5.0,
    "time_horizon_obst": 5.0,
}


def _rvo():
    try:
        import pyrvo
    except ImportError as exc:  # an optional dependency: say which extra brings it
        raise ImportError("crowd episodes need pyrvo (pip install 'gfuzzy[bench]')") from exc
    return pyrvo


def _starts(K: int, rng: np.random.Generator) -> tuple[FloatArray, FloatArray]:
    c = CROWD
    r = c["human_radius"]
    agents = [(np.array(c["start"]), np.array(c["goal"]), c["robot_radius"])]
    starts, goals = [], []
    while len(starts) < K:
        angle = rng.random() * 2 * math.pi
        p = np.array(
            [
                c["circle_radius"] * math.cos(angle) + (rng.random() - 0.5) * c["v_pref"],
                c["circle_radius"] * math.sin(angle) + (rng.random() - 0.5) * c["v_pref"],
            ]
        )
        if any(
            min(np.hypot(*(p - a_start)), np.hypot(*(p - a_goal))) < r + a_r + c["discomfort"]
            for a_start, a_goal, a_r in agents
        ):
            continue
        starts.append(p)
        goals.append(-p)
        agents.append((p, -p, r))
    return np.array(starts).reshape(-1, 2), np.array(goals).reshape(-1, 2)


def simulate_humans(starts: FloatArray, goals: FloatArray, duration: float) -> FloatArray:
    """ORCA humans walking from ``starts`` to ``goals``.

    Returns
    -------
    (K, n, 2) float
        Positions at ``t = 0, step, 2 step, ...`` up to at least ``duration``.
    """
    c = CROWD
    pyrvo = _rvo()
    dt = c["time_step"]
    n = int(math.ceil(duration / dt - 1e-9)) + 1
    sim = pyrvo.RVOSimulator(
        dt, c["neighbor_dist"], c["max_neighbors"], c["time_horizon"], c["time_horizon_obst"],
        c["human_radius"] + 0.01, c["v_pref"],
    )
    ids = [sim.add_agent((float(x), float(y))) for x, y in starts]
    out = np.empty((len(starts), n, 2))
    out[:, 0] = starts
    for k in range(1, n):
        for i, a in enumerate(ids):
            p = sim.get_agent_position(a)
            d = goals[i] - np.array([p.x, p.y])
            norm = float(np.hypot(*d))
            v = d / norm * c["v_pref"] if norm > 1.0 else d
            sim.set_agent_pref_velocity(a, (float(v[0]), float(v[1])))
        sim.do_step()
        for i, a in enumerate(ids):
            p = sim.get_agent_position(a)
            out[i, k] = (p.x, p.y)
    return out


def circle_crossing(K: int, seed, duration: float | None = None, name: str = "crowd") -> Scene:
    """One circle-crossing episode as a scene (humans as ``trajectory`` movers, one query).

    Parameters
    ----------
    K : int
        Number of humans.
    seed : int or numpy.random.Generator
    duration : float, optional
        Seconds of the humans' walk to record (default: the time limit plus 5 s).

    Returns
    -------
    Scene
        Bounds ``[-6, -6, 6, 6]``, no static obstacles, the robot disc and the query
        ``cross`` from (0, -4) to (0, 4).
    """
    c = CROWD
    rng = create_rng(seed)
    starts, goals = _starts(K, rng)
    duration = c["time_limit"] + 5.0 if duration is None else duration
    track = simulate_humans(starts, goals, duration)
    times = np.arange(track.shape[1]) * c["time_step"]
    doc = {
        "version": 1,
        "name": name,
        "bounds": list(c["bounds"]),
        "robot": {"disc": c["robot_radius"], "vmax": c["robot_vmax"]},
        "obstacles": [],
        "movers": [
            {
                "name": f"h{i}",
                "disc": c["human_radius"],
                "trajectory": np.column_stack([times, np.round(track[i], 9)]).tolist(),
            }
            for i in range(K)
        ],
        "queries": [{"name": "cross", "start": list(c["start"]), "goal": list(c["goal"]), "t0": 0.0}],
    }
    return parse_scene(doc, f"<{name}>")


def orca_robot(scene: Scene, time_limit: float | None = None) -> tuple[FloatArray, bool]:
    """CrowdNav's ORCA robot among the scene's (trajectory) humans, who ignore it.

    Every step the robot computes its ORCA velocity against the humans' current positions
    and velocities, assuming they take half of the avoidance (they do not), and moves
    with it for one step. It has arrived when its centre is within its radius of the goal
    (CrowdNav's criterion).

    Returns
    -------
    rows : (n, 3) float
        ``[t, x, y]`` of the robot, every step until arrival or the time limit.
    arrived : bool
    """
    c = CROWD
    pyrvo = _rvo()
    dt = c["time_step"]
    q = scene.queries[0]
    limit = c["time_limit"] if time_limit is None else time_limit
    pos = np.array(q.start, dtype=float)
    goal = np.array(q.goal, dtype=float)
    vel = np.zeros(2)
    rows = [[0.0, *pos]]
    t = 0.0
    while t < limit - 1e-9:
        if np.hypot(*(pos - goal)) < c["robot_radius"]:
            return np.array(rows), True
        sim = pyrvo.RVOSimulator(
            dt, c["neighbor_dist"], c["max_neighbors"], c["time_horizon"], c["time_horizon_obst"],
            c["robot_radius"] + 0.01, c["robot_vmax"],
        )
        me = sim.add_agent((float(pos[0]), float(pos[1])))
        sim.set_agent_velocity(me, (float(vel[0]), float(vel[1])))
        d = goal - pos
        norm = float(np.hypot(*d))
        pref = d / norm * c["robot_vmax"] if norm > 1.0 else d
        sim.set_agent_pref_velocity(me, (float(pref[0]), float(pref[1])))
        for mv in scene.movers:
            xy, present = mv.state(np.array([t, t + dt]))
            if not present[0]:
                continue
            v = (xy[1] - xy[0]) / dt
            h = sim.add_agent(
                (float(xy[0, 0]), float(xy[0, 1])), c["neighbor_dist"], c["max_neighbors"],
                c["time_horizon"], c["time_horizon_obst"], mv.radius + 0.01, c["v_pref"],
                (float(v[0]), float(v[1])),
            )
            sim.set_agent_pref_velocity(h, (float(v[0]), float(v[1])))
        sim.do_step()
        v = sim.get_agent_velocity(me)
        vel = np.array([v.x, v.y])
        speed = float(np.hypot(*vel))
        if speed > c["robot_vmax"]:  # RVO2's float arithmetic may overshoot by an ulp
            vel *= c["robot_vmax"] / speed * (1 - 1e-9)
        pos = pos + vel * dt
        t += dt
        rows.append([t, *pos])
    return np.array(rows), bool(np.hypot(*(pos - goal)) < c["robot_radius"])


def run_episode(scene: Scene, roadmap, options, policies) -> dict:
    """One circle-crossing episode under each of ``policies``.

    Parameters
    ----------
    scene : Scene
        From :func:`circle_crossing`: the humans' simulated tracks are its movers.
    roadmap : Roadmap
        A roadmap of the (empty) scene.
    options : NavOptions
        The navigator's settings.
    policies : sequence of {"navigator", "oracle", "orca"}
        ``navigator``: :class:`gfuzzy.Navigator` through :func:`gfuzzy.navsim.simulate`;
        ``oracle``: :func:`gfuzzy.plan` told the humans' true future (possible because they
        ignore the robot), a lower bound on the time to the goal on the same roadmap;
        ``orca``: :func:`orca_robot`.

    Returns
    -------
    dict
        Per policy: ``collision`` (bool, decided exactly), ``reached`` (bool), ``time`` (s,
        nan unless reached), ``sep`` (smallest distance to a human, m), ``latency`` (replan
        seconds, array) and, for the navigator, ``modes`` (how each replan answered).
    """
    from .navsim import min_separation, simulate
    from .planner import PlanOptions, plan

    q = scene.queries[0]
    out = {}
    limit = CROWD["time_limit"]
    if "navigator" in policies:
        res = simulate(scene, roadmap, q.start, q.goal, 0.0, CROWD["time_step"], max_time=limit, options=options)
        sep = min_separation(scene, res.trajectory.waypoints)
        out["navigator"] = {
            "collision": sep < -1e-9,
            "reached": res.reached,
            "time": res.duration if res.reached else math.nan,
            "sep": sep,
            "latency": res.replan_seconds,
            "modes": res.modes,
        }
    if "oracle" in policies:
        r = plan(scene, roadmap, q.start, q.goal, 0.0, PlanOptions(horizon=limit))
        ok = r.solved
        sep = min_separation(scene, r.trajectory.waypoints) if ok else math.nan
        out["oracle"] = {
            "collision": ok and sep < -1e-9,
            "reached": ok,
            "time": r.duration if ok else math.nan,
            "sep": sep,
            "latency": np.array([r.planning_seconds]),
        }
    if "orca" in policies:
        rows, arrived = orca_robot(scene)
        sep = min_separation(scene, rows)
        out["orca"] = {
            "collision": sep < -1e-9,
            "reached": arrived,
            "time": rows[-1, 0] if arrived else math.nan,
            "sep": sep,
            "latency": np.zeros(0),
        }
    return out


def _episode(roadmap, K: int, seed: int, options, policies) -> dict:
    return run_episode(circle_crossing(K, seed, name=f"crowd-{K}-{seed}"), roadmap, options, policies)


def _same(x):
    return x


def episodes(client, roadmap, K: int, seeds, options, policies) -> list[dict]:
    """:func:`run_episode` of K humans for each of ``seeds``, in seed order: in this process
    (``client`` None), or one task each on a ``distributed.Client`` (the roadmap travels to
    every worker once; latencies are measured in the workers)."""
    if client is None:
        return [_episode(roadmap, K, s, options, policies) for s in seeds]
    # the roadmap as a task's result, not scattered data: Dask recomputes a result that a
    # dying worker took with it, while scattered data would be lost for the whole batch
    rm = client.submit(_same, roadmap, pure=False)
    n = len(seeds)
    futures = client.map(_episode, [rm] * n, [K] * n, list(seeds), [options] * n, [policies] * n, pure=False)
    return client.gather(futures)
