"""Unseen differential-drive queries against the lattice oracle (issue 18's target: every
unseen unicycle query solved where a solution exists, verified by check).

    python tools/bench_unseen_drives.py                        # 40 cases, seed 1
    python tools/bench_unseen_drives.py --cases 40 --seed 2 -o drives-2.csv
    python tools/bench_unseen_drives.py --seed 1 --only 17 --dump out/drives/   # one case's scene
    python tools/bench_unseen_drives.py --seed 1 --only 17 --no-oracle --roadmap-seed 5 -n 400

Case ``i`` of ``--seed s`` is drawn from ``numpy.random.default_rng([s, i])``: a body of one
of :data:`BODIES` (``disc``, ``box``, ``cart`` 1.0-1.4 m long pulled by its rear,
``offcentre`` a box about a point off its middle, concave ``u``, ``l``, ``t`` and
``chevron``), always ``kinematics: unicycle``, with ``reverse`` and ``wmax`` (0.2-0.8 rad/s)
each at random, and one scenario of :data:`SCENARIOS`:

* ``door``: a wall at a random angle with a door as wide as the body across its heading plus
  0-10 cm (``_door`` of ``tools/bench_unseen.py``);
* ``corridor``: a corridor bent by 45-135 degrees, as wide as the body plus 0-10 cm, with a
  pocket at the bend large enough to turn in half the time (without it, a long body may
  not get round);
* ``clutter``: a room with 4-10 boxes and discs;
* ``arc``: a curved gap, a band round a circle as wide as the body sweeps driving tangent
  to it plus 0-6 cm, between two rooms;
* ``crop``: a 3.5-6 m crop of a bundled map (``scenes/maps``: the TurtleBot sandbox, the
  small house, the depot), start and goal where the body can turn;
* ``crop-arc``: a crop of the TurtleBot sandbox round one of its posts, the way round the
  post a curved gap 0-6 cm wider than the body's swept band (issue 18's one miss).

A bouncing mover crosses a quarter of the rooms (not the crops). Start and goal are valid by
the planner's ``query_problem`` and, with a mover, the start by ``gfuzzy check``.

Each case is planned by gfuzzy (``-n 200`` with the case's roadmap seed, then ``-n 400``
where that gave no checked answer; every answer checked by
:func:`gfuzzy.check.check.check_trajectory`), and given to ``tools/drive_oracle.py``
(movers ignored; a path it finds passes the check, so it proves a static way exists). The
table counts the cases, those the oracle proves, those gfuzzy solves (checked), those only
gfuzzy solves, those only the oracle solves (*missed*) and those neither solves. The oracle
costs 2-40 s of CPU a case (more where its finest lattice runs to 3 million poses): this
runs serially, one core, progress on stderr. Times are CPU seconds (``time.process_time``).
``--dump DIR`` writes the scene of every case gfuzzy did not solve (every case with
``--only``), the maps it needs, the oracle's path when it found one, and the commands.
"""

from __future__ import annotations

import argparse
import csv
import functools
import io
import json
import math
import os
import shutil
import sys
import time
import traceback
from collections import defaultdict
from pathlib import Path

import numpy as np
import shapely
import shapely.affinity
import yaml

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.atomic import write_atomic  # noqa: E402
from gfuzzy.check.check import check_trajectory  # noqa: E402
from gfuzzy.collision.geometry import StaticGeometry  # noqa: E402
from gfuzzy.planner.planner import Planner, PlanOptions, query_problem  # noqa: E402
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap  # noqa: E402
from gfuzzy.scene.scene import parse_scene  # noqa: E402
from tools.bench_unseen import (  # noqa: E402
    MARGIN,
    Body,
    Room,
    _door,
    _ends_valid,
    left,
    make_robot,
    polygon,
    unit,
)
from tools.drive_oracle import obstacle_geometry, solve  # noqa: E402

BODIES = ("disc", "box", "cart", "offcentre", "u", "l", "t", "chevron")
#: scenario -> weight of the draw
SCENARIOS = {"door": 0.2, "corridor": 0.15, "clutter": 0.15, "arc": 0.15, "crop": 0.2, "crop-arc": 0.15}
#: the bundled maps a crop is cut from: scene file (its bounds), map file
MAPS = (("tb3-arena.yaml", "maps/tb3_sandbox.yaml"), ("small-house.yaml", "maps/small_house.yaml"),
        ("depot.yaml", "maps/depot.yaml"))
TRIES = 30
VERTICES = (200, 400)


# --------------------------------------------------------------------------- bodies


def _footprint(rng, kind: str) -> list:
    """A concave or off-centre outline (x forward), counter-clockwise."""
    u = lambda lo, hi: float(rng.uniform(lo, hi))  # noqa: E731
    if kind == "cart":  # pulled by a point near its rear
        length, width = u(1.0, 1.4), u(0.45, 0.65)
        back = u(0.05, 0.25) * length
        pts = [(-back, -width / 2), (length - back, -width / 2), (length - back, width / 2), (-back, width / 2)]
    elif kind == "offcentre":  # a box about a point off its middle, along and across
        length, width = u(0.5, 1.0), u(0.35, 0.6)
        x0, y0 = -u(0.2, 0.8) * length, -width / 2 + u(-0.3, 0.3) * width
        pts = [(x0, y0), (x0 + length, y0), (x0 + length, y0 + width), (x0, y0 + width)]
    elif kind == "u":  # a notch in the front (or the back)
        a, b, w = u(0.25, 0.5), u(0.2, 0.45), u(0.4, 0.7)
        n, d = u(0.35, 0.6) * w, u(0.3, 0.6) * (a + b)
        pts = [(-b, -w / 2), (a, -w / 2), (a, -n / 2), (a - d, -n / 2), (a - d, n / 2), (a, n / 2), (a, w / 2), (-b, w / 2)]
    elif kind == "t":  # a crossbar in front of a stem
        a, b, w = u(0.3, 0.45), u(0.3, 0.5), u(0.45, 0.7)
        bar, stem = u(0.12, 0.25), u(0.15, 0.25)
        c = a - bar
        pts = [(a, -w / 2), (a, w / 2), (c, w / 2), (c, stem / 2), (-b, stem / 2), (-b, -stem / 2), (c, -stem / 2), (c, -w / 2)]
    elif kind == "chevron":  # an arrowhead: a notch at the back
        a, b, w = u(0.25, 0.5), u(0.2, 0.45), u(0.4, 0.7)
        pts = [(a, 0.0), (-b, w / 2), (-b + u(0.3, 0.6) * (a + b), 0.0), (-b, -w / 2)]
    else:
        raise ValueError(f"unknown body {kind!r}")
    if kind in ("u", "chevron") and rng.random() < 0.5:  # the notch at the other end
        pts = [(-x, y) for x, y in pts]
    poly = shapely.geometry.polygon.orient(shapely.Polygon(pts), 1.0)
    return [[round(float(x), 4), round(float(y), 4)] for x, y in list(poly.exterior.coords)[:-1]]


def make_drive(rng, kind: str) -> Body:
    """A differential drive of ``kind``: ``reverse`` and ``wmax`` (0.2-0.8 rad/s) each at
    random."""
    if kind in ("disc", "box", "l"):
        body = make_robot(rng, {"l": "lfoot"}.get(kind, kind), "unicycle")
        body.spec.pop("wmax", None)
    else:
        outline = _footprint(rng, kind)
        body = Body({"footprint": outline, "vmax": float(rng.uniform(0.5, 1.2)), "kinematics": "unicycle"}, outline)
    if rng.random() < 0.5:
        body.spec["reverse"] = True
    if rng.random() < 0.5:
        body.spec["wmax"] = float(rng.uniform(0.2, 0.8))
    return body


def band(body: Body, radius: float) -> tuple[float, float]:
    """The radial extent of the body driving tangent to a circle of ``radius`` round the
    origin (counter-clockwise, its reference point on the circle), from its outline sampled
    every 5 mm."""
    if body.disc:
        return radius - body.R, radius + body.R
    if "box" in body.spec:
        hl, hw = 0.5 * body.spec["box"][0], 0.5 * body.spec["box"][1]
        pts = np.array([[-hl, -hw], [hl, -hw], [hl, hw], [-hl, hw]])
    else:
        pts = np.asarray(body.spec["footprint"], float)
    ring = np.vstack([pts, pts[:1]])
    s = np.vstack([a + np.linspace(0, 1, max(2, math.ceil(np.hypot(*(b - a)) / 0.005) + 1))[:, None] * (b - a)
                   for a, b in zip(ring[:-1], ring[1:], strict=True)])
    r = np.hypot(radius - s[:, 1], s[:, 0])  # reference at (radius, 0) heading +y
    return float(r.min()), float(r.max())


# --------------------------------------------------------------------------- scenes


class Case:
    """A scene under construction: bounds, obstacle entries, movers, the maps it cuts from."""

    def __init__(self, body: Body, bounds):
        self.body, self.bounds = body, [float(b) for b in bounds]
        self.obstacles: list[dict] = []
        self.movers: list[dict] = []

    def walls(self, free) -> None:
        """Everything within the bounds but ``free`` as polygon obstacles (holes split)."""
        # free grown by 0.1 um: where its pieces meet along a line, their union can keep a
        # crack of zero width, which would be a wall of zero thickness (a line the check blocks)
        rest = shapely.box(*self.bounds).difference(free.buffer(1e-7, join_style="mitre"))
        for poly in getattr(rest, "geoms", [rest]):
            if poly.is_empty or poly.area < 1e-6:
                continue
            for piece in _without_holes(poly):
                self.obstacles.append(polygon(piece))

    def doc(self, name: str, start, goal) -> dict:
        d = {"version": 1, "name": name, "bounds": self.bounds, "robot": self.body.spec, "obstacles": self.obstacles}
        if self.movers:
            d["movers"] = self.movers
        d["queries"] = [{"name": "q", "start": [float(v) for v in start], "goal": [float(v) for v in goal]}]
        return d


def _without_holes(poly) -> list:
    """A polygon with holes cut into pieces without (along the holes' middles)."""
    if not len(poly.interiors):
        return [poly]
    x0, y0, x1, y1 = poly.bounds
    hole = shapely.Polygon(poly.interiors[0])
    x = 0.5 * (hole.bounds[0] + hole.bounds[2])
    out = []
    for half in (shapely.box(x0 - 1, y0 - 1, x, y1 + 1), shapely.box(x, y0 - 1, x1 + 1, y1 + 1)):
        part = poly.intersection(half)
        for p in getattr(part, "geoms", [part]):
            if p.geom_type == "Polygon" and p.area > 1e-6:
                out.extend(_without_holes(p))
    return out


def _pose_near(rng, geom, bounds, body: Body, centre, spread: float, tries: int = 300):
    """A pose within ``spread`` of ``centre`` where the body's circumscribed disc keeps
    MARGIN from ``geom`` and the bounds (it can turn there); None if none is found."""
    x0, y0, x1, y1 = bounds
    k = body.R + MARGIN
    for _ in range(tries):
        p = np.asarray(centre, float) + rng.uniform(-spread, spread, 2)
        if not (x0 + k <= p[0] <= x1 - k and y0 + k <= p[1] <= y1 - k):
            continue
        if geom.is_empty or shapely.Point(p).distance(geom) > k:
            return np.r_[p, rng.uniform(-math.pi, math.pi)]
    return None


def scenario_door(rng, body: Body):
    room = Room(rng, body)
    centre, n, thick = _door(room, blocked=False, slack=(0.0, 0.05))
    side = 1 if rng.random() < 0.5 else -1
    reach = thick / 2 + body.R + MARGIN
    start = room.free_point(lambda p: side * float(np.dot(p - centre, n)) < -reach)
    goal = room.free_point(lambda p: side * float(np.dot(p - centre, n)) > reach)
    if start is None or goal is None:
        return None
    case = Case(body, [0.0, 0.0, room.W, room.H])
    case.obstacles = room.obstacles
    return case, np.r_[start, rng.uniform(-math.pi, math.pi)], np.r_[goal, rng.uniform(-math.pi, math.pi)]


def scenario_corridor(rng, body: Body):
    room = Room(rng, body)
    width = body.lateral + float(rng.uniform(0.0, 0.1))
    bend = np.array([rng.uniform(2.0, room.W - 2.0), rng.uniform(1.5, room.H - 1.5)])
    h1 = rng.uniform(-math.pi, math.pi)
    h2 = h1 + rng.choice([-1, 1]) * rng.uniform(math.pi / 4, 3 * math.pi / 4)
    d1, d2, far = unit(h1), unit(h2), 3 * (room.W + room.H)
    legs = [shapely.LineString([bend - far * d1, bend]), shapely.LineString([bend, bend + far * d2])]
    free = shapely.union_all([leg.buffer(width / 2, cap_style="flat", join_style="mitre") for leg in legs])
    free = free.union(shapely.Point(bend).buffer(width / 2))
    if rng.random() < 0.5:  # a pocket to turn in
        free = free.union(shapely.Point(bend).buffer(body.R + float(rng.uniform(0.01, 0.05))))
    case = Case(body, [0.0, 0.0, room.W, room.H])
    case.walls(free)
    # the body's lateral middle on the corridor's centre line (facing back along the second
    # leg, its left is the other side)
    start = np.r_[bend - rng.uniform(body.R + 0.3, 2.0) * d1 - body.ymid * left(d1), h1]
    back = rng.random() < 0.3
    goal = np.r_[bend + rng.uniform(body.R + 0.3, 2.0) * d2 + (1 if back else -1) * body.ymid * left(d2),
                 h2 + (math.pi if back else 0.0)]
    return case, start, goal


def scenario_clutter(rng, body: Body):
    room = Room(rng, body)
    for _ in range(int(rng.integers(4, 11))):
        c = [float(rng.uniform(0.3, room.W - 0.3)), float(rng.uniform(0.3, room.H - 0.3))]
        if rng.random() < 0.6:
            room.add({"box": {"center": c, "size": [float(rng.uniform(0.2, 0.9)), float(rng.uniform(0.2, 0.9))],
                              "angle": float(rng.uniform(-math.pi, math.pi))}})
        else:
            room.add({"polygon": polygon(shapely.Point(c).buffer(float(rng.uniform(0.1, 0.4)), quad_segs=4))["polygon"]})
    start = room.free_point(lambda p: p[0] < room.W / 2)
    goal = room.free_point(lambda p: p[0] > room.W / 2 + 1.0)
    if start is None or goal is None:
        return None
    case = Case(body, [0.0, 0.0, room.W, room.H])
    case.obstacles = room.obstacles
    return case, np.r_[start, rng.uniform(-math.pi, math.pi)], np.r_[goal, rng.uniform(-math.pi, math.pi)]


def _arc_free(body: Body, radius: float, spare: float, span: float, inner_free: bool):
    """The curved gap round the origin from angle 0 to ``span`` (counter-clockwise), as wide
    as the body's band plus ``spare``, with a room before it and one after; the radii."""
    lo, hi = band(body, radius)
    rin, rout = lo - spare / 2, hi + spare / 2
    t = np.linspace(0.0, span, 64)
    outer = list(zip(rout * np.cos(t), rout * np.sin(t), strict=True))
    if inner_free:  # the whole pie: what lies inside is the map's
        ring = shapely.Polygon([(0.0, 0.0), *outer])
    else:
        ring = shapely.Polygon(outer + list(zip(rin * np.cos(t[::-1]), rin * np.sin(t[::-1]), strict=True)))
    r0 = max(rin - 0.9, 0.3) if not inner_free else 0.0
    e0, t0 = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    e1, t1 = unit(span), unit(span + math.pi / 2)
    before = shapely.Polygon([r0 * e0, (rout + 0.9) * e0, (rout + 0.9) * e0 - 1.9 * t0, r0 * e0 - 1.9 * t0])
    after = shapely.Polygon([r0 * e1, (rout + 0.9) * e1, (rout + 0.9) * e1 + 1.9 * t1, r0 * e1 + 1.9 * t1])
    return shapely.union_all([ring, before, after]), rin, rout


def _place(geom, angle: float, centre):
    return shapely.affinity.translate(shapely.affinity.rotate(geom, angle, origin=(0, 0), use_radians=True), *centre)


def _arc_query(rng, radius: float, span: float, angle: float, centre):
    """Start in the room before the gap facing into it, goal in the room after."""
    c, s = math.cos(angle), math.sin(angle)
    rot = lambda p: np.array([c * p[0] - s * p[1], s * p[0] + c * p[1]]) + centre  # noqa: E731
    back, on = rng.uniform(0.6, 1.2), rng.uniform(0.6, 1.2)
    start = np.r_[rot(np.array([radius, -back])), angle + math.pi / 2 + rng.uniform(-0.3, 0.3)]
    goal = np.r_[rot(radius * unit(span) + on * unit(span + math.pi / 2)), angle + span + math.pi / 2 + rng.uniform(-0.3, 0.3)]
    return start, goal


def scenario_arc(rng, body: Body):
    radius, spare, span = rng.uniform(0.9, 2.0), rng.uniform(0.0, 0.06), rng.uniform(math.pi / 3, 2 * math.pi / 3)
    free, rin, _ = _arc_free(body, radius, spare, span, inner_free=False)
    if rin < 0.15:
        return None
    angle = float(rng.uniform(-math.pi, math.pi))
    free = _place(free, angle, (0.0, 0.0))
    x0, y0, x1, y1 = free.bounds
    free = shapely.affinity.translate(free, -x0, -y0)
    case = Case(body, [0.0, 0.0, x1 - x0, y1 - y0])
    case.walls(free)
    start, goal = _arc_query(rng, radius, span, angle, np.array([-x0, -y0]))
    return case, start, goal


def scenario_crop(rng, body: Body):
    scene_file, map_file = MAPS[int(rng.integers(len(MAPS)))]
    with open(ROOT / "scenes" / scene_file) as f:
        bounds = yaml.safe_load(f).get("bounds")
    if bounds is None:
        bounds = _map_scene(scene_file).bounds
    w, h = rng.uniform(3.5, 6.0), rng.uniform(3.5, 6.0)
    x0, y0 = rng.uniform(bounds[0], max(bounds[0], bounds[2] - w)), rng.uniform(bounds[1], max(bounds[1], bounds[3] - h))
    crop = [x0, y0, min(x0 + w, bounds[2]), min(y0 + h, bounds[3])]
    case = Case(body, crop)
    case.obstacles = [{"map": {"file": map_file}}]
    geom = obstacle_geometry(_map_scene(scene_file))
    mid = np.array([(crop[0] + crop[2]) / 2, (crop[1] + crop[3]) / 2])
    start = _pose_near(rng, geom, crop, body, mid, 3.0)
    if start is None:
        return None
    for _ in range(20):
        goal = _pose_near(rng, geom, crop, body, mid, 3.0)
        if goal is not None and np.hypot(*(goal[:2] - start[:2])) > 1.5:
            return case, start, goal
    return None


@functools.cache
def tb3_posts() -> list:
    """The TurtleBot sandbox's nine posts: (middle, reach) of each one's cells (the reach
    is the distance of its far corners from the middle)."""
    geom = obstacle_geometry(_map_scene("tb3-arena.yaml"))
    out = []
    for p in getattr(geom, "geoms", [geom]):
        x0, y0, x1, y1 = p.bounds
        if x1 - x0 < 1.0 and y1 - y0 < 1.0:
            out.append(((0.5 * (x0 + x1), 0.5 * (y0 + y1)), 0.5 * math.hypot(x1 - x0, y1 - y0)))
    return tuple(sorted(out))


def scenario_crop_arc(rng, body: Body):
    """Round a post of the TurtleBot sandbox through a quarter of a disc drawn round it."""
    posts = tb3_posts()
    post, reach = posts[int(rng.integers(len(posts)))]
    post = np.asarray(post)
    spare = rng.uniform(0.0, 0.06)
    radius = 1.0
    for _ in range(3):  # the body's inner side spare / 2 from the post's corners
        radius += reach + spare / 2 - band(body, radius)[0]
    free, _, _ = _arc_free(body, radius, spare, math.pi / 2, inner_free=True)
    angle = float(rng.integers(4)) * math.pi / 2
    free = _place(free, angle, post)
    case = Case(body, free.bounds)
    case.obstacles = [{"map": {"file": "maps/tb3_sandbox.yaml", "unknown": "free"}}]
    case.walls(free)
    start, goal = _arc_query(rng, radius, math.pi / 2, angle, post)
    return case, start, goal


BUILDERS = {"door": scenario_door, "corridor": scenario_corridor, "clutter": scenario_clutter,
            "arc": scenario_arc, "crop": scenario_crop, "crop-arc": scenario_crop_arc}

_MAP_SCENES: dict = {}


def _map_scene(scene_file: str):
    if scene_file not in _MAP_SCENES:
        from gfuzzy.scene.scene import load_scene

        _MAP_SCENES[scene_file] = load_scene(ROOT / "scenes" / scene_file)
    return _MAP_SCENES[scene_file]


def _mover(rng, case: Case, body: Body) -> None:
    """A bouncing mover across the room, between the start's side and the goal's."""
    x0, y0, x1, y1 = case.bounds
    a = [float(rng.uniform(x0 + 0.3, x1 - 0.3)), float(rng.uniform(y0 + 0.3, y1 - 0.3))]
    b = [float(rng.uniform(x0 + 0.3, x1 - 0.3)), float(rng.uniform(y0 + 0.3, y1 - 0.3))]
    case.movers.append({"name": "m0", "disc": float(rng.uniform(0.1, 0.2)), "speed": float(rng.uniform(0.3, 0.8)),
                        "path": [a, b], "mode": "bounce", "offset": float(rng.uniform(0, 3))})


def make_case(seed: int, index: int, bodies=BODIES, scenarios=tuple(SCENARIOS)) -> dict:
    """Case ``index`` of ``seed``: its scene document and scene, query and roadmap seed.
    The same arguments give the same case."""
    rng = np.random.default_rng([seed, index])
    kind = bodies[index % len(bodies)]
    names = list(scenarios)
    weights = np.array([SCENARIOS[s] for s in names])
    scenario = str(rng.choice(names, p=weights / weights.sum()))
    for attempt in range(TRIES):
        body = make_drive(rng, kind)
        got = BUILDERS[scenario](rng, body)
        if got is None:
            continue
        case, start, goal = got
        mover = not scenario.startswith("crop") and rng.random() < 0.25
        if mover:
            _mover(rng, case, body)
        doc = case.doc(f"drives-{seed}-{index}", start, goal)
        scene = parse_scene(doc, f"case {index}", folder=ROOT / "scenes")
        q = scene.queries[0]
        if query_problem(StaticGeometry(scene), q.start, q.goal) or not _ends_valid(scene, q):
            continue
        return {"index": index, "body": kind, "scenario": scenario, "reverse": bool(body.spec.get("reverse")),
                "wmax": body.spec.get("wmax", ""), "mover": mover, "doc": doc, "scene": scene, "query": q,
                "roadmap_seed": int(rng.integers(1, 1000)), "attempts": attempt + 1}
    raise RuntimeError(f"case {index}: no valid {scenario} scene in {TRIES} draws")


# --------------------------------------------------------------------------- running


def plan_case(case: dict, vertices=VERTICES, roadmap_seed: int | None = None, time_limit: float | None = None,
              drive_repair: bool = True) -> dict:  # fmt: skip
    """gfuzzy on the case: each roadmap size in turn until a checked answer (``time_limit``:
    each plan's budget, wall-clock seconds; None: the planner's default; ``drive_repair``:
    ``PlanOptions.drive_repair``)."""
    opts = PlanOptions(drive_repair=drive_repair) if time_limit is None else PlanOptions(time_limit=time_limit,
                                                                                          drive_repair=drive_repair)
    scene, q = case["scene"], case["query"]
    seed = case["roadmap_seed"] if roadmap_seed is None else roadmap_seed
    out = {"gfuzzy": "", "vertices": "", "status": "", "message": "", "duration": "", "cpu_s": 0.0, "tries": []}
    for n in vertices:
        t = time.process_time()
        rm = build_roadmap(scene, RoadmapOptions(vertices=n, seed=seed))
        build = time.process_time() - t
        t = time.process_time()
        res = Planner(scene, rm).plan(q.start, q.goal, q.t0, opts, hold=q.hold)
        plan = time.process_time() - t
        out["cpu_s"] += build + plan
        out["status"], out["message"], out["vertices"] = res.status.value, res.message, n
        out["tries"].append(f"-n {n}: {res.status.value} build {build:.2f} plan {plan:.2f}")
        if res.solved:
            rep = check_trajectory(scene, res.trajectory.waypoints, query=q)
            if rep.valid:
                out["gfuzzy"], out["duration"] = "solved", round(float(res.duration), 3)
                return out
            out["status"], out["message"] = "check_reject", str(rep.reason)
    out["gfuzzy"] = "check_reject" if out["status"] == "check_reject" else "unsolved"
    return out


def run_case(case: dict, vertices=VERTICES, oracle: bool = True, roadmap_seed: int | None = None,
             time_limit: float | None = None, drive_repair: bool = True) -> dict:
    row = {k: case[k] for k in ("index", "body", "scenario", "reverse", "wmax", "mover")}
    row["wmax"] = round(row["wmax"], 3) if row["wmax"] != "" else ""
    row["roadmap_seed"] = case["roadmap_seed"] if roadmap_seed is None else roadmap_seed
    try:
        got = plan_case(case, vertices, roadmap_seed, time_limit, drive_repair)
        row.update({k: got[k] for k in ("gfuzzy", "vertices", "status", "message", "duration")})
        row["gfuzzy_s"] = round(got["cpu_s"], 2)
        row["tries"] = "; ".join(got["tries"])
    except Exception as exc:  # noqa: BLE001 - a benchmark counts tracebacks, it does not stop at one
        row.update(gfuzzy="error", message=f"{type(exc).__name__}: {exc}", traceback=traceback.format_exc())
    row["oracle"], row["oracle_s"], row["oracle_lattice"], row["oracle_reason"] = "", "", "", ""
    if oracle:
        res = solve(case["scene"], case["query"])
        row["oracle"] = "proved" if res["verified"] else "not_found"
        row["oracle_s"] = round(res["seconds"], 2)
        row["oracle_lattice"] = res["lattice"]
        row["oracle_reason"] = res["reason"]
        case["oracle_path"] = res["waypoints"] if res["verified"] else None
    row["outcome"] = outcome(row)
    return row


def outcome(row: dict) -> str:
    """``both``, ``gfuzzy-only``, ``missed`` (the oracle only), ``neither``; ``check_reject``
    or ``error`` whatever the oracle says; without the oracle, gfuzzy's result."""
    if row["gfuzzy"] in ("check_reject", "error"):
        return row["gfuzzy"]
    solved = row["gfuzzy"] == "solved"
    if row["oracle"] == "":
        return "solved" if solved else "unsolved"
    proved = row["oracle"] == "proved"
    return {(True, True): "both", (True, False): "gfuzzy-only", (False, True): "missed", (False, False): "neither"}[(solved, proved)]


# --------------------------------------------------------------------------- output


def table(rows: list[dict], key=None) -> str:
    """Cases, oracle-proved, gfuzzy solved and checked, gfuzzy only, missed, neither, per
    group (``key``) and in all; median CPU seconds."""
    groups = defaultdict(list)
    for r in rows:
        groups[key(r) if key else "all"].append(r)
    head = ["group", "cases", "oracle proves", "gfuzzy solves (checked)", "of them at -n 400", "gfuzzy only",
            "missed (oracle only)", "neither", "check rejects / errors", "gfuzzy s (median)", "oracle s (median)"]
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    names = (sorted(groups) + ["all"]) if key else ["all"]
    for name in names:
        g = rows if name == "all" else groups[name]
        count = lambda o, g=g: sum(r["outcome"] == o for r in g)  # noqa: E731
        med = lambda v: f"{float(np.median(v)):.1f}" if v else "-"  # noqa: E731
        cells = [name, len(g), sum(r["oracle"] == "proved" for r in g), sum(r["gfuzzy"] == "solved" for r in g),
                 sum(r["gfuzzy"] == "solved" and r["vertices"] != VERTICES[0] for r in g), count("gfuzzy-only"),
                 count("missed"), count("neither"), count("check_reject") + count("error"),
                 med([r["gfuzzy_s"] for r in g if r.get("gfuzzy_s", "") != ""]),
                 med([r["oracle_s"] for r in g if r["oracle_s"] != ""])]
        lines.append("| " + " | ".join(str(c) for c in cells) + " |")
    return "\n".join(lines)


FIELDS = ["index", "body", "scenario", "reverse", "wmax", "mover", "roadmap_seed", "outcome", "gfuzzy", "vertices",
          "status", "duration", "gfuzzy_s", "oracle", "oracle_lattice", "oracle_s", "oracle_reason", "tries", "message"]


def write_csv(path: str, rows: list[dict]) -> None:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=FIELDS, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    write_atomic(path, buf.getvalue())


def dump(folder: Path, seed: int, case: dict, row: dict, vertices) -> Path:
    """The case's scene (query ``q``), the maps it names, the oracle's path when it found
    one, and the commands that reproduce it; returns the scene's path."""
    folder.mkdir(parents=True, exist_ok=True)
    stem = case["doc"]["name"]
    path = folder / f"{stem}.yaml"
    maps = [ob["map"]["file"] for ob in case["doc"]["obstacles"] if "map" in ob]
    for m in maps:  # a map lies in the scene's folder: copy it and its image
        (folder / "maps").mkdir(exist_ok=True)
        src = ROOT / "scenes" / m
        shutil.copyfile(src, folder / m)
        image = yaml.safe_load(src.read_text())["image"]
        shutil.copyfile(src.parent / image, folder / "maps" / image)
    rm = folder / f"{stem}.rm.json"
    head = (f"# tools/bench_unseen_drives.py --seed {seed} --only {case['index']}: {case['body']} {case['scenario']}"
            f"{' reverse' if case['reverse'] else ''}: {row['outcome']} ({row['message'][:100]})\n"
            f"# python -m gfuzzy roadmap {path} -n {vertices[0]} --seed {row['roadmap_seed']} -o {rm}\n"
            f"# python -m gfuzzy plan {path} --roadmap {rm} --query q -o {folder / stem}.plan.json\n"
            f"# python tools/drive_oracle.py {path} -o {folder / stem}.oracle.json\n")
    write_atomic(path, head + yaml.safe_dump(case["doc"], sort_keys=False, default_flow_style=None, width=200))
    wp = case.get("oracle_path")
    if wp is not None:
        doc = {"version": 1, "scene": stem, "query": "q", "status": "solved", "message": "tools/drive_oracle.py",
               "duration": float(wp[-1, 0] - wp[0, 0]), "waypoints": wp.tolist()}
        write_atomic(folder / f"{stem}.oracle.json", json.dumps(doc))
    return path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", type=int, default=40)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("-n", "--vertices", type=int, nargs="+", default=list(VERTICES),
                    help="roadmap sizes tried in turn until a checked answer (default 200 400)")
    ap.add_argument("--roadmap-seed", type=int, help="every case's roadmap seed (default: drawn per case)")
    ap.add_argument("--bodies", nargs="+", choices=BODIES, default=list(BODIES))
    ap.add_argument("--scenarios", nargs="+", choices=list(SCENARIOS), default=list(SCENARIOS))
    ap.add_argument("--only", type=int, nargs="+", help="run only these case indices")
    ap.add_argument("--no-oracle", action="store_true", help="gfuzzy only")
    ap.add_argument("--no-proof", action="store_true", help="build every drive's graph, as before the lanes' "
                    "proof that its ends are apart (gfuzzy/timespace/unireach.py): its cost, paired")
    ap.add_argument("--time-limit", type=float, help="each plan's budget, wall-clock seconds (default: the planner's 60; "
                    "on a loaded machine a larger one keeps timeouts out of the table)")
    ap.add_argument("--drive-repair", action=argparse.BooleanOptionalAction, default=True,
                    help="PlanOptions.drive_repair (default on, as gfuzzy plan's; --no-drive-repair: off, "
                         "the planner before session 38)")
    ap.add_argument("-o", "--output", help="CSV, one row per case (written atomically)")
    ap.add_argument("--dump", help="folder for the scene and commands of each case gfuzzy did not solve "
                    "(of every case with --only)")
    a = ap.parse_args(argv)
    if a.cases < 1 or min(a.vertices) < 2:
        print("bench_unseen_drives: --cases must be >= 1 and -n >= 2", file=sys.stderr)
        return 2
    indices = a.only if a.only else range(a.cases)
    if a.no_proof:
        import gfuzzy.timespace.unireach as unireach

        unireach.ends_apart = lambda *args, **kwargs: False
    rows, t0 = [], time.perf_counter()
    for k, index in enumerate(indices, 1):
        try:
            case = make_case(a.seed, index, tuple(a.bodies), tuple(a.scenarios))
        except Exception as exc:  # noqa: BLE001
            print(f"[{k}/{len(indices)}] case {index}: generator: {type(exc).__name__}: {exc}", file=sys.stderr, flush=True)
            continue
        row = run_case(case, a.vertices, oracle=not a.no_oracle, roadmap_seed=a.roadmap_seed, time_limit=a.time_limit,
                       drive_repair=a.drive_repair)  # fmt: skip
        rows.append(row)
        print(f"[{k}/{len(indices)}] case {index} {row['body']} {row['scenario']}{' rev' if row['reverse'] else ''}"
              f"{' mover' if row['mover'] else ''}: {row['outcome']} (gfuzzy {row['status']} at -n {row['vertices']}, "
              f"{row.get('gfuzzy_s', '')} s; oracle {row['oracle']} {row['oracle_s']} s) {row['message'][:80]}",
              file=sys.stderr, flush=True)
        if "traceback" in row:
            print(row["traceback"], file=sys.stderr)
        if a.output:  # after each case: a long run interrupted keeps what it measured
            write_csv(a.output, rows)
        if a.dump and (a.only or row["gfuzzy"] != "solved"):
            dump(Path(a.dump), a.seed, case, row, a.vertices)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    which = f"--only {' '.join(map(str, a.only))}" if a.only else f"--cases {a.cases}"
    limit = ("" if a.time_limit is None else f" --time-limit {a.time_limit:g}") + (" --no-proof" if a.no_proof else "")
    limit += "" if a.drive_repair else " --no-drive-repair"
    print(f"# tools/bench_unseen_drives.py {which} --seed {a.seed} -n {' '.join(map(str, a.vertices))}{limit}: {len(rows)} "
          f"cases in {time.perf_counter() - t0:.0f} s, load average {load:.2f}; times: CPU seconds")
    print(table(rows))
    print()
    print(table(rows, lambda r: r["scenario"]))
    print()
    print(table(rows, lambda r: r["body"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
