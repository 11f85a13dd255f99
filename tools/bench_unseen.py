"""Unseen rooms: procedurally generated scenes, each query planned and checked, with an
independent witness where one can be built.

    python tools/bench_unseen.py                           # 24 cases, seed 1, -n 200
    python tools/bench_unseen.py --cases 240 --seed 7 -o unseen.csv
    python tools/bench_unseen.py --kinds box lfoot --kinematics unicycle --only 5 --dump out/

Every case is drawn from ``numpy.random.default_rng([seed, case])``: a room, a robot of the
family (``disc``, ``box``, ``cart`` a rectangle pulled by an off-centre reference point,
``lfoot`` a concave L) with random dimensions and one kinematics (``holonomic``,
``unicycle``, ``unicycle-rev`` with ``reverse``), one scenario and one query:

* ``door``: a wall across the room at a random angle and thickness with a door as wide as
  the robot across its heading plus 1-5 cm per side; ``door-movers`` adds movers
  crossing the door or walking beside it; ``blocked`` makes the door narrower than the
  robot across its heading (a negative control: no witness);
* ``dock``: an alcove in a wall to enter nose first or to leave, narrow (no room to turn:
  a forward-only robot cannot leave it) or wide enough to turn in;
* ``corridor``: a corridor as wide as the robot plus 1-5 cm per side with a bend of
  60-120 degrees and a pocket at the bend just large enough to turn in; the goal faces
  along the second leg or back at the bend (backed in);
* ``park``: parking beside a wall 1-5 cm from it, sometimes with a block 1-5 cm in front
  of the nose; the query parks or leaves.

The **witness** is a motion built by construction (turns in place and straight drives
through the door's centre, the alcove's axis, the corridor's centre lines; waits before
setting off among movers) that :func:`gfuzzy.check.check.check_trajectory` accepts: it
proves that the query has an answer, so ``no_path`` on such a case is counted as *missed*.
Where the construction needs a backward drive that the robot cannot make, or for a blocked
door, there is none, and ``no_path`` is counted as *no path (no witness)*. The witness
shares no code with the planner. Start and goal are proven valid by the same check.

Each case builds its roadmap (``RoadmapOptions(vertices, seed)``, the seed drawn per case),
plans with the default options, and checks a solved answer independently. Times are CPU
seconds of this process (``time.process_time``). ``--dump DIR`` writes the scene YAML
(query ``q``) and the witness of every case that is not solved-and-checked, with the
commands that reproduce it.
"""

from __future__ import annotations

import argparse
import csv
import io
import math
import os
import statistics
import sys
import time
import traceback
from collections import defaultdict
from pathlib import Path

import numpy as np
import shapely
import yaml

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.atomic import write_atomic  # noqa: E402
from gfuzzy.check.check import check_trajectory  # noqa: E402
from gfuzzy.planner.planner import Planner  # noqa: E402
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap  # noqa: E402
from gfuzzy.scene.scene import parse_scene  # noqa: E402

KINDS = ("disc", "box", "cart", "lfoot")
KINEMATICS = ("holonomic", "unicycle", "unicycle-rev")
#: scenario -> weight of the draw
SCENARIOS = {"door": 0.25, "door-movers": 0.15, "blocked": 0.08, "dock": 0.17, "corridor": 0.17, "park": 0.18}
#: distance kept from everything at a pose where the witness turns (m)
MARGIN = 0.03
#: how often a scenario is drawn again when its witness fails its check (starts among movers)
TRIES = 12
OUTCOMES = ("solved", "check_reject", "missed", "no_path", "invalid_query", "timeout", "error")


# --------------------------------------------------------------------------- robots


class Body:
    """A robot of the family: the scene's ``robot`` entry and its extents about the reference
    point (x forward, y left)."""

    def __init__(self, spec: dict, outline: list | None, radius: float | None = None):
        self.spec = spec
        if outline is None:  # a disc
            self.xmin, self.xmax, self.ymin, self.ymax = -radius, radius, -radius, radius
            self.R = radius
        else:
            pts = np.asarray(outline, float)
            self.xmin, self.ymin = pts.min(axis=0)
            self.xmax, self.ymax = pts.max(axis=0)
            self.R = float(np.hypot(pts[:, 0], pts[:, 1]).max())
        self.disc = outline is None

    @property
    def lateral(self) -> float:
        """The body's width across its heading."""
        return float(self.ymax - self.ymin)

    @property
    def ymid(self) -> float:
        return float(0.5 * (self.ymax + self.ymin))

    @property
    def unicycle(self) -> bool:
        return self.spec.get("kinematics") == "unicycle"

    @property
    def backward(self) -> bool:
        """Can it drive backwards (a holonomic robot moves any way)?"""
        return not self.unicycle or bool(self.spec.get("reverse"))


def make_robot(rng: np.random.Generator, kind: str, kinematics: str) -> Body:
    """A robot of ``kind`` with random dimensions and speed, of ``kinematics``."""
    u = lambda lo, hi: float(rng.uniform(lo, hi))  # noqa: E731
    if kind == "disc":
        r = u(0.15, 0.35)
        spec, outline = {"disc": r}, None
    elif kind == "box":
        length, width = u(0.5, 1.1), u(0.3, 0.6)
        spec = {"box": [length, width]}
        outline = [[-length / 2, -width / 2], [length / 2, width / 2]]
    elif kind == "cart":  # a rectangle pulled by a reference point near its rear, off the axis
        length, width = u(0.5, 1.0), u(0.35, 0.6)
        back, side = u(0.05, 0.3) * length, u(-0.05, 0.05)
        outline = [[-back, side - width / 2], [length - back, side - width / 2],
                   [length - back, side + width / 2], [-back, side + width / 2]]
        spec = {"footprint": outline}
    elif kind == "lfoot":  # a bar with an arm to one side at its rear: concave
        a, b, w, arm = u(0.3, 0.6), u(0.1, 0.3), u(0.3, 0.5), u(0.15, 0.35)
        c = -b + u(0.25, 0.6) * (a + b)
        outline = [[a, -w / 2], [a, w / 2], [c, w / 2], [c, w / 2 + arm], [-b, w / 2 + arm], [-b, -w / 2]]
        if rng.random() < 0.5:  # the arm to the right: mirrored, and wound counter-clockwise again
            outline = [[x, -y] for x, y in reversed(outline)]
        spec = {"footprint": outline}
    else:
        raise ValueError(f"unknown robot kind {kind!r}")
    spec["vmax"] = u(0.5, 1.2)
    body = Body(spec, outline, spec.get("disc"))
    if kinematics != "holonomic":
        spec["kinematics"] = "unicycle"
        if rng.random() < 0.5:  # a turning rate below the default vmax / r
            spec["wmax"] = u(0.5, 1.0) * spec["vmax"] / body.R
        if kinematics == "unicycle-rev":
            spec["reverse"] = True
    return body


# --------------------------------------------------------------------------- geometry


def unit(h: float) -> np.ndarray:
    return np.array([math.cos(h), math.sin(h)])


def left(d: np.ndarray) -> np.ndarray:
    return np.array([-d[1], d[0]])


def heading(d: np.ndarray) -> float:
    return math.atan2(d[1], d[0])


def box(center, size, angle: float) -> dict:
    return {"box": {"center": [float(center[0]), float(center[1])], "size": [float(size[0]), float(size[1])], "angle": float(angle)}}


def polygon(shape) -> dict:
    """A shapely polygon (no holes) as a scene obstacle entry."""
    return {"polygon": [[float(x), float(y)] for x, y in list(shape.exterior.coords)[:-1]]}


def shape_of(ob: dict):
    """A scene obstacle entry as a shapely polygon."""
    if "box" in ob:
        b = ob["box"]
        c, (sx, sy), a = np.asarray(b["center"]), b["size"], b["angle"]
        ax, ay = unit(a), left(unit(a))
        corners = [c + i * sx / 2 * ax + j * sy / 2 * ay for i, j in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        return shapely.Polygon(corners)
    return shapely.Polygon(ob["polygon"])


class Room:
    """A scene under construction: bounds, static obstacles (entries and their union) and movers."""

    def __init__(self, rng: np.random.Generator, body: Body):
        self.rng, self.body = rng, body
        self.W, self.H = float(rng.uniform(5.0, 7.0)), float(rng.uniform(3.5, 5.0))
        self.obstacles: list[dict] = []
        self.movers: list[dict] = []
        self._union = None

    def add(self, ob: dict) -> None:
        self.obstacles.append(ob)
        self._union = None

    @property
    def union(self):
        if self._union is None:
            self._union = shapely.union_all([shape_of(o) for o in self.obstacles]) if self.obstacles else shapely.Polygon()
        return self._union

    def roomy(self, p, q=None) -> bool:
        """Is the robot's circumscribed disc at ``p`` (along ``p``-``q``) clear of the bounds and
        the obstacles by MARGIN? There it may turn and drive any way."""
        k = self.body.R + MARGIN
        pts = [p] if q is None else [p, q]
        for x, y in pts:
            if not (k <= x <= self.W - k and k <= y <= self.H - k):
                return False
        geom = shapely.Point(p) if q is None else shapely.LineString([p, q])
        return self.union.is_empty or geom.distance(self.union) > k

    def free_point(self, keep=lambda p: True, tries: int = 400):
        """A random point where the robot may turn, with ``keep(p)``; None if none is found."""
        k = self.body.R + MARGIN
        for _ in range(tries):
            p = np.array([self.rng.uniform(k, self.W - k), self.rng.uniform(k, self.H - k)])
            if keep(p) and self.roomy(p):
                return p
        return None

    def doc(self, name: str, start, goal) -> dict:
        dof = 2 if self.body.disc and not self.body.unicycle else 3
        q = {"name": "q", "start": [float(v) for v in start[:dof]], "goal": [float(v) for v in goal[:dof]]}
        d = {"version": 1, "name": name, "bounds": [0.0, 0.0, self.W, self.H], "robot": self.body.spec, "obstacles": self.obstacles}
        if self.movers:
            d["movers"] = self.movers
        d["queries"] = [q]
        return d


# --------------------------------------------------------------------------- witnesses


class Motion:
    """Turns in place and straight drives from a pose (x, y, heading)."""

    def __init__(self, pose):
        self.poses = [np.asarray(pose, float)]
        self.ok = True  # False once a drive the robot cannot make was asked for

    def drive(self, p, body: Body, backward: bool = False) -> Motion:
        cur = self.poses[-1]
        d = np.asarray(p, float) - cur[:2]
        if np.hypot(*d) < 1e-12:
            return self
        h = heading(-d if backward else d)
        if backward and not body.backward:
            self.ok = False
        self.poses += [np.r_[cur[:2], h], np.r_[p, h]]
        return self

    def turn(self, h: float) -> Motion:
        self.poses.append(np.r_[self.poses[-1][:2], h])
        return self

    def rows(self, body: Body, dof: int, wait: float = 0.0) -> np.ndarray:
        """Timed rows ``[t, x, y(, heading)]``, each step a little slower than the robot may go."""
        spec = body.spec
        wmax = spec.get("wmax", spec["vmax"] / body.R)
        out, t = [np.r_[0.0, self.poses[0]]], 0.0
        if wait > 0:
            t = wait
            out.append(np.r_[t, self.poses[0]])
        for a, b in zip(self.poses[:-1], self.poses[1:], strict=True):
            dist = float(np.hypot(*(b[:2] - a[:2])))
            dh = abs(math.remainder(b[2] - a[2], 2 * math.pi))
            if dof == 2:
                dh = 0.0
            if dist < 1e-9 and dh < 1e-9:  # no motion (a turn to the heading it has)
                continue
            dt = 1.02 * max((dist + dh * body.R) / spec["vmax"], dh / wmax)
            t += dt
            out.append(np.r_[t, b])
        rows = np.array(out)
        return rows[:, : dof + 1]


def witness_for(scene, query, motion: Motion | None, body: Body, dof: int, waits=(0.0,)):
    """The motion's rows if the robot can make them and the check accepts them (after the
    first wait in ``waits`` that works), else None."""
    if motion is None or not motion.ok:
        return None
    for wait in waits:
        rows = motion.rows(body, dof, wait)
        rows[0, 1:], rows[-1, 1:] = query.start, query.goal  # the query's own numbers
        # the verdict only: measuring each refused wait's deepest overlap took 3/4 of the time
        if check_trajectory(scene, rows, query=query, deepest=False).valid:
            return rows
    return None


# --------------------------------------------------------------------------- scenarios


def _door(room: Room, blocked: bool, slack=(0.01, 0.05)):
    """A wall across the room with a door (``slack`` the range of its spare width per side);
    returns the door's centre, the wall's normal and thickness (the wall's pieces are added
    to the room)."""
    rng, body = room.rng, room.body
    phi = rng.uniform(-0.6, 0.6) + (math.pi / 2 if rng.random() < 0.5 else 0.0)
    n, u = unit(phi), left(unit(phi))
    c0 = np.array([room.W / 2, room.H / 2]) + rng.uniform(-0.3, 0.3, 2)
    thick, slack = rng.uniform(0.05, 0.3), rng.uniform(*slack)
    width = body.lateral + (-2 * slack if blocked else 2 * slack)
    s = rng.uniform(-1.0, 1.0)
    big = 2 * math.hypot(room.W, room.H)
    inside = shapely.box(0, 0, room.W, room.H)
    for sign in (1, -1):  # the wall's two pieces, cut at the bounds
        piece = shape_of(box(c0 + (s + sign * (width / 2 + big / 2)) * u, [thick, big], phi)).intersection(inside)
        if piece.geom_type == "Polygon" and piece.area > 1e-6:
            room.add(polygon(piece))
    return c0 + s * u, n, thick


def _through_door(room: Room, centre, n, thick):
    """Start on one side, goal on the other, and the motion through the door's centre."""
    rng, body = room.rng, room.body
    d = n if rng.random() < 0.5 else -n
    ref = centre - body.ymid * left(d)
    off = thick / 2 + body.R + MARGIN
    p_in, p_out = ref - off * d, ref + off * d
    if not (room.roomy(p_in) and room.roomy(p_out)):
        return None
    side = lambda sgn: (lambda p: sgn * float(np.dot(p - centre, d)) > off)  # noqa: E731
    start, goal = room.free_point(side(-1)), room.free_point(side(1))
    if start is None or goal is None:
        return None
    start, goal = np.r_[start, rng.uniform(-math.pi, math.pi)], np.r_[goal, rng.uniform(-math.pi, math.pi)]
    m = Motion(start).drive(p_in, body).turn(heading(d)).drive(p_out, body).drive(goal[:2], body).turn(goal[2])
    return start, goal, m, ref, d


def _movers(room: Room, ref, d) -> None:
    """One to three movers: through the door (bounce), along the wall on one side, or a loop."""
    rng = room.rng
    for i in range(int(rng.integers(1, 4))):
        what = rng.choice(["through", "along", "loop"])
        shape = {"disc": float(rng.uniform(0.08, 0.2))} if rng.random() < 0.7 else {"box": [float(rng.uniform(0.15, 0.4)), float(rng.uniform(0.15, 0.4))]}
        speed = float(rng.uniform(0.3, 0.9))
        side = d * rng.choice([-1, 1]) * rng.uniform(0.8, 1.4)
        if what == "through":
            path = [ref - 1.5 * d, ref + 1.5 * d]
        elif what == "along":
            path = [ref + side - 2.5 * left(d), ref + side + 2.5 * left(d)]
        else:
            c = ref + side
            path = [c + 0.6 * np.array(v) for v in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        path = [[float(min(max(p[0], 0.1), room.W - 0.1)), float(min(max(p[1], 0.1), room.H - 0.1))] for p in path]
        mode = "loop" if what == "loop" else str(rng.choice(["bounce", "loop"]))
        room.movers.append({"name": f"m{i}", **shape, "speed": speed, "path": path, "mode": mode, "offset": float(rng.uniform(0, 3))})


def scenario_door(room: Room, kind: str):
    centre, n, thick = _door(room, blocked=kind == "blocked")
    got = _through_door(room, centre, n, thick)
    if got is None:
        return None
    start, goal, motion, ref, d = got
    if kind == "door-movers":
        _movers(room, ref, d)
    return start, goal, (None if kind == "blocked" else motion)


def scenario_dock(room: Room, _kind: str):
    """An alcove in the top wall (a band of its depth): dock into it nose first, or leave it."""
    rng, body = room.rng, room.body
    slack = rng.uniform(0.01, 0.05)
    wide = rng.random() < 0.35
    if wide:  # room to turn inside
        aw = depth = 2 * body.R + 2 * slack
    else:
        aw, depth = body.lateral + 2 * slack, body.xmax - body.xmin + slack
    ax = rng.uniform(aw / 2 + 0.3, room.W - aw / 2 - 0.3)
    top = room.H
    for lo, hi in ((0.0, ax - aw / 2), (ax + aw / 2, room.W)):
        room.add(box([(lo + hi) / 2, top - depth / 2], [hi - lo, depth], 0.0))
    up = math.pi / 2
    if wide:
        dock = np.array([ax, top - depth / 2, up])
    else:
        dock = np.array([ax + body.ymid, top - slack - body.xmax, up])
    outside = np.array([dock[0], top - depth - body.R - MARGIN])
    if not room.roomy(outside):
        return None
    far = room.free_point(lambda p: p[1] < outside[1])
    if far is None:
        return None
    far = np.r_[far, rng.uniform(-math.pi, math.pi)]
    if rng.random() < 0.5:  # dock
        m = Motion(far).drive(outside, body).turn(up).drive(dock[:2], body)
        return far, dock, m
    m = Motion(dock)
    if wide:
        m.turn(-up).drive(outside, body)
    else:
        m.drive(outside, body, backward=True)
    return dock, far, m.drive(far[:2], body).turn(far[2])


def scenario_corridor(room: Room, _kind: str):
    """An L corridor (bend 60-120 degrees) as wide as the robot plus 1-5 cm per side, with a
    pocket at the bend just large enough to turn in; the rest of the room is blocked."""
    rng, body = room.rng, room.body
    slack, pocket = rng.uniform(0.01, 0.05), body.R + rng.uniform(0.01, 0.05)
    bend = np.array([rng.uniform(2.0, room.W - 2.0), rng.uniform(1.5, room.H - 1.5)])
    h1 = rng.uniform(-math.pi, math.pi)
    h2 = h1 + rng.choice([-1, 1]) * rng.uniform(math.pi / 3, 2 * math.pi / 3)
    d1, d2 = unit(h1), unit(h2)
    width, far, reach = body.lateral + 2 * slack, 3 * (room.W + room.H), body.R + MARGIN
    legs = [shapely.LineString([bend + body.ymid * left(d1) - far * d1, bend + body.ymid * left(d1) + reach * d1]),
            shapely.LineString([bend + body.ymid * left(d2) - reach * d2, bend + body.ymid * left(d2) + far * d2])]
    free = shapely.union_all([leg.buffer(width / 2, cap_style="flat", join_style="mitre") for leg in legs]
                             + [shape_of(box(bend, [2 * pocket, 2 * pocket], h1))])
    walls = shapely.box(0, 0, room.W, room.H).difference(free)
    for poly in getattr(walls, "geoms", [walls]):
        if poly.is_empty or poly.area < 1e-6:
            continue
        if len(poly.interiors):
            return None
        room.add(polygon(poly))
    start = np.r_[bend - rng.uniform(body.R + 0.3, 2.5) * d1, h1]
    backed = rng.random() < 0.3
    goal = np.r_[bend + rng.uniform(body.R + 0.3, 2.5) * d2, h2 + (math.pi if backed else 0.0)]
    m = Motion(start).drive(bend, body).turn(goal[2]).drive(goal[:2], body, backward=backed)
    return start, goal, m


def scenario_park(room: Room, _kind: str):
    """Park beside a free-standing wall 1-5 cm from it (sometimes 1-5 cm behind a block at
    the nose), approaching from behind the wall's end; or leave that place."""
    rng, body = room.rng, room.body
    h = rng.uniform(-math.pi, math.pi)
    d, nu = unit(h), left(unit(h))
    length, thick, slack = rng.uniform(1.5, 3.0), rng.uniform(0.1, 0.25), rng.uniform(0.01, 0.05)
    c = np.array([room.W / 2, room.H / 2]) + rng.uniform(-0.5, 0.5, 2)
    room.add(box(c, [length, thick], h))
    side = rng.choice([-1, 1])
    across = thick / 2 + slack - body.ymin if side > 0 else -thick / 2 - slack - body.ymax
    along = rng.uniform(-length / 2 - body.xmin + 0.05, length / 2 - body.xmax)
    goal = np.r_[c + across * nu + along * d, h]
    nose = rng.random() < 0.5
    if nose:  # a block in front of the nose, on the robot's side of the wall
        gap = rng.uniform(0.01, 0.05)
        lo, hi = sorted([side * thick / 2, across + (body.ymax if side > 0 else body.ymin) + side * 0.1])
        room.add(box(c + (along + body.xmax + gap + 0.1) * d + (lo + hi) / 2 * nu, [0.2, hi - lo], h))
    behind = c + across * nu - (length / 2 + body.R + MARGIN) * d
    ahead = c + across * nu + (length / 2 + body.R + MARGIN) * d
    if not room.roomy(behind):
        return None
    other = room.free_point(lambda p: room.roomy(p, behind))
    if other is None:
        return None
    other = np.r_[other, rng.uniform(-math.pi, math.pi)]
    if rng.random() < 0.5:
        return other, goal, Motion(other).drive(behind, body).turn(h).drive(goal[:2], body)
    m = Motion(goal)
    if body.backward or nose or not room.roomy(ahead):
        m.drive(behind, body, backward=True)
    else:
        m.drive(ahead, body)
    return goal, other, m.drive(other[:2], body).turn(other[2])


BUILDERS = {"door": scenario_door, "door-movers": scenario_door, "blocked": scenario_door,
            "dock": scenario_dock, "corridor": scenario_corridor, "park": scenario_park}


# --------------------------------------------------------------------------- cases


def make_case(seed: int, index: int, kinds=KINDS, kinematics=KINEMATICS, scenarios=tuple(SCENARIOS)) -> dict:
    """Case ``index`` of ``seed``: its scene document, query, witness rows (or None) and
    roadmap seed. The same arguments give the same case."""
    rng = np.random.default_rng([seed, index])
    kind, kin = kinds[index % len(kinds)], kinematics[(index // len(kinds)) % len(kinematics)]
    names = list(scenarios)
    weights = np.array([SCENARIOS[s] for s in names])
    scenario = str(rng.choice(names, p=weights / weights.sum()))
    for attempt in range(TRIES):
        body = make_robot(rng, kind, kin)
        room = Room(rng, body)
        got = BUILDERS[scenario](room, scenario)
        if got is None:
            continue
        start, goal, motion = got
        doc = room.doc(f"unseen-{seed}-{index}", start, goal)
        scene = parse_scene(doc, f"case {index}")
        query = scene.queries[0]
        waits = np.arange(0.0, 20.0, 0.5) if room.movers else (0.0,)
        rows = witness_for(scene, query, motion, body, scene.robot.dof, waits)
        if rows is None and not _ends_valid(scene, query):
            continue  # a start or goal the check refuses (a mover on it): draw again
        if rows is None and motion is not None and motion.ok:
            continue  # the construction should have held: draw again (movers in the way)
        return {"index": index, "kind": kind, "kinematics": kin, "scenario": scenario, "doc": doc,
                "scene": scene, "query": query, "witness": rows, "roadmap_seed": int(rng.integers(1, 1000)),
                "attempts": attempt + 1}
    raise RuntimeError(f"case {index}: no valid {scenario} scene in {TRIES} draws")


def _ends_valid(scene, query) -> bool:
    """Are the start (at t0) and the goal (for good) valid, by the independent check?"""
    start = np.array([[query.t0, *query.start], [query.t0 + 1e-3, *query.start]])
    goal = np.array([[0.0, *query.goal], [1e-3, *query.goal]])
    if scene.movers:
        return check_trajectory(scene, start, deepest=False).valid
    return check_trajectory(scene, start, deepest=False).valid and check_trajectory(scene, goal, deepest=False).valid


def run_case(case: dict, vertices: int) -> dict:
    """Build the roadmap, plan the query, check the answer; a CSV row."""
    row = {k: case[k] for k in ("index", "kind", "kinematics", "scenario", "roadmap_seed")}
    row.update(witness=case["witness"] is not None, status="", outcome="", message="", build_s="", plan_s="", duration="")
    scene, q = case["scene"], case["query"]
    try:
        t = time.process_time()
        rm = build_roadmap(scene, RoadmapOptions(vertices=vertices, seed=case["roadmap_seed"]))
        row["build_s"] = round(time.process_time() - t, 3)
        t = time.process_time()
        res = Planner(scene, rm).plan(q.start, q.goal, q.t0, hold=q.hold)
        row["plan_s"] = round(time.process_time() - t, 3)
        row["status"] = res.status.value
        row["outcome"], row["message"] = _outcome(scene, q, res, row["witness"])
        if res.solved:
            row["duration"] = round(float(res.duration), 3)
    except Exception as exc:  # noqa: BLE001 - a benchmark counts tracebacks, it does not stop at one
        row["outcome"] = "error"
        row["message"] = f"{type(exc).__name__}: {exc}"
        row["traceback"] = traceback.format_exc()
    return row


def _outcome(scene, q, res, witness: bool) -> tuple[str, str]:
    status = res.status.value
    if status == "solved":
        rep = check_trajectory(scene, res.trajectory.waypoints, query=q)
        return ("solved", "") if rep.valid else ("check_reject", rep.reason)
    if status == "no_path":
        return ("missed" if witness else "no_path"), res.message
    return status, res.message


# --------------------------------------------------------------------------- output


def table(rows: list[dict], key) -> str:
    groups = defaultdict(list)
    for r in rows:
        groups[key(r)].append(r)
    head = ["group", "cases", "witness", *OUTCOMES, "plan s (median)", "build s (median)"]
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for name in sorted(groups) + ["all"]:
        g = rows if name == "all" else groups[name]
        counts = [sum(r["outcome"] == o for r in g) for o in OUTCOMES]
        plan = [r["plan_s"] for r in g if r["plan_s"] != ""]
        build = [r["build_s"] for r in g if r["build_s"] != ""]
        med = lambda v: f"{statistics.median(v):.2f}" if v else "-"  # noqa: E731
        cells = [name, len(g), sum(r["witness"] for r in g), *counts, med(plan), med(build)]
        lines.append("| " + " | ".join(str(c) for c in cells) + " |")
    return "\n".join(lines)


def write_csv(path: str, rows: list[dict]) -> None:
    fields = ["index", "kind", "kinematics", "scenario", "roadmap_seed", "witness", "status", "outcome",
              "plan_s", "build_s", "duration", "message"]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=fields, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    write_atomic(path, buf.getvalue())


def dump(folder: Path, case: dict, row: dict, vertices: int) -> None:
    """The case's scene (query ``q``), its witness and the commands that reproduce it."""
    folder.mkdir(parents=True, exist_ok=True)
    stem = f"unseen-{case['doc']['name'].split('-', 1)[1]}"
    scene_path = folder / f"{stem}.yaml"
    head = (f"# tools/bench_unseen.py case {case['index']}: {case['kind']} {case['kinematics']} {case['scenario']}: "
            f"{row['outcome']} ({row['message'][:120]})\n"
            f"# python -m gfuzzy roadmap {scene_path} -n {vertices} --seed {case['roadmap_seed']} -o {folder / stem}.rm.json\n"
            f"# python -m gfuzzy plan {scene_path} --roadmap {folder / stem}.rm.json --query q -o {folder / stem}.plan.json\n")
    write_atomic(scene_path, head + yaml.safe_dump(case["doc"], sort_keys=False, default_flow_style=None, width=200))
    if case["witness"] is not None:
        import json

        doc = {"version": 1, "scene": case["doc"]["name"], "query": "q", "status": "solved", "message": "witness",
               "duration": float(case["witness"][-1, 0] - case["witness"][0, 0]), "roadmap_distance": 0.0,
               "delay_factor": 1.0, "planning_seconds": 0.0, "stats": {}, "waypoints": case["witness"].tolist()}
        write_atomic(folder / f"{stem}.witness.json", json.dumps(doc))


def _one(args) -> tuple[dict, dict]:
    seed, index, kinds, kinematics, scenarios, vertices = args
    try:
        case = make_case(seed, index, kinds, kinematics, scenarios)
    except Exception as exc:  # noqa: BLE001
        row = {"index": index, "kind": kinds[index % len(kinds)], "kinematics": kinematics[(index // len(kinds)) % len(kinematics)],
               "scenario": "?", "roadmap_seed": "", "witness": False, "status": "", "outcome": "error",
               "message": f"generator: {type(exc).__name__}: {exc}", "build_s": "", "plan_s": "", "duration": "",
               "traceback": traceback.format_exc()}
        return None, row
    return case, run_case(case, vertices)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", type=int, default=24)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("-n", "--vertices", type=int, default=200)
    ap.add_argument("--kinds", nargs="+", choices=KINDS, default=list(KINDS))
    ap.add_argument("--kinematics", nargs="+", choices=KINEMATICS, default=list(KINEMATICS))
    ap.add_argument("--scenarios", nargs="+", choices=list(SCENARIOS), default=list(SCENARIOS))
    ap.add_argument("--only", type=int, nargs="+", help="run only these case indices")
    ap.add_argument("--workers", type=int, default=0, help="processes (0: this one, sequentially)")
    ap.add_argument("-o", "--output", help="CSV, one row per case (written atomically)")
    ap.add_argument("--dump", help="folder for the scene, witness and commands of each case not solved and checked")
    a = ap.parse_args(argv)
    if a.cases < 1 or a.workers < 0:
        print("bench_unseen: --cases must be >= 1 and --workers >= 0", file=sys.stderr)
        return 2
    indices = a.only if a.only else range(a.cases)
    jobs = [(a.seed, i, tuple(a.kinds), tuple(a.kinematics), tuple(a.scenarios), a.vertices) for i in indices]
    rows = []
    t0 = time.perf_counter()
    results = _results(jobs, a.workers)
    for k, (case, row) in enumerate(results, 1):
        rows.append(row)
        print(f"[{k}/{len(jobs)}] case {row['index']} {row['kind']} {row['kinematics']} {row['scenario']}: "
              f"{row['outcome']} build {row['build_s']} plan {row['plan_s']} {row['message'][:100]}", file=sys.stderr, flush=True)
        if "traceback" in row:
            print(row["traceback"], file=sys.stderr)
        if a.dump and case is not None and row["outcome"] != "solved":
            dump(Path(a.dump), case, row, a.vertices)
    rows.sort(key=lambda r: r["index"])
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    which = f"--only {' '.join(map(str, a.only))}" if a.only else f"--cases {a.cases}"
    print(f"# tools/bench_unseen.py {which} --seed {a.seed} -n {a.vertices}: {len(rows)} cases "
          f"in {time.perf_counter() - t0:.0f} s, load average {load:.2f}; times: CPU seconds")
    print(table(rows, lambda r: f"{r['kind']} {r['kinematics']}"))
    print()
    print(table(rows, lambda r: r["scenario"]))
    if a.output:
        write_csv(a.output, rows)
    return 0


def _results(jobs, workers: int):
    if workers == 0:
        for job in jobs:
            yield _one(job)
        return
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(workers) as pool:
        yield from pool.map(_one, jobs)


if __name__ == "__main__":
    sys.exit(main())
