"""A differential drive's simple motions: paths through via-points, timed rows, evasions.

Every motion here is a sequence of turns in place and straight moves along the heading
(CONTRACT section 6): the GA's refined path (:func:`turn_path`), the navigator's direct
motion to the goal (:func:`drive_rows`) and its evasive candidates (:func:`evasions`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, check_number
from ..poses import wrap_angle
from ..settings import SPEED_SAFETY
from ..typed import FloatArray

__all__ = ["turn_path", "drive_rows", "settle_at", "evasions", "reach_fraction", "turn_free", "pick_turn", "lane_turn", "fan", "Fan", "SAME_HEADING", "MERGE_HEADING"]

#: A turn's sweep is certified in arcs of at most this (rad): ``motion_free`` turns along
#: the shorter arc.
_ARC = 0.5 * math.pi

#: Headings closer than this (rad) are the same.
SAME_HEADING = 1e-9
#: Headings within this (rad) share a copy at a vertex, or need no turn before a lane:
#: below half of ``SAME_HEADING``, so the two ends of a lane joined after it differ by less
#: than the check's 1e-9 rad.
MERGE_HEADING = 0.4 * SAME_HEADING

#: The fractions of an evasive straight move tried, longest first (:func:`reach_fraction`).
REACH_FRACTIONS = (1.0, 0.5, 0.25)
#: Steps of the sphere tracing (two clearances each) that certify one piece of the fan
#: (:func:`fan`) at most: about 30 ms of FCL queries.
FAN_TRACE_STEPS = 256


def _xy_pose(robot, x: float, y: float, h: float) -> list:
    """A pose for the static geometry: [x, y] for a disc, [x, y, h] otherwise."""
    return [x, y] if robot.shape == "disc" else [x, y, h]


def turn_free(geometry, x: float, y: float, h: float, dh: float, max_steps: int = 100_000,
              swept: bool | None = None) -> bool:  # fmt: skip
    """Whether turning in place at (x, y) from ``h`` by ``dh`` (signed, any size) is free,
    the sweep certified (a disc: the pose alone) within ``max_steps`` of the tracing per arc.
    ``swept``: whether ``geometry.sweep_bound(x, y) > 0``, when the caller knows it."""
    robot = geometry.robot
    if robot.shape == "disc":
        return geometry.clearance1([x, y]) >= 0
    if swept is None:
        swept = geometry.sweep_bound(x, y) > 0
    if swept:  # the circumscribed disc is free: so is every heading
        return True
    n = max(1, int(math.ceil(abs(dh) / _ARC)))
    prev = [x, y, wrap_angle(h)]
    for i in range(1, n + 1):
        cur = [x, y, wrap_angle(h + dh * i / n)]
        if not geometry.motion_free(prev, cur, max_steps):
            return False
        prev = cur
    return True


def pick_turn(geometry, x: float, y: float, h1: float, h2: float, max_steps: int = 100_000,
              same: float = SAME_HEADING) -> float | None:  # fmt: skip
    """The signed turn from ``h1`` to ``h2``: the shorter arc when its sweep is free, else
    the longer one, else None (0 when the headings are within ``same``; a lane joined after
    it, whose ends differ by up to ``same`` more, wants ``MERGE_HEADING``)."""
    d = float(wrap_angle(h2 - h1))
    if abs(d) <= same:
        return 0.0
    for dh in (d, d - math.copysign(2 * math.pi, d)):
        if turn_free(geometry, x, y, h1, dh, max_steps):
            return dh
    return None


def lane_turn(geometry, x: float, y: float, h1: float, h2: float, max_steps: int = 100_000) -> float | None:
    """:func:`pick_turn` before a lane or after it: headings more than ``MERGE_HEADING``
    apart need a turn, so the lane's two ends differ by less than the check's 1e-9 rad
    (counted from ``SAME_HEADING`` they differed by up to twice it, and answers turned
    1.2e-9 to 1.8e-9 rad while moving)."""
    return pick_turn(geometry, x, y, h1, h2, max_steps, same=MERGE_HEADING)


def _free(geometry, a, b, max_steps: int = 100_000) -> bool:
    """Static certification of a -> b (a disc's body ignores the heading) within
    ``max_steps`` of the sphere tracing (beyond: not certified)."""
    if geometry.robot.shape == "disc":
        return geometry.motion_free(list(a[:2]), list(b[:2]), max_steps)
    return geometry.motion_free(list(a), list(b), max_steps)


def turn_path(start: FloatArray, via: FloatArray, goal: FloatArray, reverse: bool = False) -> FloatArray:
    """A unicycle path through via-points: straight segments joined by turns in place.

    The robot turns in place at the start towards the first via-point, drives there, turns
    towards the next one, ..., drives to the goal's position and turns to the goal's
    heading; every turn takes the shorter arc. (The GA moves via-points; this is the path a
    differential drive follows through them.)

    Parameters
    ----------
    start, goal : (3,) float
        Poses ``[x, y, heading]``.
    via : (m, 2) float
    reverse : bool
        Unused for now: the path drives forwards (allowed either way).

    Returns
    -------
    (n, 3) float
        Poses; consecutive ones differ only in heading (a turn) or only in position along
        their common heading (a straight move). Repeated poses are dropped.
    """
    pts = np.vstack([np.asarray(start, dtype=float)[None, :2], np.asarray(via, dtype=float).reshape(-1, 2),
                     np.asarray(goal, dtype=float)[None, :2]])  # fmt: skip
    keep = np.ones(len(pts), dtype=bool)
    keep[1:] = np.hypot(*np.diff(pts, axis=0).T) > 1e-12
    pts = pts[keep]
    out = [np.asarray(start, dtype=float)]
    h = float(start[2])
    for a, b in zip(pts[:-1], pts[1:], strict=True):
        hn = math.atan2(b[1] - a[1], b[0] - a[0])
        if abs(wrap_angle(hn - h)) > SAME_HEADING:
            out.append(np.array([a[0], a[1], h + wrap_angle(hn - h)]))
        h = out[-1][2] if abs(wrap_angle(hn - h)) > SAME_HEADING else h
        out.append(np.array([b[0], b[1], h]))
    g = np.asarray(goal, dtype=float)
    if abs(wrap_angle(g[2] - h)) > SAME_HEADING:
        out.append(np.array([g[0], g[1], h + wrap_angle(g[2] - h)]))
    path = np.array(out)
    path[-1, :2] = g[:2]
    path[:, 2] = wrap_angle(path[:, 2])
    return path


def drive_rows(geometry, t: float, pose, via, goal, vplan: float) -> FloatArray | None:
    """Rows ``[t, x, y, heading]`` of driving from ``pose`` through ``via`` to ``goal`` at
    ``vplan``, turning in place at the robot's full turning rate (:func:`turn_path`), each
    piece statically certified; None when one is not free."""
    robot = geometry.robot
    rate = robot.turn_rate * SPEED_SAFETY
    path = turn_path(pose, np.asarray(via, dtype=float).reshape(-1, 2), goal)
    rows = [[t, *pose]]
    for a, b in zip(path[:-1], path[1:], strict=True):
        if not _free(geometry, a, b):
            return None
        dh = abs(wrap_angle(b[2] - a[2]))
        rows.append([rows[-1][0] + float(np.hypot(*(b[:2] - a[:2]))) / vplan + dh / rate, *b])
    rows[-1][1:] = list(goal)
    return np.array(rows, dtype=float)


def settle_at(rows: FloatArray, goal, robot) -> FloatArray:
    """A differential drive's rows ``[t, x, y, heading]`` ending at ``goal`` when their last
    pose is within a hair of it, without breaking the rows' rule (CONTRACT section 6).

    A run stops at the first pose within the goal tolerance (1e-6 in the metric): the end
    of the lane into the goal, before the turn to the goal's heading when that turn is a
    hair (6e-7 rad on a pedestrian replay), or inside that turn. Writing the goal's pose
    over that last row made the last straight move turn, and leaving it left the heading
    up to 3e-6 rad off the goal's; ``gfuzzy check`` refused both. The last row takes the
    goal's position when within 1e-9 m of it, and what is left of the turn becomes a row of
    its own, in place (at the robot's turning rate, at least 1 us).

    Parameters
    ----------
    rows : (n, 4) float
    goal : (3,) float
    robot : Robot
        A unicycle (its ``turn_rate``).

    Returns
    -------
    (n or n + 1, 4) float
    """
    goal = np.asarray(goal, dtype=float)
    rows = np.array(rows, dtype=float)
    last = rows[-1]
    if math.hypot(last[1] - goal[0], last[2] - goal[1]) <= 1e-9:
        last[1:3] = goal[:2]
    dh = abs(wrap_angle(goal[2] - last[3]))
    if dh <= SAME_HEADING:
        last[3] = goal[2]
        return rows
    turn = [last[0] + max(dh / (robot.turn_rate * SPEED_SAFETY), 1e-6), last[1], last[2], goal[2]]
    return np.vstack([rows, turn])


def evasions(geometry, t: float, pose, T: float, cover: float, headings: int, vplan: float, speeds=(1.0, 0.5),
             stops=()) -> list:  # fmt: skip
    """Evasive candidates of a differential drive: standing still, or turning in place to
    one of ``headings`` headings and then driving straight along it (forwards; backwards too
    with ``robot.reverse``) at each of ``speeds`` (fractions of ``vplan``) for what is left
    of ``T`` (or half, or a quarter of it, whichever is statically free), then standing
    until ``cover``; and, for each of ``stops`` (s) shorter than what is left, the same
    drive stopped after that long (a stop point: out of someone's way, and standing).

    The headings are the current one and ``headings`` evenly spaced ones from the world's
    x axis: a turn started by one call still has its target among the next call's
    candidates (on a grid that turned with the robot, a turn under way found its target
    between two candidates, and the robot turned back and forth in place).

    Returns
    -------
    list of (r, 4) float
        Rows of each candidate, from ``[t, *pose]``; the first stands still.
    """
    robot = geometry.robot
    rate = robot.turn_rate * SPEED_SAFETY
    pose = np.asarray(pose, dtype=float)
    out = [np.array([[t, *pose], [t + max(T, cover), *pose]])]
    grid = np.arange(headings) * (2 * math.pi / headings)
    grid = np.concatenate([[pose[2]], grid[np.abs(wrap_angle(grid - pose[2])) > 1e-6]])
    for h in grid.tolist():
        turned = np.array([pose[0], pose[1], wrap_angle(pose[2] + float(wrap_angle(h - pose[2])))])
        # the arc the rows turn along (the shorter one between the two headings): at a half
        # turn its sign may differ from the one aimed at, and the sweep is not symmetric
        dh = float(wrap_angle(turned[2] - pose[2]))
        t_turn = abs(dh) / rate
        left = T - t_turn
        if left <= 0 or (t_turn > 0 and not turn_free(geometry, pose[0], pose[1], pose[2], dh)):
            continue
        head = [t, *pose]
        for sign in (1.0, -1.0) if robot.reverse else (1.0,):
            unit = sign * vplan * np.array([math.cos(turned[2]), math.sin(turned[2])])
            for speed, f in zip(speeds, _reaches(geometry, turned, unit, left, speeds), strict=True):
                if f is None:
                    continue
                full = left * f
                for move in (full, *(s for s in stops if s < full - 1e-9)):
                    end = turned.copy()
                    end[:2] += unit * speed * move
                    rows = [head] + ([[t + t_turn, *turned]] if t_turn > 0 else [])
                    rows.append([t + t_turn + move, *end])
                    if cover > t_turn + move:
                        rows.append([t + cover, *end])
                    out.append(np.array(rows, dtype=float))
    return out


def _reaches(geometry, pose, unit, left: float, speeds, fractions=REACH_FRACTIONS) -> list:
    """:func:`reach_fraction` of the moves by ``unit * speed * left`` for each of ``speeds``, all
    along one ray from ``pose``: the speeds' fractions are often the same move (half speed,
    whole way; full speed, half way), and a move shorter than one found free is free (a
    part of a free straight move, in the convex bounds), one longer than one found blocked
    blocked, so each length is decided once (an evasion among a map's walls, a reversing
    drive's two rays per heading, spent 240 ms of CPU deciding the same moves again)."""
    free, blocked = 0.0, math.inf  # lengths along the ray, in units of |unit| * left, known free / not
    out = []
    for speed in speeds:
        found = None
        for f in fractions:
            n = speed * f
            if n <= free:
                found = f
                break
            if n >= blocked:
                continue
            end = np.array(pose, dtype=float)
            end[:2] += (unit * speed * left) * f  # reach_fraction's end, bit for bit
            if geometry.bounds_clearance(end[None])[0] >= 0 and _free(geometry, pose, end):
                free, found = n, f
                break
            blocked = n
        out.append(found)
    return out


def reach_fraction(geometry, pose, shift, fractions=REACH_FRACTIONS) -> float | None:
    """The first of ``fractions`` of the straight move from ``pose`` by ``shift`` (2,) (the
    heading kept) that stays in bounds and is statically free; None when none is. The
    evasive motions' reach, a holonomic robot's (:func:`gfuzzy.navigation.evasion.holonomic_evasion`)
    and a differential drive's (:func:`evasions`)."""
    for f in fractions:
        end = np.array(pose, dtype=float)
        end[:2] += np.asarray(shift, dtype=float) * f
        if geometry.bounds_clearance(end[None])[0] >= 0 and _free(geometry, pose, end):
            return f
    return None


@dataclass(frozen=True)
class Fan:
    """Straight lanes out of a unicycle's start (see :func:`fan`).

    Attributes
    ----------
    offsets : tuple of float
        Headings (rad) relative to the start's heading; 0 drives on without turning.
    distances : tuple of float
        Points (m) along each lane from which the robot may turn to the goal: positive,
        finite and increasing (a lane runs forward from the start).

    Raises
    ------
    InputError
        If an offset is not finite or a distance is not positive, finite and increasing.
    """

    offsets: tuple = tuple(math.radians(a) for a in (0, 10, -10, 20, -20, 35, -35, 50, -50, 70, -70))
    distances: tuple = (1.0, 2.0, 3.0)

    def __post_init__(self) -> None:
        for i, off in enumerate(self.offsets):
            if not math.isfinite(off):
                raise InputError(f"Fan.offsets[{i}] must be finite, got {off!r}")
        for i, d in enumerate(self.distances):
            # a lane runs forward only: a robot that cannot reverse has no backward one
            check_number(f"Fan.distances[{i}]", d)
            if i and not d > self.distances[i - 1]:
                raise InputError(f"Fan.distances[{i}] must be greater than the one before, got {d!r}")


def fan(ex, geometry, start, s_id: int, goal, g_id: int, options: Fan, expired=None) -> None:
    """Join ``start`` (node ``s_id``) to ``goal`` (node ``g_id``) through two-leg motions.

    For each heading ``start[2] + offset`` (the turn's sweep free) a straight lane leaves the
    start, through points at ``options.distances`` (as far as it is statically free); from
    each point the robot turns towards the goal's position, drives straight there and turns
    to the goal's heading (when that lane and both turns are free). A differential drive
    among people detours with few turns: the roadmap's lanes zigzag, each vertex a turn.

    ``ex`` is the query's :class:`gfuzzy.timespace.uniends._Extras` (``node``, ``turn``,
    ``lane``): the pieces go into it. ``expired`` (a callable, optional): once it returns
    True no further heading or point is tried (the offsets are in order of preference,
    straight ahead first); among walls each heading's static checks cost milliseconds. A
    piece whose certification needs more than ``FAN_TRACE_STEPS`` steps of the sphere
    tracing (a lane grazing a wall along its length: thousands of steps, a second) is left
    out: the fan offers detours, the roadmap's graph keeps every way.
    """
    n = FAN_TRACE_STEPS
    sx, sy, sh = (float(v) for v in start)
    gx, gy, gh = (float(v) for v in goal)
    for off in options.offsets:
        if expired is not None and expired():
            return
        h = sh + off
        if off != 0.0 and not turn_free(geometry, sx, sy, sh, off, n):
            continue
        prev, px, py = s_id, sx, sy
        if off != 0.0:
            prev = ex.node(sx, sy, h)
            ex.turn(s_id, prev, off)
        c, s = math.cos(h), math.sin(h)
        for d in options.distances:
            if expired is not None and expired():
                return
            qx, qy = sx + d * c, sy + d * s
            if not _free(geometry, (px, py, h), (qx, qy, h), n):
                break
            node = ex.node(qx, qy, h)
            ex.lane(prev, node)
            prev, px, py = node, qx, qy
            if math.hypot(gx - qx, gy - qy) <= 1e-9:
                continue
            hg = math.atan2(gy - qy, gx - qx)
            d1 = lane_turn(geometry, qx, qy, h, hg, n)
            d2 = lane_turn(geometry, gx, gy, hg, gh, n)
            if d1 is None or d2 is None or not _free(geometry, (qx, qy, hg), (gx, gy, hg), n):
                continue
            a = node if d1 == 0.0 else ex.node(qx, qy, hg)
            ex.turn(node, a, d1)
            b = g_id if d2 == 0.0 else ex.node(gx, gy, hg)
            ex.lane(a, b)
            ex.turn(b, g_id, d2)
