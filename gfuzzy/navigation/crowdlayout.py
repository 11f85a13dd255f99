"""Where a crowd episode starts: CrowdNav's and CrowdNav++'s placement of the humans.

The protocols draw each human's start (and goal) at random and redraw one that comes
within ``r + r' + 0.2`` m of an earlier agent's (rejection sampling: CrowdNav's
``generate_circle_crossing_human`` and ``generate_square_crossing_human``, CrowdNav++'s
arena). Rejection sampling can jam: the humans placed first may leave no room for the
rest, and a count that does not fit is never placed (CrowdNav loops forever). Here every
draw of a start counts: every ``RESTART_EVERY`` of them the placement starts over, and
after ``DRAW_BUDGET`` it is refused with an :class:`InputError` that says how many
humans the attempts placed at most; a square's goal, drawn again until one is far
enough, is refused after ``GOAL_DRAW_BUDGET`` draws of its own (CrowdNav's loop hangs there).

The candidates are tested in blocks with numpy, reading the generator's doubles in the
order the one-draw-at-a-time loop reads them, so a layout is the one that loop draws (the
same seed, the same episodes as before the blocks) and a refusal takes one to five seconds
(a million draws one at a time took about 40 s). The generator is left where that loop
leaves it (a caller's generator may serve more than the layout).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..typed import FloatArray

__all__ = ["CROWD", "ARENA", "SQUARE_WIDTH", "Layout", "layout", "RESTART_EVERY", "DRAW_BUDGET", "GOAL_DRAW_BUDGET"]

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
#: CrowdNav's square crossing: the square's width (m).
SQUARE_WIDTH = 10.0
#: CrowdNav++'s arena: half its side (m), the humans' circle, the robot's sensing range
#: (m), time limit (s), how often (s) and how likely a human changes goal, the least
#: distance between the robot's start and goal (m).
ARENA = {"size": 6.0, "circle_radius": 6.0 * math.sqrt(2.0), "sense": 5.0, "time_limit": 50.0,
         "goal_every": 5.0, "goal_chance": 0.5, "min_travel": 8.0}  # fmt: skip

#: Draws (of starts and goals) after which a jammed placement starts over.
RESTART_EVERY = 100_001
#: Draws after which the placement is refused.
DRAW_BUDGET = 1_000_000
#: Draws of one square crossing's goal after which the placement is refused (CrowdNav's
#: loop draws on for ever; a dense square's goal took it 1.63 million draws once: the
#: episode is kept as it was).
GOAL_DRAW_BUDGET = 2_000_000
#: Slack (m) of the block test: a candidate within it of a threshold is decided by the
#: exact test of the one-at-a-time loop (numpy's vectorised sine may differ by an ulp).
_SLACK = 1e-9
_MAX_BLOCK = 8192


@dataclass(frozen=True)
class Layout:
    """Where an episode starts: the robot's start and goal, the humans' starts and goals."""

    start: FloatArray
    goal: FloatArray
    human_starts: FloatArray
    human_goals: FloatArray


class _Doubles:
    """The generator's uniform doubles in order, drawn ahead in blocks; :meth:`settle`
    leaves the generator after the doubles used, as if they had been drawn one by one."""

    def __init__(self, rng: np.random.Generator):
        self.rng, self.buf, self.pos = rng, np.empty(0), 0
        self.state, self.used = rng.bit_generator.state, 0

    def settle(self) -> None:
        """Put the generator back after the doubles :meth:`skip` used (none read ahead)."""
        self.rng.bit_generator.state = self.state
        left = self.used
        while left:
            n = min(left, 1 << 16)
            self.rng.random(n)
            left -= n

    def peek(self, n: int) -> FloatArray:
        if self.pos + n > len(self.buf):
            self.buf = np.concatenate([self.buf[self.pos :], self.rng.random(max(n, 1 << 16))])
            self.pos = 0
        return self.buf[self.pos : self.pos + n]

    def skip(self, n: int) -> None:
        self.peek(n)
        self.pos += n
        self.used += n


class _Ring:
    """Candidates on a ring (``circle``, ``arena``): three doubles each (the angle, then an
    offset per coordinate)."""

    width = 3

    def __init__(self, radius: float, offset: float, scale: float):
        self.radius, self.offset, self.scale = radius, offset, scale

    def points(self, u: FloatArray) -> FloatArray:
        a = u[:, 0] * 2 * math.pi
        return np.column_stack([self.radius * np.cos(a), self.radius * np.sin(a)]) + (u[:, 1:] - self.offset) * self.scale

    def point(self, u: FloatArray) -> FloatArray:
        a = float(u[0]) * 2 * math.pi  # as the one-at-a-time loop computes it
        return np.array([self.radius * math.cos(a), self.radius * math.sin(a)]) + (u[1:] - self.offset) * self.scale


class _SquareSide:
    """Starts of the square crossing (``sign`` None: three doubles, the side then x, y) or
    goals on the side opposite ``sign`` (two doubles, x, y)."""

    def __init__(self, width: float, sign: float | None = None):
        self.sign = sign
        self.width = 3 if sign is None else 2
        self.side = width

    def points(self, u: FloatArray) -> FloatArray:
        if self.sign is None:
            sign = np.where(u[:, 0] > 0.5, -1.0, 1.0)
            x, y = u[:, 1], u[:, 2]
        else:
            sign, x, y = -self.sign, u[:, 0], u[:, 1]
        return np.column_stack([x * self.side * 0.5 * sign, (y - 0.5) * self.side])

    def point(self, u: FloatArray) -> FloatArray:
        return self.points(np.asarray(u)[None, :])[0]


class _Placement:
    """The agents placed so far and the draws spent."""

    def __init__(self, scenario: str, humans: int, start, goal, robot_radius: float, radius: float, gap: float):
        self.scenario, self.humans = scenario, humans
        self.robot = (np.asarray(start, float), np.asarray(goal, float), robot_radius)
        self.radius, self.gap = radius, gap
        self.draws, self.best, self.attempts, self.next_restart = 0, 0, 1, RESTART_EVERY
        self.goal_draws = 0  # the draws of a square's goal, bounded apart (they do not count toward a restart)
        self.reset()

    def reset(self) -> None:
        s, g, rr = self.robot
        self.starts, self.goals, self.radii = [s], [g], [rr]

    @property
    def placed(self) -> int:
        return len(self.starts) - 1

    def refuse(self) -> InputError:
        return InputError(
            f"cannot place {self.humans} humans in the {self.scenario} scenario: its protocol keeps each one's "
            f"start and goal {2 * self.radius + self.gap:g} m from the others', and {self.attempts} attempts of "
            f"up to {RESTART_EVERY - 1} random draws placed at most {self.best} (give fewer --humans)"
        )

    def room(self, counted: bool = True) -> int:
        """Draws left before the next restart or the refusal (0: a restart is due); of the
        goals' own budget when not ``counted``."""
        if not counted:
            if self.goal_draws >= GOAL_DRAW_BUDGET:
                raise self.refuse()
            return GOAL_DRAW_BUDGET - self.goal_draws
        if self.draws >= DRAW_BUDGET:
            raise self.refuse()
        return min(self.next_restart - 1, DRAW_BUDGET) - self.draws

    def restart_if_due(self) -> bool:
        """Start over when the next draw is the restart's (that draw is then made as usual)."""
        if self.room() == 0:
            self.next_restart += RESTART_EVERY
            self.attempts += 1
            self.reset()
            return True
        return False

    def far(self, pts: FloatArray, ends: list, slack: float = 0.0) -> np.ndarray:
        """(n,) True where every point is at least ``radius + r + gap`` from each of
        ``ends`` (agents' starts, goals, or both in turn), ``r`` the end's agent's radius."""
        e = np.asarray(ends)
        th = np.array([self.radius + r + self.gap for r in self.radii])
        th = np.tile(th, len(e) // len(th))
        dx = pts[:, None, 0] - e[None, :, 0]
        dy = pts[:, None, 1] - e[None, :, 1]
        return np.all(dx * dx + dy * dy >= (th[None, :] - slack) ** 2, axis=1)

    def exact_far(self, p: FloatArray, ends: list) -> bool:
        # the one-at-a-time loop's test, to the last bit
        return all(np.hypot(*(p - e)) >= self.radius + r + self.gap for e, r in zip(ends, self.radii, strict=True))

    def spend(self, n: int, counted: bool) -> None:
        if counted:
            self.draws += n
        else:
            self.goal_draws += n

    def add(self, p: FloatArray, g: FloatArray) -> None:
        self.starts.append(p)
        self.goals.append(g)
        self.radii.append(self.radius)
        self.best = max(self.best, self.placed)


def _first(stream: _Doubles, place: _Placement, kind, ends: str, counted: bool = True) -> FloatArray | None:
    """The doubles of the first candidate of ``kind`` far enough from the agents'
    ``ends`` ("starts", "goals" or "both"), reading ``kind.width`` doubles a candidate;
    None when the draws ran out before the next restart (the stream then stands after
    them). Draws not ``counted`` (the square's goals) spend the goals' own budget."""
    block, w = 16, kind.width
    agents = {"starts": place.starts, "goals": place.goals, "both": place.starts + place.goals}[ends]
    lists = [place.starts, place.goals] if ends == "both" else [agents]
    while True:
        room = place.room(counted)
        if room == 0:
            return None
        n = min(block, room)
        u = stream.peek(n * w).reshape(n, w)
        for j in np.flatnonzero(place.far(kind.points(u), agents, _SLACK)):
            if all(place.exact_far(kind.point(u[j]), e) for e in lists):
                place.spend(int(j) + 1, counted)
                stream.skip((int(j) + 1) * w)
                return u[j].copy()
        place.spend(n, counted)
        stream.skip(n * w)
        block = min(2 * block, _MAX_BLOCK)


def _place_ring(stream: _Doubles, place: _Placement, ring: _Ring) -> None:
    while place.placed < place.humans:
        if place.restart_if_due():
            continue
        u = _first(stream, place, ring, "both")
        if u is not None:
            p = ring.point(u)
            place.add(p, -p)


def _place_square(stream: _Doubles, place: _Placement, width: float) -> None:
    starts = _SquareSide(width)
    while place.placed < place.humans:
        if place.restart_if_due():
            continue
        u = _first(stream, place, starts, "starts")
        if u is None:
            continue
        goals = _SquareSide(width, -1.0 if u[0] > 0.5 else 1.0)
        place.goal_draws = 0  # each start's goal: refused after GOAL_DRAW_BUDGET draws (CrowdNav's loop hangs)
        g = _first(stream, place, goals, "goals", counted=False)
        place.add(starts.point(u), goals.point(g))


def layout(setting, rng: np.random.Generator) -> Layout:
    """Draw an episode's robot and humans as the scenario's protocol does.

    * ``circle`` (CrowdNav): robot (0, -4) -> (0, 4); humans on the circle of radius 4 at a
      uniform angle, each coordinate perturbed by U[-0.5, 0.5) m, walking to the opposite point;
      a draw within ``r + r' + 0.2`` of an earlier agent's start or goal is redrawn.
    * ``square`` (CrowdNav): robot as above; a human starts at ``x = U[0, 1) 5 s``,
      ``y = U[-5, 5)`` on a random side ``s`` and walks to ``x = U[0, 1) 5 (-s)``, ``y =
      U[-5, 5)``, start and goal each redrawn when near an earlier agent's start (goal).
    * ``arena`` (CrowdNav++): robot start and goal uniform in [-6, 6]^2, at least 8 m
      apart; humans on the circle of radius 6 sqrt(2) (the arena's corners) perturbed by
      U[0, 2) m per coordinate, walking to the opposite point.

    Every :data:`RESTART_EVERY` draws of a start the humans are all drawn again (those
    placed may leave the rest no room), and after :data:`DRAW_BUDGET` of them (or
    :data:`GOAL_DRAW_BUDGET` draws of one square's goal) the placement is refused. The generator is left as the
    one-at-a-time loop leaves it.

    Parameters
    ----------
    setting : CrowdSetting
    rng : numpy.random.Generator

    Returns
    -------
    Layout

    Raises
    ------
    InputError
        ``setting.humans`` could not be placed.
    """
    c = CROWD
    if setting.scenario == "arena":
        while True:
            p = rng.uniform(-ARENA["size"], ARENA["size"], 4)
            if math.hypot(p[0] - p[2], p[1] - p[3]) >= ARENA["min_travel"]:
                break
        start, goal = p[:2], p[2:]
    else:
        start, goal = np.array(c["start"], float), np.array(c["goal"], float)
    place = _Placement(setting.scenario, setting.humans, start, goal, c["robot_radius"], c["human_radius"],
                       c["discomfort"])  # fmt: skip
    stream = _Doubles(rng)
    if setting.scenario == "square":
        _place_square(stream, place, SQUARE_WIDTH)
    elif setting.scenario == "arena":
        _place_ring(stream, place, _Ring(ARENA["circle_radius"], 0.0, 2.0))
    else:
        _place_ring(stream, place, _Ring(c["circle_radius"], 0.5, c["v_pref"]))
    stream.settle()
    hs, hg = place.starts[1:], place.goals[1:]
    return Layout(start, goal, np.array(hs).reshape(-1, 2), np.array(hg).reshape(-1, 2))
