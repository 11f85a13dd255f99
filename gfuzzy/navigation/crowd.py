"""Crowd navigation benchmarks: CrowdNav's and CrowdNav++'s protocols (``gfuzzy crowd``).

After Chen, Liu, Kreiss & Alahi, "Crowd-Robot Interaction: Crowd-aware Robot Navigation
with Attention-based Deep Reinforcement Learning" (ICRA 2019) and its CrowdNav code, and
Liu et al., "Intention Aware Robot Crowd Navigation with Attention-Based Interaction
Graph" (ICRA 2023) and its CrowdNav++ code (read, not copied):

* :func:`layout` draws an episode: ``circle`` (K humans, discs of radius 0.3 with a
  preferred speed of 1 m/s, on a circle of radius 4 at a uniform angle, each coordinate
  perturbed by U[-0.5, 0.5) m, walking to the opposite point; a draw within ``0.3 + r +
  0.2`` m of an earlier agent's start or goal, the robot's included, is redrawn; the robot
  from (0, -4) to (0, 4) within 25 s), ``square`` (CrowdNav's square crossing, width
  10 m) and ``arena`` (CrowdNav++: 12 x 12 m, humans on the circle of radius 6 sqrt(2)
  who change goals, 5 m sensing, 50 s).
* The humans (:mod:`gfuzzy.navigation.humans`) are ORCA agents with CrowdNav's parameters, or a
  social-force crowd; *visible* humans take the robot as one more agent.
* :func:`run_episode` runs each policy (``navigator``, ``orca``, ``social-force``,
  ``oracle``) in a closed loop with time step 0.25 s, observing through
  :class:`gfuzzy.navigation.sensing.Sensor`; positions move linearly between samples (a scene's
  ``trajectory`` mover), so collisions are decided exactly. Results are typed
  (:class:`Episode`, :class:`Outcome`, :class:`PolicySummary`).

:func:`circle_crossing` and :func:`orca_robot` are the older one-scene helpers (humans who
ignore the robot, as ``trajectory`` movers of a scene; CrowdNav's ORCA robot).

``pyrvo`` is an optional dependency (the ``crowd`` and ``test`` extras).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from enum import Enum

import numpy as np

from ..errors import InputError, check_interrupt
from ..rng import create_rng
from ..scene.scene import Mover, Scene, parse_scene
from ..typed import FloatArray
from .crowdlayout import ARENA, CROWD, Layout, layout
from .sensing import Sensor, SensorOptions
from .socialmetrics import INTRUSION_HORIZON, SocialMetrics, social_metrics

__all__ = [
    "CROWD", "ARENA", "SCENARIOS", "POLICIES", "CROWD_MODELS", "KINEMATICS", "CSV_COLUMNS", "Outcome",
    "CrowdSetting", "Layout", "Episode", "circle_crossing", "simulate_humans", "orca_robot",
    "layout", "episode_layout", "crowd_scene", "crowd_roadmap", "run_episode", "episodes", "MAX_EPISODES",
]  # fmt: skip

#: Most episodes one run may ask for: every layout is drawn before the first episode (3-10 ms
#: each) and each episode takes seconds; ``--episodes 1e9`` drew layouts for days, saying nothing.
MAX_EPISODES = 10_000


def _rvo():
    try:
        import pyrvo
    except ImportError as exc:  # an optional dependency: say which extra brings it
        raise ImportError("crowd episodes need pyrvo (pip install 'gfuzzy[crowd]')") from exc
    return pyrvo


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
    lay = layout(CrowdSetting("circle", K), rng)
    starts, goals = lay.human_starts, lay.human_goals
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


# ---------------------------------------------------------------------------------------
# The crowd benchmarks of ``gfuzzy crowd`` (CONTRACT.md section 7)

SCENARIOS = ("circle", "square", "arena")
POLICIES = ("navigator", "orca", "social-force", "oracle")
#: The oracle's ``modes`` in an episode where :func:`gfuzzy.plan` found no plan: the robot
#: stood at its start (a collision is then someone walking into it; an arena's unicycle).
NO_PLAN = "no_plan"
CROWD_MODELS = ("orca", "social-force")
KINEMATICS = ("holonomic", "unicycle")
class Outcome(str, Enum):
    """How an episode ended (CrowdNav's ``ReachGoal``, ``Collision``, ``Timeout``)."""

    SUCCESS = "success"
    COLLISION = "collision"
    TIMEOUT = "timeout"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class CrowdSetting:
    """One benchmark setting: what every episode of a run shares.

    Attributes
    ----------
    scenario : {"circle", "square", "arena"}
    humans : int
    visible : bool
        The humans see the robot and react to it.
    crowd : {"orca", "social-force"}
        How the humans move.
    kinematics : {"holonomic", "unicycle"}
    sensor : SensorOptions
        How the robot observes (its ``sense`` is the scenario's unless set).
    goal_changes : bool
        ``arena``: every 5 s each human draws a new goal with chance 0.5 (CrowdNav++'s
        ``random_goal_changing``, on in its default configuration); False: a human changes
        goal only on arrival (its non-randomised test, where its policy scored success
        0.92, intrusion 4.23 %).
    reverse : bool
        ``unicycle``: the robot may drive backwards (the scene's ``robot.reverse``).
    """

    scenario: str = "circle"
    humans: int = 5
    visible: bool = False
    crowd: str = "orca"
    kinematics: str = "holonomic"
    sensor: SensorOptions = field(default_factory=SensorOptions)
    goal_changes: bool = True
    reverse: bool = False

    def __post_init__(self):
        if self.scenario not in SCENARIOS:
            raise InputError(f"scenario must be one of {', '.join(SCENARIOS)}, got {self.scenario!r}")
        if self.crowd not in CROWD_MODELS:
            raise InputError(f"crowd must be one of {', '.join(CROWD_MODELS)}, got {self.crowd!r}")
        if self.kinematics not in KINEMATICS:
            raise InputError(f"kinematics must be one of {', '.join(KINEMATICS)}, got {self.kinematics!r}")
        if self.reverse and self.kinematics != "unicycle":
            raise InputError("reverse is only for a unicycle robot (kinematics unicycle)")
        if not 0 <= self.humans <= 200:
            raise InputError(f"humans must be between 0 and 200, got {self.humans}")

    @property
    def time_limit(self) -> float:
        return ARENA["time_limit"] if self.scenario == "arena" else CROWD["time_limit"]

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        h = ARENA["size"] + 1.0 if self.scenario == "arena" else 6.0
        return (-h, -h, h, h)

    @property
    def sense(self) -> float:
        if math.isfinite(self.sensor.sense):
            return self.sensor.sense
        return ARENA["sense"] if self.scenario == "arena" else math.inf


@dataclass(frozen=True)
class Episode:
    """One episode of one policy (a row of ``gfuzzy crowd``'s CSV).

    Attributes
    ----------
    policy : str
    seed : int
        The episode's number within the run (its layout is drawn from the run's seed and it).
    outcome : Outcome
    time : float
        Seconds to the goal (nan unless ``outcome`` is success).
    min_separation : float
        Smallest gap to a human over the episode (m; negative: a collision).
    social : SocialMetrics
        Discomfort and intrusion counts over the episode's steps.
    replan_seconds : (n,) float
        Wall-clock time of each of the policy's decisions.
    modes : tuple of (str, int)
        The navigator's answers (``NavMode``) and how often.
    path_length : float
        Metres the robot travelled.
    """

    policy: str
    seed: int
    outcome: Outcome
    time: float
    min_separation: float
    social: SocialMetrics
    replan_seconds: FloatArray = field(compare=False, repr=False)
    modes: tuple = ()
    path_length: float = 0.0

    @property
    def reached(self) -> bool:
        return self.outcome == Outcome.SUCCESS

    @property
    def collision(self) -> bool:
        return self.outcome == Outcome.COLLISION

    @property
    def intrusion_ratio(self) -> float:
        """CrowdNav++'s intrusion ratio of the episode: intrusion steps over its steps,
        plus one (CrowdNav++ tests arrival, collision and the time limit at the start of a
        step, so the step that finds the episode over is counted, never as an intrusion)."""
        return self.social.intrusion_steps / (self.social.steps + 1)

    def row(self, setting: CrowdSetting, run_seed: int | None = None) -> dict:
        """The CSV row (the column names are the file format); ``run_seed``: the run's
        ``--seed`` (episode ``i`` of seed ``s`` is the same episode in every run)."""
        lat = self.replan_seconds
        q = (lambda p: round(float(np.quantile(lat, p)) * 1e3, 3)) if len(lat) else (lambda p: "")
        return {
            "scenario": setting.scenario, "humans": setting.humans, "visible": int(setting.visible),
            "crowd": setting.crowd, "kinematics": setting.kinematics,
            "reverse": int(setting.reverse), "policy": self.policy, "episode": self.seed,
            "outcome": str(self.outcome), "success": int(self.reached), "collision": int(self.collision),
            "timeout": int(self.outcome == Outcome.TIMEOUT),
            "time": "" if math.isnan(self.time) else round(self.time, 4),
            "min_separation": round(self.min_separation, 4) if math.isfinite(self.min_separation) else "",
            "steps": self.social.steps, "discomfort_steps": self.social.discomfort_steps,
            "discomfort_frequency": round(self.social.discomfort_frequency, 5),
            "intrusion_steps": self.social.intrusion_steps, "intrusion_ratio": round(self.intrusion_ratio, 5),
            "path_length": round(self.path_length, 4), "replans": len(lat),
            "replan_p50_ms": q(0.5), "replan_p95_ms": q(0.95), "replan_max_ms": round(float(lat.max()) * 1e3, 3) if len(lat) else "",
            "modes": " ".join(f"{k}:{v}" for k, v in self.modes),
            "seed": "" if run_seed is None else run_seed, "velocity": setting.sensor.velocity,
            "noise": setting.sensor.noise, "fov": setting.sensor.fov, "occlusion": int(setting.sensor.occlusion),
            "sense": setting.sense if math.isfinite(setting.sense) else "",
            "goal_changes": int(setting.goal_changes and setting.scenario == "arena"),
        }  # fmt: skip


CSV_COLUMNS = tuple(Episode("x", 0, Outcome.TIMEOUT, math.nan, 0.0, SocialMetrics(0, 0, 0), np.zeros(0)).row(CrowdSetting()))


def episode_layout(setting: CrowdSetting, seed: int, index: int) -> Layout:
    """Episode ``index``'s layout in the run of ``seed`` (drawn from
    ``numpy.random.default_rng([seed, index])``: the same in every policy and process).

    Raises
    ------
    InputError
        The scenario's protocol cannot place the setting's humans (the message names the
        episode).
    """
    try:
        return layout(setting, np.random.default_rng([seed, index]))
    except InputError as exc:
        raise InputError(f"episode {index}: {exc}") from None


def _new_goal(rng: np.random.Generator) -> FloatArray:
    """A new goal on CrowdNav++'s circle (a uniform angle, U[-0.5, 0.5) m noise)."""
    angle = rng.random() * 2 * math.pi
    R = ARENA["circle_radius"]
    return np.array([R * math.cos(angle), R * math.sin(angle)]) + (rng.random(2) - 0.5) * CROWD["v_pref"]


class _World:
    """The humans of one episode, step by step: their positions at every step end."""

    def __init__(self, setting: CrowdSetting, lay: Layout, rng: np.random.Generator, visible: bool):
        from .humans import OrcaCrowd, SocialForceCrowd

        c = CROWD
        model = OrcaCrowd if setting.crowd == "orca" else SocialForceCrowd
        self.crowd = model(lay.human_starts, lay.human_goals, c["human_radius"], c["v_pref"], c["time_step"],
                           visible, c["robot_radius"])  # fmt: skip
        self.setting, self.rng, self.k = setting, rng, 0
        self.track = [self.crowd.pos.copy()]
        self.vel = np.zeros_like(self.crowd.pos)

    def truth(self) -> FloatArray:
        """(K, 5) ``[x, y, vx, vy, r]`` now (velocity: that of the last step)."""
        pos = self.track[-1]
        return np.column_stack([pos, self.vel, np.full(len(pos), CROWD["human_radius"])]).reshape(-1, 5)

    def step(self, robot_xy=None, robot_vel=None) -> None:
        self.crowd.step(robot_xy, robot_vel)
        self.k += 1
        self.vel = (self.crowd.pos - self.track[-1]) / CROWD["time_step"]
        self.track.append(self.crowd.pos.copy())
        if self.setting.scenario == "arena":  # CrowdNav++'s goal changes
            c = self.crowd
            every = int(round(ARENA["goal_every"] / CROWD["time_step"]))
            if self.setting.goal_changes and self.k % every == 0:
                for i in range(len(c.goals)):
                    if self.rng.random() <= ARENA["goal_chance"]:
                        c.goals[i] = _new_goal(self.rng)
            arrived = np.hypot(*(c.goals - c.pos).T) < CROWD["human_radius"]
            for i in np.nonzero(arrived)[0]:
                c.goals[i] = _new_goal(self.rng)

    def tracks(self) -> FloatArray:
        return np.stack(self.track, axis=1)  # (K, n, 2)


def _movers(tracks: FloatArray) -> tuple:
    c = CROWD
    times = np.arange(tracks.shape[1]) * c["time_step"]
    return tuple(
        Mover(f"h{i}", "disc", c["human_radius"], (0.0, 0.0), trajectory=np.column_stack([times, tracks[i]]))
        for i in range(len(tracks))
    )


#: A unicycle robot's largest turning rate in the benchmarks (rad/s; issue 19's setting).
UNICYCLE_WMAX = 1.0


def _robot_doc(setting: CrowdSetting) -> dict:
    c = CROWD
    doc = {"disc": c["robot_radius"], "vmax": c["robot_vmax"]}
    if setting.kinematics == "unicycle":
        doc.update(kinematics="unicycle", wmax=UNICYCLE_WMAX, reverse=setting.reverse)
    return doc


def _poses(setting: CrowdSetting, lay: Layout) -> tuple[FloatArray, FloatArray]:
    """The robot's start and goal poses: a unicycle starts and ends facing from its start
    to its goal."""
    if setting.kinematics != "unicycle":
        return lay.start.astype(float), lay.goal.astype(float)
    theta = math.atan2(*(lay.goal - lay.start)[::-1])
    return np.array([*lay.start, theta]), np.array([*lay.goal, theta])


def crowd_scene(setting: CrowdSetting, lay: Layout | None = None, tracks: FloatArray | None = None,
                name: str = "crowd") -> Scene:  # fmt: skip
    """The episode's world as a scene: bounds, the robot (disc 0.3, vmax 1), no static
    obstacles, the humans' ``tracks`` (K, n, 2) as ``trajectory`` movers, the query."""
    doc = {
        "version": 1, "name": name, "bounds": list(setting.bounds),
        "robot": _robot_doc(setting), "obstacles": [],
        "movers": [], "queries": [],
    }  # fmt: skip
    if lay is not None:
        start, goal = _poses(setting, lay)
        doc["queries"] = [{"name": "cross", "start": start.tolist(), "goal": goal.tolist(), "t0": 0.0}]
    scene = parse_scene(doc, f"<{name}>")
    if tracks is not None and len(tracks):
        scene = replace(scene, movers=_movers(tracks))
    return scene


def _roadmap_options(setting: CrowdSetting):
    from ..roadmap.roadmap import RoadmapOptions

    return RoadmapOptions(vertices=500 if setting.scenario == "arena" else 400, seed=1)


def crowd_roadmap(setting: CrowdSetting):
    """The navigator's roadmap of the scenario's empty square (seeded: 400 vertices, 500
    for the arena)."""
    from ..roadmap.roadmap import build_roadmap

    # a unicycle navigates on the roadmap of the plane too (its own graph turns in place)
    return build_roadmap(crowd_scene(replace(setting, kinematics="holonomic", reverse=False)), _roadmap_options(setting))


def run_episode(setting: CrowdSetting, roadmap, seed: int, index: int, policies, options=None,
                oracle_dt: float | None = None) -> list[Episode]:  # fmt: skip
    """One episode of the benchmark under each of ``policies``.

    Parameters
    ----------
    setting : CrowdSetting
    roadmap : Roadmap
        Of :func:`crowd_scene` (``setting``), for the navigator and the oracle.
    seed, index : int
        The run's seed and the episode's number: the layout and the humans' goal changes
        are drawn from ``numpy.random.default_rng([seed, index])``.
    policies : sequence of str
        ``navigator`` (:class:`gfuzzy.Navigator`), ``orca`` (CrowdNav's ORCA robot),
        ``social-force`` (a social-force robot), ``oracle`` (:func:`gfuzzy.plan` told the
        humans' true future; only when they do not see the robot).
    options : NavOptions, optional
        The navigator's settings.
    oracle_dt : float, optional
        The oracle's time step (default: ``PlanOptions``'s). A differential drive's turns
        take whole steps, so a finer step can solve an episode a coarser one cannot.

    Returns
    -------
    list of Episode
        One per policy, in the order given. Invisible humans walk the same way in every
        policy's episode; visible ones start the same way and then react to each robot.

    Notes
    -----
    Every 0.25 s the robot observes the humans through ``setting.sensor`` (within the
    scenario's range), its policy answers, and the robot moves along the answer for
    0.25 s while the humans take one step (seeing the robot where it was, moving as it
    last moved, when visible). The episode ends with a collision (the gap between the
    robot and a human, computed exactly over the step, below 0), at success (the robot's
    centre within its radius of the goal at a step's end, CrowdNav's test), or at the
    time limit (25 s; 50 s in the arena).
    """
    from ..planner.planner import PlanOptions, plan
    from .crowdpolicies import NavigatorPolicy, OraclePolicy, OrcaPolicy, SocialForcePolicy
    from .lookout import knowing_view
    from .navigator import Navigator, NavOptions

    if setting.kinematics == "unicycle" and set(policies) - {"navigator", "oracle"}:
        raise InputError("with a unicycle robot only the navigator and oracle policies run (ORCA and social "
                         "force are holonomic here)")
    if "oracle" in policies and setting.visible:
        raise InputError("the oracle policy needs humans who ignore the robot (not --visible)")
    c = CROWD
    dt, limit = c["time_step"], setting.time_limit
    n_steps = int(round(limit / dt))
    extra = int(math.ceil(INTRUSION_HORIZON / dt)) + 1
    lay = episode_layout(setting, seed, index)
    tracks = None
    if not setting.visible:  # the same walk for every policy, known in advance for the oracle
        world = _World(setting, lay, np.random.default_rng([seed, index, 1]), False)
        for _ in range(n_steps + extra):
            world.step()
        tracks = world.tracks()
    out = []
    for policy in policies:
        scene = crowd_scene(setting, lay, tracks, f"crowd-{setting.scenario}-{index}")
        if policy == "navigator":
            nav_opts = knowing_view(options or NavOptions(), setting.sensor.fov)
            act = NavigatorPolicy(Navigator(scene, roadmap, _poses(setting, lay)[1], nav_opts))
        elif policy == "orca":
            act = OrcaPolicy(lay.goal, CROWD)
        elif policy == "social-force":
            act = SocialForcePolicy(lay.goal, CROWD)
        elif policy == "oracle":
            plan_opts = PlanOptions(horizon=limit) if oracle_dt is None else PlanOptions(horizon=limit, dt=oracle_dt)
            res = plan(scene, roadmap, *_poses(setting, lay), 0.0, plan_opts)
            act = OraclePolicy(res.trajectory if res.solved else None, CROWD["robot_radius"])
        else:
            raise InputError(f"policy must be one of {', '.join(POLICIES)}, got {policy!r}")
        world = None if tracks is not None else _World(setting, lay, np.random.default_rng([seed, index, 1]), True)
        out.append(_drive(setting, policy, index, lay, act, tracks, world, n_steps, extra))
    return out


def _drive(setting, policy, index, lay, act, tracks, world, n_steps, extra) -> Episode:
    """The closed loop of one policy's episode (see :func:`run_episode`)."""
    from .crowdpolicies import piece_of
    from .navigator import BUDGET_CLOCKS

    # the navigator's replan times on its budget's clock (as gfuzzy navigate reports them)
    clock = BUDGET_CLOCKS[act.nav.options.budget_clock] if hasattr(act, "nav") else time.perf_counter
    c = CROWD
    dt, rr = c["time_step"], c["robot_radius"]
    sensor = Sensor(crowd_scene(setting), replace(setting.sensor, sense=setting.sense))
    pose = _poses(setting, lay)[0].copy()
    heading = math.atan2(*(lay.goal - lay.start)[::-1])
    rows = [np.array([0.0, *pose])]
    vel = np.zeros(2)
    seconds: list[float] = []
    modes: dict = {}
    outcome, t_goal, k = Outcome.TIMEOUT, math.nan, 0
    radius = np.full(setting.humans, c["human_radius"])
    for k in range(n_steps):
        t = k * dt
        if world is not None:
            truth = world.truth()
            here = world.track[-1]
        else:
            here = tracks[:, k]
            prev = tracks[:, k - 1] if k else here
            truth = np.column_stack([here, (here - prev) / dt, radius]).reshape(-1, 5)
        obs = sensor.observe(t, pose, heading, truth)
        c0 = clock()
        traj = act(t, pose, obs, sensor.unknown) if hasattr(act, "nav") else act(t, pose, obs)
        seconds.append(clock() - c0)
        check_interrupt()  # a Ctrl-C native code dropped during the step stops the run here
        if hasattr(act, "nav"):
            m = str(act.nav.last.mode)
            modes[m] = modes.get(m, 0) + 1
        piece = piece_of(traj, t, t + dt)
        piece[0, 1:] = pose
        rows.extend(piece[1:])
        new = piece[-1, 1:].copy()
        if world is not None:
            world.step(pose[:2], vel)
            nxt = world.track[-1]
        else:
            nxt = tracks[:, k + 1]
        step_tracks = np.stack([here, nxt], axis=1)  # (K, 2, 2)
        gap = _step_gap(piece, step_tracks, t, dt, rr + c["human_radius"])
        d = new[:2] - pose[:2]
        if len(new) == 3:  # a unicycle looks where it faces
            heading = float(new[2])
        elif np.hypot(*d) > 1e-9:
            heading = math.atan2(d[1], d[0])
        vel = d / dt
        pose = new
        if gap < 0:
            outcome = Outcome.COLLISION
            break
        if np.hypot(*(pose[:2] - lay.goal)) < rr:
            outcome, t_goal = Outcome.SUCCESS, t + dt
            break
    if policy == "oracle" and act.traj is None:  # it stood at its start: say why, beside its outcome
        modes[NO_PLAN] = 1
    w = np.array(rows)
    keep = np.ones(len(w), dtype=bool)
    keep[1:] = np.diff(w[:, 0]) > 1e-9
    w = w[keep]
    if world is not None:  # the humans' next 1.25 s, for the intrusion test
        for _ in range(extra):
            world.step(pose[:2], np.zeros(2))
        tracks_used = world.tracks()
    else:
        tracks_used = tracks
    movers = _movers(tracks_used)
    social = social_metrics(w, rr, movers, dt)
    sep = min(
        (_disc_track(w, mv.trajectory, rr + mv.radius) for mv in movers),
        default=math.inf,
    )
    length = float(np.sum(np.hypot(*np.diff(w[:, 1:3], axis=0).T)))
    return Episode(policy, index, outcome, t_goal, sep, social, np.array(seconds), tuple(sorted(modes.items())), length)


def _step_gap(piece: FloatArray, step_tracks: FloatArray, t: float, dt: float, radii: float) -> float:
    times = np.array([t, t + dt])
    return min(
        (_disc_track(piece, np.column_stack([times, step_tracks[i]]), radii) for i in range(len(step_tracks))),
        default=math.inf,
    )


def _disc_track(w, track, radii) -> float:
    from .navsim import _disc_track_separation

    return _disc_track_separation(w, track, radii)


def _run_one(setting, roadmap, seed, index, policies, options):
    return run_episode(setting, roadmap, seed, index, policies, options)


def _same(x):
    return x


def episodes(setting: CrowdSetting, roadmap, seed: int, count: int, policies, options=None, client=None,
             progress=None) -> list[list[Episode]]:  # fmt: skip
    """:func:`run_episode` for episodes ``0 .. count - 1``, in order: in this process
    (``client`` None) or one task each on a ``distributed.Client`` (the roadmap travels
    to every worker once; replan times are measured in the workers). ``progress(done,
    total)`` is called as episodes finish. ``count`` is at most :data:`MAX_EPISODES`
    (:class:`InputError` otherwise)."""
    if not 1 <= count <= MAX_EPISODES:
        raise InputError(f"episodes must be between 1 and {MAX_EPISODES}, got {count}")
    if client is None:
        out = []
        for i in range(count):
            out.append(run_episode(setting, roadmap, seed, i, policies, options))
            if progress:
                progress(i + 1, count)
        return out
    from distributed import as_completed

    # the roadmap as a task's result, not scattered data: Dask recomputes a result that a
    # dying worker took with it, while scattered data would be lost for the whole batch
    rm = client.submit(_same, roadmap, pure=False)
    futures = [client.submit(_run_one, setting, rm, seed, i, list(policies), options, pure=False) for i in range(count)]
    done = 0
    for _ in as_completed(futures):
        done += 1
        if progress:
            progress(done, count)
        check_interrupt()
    return client.gather(futures)
