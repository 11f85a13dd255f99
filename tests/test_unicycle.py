"""The differential drive (``kinematics: unicycle``): scenes, the checker's row rule, plans.

The oracles here share no code with the planner: a breadth-first search over (place along
the motion, time step) with its own mover positions and its own safety test, and a Dijkstra
over (vertex, heading) with the turning time written out, on tiny cases.
"""

from __future__ import annotations

import heapq
import math

import numpy as np
import pytest

from gfuzzy.check.check import check_trajectory
from gfuzzy.errors import SceneError
from gfuzzy.planner.planner import Planner, PlanOptions, query_problem
from gfuzzy.roadmap.roadmap import Roadmap
from gfuzzy.scene.scene import parse_scene
from gfuzzy.timespace.drive import turn_path


def doc(robot=None, movers=(), obstacles=(), queries=(), bounds=(0, 0, 6, 4)):
    return {
        "version": 1,
        "name": "u",
        "bounds": list(bounds),
        "robot": robot or {"disc": 0.2, "vmax": 1.0, "kinematics": "unicycle"},
        "obstacles": list(obstacles),
        "movers": list(movers),
        "queries": list(queries),
    }


# --------------------------------------------------------------------------- scene


def test_scene_takes_the_unicycle_keys():
    sc = parse_scene(doc({"box": [0.6, 0.4], "vmax": 0.8, "kinematics": "unicycle", "wmax": 1.5, "reverse": True}))
    r = sc.robot
    assert r.unicycle and r.reverse and r.wmax == 1.5 and r.dof == 3 and r.space_dof == 3
    assert r.turn_rate == pytest.approx(min(1.5, 0.8 / r.circumradius))
    disc = parse_scene(doc()).robot
    assert disc.dof == 3 and disc.space_dof == 2 and not disc.reverse
    assert disc.turn_rate == pytest.approx(1.0 / 0.2)  # default: vmax / r
    assert parse_scene(doc({"disc": 0.2, "vmax": 1.0})).robot.dof == 2


@pytest.mark.parametrize(
    "robot, place",
    [
        ({"disc": 0.2, "vmax": 1.0, "kinematics": "tank"}, "robot.kinematics"),
        ({"disc": 0.2, "vmax": 1.0, "kinematics": "unicycle", "wmax": 0}, "robot.wmax"),
        ({"disc": 0.2, "vmax": 1.0, "kinematics": "unicycle", "wmax": -1.0}, "robot.wmax"),
        ({"disc": 0.2, "vmax": 1.0, "kinematics": "unicycle", "reverse": "yes"}, "robot.reverse"),
        ({"disc": 0.2, "vmax": 1.0, "wmax": 1.0}, "robot.wmax"),
    ],
)
def test_bad_unicycle_keys_name_their_place(robot, place):
    with pytest.raises(SceneError) as err:
        parse_scene(doc(robot))
    assert place in str(err.value)


def test_a_unicycle_pose_needs_a_heading_even_for_a_disc():
    q = {"name": "q", "start": [1, 1], "goal": [2, 2, 0]}
    with pytest.raises(SceneError) as err:
        parse_scene(doc(queries=[q]))
    assert "queries[0].start" in str(err.value)


# --------------------------------------------------------------------------- check


def rows(*r):
    return np.array(r, dtype=float)


@pytest.fixture(scope="module")
def disc_scene():
    return parse_scene(doc({"disc": 0.2, "vmax": 1.0, "kinematics": "unicycle", "wmax": 2.0}))


def test_check_accepts_waits_turns_in_place_and_straight_moves(disc_scene):
    w = rows([0, 1, 1, 0], [1, 1, 1, 0], [1.5, 1, 1, 1.0], [2.5, 1 + 0.5 * math.cos(1), 1 + 0.5 * math.sin(1), 1.0])
    rep = check_trajectory(disc_scene, w)
    assert rep.valid, rep.reason


@pytest.mark.parametrize(
    "w, words",
    [
        (rows([0, 1, 1, 0], [1, 1, 1.1, 0]), "slides sideways"),
        (rows([0, 1, 1, 0], [1, 1.2, 1, 0.3]), "turns while moving"),
        (rows([0, 1, 1, 0], [1, 0.5, 1, 0]), "drives backwards"),
        (rows([0, 1, 1, 0], [0.1, 1, 1, 0.3]), "faster than wmax"),
        (rows([0, 1, 1, 0], [1, 2, 1, 0], [2, 2, 1.000003, 0]), "slides sideways"),
    ],
)
def test_check_rejects_what_a_differential_drive_cannot_do(disc_scene, w, words):
    rep = check_trajectory(disc_scene, w)
    assert not rep.valid and words in rep.reason


def test_check_allows_backwards_only_with_reverse():
    w = rows([0, 2, 1, 0], [1, 1.5, 1, 0])
    fwd = parse_scene(doc({"disc": 0.2, "vmax": 1.0, "kinematics": "unicycle"}))
    rev = parse_scene(doc({"disc": 0.2, "vmax": 1.0, "kinematics": "unicycle", "reverse": True}))
    assert not check_trajectory(fwd, w).valid
    assert check_trajectory(rev, w).valid
    # the same rows for a holonomic robot with heading (a box) slide sideways legally
    box = parse_scene(doc({"box": [0.4, 0.2], "vmax": 1.0}))
    assert check_trajectory(box, rows([0, 2, 1, 0], [1, 2, 1.5, 0])).valid


def test_turn_path_is_straight_moves_and_turns_in_place(disc_scene):
    path = turn_path([1, 1, 0.0], [[2, 2], [3, 1.5]], [4, 1, 2.0])
    t = np.arange(len(path), dtype=float) * 3.0  # slow enough for any turn
    rep = check_trajectory(disc_scene, np.column_stack([t, path]))
    assert rep.valid, rep.reason
    assert np.allclose(path[0], [1, 1, 0]) and np.allclose(path[-1], [4, 1, 2.0])


# --------------------------------------------------------------------------- planning oracles


def _far_roadmap(scene, pts=((5.6, 3.6), (5.7, 3.6))):
    """A roadmap far from the action: only the direct start-goal connection is useful."""
    v = np.array(pts, dtype=float)
    return Roadmap(v, np.array([[0, 1]]), np.array([np.hypot(*(v[1] - v[0]))]), scene.name, scene.static_hash,
                   scene.robot.circumradius)  # fmt: skip


def _oracle_bfs(L, turn, dt, vmax, wmax, mover, r_robot, r_mover, start_xy, t_max=400):
    """Earliest arrival: drive L along +x from ``start_xy`` (heading 0), then turn ``turn`` rad
    in place; wait anywhere. Every step's pose must keep the safety margin from the mover
    (its centre at ``mover(t)``): distance - radii >= (vmax + mover speed) dt / 2.

    BFS over (place along the motion, step). Returns the arrival step or None.
    """
    k = max(1, math.ceil(L / (vmax * dt)))
    kt = max(1, math.ceil(abs(turn) / (wmax * dt)))
    n_places = k + kt + 1

    def xy(u):
        return start_xy[0] + L * min(u, k) / k, start_xy[1]

    def safe(u, n):
        mx, my, speed = mover(n * dt)
        x, y = xy(u)
        return math.hypot(x - mx, y - my) - r_robot - r_mover >= 0.5 * (vmax + speed) * dt

    reach = {0} if safe(0, 0) else set()
    for n in range(t_max):
        if n_places - 1 in reach:
            return n
        nxt = set()
        for u in reach:
            for w in (u, u + 1):
                if w < n_places and safe(w, n + 1):
                    nxt.add(w)
        reach = nxt
    return None


@pytest.mark.parametrize("backend", ["compiled", "reference"])
@pytest.mark.parametrize("cross_at", [0.6, 1.2, 3.0])
def test_plan_equals_a_brute_force_search_with_a_crossing_mover(backend, cross_at):
    """Start facing the goal, a mover crossing the straight line: the planner's arrival
    equals a BFS over (place, step) written here (its own positions and safety test)."""
    dt, vmax, wmax, r, rm = 0.1, 1.0, 1.0, 0.2, 0.25
    L, turn = 1.95, 0.5 * math.pi
    sy = 1.0
    speed = 0.8
    y0 = sy - speed * cross_at  # the mover's centre crosses y = 1 at t = cross_at
    mover = {"name": "m", "disc": rm, "speed": speed, "path": [[2.0, y0], [2.0, y0 + 40]], "mode": "once"}
    sc = parse_scene(doc({"disc": r, "vmax": vmax, "kinematics": "unicycle", "wmax": wmax}, movers=[mover],
                         bounds=(0, -40, 6, 44)))  # fmt: skip
    planner = Planner(sc, _far_roadmap(sc))
    res = planner.plan([1.0, sy, 0.0], [1.0 + L, sy, turn], 0.0, PlanOptions(dt=dt, backend=backend))
    assert res.solved, res.message
    rep = check_trajectory(sc, res.trajectory.waypoints)
    assert rep.valid, rep.reason

    def where(t):
        return 2.0, y0 + speed * t, speed

    n = _oracle_bfs(L, turn, dt, vmax * (1 - 1e-9), wmax * (1 - 1e-9), where, r, rm, (1.0, sy))
    assert n is not None
    assert res.duration == pytest.approx(n * dt, abs=1e-9)
    free = math.ceil(L / (vmax * dt)) + math.ceil(turn / (wmax * dt))
    if cross_at < 2.5:  # the mover is in the way: the answer waits
        assert n > free


def _oracle_static(verts, edges, start, goal, vmax, w):
    """Shortest time over (vertex, heading) with turns in place of |dh| / w and straight
    moves along the heading (forwards): Dijkstra written out. Start and goal are
    vertices 0 and 1 of ``verts`` with their headings."""
    adj = {i: [] for i in range(len(verts))}
    for a, b in edges:
        adj[a].append(b)
        adj[b].append(a)

    def wrap(x):
        return (x + math.pi) % (2 * math.pi) - math.pi

    best = {}
    heap = [(0.0, 0, start[2])]
    while heap:
        t, v, h = heapq.heappop(heap)
        key = (v, round(h, 9))
        if key in best:
            continue
        best[key] = t
        if v == 1:
            heapq.heappush(heap, (t + abs(wrap(goal[2] - h)) / w, -1, goal[2]))
        if v == -1:
            return t
        for u in adj.get(v, []):
            d = np.subtract(verts[u], verts[v])
            hn = math.atan2(d[1], d[0])
            heapq.heappush(heap, (t + abs(wrap(hn - h)) / w + math.hypot(*d) / vmax, u, hn))
    return math.inf


def test_static_plan_is_near_the_exact_turn_and_drive_optimum():
    """No movers: the answer obeys the rule and its duration lies between the exact
    optimum on the same roadmap (a Dijkstra over (vertex, heading) written here) and that
    optimum plus one step per piece of it (each piece is cut up to a whole step)."""
    dt, vmax, wmax = 0.05, 1.0, 1.5
    wall = {"box": {"center": [3.0, 2.0], "size": [0.4, 2.4]}}
    sc = parse_scene(doc({"disc": 0.2, "vmax": vmax, "kinematics": "unicycle", "wmax": wmax}, obstacles=[wall]))
    start, goal = np.array([1.0, 2.0, math.pi]), np.array([5.0, 2.0, 0.5])
    verts = np.array([[1.0, 2.0], [5.0, 2.0], [2.0, 0.5], [4.0, 0.5], [2.0, 3.5], [4.0, 3.5], [3.0, 0.4]])
    edges = [(2, 6), (6, 3), (4, 5), (2, 4), (3, 5)]
    rm = Roadmap(verts[2:], np.array(edges) - 2, np.array([np.hypot(*(verts[b] - verts[a])) for a, b in edges]),
                 sc.name, sc.static_hash, sc.robot.circumradius)  # fmt: skip
    res = Planner(sc, rm).plan(start, goal, 0.0, PlanOptions(dt=dt))
    assert res.solved, res.message
    rep = check_trajectory(sc, res.trajectory.waypoints)
    assert rep.valid, rep.reason
    conn = [(0, 2), (0, 4), (3, 1), (5, 1), (2, 6), (6, 3), (4, 5), (2, 4), (3, 5)]
    best = _oracle_static(verts, conn, start, goal, vmax, wmax)
    pieces = 2 * 4 + 3  # at most 4 lanes and turns on each side of the 3 lanes in between
    assert best - 1e-9 <= res.duration <= best + (pieces + 2) * dt


def door_lanes_scene():
    """A disc drive (radius 0.2) and a wall at x = 3, 0.3 thick, with a door 0.45 wide at
    y = 2; a roadmap whose only way through runs on the door's axis from (1, 2) to (5, 2)
    through a vertex in the door, and a vertex off the axis on either side."""
    walls = [{"box": {"center": [3.0, 0.8875], "size": [0.3, 1.775]}}, {"box": {"center": [3.0, 3.1125], "size": [0.3, 1.775]}}]
    sc = parse_scene(doc(obstacles=walls))
    verts = np.array([[1.0, 2.0], [3.0, 2.0], [5.0, 2.0], [2.2, 3.5], [3.8, 0.5]])
    edges = np.array([[0, 1], [1, 2], [0, 3], [2, 4]])
    rm = Roadmap(verts, edges, np.hypot(*(verts[edges[:, 1]] - verts[edges[:, 0]]).T), sc.name, sc.static_hash,
                 sc.robot.circumradius)  # fmt: skip
    return sc, rm


def test_a_disc_drive_gets_turn_points_where_a_lane_leaves_a_door():
    """A drive turns only at vertices: a lane through a door from a vertex in it ran on to
    the next vertex, 2 m beyond the door on its axis (the unseen rooms' seed 2 case 88: the
    axis a mover's line). Each lane from a vertex in a passage gets a turn point where the
    disc has a radius of clearance, just outside the door, with lanes to the nearest
    vertices the disc sweeps free: here the vertices off the axis, straight."""
    from gfuzzy.collision.geometry import StaticGeometry
    from gfuzzy.timespace.unilanes import lanes

    sc, rm = door_lanes_scene()
    geo = StaticGeometry(sc)
    ln = lanes(rm, geo, 1.0)
    new = ln.xy[len(rm.vertices) :]
    assert len(new) == 2
    for p, side in zip(sorted(new.tolist()), (-1, 1), strict=True):
        assert abs(p[1] - 2.0) < 1e-12 and 0.15 < side * (p[0] - 3.0) < 0.5, p  # on the axis, just outside
        assert geo.clearance1(np.array(p)) >= 0.2
    pairs = {tuple(ln.xy[e].round(6).ravel().tolist()) for e in ln.edges}
    ends = {tuple(p) for e in pairs for p in (e[:2], e[2:])}
    assert (2.2, 3.5) in ends and (3.8, 0.5) in ends
    i = len(rm.vertices)
    linked = {int(b if a >= i else a) for a, b in ln.edges if (a >= i) != (b >= i)}
    assert {3, 4} <= linked  # the vertices off the axis, each from the turn point on its side
    for a, b in ln.edges:
        assert geo.sweep_free(ln.xy[a], ln.xy[b])


def plane_lanes(obstacles, verts, edges):
    """The lanes (stretch 1) of a disc drive (radius 0.2) among ``obstacles`` on a roadmap of
    ``verts`` and ``edges``, with its geometry and its number of vertices."""
    from gfuzzy.collision.geometry import StaticGeometry
    from gfuzzy.timespace.unilanes import lanes

    sc = parse_scene(doc(obstacles=obstacles))
    verts, edges = np.array(verts, dtype=float), np.array(edges)
    rm = Roadmap(verts, edges, np.hypot(*(verts[edges[:, 1]] - verts[edges[:, 0]]).T), sc.name, sc.static_hash,
                 sc.robot.circumradius)  # fmt: skip
    geo = StaticGeometry(sc)
    return lanes(rm, geo, 1.0), geo, len(verts)


def test_a_disc_drive_gets_turn_points_in_a_passage_only():
    """A vertex 2 cm from a wall (less than half a radius) beside one wall is in no passage:
    a radius away from the wall the disc has a radius of clearance, and its lanes get no
    turn points (107 on tb3-arena-unicycle at stretch 1, a slower search for every plan). A
    second wall 0.5 m from the first (a corridor 2.5 radii wide) pinches it: the lanes
    leaving the corridor get one each; 0.94 m from it (4.7 radii: a radius and a third of
    clearance in its middle) it does not."""
    floor = {"box": {"center": [3.0, 0.5], "size": [3.0, 1.0]}}
    verts, edges = [[3.0, 1.22], [1.5, 3.0], [4.5, 3.0], [0.5, 1.22], [5.5, 1.22]], [[0, 1], [0, 2], [0, 3], [0, 4]]
    ln, geo, n = plane_lanes([floor], verts, edges)
    assert geo.clearance1(np.array(verts[0])) < 0.1 and len(ln.xy) == n
    ceiling = {"box": {"center": [3.0, 2.0], "size": [3.0, 1.0]}}
    ln, geo, n = plane_lanes([floor, ceiling], verts, [[0, 3], [0, 4]])
    new = sorted(ln.xy[n:].tolist())
    assert len(new) == 2 and new[0][0] < 1.5 < 4.5 < new[1][0], new  # just out of the corridor, either end
    assert all(geo.clearance1(np.array(p)) >= 0.2 for p in new)
    wide = {"box": {"center": [3.0, 2.44], "size": [3.0, 1.0]}}
    ln, geo, n = plane_lanes([floor, wide], verts, [[0, 3], [0, 4]])
    assert len(ln.xy) == n


def test_a_passage_end_is_a_radius_from_the_vertex_and_two_from_the_far_end():
    """The point where a lane from a vertex in a passage has a radius of clearance is no
    turn point within a radius of the vertex (the disc turns there about as well) nor within
    two of the lane's far end (it turns there)."""
    from gfuzzy.collision.geometry import StaticGeometry
    from gfuzzy.timespace.unilanes import _passage_end

    geo = StaticGeometry(parse_scene(doc(obstacles=[{"box": {"center": [3.0, 0.5], "size": [6.0, 1.0]}}])))
    r = 0.2
    touch, half = np.array([3.0, 1.2]), np.array([3.0, 1.3])  # clearance 0 and half a radius
    p = _passage_end(geo, touch, np.array([3.0, 3.0]), r)
    assert p is not None and 1.4 <= p[1] <= 1.4 + 0.05 * r  # a radius on: a radius of clearance (within 5%)
    assert _passage_end(geo, half, np.array([3.0, 3.0]), r) is None  # that within a radius of it
    assert _passage_end(geo, touch, np.array([3.0, 1.2 + 2.5 * r]), r) is None  # within two of the far end


def test_a_disc_drive_gets_one_turn_point_where_lanes_leave_a_door_together():
    """Two vertices in the door (of :func:`door_lanes_scene`) 5 cm apart, each with a lane
    out to the same vertex beyond it: their points where the disc has a radius of clearance
    lie within a radius of each other, and only the first is a turn point."""
    sc, rm = door_lanes_scene()
    walls = [{"box": {"center": [3.0, 0.8875], "size": [0.3, 1.775]}}, {"box": {"center": [3.0, 3.1125], "size": [0.3, 1.775]}}]
    verts = [*rm.vertices[:, :2].tolist(), [3.05, 2.0]]
    ln, geo, n = plane_lanes(walls, verts, [*rm.edges.tolist(), [0, 5], [5, 2]])
    new = ln.xy[n:]
    assert len(new) == 2 and math.hypot(*(new[0] - new[1])) > 0.2, new  # one each side of the door


def test_a_disc_drive_gets_turn_points_in_a_door_with_a_third_of_a_radius_to_spare():
    """A door 0.54 m wide (the disc 0.4 across, 0.07 m of clearance centred: more than a
    quarter of a radius, less than half) is a passage: its lanes get turn points."""
    walls = [{"box": {"center": [3.0, 0.865], "size": [0.3, 1.73]}}, {"box": {"center": [3.0, 3.135], "size": [0.3, 1.73]}}]
    sc, rm = door_lanes_scene()
    ln, geo, n = plane_lanes(walls, rm.vertices[:, :2], rm.edges)
    assert 0.25 * 0.2 < geo.clearance1(np.array([3.0, 2.0])) < 0.5 * 0.2
    assert len(ln.xy) == n + 2


def test_a_query_end_joins_only_the_roadmaps_vertices_not_turn_points():
    """A goal just beyond the door's turn point (of :func:`door_lanes_scene`): its lanes run
    to roadmap vertices only. Turn points among an end's nearest took the place of the
    vertices that lead on (unseen rooms seed 3 case 8: the same answer, its plan 0.28 ->
    15.7 s of CPU with the end joined to them)."""
    from gfuzzy.timespace.unicycle import _base
    from gfuzzy.timespace.uniends import _Extras

    sc, rm = door_lanes_scene()
    planner = Planner(sc, rm)
    base = _base(rm, planner.geometry, 1.0, sc.robot.vmax, 0.1)
    turn_points = base.vertex_xy[base.roadmap_vertices :]
    assert len(turn_points) == 2 and base.roadmap_vertices == len(rm.vertices)
    goal = np.array([*(turn_points[np.argmax(turn_points[:, 0])] + [0.1, 0.05]), 0.0])
    ex = _Extras(base, planner.geometry, sc.robot.vmax / sc.robot.turn_rate, 10**6)
    g = ex.node(*goal)
    ex.join(goal, g, 10, False, False)
    ends = [ex.pose(a)[:2] for a, b, dh, _ in ex.pieces if dh == 0.0 and a != g]
    assert ends and all(np.isclose(rm.vertices[:, :2], e).all(axis=1).any() for e in ends), ends


def case88_doc() -> dict:
    """The unseen rooms' seed 2 case 88: a disc drive, a door 0.34 wide in a wall 0.29 thick
    (two polygons), a box mover bouncing along the door's axis through it."""
    robot = {"disc": 0.15261576652492018, "vmax": 0.6393446764407181, "kinematics": "unicycle"}
    walls = [[[2.166813180476964, 0.9431009552319747], [1.905511775245976, 1.0623612897677273],
              [3.0515379138064933, 3.5733238960945584], [3.3672708188643066, 3.5733238960945584]],
             [[1.7640753672880276, 0.752471733494886], [2.0253767725190146, 0.6332113989591335],
              [1.7363733390894753, 0.0], [1.420640434031663, 0.0]]]  # fmt: skip
    mover = {"name": "m0", "box": [0.27884447608881063, 0.35445650976480836], "speed": 0.34002554386108097,
             "path": [[0.6008541966979437, 1.4705976490532684], [3.3300343510670474, 0.22497503967359211]],
             "mode": "bounce", "offset": 2.83649868934185}  # fmt: skip
    query = {"name": "q", "start": [1.4111599826616816, 2.238834604273608, 0.7138001476264089],
             "goal": [4.3575809392649925, 3.2635786147791315, -1.7400118065285501]}  # fmt: skip
    return doc(robot, [mover], [{"polygon": w} for w in walls], [query], (0.0, 0.0, 5.012897710984311, 3.5733238960945584))


def test_a_disc_drive_turns_off_a_movers_line_just_beyond_the_door():
    """Case 88 (roadmap -n 200, seed 193): the lanes through the door ran along the mover's
    line to vertices 1.6 m and 1.1 m on, and the drive, stopping there to turn, met the
    mover coming back (no_path; a witness waits 5.5 s and arrives in 15.55 s). With the turn
    points it leaves the line just beyond the door: solved and checked."""
    from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap

    sc = parse_scene(case88_doc())
    rm = build_roadmap(sc, RoadmapOptions(vertices=200, seed=193))
    q = sc.queries[0]
    res = Planner(sc, rm).plan(q.start, q.goal, 0.0, PlanOptions())
    assert res.solved, res.message
    rep = check_trajectory(sc, res.trajectory.waypoints)
    assert rep.valid, rep.reason


def test_reverse_drives_backwards_when_turning_is_slow():
    """With a slow turn the robot backs up to a goal behind it; without reverse it must
    turn around first, which takes longer (and the checker tells the two apart)."""
    base = {"disc": 0.2, "vmax": 1.0, "kinematics": "unicycle", "wmax": 0.2}
    out = {}
    for rev in (False, True):
        sc = parse_scene(doc(dict(base, reverse=rev)))
        res = Planner(sc, _far_roadmap(sc)).plan([3.0, 2.0, 0.0], [2.0, 2.0, 0.0], 0.0, PlanOptions(dt=0.1))
        assert res.solved, res.message
        assert check_trajectory(sc, res.trajectory.waypoints).valid
        out[rev] = (sc, res)
    assert out[True][1].duration < out[False][1].duration
    assert out[True][1].duration == pytest.approx(1.0 + 0.1, abs=0.11)  # about 1 m backwards
    assert not check_trajectory(out[False][0], out[True][1].trajectory.waypoints).valid


def test_box_unicycle_plans_on_an_se2_roadmap():
    """A box robot's lanes come from the SE(2) roadmap's positions, certified with the
    body held along each lane; the answer passes a gap only lengthwise."""
    from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap

    walls = [{"box": {"center": [3.0, 0.85], "size": [0.2, 1.7]}}, {"box": {"center": [3.0, 3.15], "size": [0.2, 1.7]}}]
    robot = {"box": [0.8, 0.4], "vmax": 1.0, "kinematics": "unicycle"}
    sc = parse_scene(doc(robot, obstacles=walls))
    rm = build_roadmap(sc, RoadmapOptions(vertices=150, seed=2))
    res = Planner(sc, rm).plan([1.0, 2.0, 1.5], [5.0, 2.0, -1.5], 0.0, PlanOptions(dt=0.1))
    assert res.solved, res.message
    rep = check_trajectory(sc, res.trajectory.waypoints)
    assert rep.valid, rep.reason
    w = res.trajectory.waypoints
    near = np.abs(w[:, 1] - 3.0) < 0.5  # in the gap (0.6 wide): the box is lengthwise
    assert near.any() and np.all(np.abs(np.cos(w[near, 3])) > 0.9)


# --------------------------------------------------------------------------- replanning, navigation


def _crossing_scene(reverse=False):
    mover = {"name": "m", "disc": 0.3, "speed": 0.7, "path": [[3.0, 0.4], [3.0, 3.6]], "mode": "bounce"}
    wall = {"box": {"center": [3.0, 3.3], "size": [0.3, 1.4]}}
    robot = {"disc": 0.25, "vmax": 1.0, "kinematics": "unicycle", "wmax": 2.0, "reverse": reverse}
    return parse_scene(doc(robot, movers=[mover], obstacles=[wall]))


@pytest.fixture(scope="module")
def crossing():
    from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap

    sc = _crossing_scene()
    return sc, build_roadmap(sc, RoadmapOptions(vertices=120, seed=4))


def test_plan_from_a_prepared_goal_arrives_with_a_fresh_plan(crossing):
    sc, rm = crossing
    planner = Planner(sc, rm)
    goal = [5.2, 2.0, -2.0]
    prepared = planner.prepare(goal, PlanOptions(dt=0.1))
    for start, t0 in (([0.8, 2.0, 0.3], 0.0), ([1.0, 0.8, 2.5], 1.3), ([0.7, 3.2, -1.0], 4.0)):
        fresh = planner.plan(start, goal, t0, PlanOptions(dt=0.1))
        kept = planner.plan_from(prepared, start, t0)
        assert fresh.solved and kept.solved
        assert kept.duration == pytest.approx(fresh.duration, abs=1e-9)
        assert check_trajectory(sc, kept.trajectory.waypoints).valid


def test_the_navigator_drives_a_unicycle_by_the_rule(crossing):
    """Every trajectory the navigator returns (plans, direct motions, evasions) turns only
    in place and drives only along the heading; the simulated run reaches the goal."""
    from gfuzzy.navigation.navigator import Navigator, NavOptions
    from gfuzzy.navigation.navsim import simulate

    sc, rm = crossing
    res = simulate(sc, rm, [0.8, 2.0, 0.0], [5.2, 2.0, 0.0], 0.0, 0.25, max_time=40.0,
                   options=NavOptions(time_budget=5.0))  # fmt: skip
    assert res.reached
    rep = check_trajectory(sc, res.trajectory.waypoints)
    assert rep.valid, rep.reason
    nav = Navigator(sc, rm, [5.2, 2.0, 0.0])
    pose = np.array([1.5, 2.0, 0.7])
    crowd = np.array([[1.9, 2.0, -0.8, 0.0, 0.3], [1.5, 2.6, 0.0, -0.8, 0.3]])  # about to hit it
    evasive = nav._evasive(0.0, pose, crowd)
    from gfuzzy.check.rows import unicycle_problem as _unicycle_problem

    assert len(evasive.waypoints) >= 2 and _unicycle_problem(sc.robot, evasive.waypoints) is None
    direct = nav._direct(0.0, np.array([4.5, 2.0, 2.0]), np.zeros((0, 5)))
    assert direct is not None and _unicycle_problem(sc.robot, direct.waypoints) is None


@pytest.mark.parametrize("v1, sy", [(0.67, 0.67), (0.675, 0.668)])
def test_a_small_turn_in_a_tight_corridor_needs_no_ring_heading(v1, sy, monkeypatch):
    """A 1.2 x 0.3 box in a corridor 0.34 wide that bends by 0.02 rad: the turn at the bend
    fits, but the turning ring's headings around it (a turning step, 0.068 rad, apart) do
    not. Copies with no ring point between them join directly (before: no_path), the
    roadmap's own (the lanes' headings, ``v1`` centred) and those a start's lane adds at a
    vertex (``v1`` 5 mm off the axis: the start arrives at 0.01 rad, the lane leaves at -0.003).
    The points an end adds on its own heading line (``_Extras.along``, tested apart) would
    find this way too: they are left out, so that the direct joins are what is tested."""
    from gfuzzy.timespace import unicycle

    monkeypatch.setattr(unicycle._Extras, "along", lambda *args, **kw: None)
    d, w, length = 0.02, 0.17, 4.0
    u, n = np.array([math.cos(d), math.sin(d)]), np.array([-math.sin(d), math.cos(d)])
    bend = np.array([3.0, 0.67])
    top0, top1 = bend + w * n, bend + w * n + length * u
    bot0, bot1 = bend - w * n, bend - w * n + length * u
    upper = [[0, 0.84], top0.tolist(), top1.tolist(), [top1[0], 1.5], [0, 1.5]]
    lower = [[0, 0.5], [3.0, 0.5], bot0.tolist(), bot1.tolist(), [bot1[0], 0], [0, 0]]
    robot = {"box": [1.2, 0.3], "vmax": 0.6, "kinematics": "unicycle"}
    sc = parse_scene(doc(robot, obstacles=[{"polygon": upper}, {"polygon": lower}], bounds=(0, 0, float(top1[0]), 1.5)))
    verts = np.array([[1.5, v1], bend, bend + 2.4 * u])
    rm = Roadmap(verts, np.array([[0, 1], [1, 2]]), np.hypot(*np.diff(verts, axis=0).T), sc.name, sc.static_hash,
                 sc.robot.circumradius)  # fmt: skip
    start, goal = [0.8, sy, 0.0], [*(bend + 3.2 * u), d]
    res = Planner(sc, rm).plan(start, goal, 0.0, PlanOptions())
    assert res.solved, res.message
    rep = check_trajectory(sc, res.trajectory.waypoints)
    assert rep.valid, rep.reason
    best = (2.2 + 3.2) / 0.6 + d / sc.robot.turn_rate  # drive, turn 0.02 rad, drive
    assert best - 1e-9 <= res.duration <= best + 6 * 0.07


def test_ring_tracing_finds_the_headings_and_arcs_each_checked_alone():
    """A box's turning ring beside walls: sphere tracing round it (one query proves the
    headings within clearance / r) gives the free headings and arcs that checking every
    heading and arc gives, a heading that touches a wall exactly included (it has nothing
    to spare, and must not stall the tracing)."""
    from gfuzzy.collision.geometry import StaticGeometry
    from gfuzzy.timespace.drive import turn_free
    from gfuzzy.timespace.unilanes import _ring_free

    walls = [{"box": {"center": [1.5, 0.5], "size": [0.4, 0.4], "angle": 0.3}}, {"disc": {"center": [0.4, 1.6], "radius": 0.3}},
             # a thin post the front corner sweeps between two free headings (50 and 51) of the ring at (2.2, 1.5)
             {"disc": {"center": [2.5679437247068657, 1.9168373968933667], "radius": 0.004}}]  # fmt: skip
    sc = parse_scene(doc({"box": [1.0, 0.5], "vmax": 1.0, "kinematics": "unicycle"}, obstacles=walls, bounds=(0, 0, 3, 3)))
    geo = StaticGeometry(sc)
    n = 90
    step = 2 * math.pi / n
    grid = step * (np.arange(n) - n // 2)  # from -pi, heading 0 exactly among them
    sites = [(1.0, 1.2), (1.3, 1.5), (0.9, 0.9), (2.0, 1.0), (1.5, 2.45), (0.7, 0.5)]
    sites.append((2.2, 1.5))  # an arc blocked between two free headings
    sites.append((1.5, 2.75))  # heading 0: its long side touches the top bound (y = 3) exactly
    seen, blocked_between = [], 0
    for x, y in sites:
        ok, arcs = _ring_free(geo, x, y, grid, step)
        want_ok = np.array([geo.clearance1([x, y, h]) >= 0 for h in grid])
        want_arcs = np.array([want_ok[i] and want_ok[(i + 1) % n] and turn_free(geo, x, y, grid[i], grid[(i + 1) % n] - grid[i]
                              if i + 1 < n else grid[0] + 2 * math.pi - grid[i], swept=False) for i in range(n)])  # fmt: skip
        np.testing.assert_array_equal(ok, want_ok)
        np.testing.assert_array_equal(arcs, want_arcs)
        blocked_between += int(np.sum(want_ok & np.roll(want_ok, -1) & ~want_arcs))
        seen.append((want_ok.mean(), geo.clearance1([x, y, 0.0])))
    assert blocked_between  # the post's arc: two free headings, the turn between them not
    assert any(0 < f < 1 for f, _ in seen)  # some rings are partly blocked
    assert seen[-1][1] == 0.0  # the touching heading


@pytest.mark.parametrize(
    "robot, start, goal",
    [
        ({"disc": 0.25}, [0.25, 0.25, 0.5 * math.pi], [3.0, 2.0, 0.0]),  # in the corner, touching two sides
        ({"box": [0.5, 0.25]}, [0.25, 1.5, 0.0], [3.0, 1.5, 0.0]),  # its back against the left side
    ],
)
def test_a_start_touching_the_bounds_drives_off(robot, start, goal):
    """Touching is allowed: a robot parked against the bounds (clearance exactly 0) drives
    away from them. A motion that holds its heading meets the bounds exactly at its ends,
    so only the obstacles are traced (before: no_path, no motion from clearance 0 could be
    certified)."""
    sc = parse_scene(doc(dict(robot, vmax=1.0, kinematics="unicycle")))
    planner = Planner(sc, _far_roadmap(sc))
    assert planner.geometry.clearance1(start if "box" in robot else start[:2]) == 0.0
    res = planner.plan(start, goal, 0.0, PlanOptions(dt=0.1))
    assert res.solved, res.message
    rep = check_trajectory(sc, res.trajectory.waypoints)
    assert rep.valid, rep.reason


@pytest.mark.parametrize("robot", [{"disc": 0.2}, {"box": [0.5, 0.25]}])
def test_a_query_whose_start_is_its_goal_stays(robot):
    """Start = goal: one step's stay, as a holonomic robot's answer (before: a turn of 0 was no
    piece of the graph, and the search drove out to the roadmap and back round a loop; 2.80 s
    on tb3-arena-unicycle, 8.61 s for a T footprint on the same map; here no_path or a drive
    to the far vertices and back)."""
    sc = parse_scene(doc(dict(robot, vmax=1.0, kinematics="unicycle")))
    pose = [2.0, 2.0, 0.3]
    res = Planner(sc, _far_roadmap(sc)).plan(pose, pose, 0.0, PlanOptions(dt=0.1))
    assert res.solved, res.message
    w = res.trajectory.waypoints
    assert res.trajectory.duration <= 0.1 + 1e-9 and np.allclose(w[:, 1:], pose), w
    assert check_trajectory(sc, w).valid


def test_check_decides_a_disc_turning_in_place_against_a_wall(disc_scene):
    """A disc touching the bounds while it turns in place keeps its clearance of 0 the
    whole turn: its body does not move, so the check decides it (before: 'could not
    decide: too many evaluations', bisecting at the turn's configuration speed)."""
    w = rows([0, 0.2, 0.2, 0.0], [2, 0.2, 0.2, 1.0], [3, 0.2 + 0.5 * math.cos(1.0), 0.2 + 0.5 * math.sin(1.0), 1.0])
    rep = check_trajectory(disc_scene, w)
    assert rep.valid, rep.reason
    assert rep.min_clearance == 0.0
    out = rows([0, 0.2, 0.2, 0.0], [2, 0.2, 0.2, math.pi], [3, 0.1, 0.2, math.pi])  # then into the wall: caught
    rep = check_trajectory(disc_scene, out)
    assert not rep.valid and rep.time == pytest.approx(2.0, abs=1e-3), rep.reason


@pytest.mark.parametrize(
    "reverse, start, goal",
    [
        (True, [4.6, 1.5, 0.0], [1.0, 1.0, math.pi]),  # nose against the right side: back away
        (False, [1.0, 1.0, math.pi], [4.6, 2.0, 0.0]),  # park nose against it
    ],
)
def test_an_end_that_cannot_turn_joins_along_its_heading(reverse, start, goal):
    """A box parked nose to the bounds cannot turn there (its front corners would swing out):
    it leaves backwards, or arrives forwards, along its own heading. The roadmap has no
    vertex on that line; the end joins through points on it from which the robot turns
    (before: no_path). Without reverse the first one has no way out (checked by hand: it can
    neither turn nor back up), which stays no_path."""
    robot = {"box": [0.8, 0.5], "vmax": 1.0, "kinematics": "unicycle", "reverse": reverse}
    sc = parse_scene(doc(robot, bounds=(0, 0, 5, 3)))
    verts = np.array([[2.0, 2.3], [1.5, 0.5], [3.5, 0.6]])
    rm = Roadmap(verts, np.array([[0, 1], [1, 2], [0, 2]]), np.hypot(*(verts[[1, 2, 2]] - verts[[0, 1, 0]]).T),
                 sc.name, sc.static_hash, sc.robot.circumradius)  # fmt: skip
    planner = Planner(sc, rm)
    res = planner.plan(start, goal, 0.0, PlanOptions(dt=0.1))
    assert res.solved, res.message
    rep = check_trajectory(sc, res.trajectory.waypoints)
    assert rep.valid, rep.reason
    if reverse:
        fwd = parse_scene(doc(dict(robot, reverse=False), bounds=(0, 0, 5, 3)))
        assert Planner(fwd, rm).plan(start, goal, 0.0, PlanOptions(dt=0.1)).status.value == "no_path"


def test_a_pose_out_of_bounds_says_by_how_much():
    """A cart meant to touch the top of the bounds (y 5.4 + half-length 0.6 = 6 on paper)
    lies 3e-16 m beyond it in floating point: a rounding, so it touches (as the check says;
    it was 'out of bounds (by 3.33e-16 m)'). A micrometre beyond is out: invalid_query,
    'out of bounds' and by how much (before: 'collides with a static obstacle', in a scene
    without one)."""
    sc = parse_scene(doc({"box": [1.2, 0.3], "vmax": 1.0, "kinematics": "unicycle"}, bounds=(0, 0, 6, 6)))
    planner = Planner(sc, _far_roadmap(sc))
    assert query_problem(planner.geometry, [5.3, 5.4, 0.5 * math.pi], [3.0, 3.0, 0.0]) == ""
    res = planner.plan([5.3, 5.400001, 0.5 * math.pi], [3.0, 3.0, 0.0], 0.0)
    assert res.status.value == "invalid_query"
    assert "start [5.3, 5.400001, 1.5707963267948966] is out of bounds (by 1e-06 m)" in res.message, res.message
    walled = parse_scene(doc({"box": [1.2, 0.3], "vmax": 1.0}, obstacles=[{"disc": {"center": [2.0, 2.0], "radius": 0.5}}]))
    res = Planner(walled, _far_roadmap(walled)).plan([2.2, 2.0, 0.0], [1.0, 3.5, 0.0], 0.0)
    assert res.message == "start [2.2, 2.0, 0.0] collides with a static obstacle"  # an obstacle is still named


def test_a_turn_whose_ends_are_inside_the_bounds_but_whose_middle_is_not():
    """Only a motion that holds its heading meets the bounds at its ends alone. A box 0.8 x
    0.5 turning a quarter at (4.55, 1.5) in bounds 5 wide fits at 0 and at pi / 2 and
    swings a corner 0.02 m out at pi / 4: the geometry refuses that turn, the planner finds
    no way (it can neither turn there nor back up) and the check refuses it, for a unicycle
    and for a holonomic box alike."""
    for kin in ("unicycle", "holonomic"):
        sc = parse_scene(doc({"box": [0.8, 0.5], "vmax": 1.0, "kinematics": kin}, bounds=(0, 0, 5, 3)))
        planner = Planner(sc, _far_roadmap(sc))
        geo = planner.geometry
        a, b = [4.55, 1.5, 0.0], [4.55, 1.5, 0.5 * math.pi]
        assert geo.clearance1(a) > 0 and geo.clearance1(b) > 0 and geo.clearance1([4.55, 1.5, 0.25 * math.pi]) < 0
        assert not geo.motion_free(a, b)
        rep = check_trajectory(sc, rows([0.0, *a], [1.0, *a], [3.0, *b]))
        assert not rep.valid and "bounds" in rep.reason, rep.reason
    uni = parse_scene(doc({"box": [0.8, 0.5], "vmax": 1.0, "kinematics": "unicycle"}, bounds=(0, 0, 5, 3)))
    res = Planner(uni, _far_roadmap(uni)).plan(a, [1.0, 1.0, math.pi], 0.0, PlanOptions(dt=0.1))
    assert res.status.value == "no_path", res.message


def test_an_end_joined_along_its_heading_is_certified_against_walls():
    """The points on a pose's own heading line that join it to the roadmap are reached by
    certified motions: a box with its nose against a 2 cm wall (it can neither turn nor
    back up) gets no way through the wall."""
    robot = {"box": [0.8, 0.5], "vmax": 1.0, "kinematics": "unicycle"}
    sc = parse_scene(doc(robot, obstacles=[{"box": {"center": [3.0, 2.5], "size": [0.02, 5.0]}}], bounds=(0, 0, 6, 6)))
    res = Planner(sc, _far_roadmap(sc, pts=((5.0, 1.0), (5.5, 2.0)))).plan([2.59, 1.0, 0.0], [5.0, 1.0, 0.0], 0.0,
                                                                        PlanOptions(dt=0.1))  # fmt: skip
    if res.solved:  # never, by hand; were it, it must pass the check
        rep = check_trajectory(sc, res.trajectory.waypoints)
        assert rep.valid, rep.reason
    assert res.status.value == "no_path", res.message


def test_the_nearest_points_are_the_same_by_blocks_and_by_a_tree(monkeypatch):
    """Many points (a large roadmap) ask a k-d tree instead of the blocks, whose time grows
    with the square of the points (20,000: 15 s); the neighbours are the same, duplicates
    included, and never the point itself."""
    from gfuzzy.timespace import unilanes

    rng = np.random.default_rng(4)
    xy = np.vstack([rng.uniform(0, 20, (400, 2)), np.full((3, 2), 5.0)])  # three points at one place
    monkeypatch.setattr(unilanes, "KDTREE_FROM", 10**9)
    blocks = unilanes._nearest(xy, 6, rows=64)
    monkeypatch.setattr(unilanes, "KDTREE_FROM", 0)
    tree = unilanes._nearest(xy, 6)
    assert tree.shape == blocks.shape and not (tree == np.arange(len(xy))[:, None]).any()
    d = lambda idx: np.sort(np.hypot(*(xy[idx] - xy[:, None, :]).transpose(2, 0, 1)), axis=1)  # noqa: E731
    np.testing.assert_allclose(d(tree), d(blocks))  # the same distances (ties may pick others)


@pytest.mark.parametrize("spacing, count", [(0.7e-9, 3), (0.35e-9, 5)])
def test_a_lane_joins_copies_whose_headings_the_check_calls_the_same(spacing, count):
    """Lanes into one vertex at headings ``spacing`` rad apart (nearly collinear vertices, as
    a roadmap's passage chains make): the copies they share are measured from their group's
    first heading. Before, each was merged with the previous one, so a chain of three shared
    a copy 1.4e-9 from the third lane's heading, and an answer driving that lane turned while
    moving (``gfuzzy check``: "turns while moving" on two unseen scenes' answers); five
    lanes 0.35e-9 apart (each within the merge tolerance of the previous) did the same."""
    from gfuzzy.timespace.drive import SAME_HEADING
    from gfuzzy.timespace.unicycle import _base

    robot = {"box": [0.6, 0.4], "vmax": 1.0, "kinematics": "unicycle"}
    sc = parse_scene(doc(robot))
    verts = np.array([[2.0 - i * spacing, 1.0] for i in range(count)] + [[2.0, 2.0], [2.0, 3.0]])
    edges = np.array([[i, count] for i in range(count)] + [[count, count + 1]])
    rm = Roadmap(verts, edges, np.hypot(*(verts[edges[:, 1]] - verts[edges[:, 0]]).T), sc.name, sc.static_hash,
                 sc.robot.circumradius)  # fmt: skip
    planner = Planner(sc, rm)
    base = _base(rm, planner.geometry, 1.0, 1.0, 0.07)
    lane = (base.dh == 0.0) & (base.a >= 0) & (base.b >= 0)
    assert lane.sum() >= 4
    gap = np.abs(np.angle(np.exp(1j * (base.poses[base.a[lane], 2] - base.poses[base.b[lane], 2]))))
    assert gap.max() <= SAME_HEADING, gap.max()
    for a in range(count):  # drive each lane in, then on north
        res = planner.plan([*verts[a], math.pi / 2], [2.0, 3.5, math.pi / 2], 0.0, PlanOptions())
        assert res.solved, res.message
        rep = check_trajectory(sc, res.trajectory.waypoints)
        assert rep.valid, rep.reason


LFOOT = [[0.5, -0.2], [0.5, 0.2], [0.1, 0.2], [0.1, 0.5], [-0.2, 0.5], [-0.2, -0.2]]


def _lfoot_scene():
    """The unseen scene ``lfoot``: an L footprint, two rooms joined by a 0.75 door in a 0.3
    wall, a disc, and an L obstacle in the east room."""
    robot = {"footprint": LFOOT, "vmax": 0.8, "kinematics": "unicycle", "wmax": 1.0}
    walls = [{"box": {"center": [3.5, 0.8], "size": [0.3, 1.6]}}, {"box": {"center": [3.5, 3.175], "size": [0.3, 1.65]}},
             {"disc": {"center": [1.5, 2.8], "radius": 0.4}},
             {"polygon": [[5, 1], [6, 1], [6, 1.3], [5.3, 1.3], [5.3, 2.2], [5, 2.2]]}]  # fmt: skip
    return parse_scene(doc(robot, obstacles=walls, bounds=(0, 0, 7, 4)))


@pytest.fixture(scope="module")
def lfoot_roadmap():
    """``lfoot_roadmap(seed)``: the scene ``lfoot`` and its roadmap of that seed, built once
    for the module (the door and the corner tests plan on the same one: 6 s each)."""
    from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap

    built = {}

    def get(seed):
        if seed not in built:
            sc = _lfoot_scene()
            built[seed] = sc, build_roadmap(sc, RoadmapOptions(seed=seed))
        return built[seed]

    return get


@pytest.mark.parametrize("seed", [1, pytest.param(2, marks=pytest.mark.slow)])  # roadmap seed 2: `make slow`
def test_an_l_footprint_drives_through_a_door_with_2_5_cm_per_side(seed, lfoot_roadmap):
    """An L footprint (an arm on its left) as a differential drive without reverse, through
    a 0.75 door in a 0.3 wall (2.5 cm per side when it crosses square to the wall): it needs
    lanes on the door's middle line *facing east*, reaching places beyond the wall where it
    turns round. The roadmap's chains cross the door both ways for a footprint that is not
    the same body turned by pi (``gfuzzy.roadmap.passage.Chains``); before, the door was
    missed on seeds 1 and 2 (the unseen scene ``lfoot``, issue 18's review)."""
    sc, rm = lfoot_roadmap(seed)
    res = Planner(sc, rm).plan([1.0, 1.0, 0.0], [5.5, 3.0, math.pi], 0.0, PlanOptions())
    assert res.solved, res.message
    rep = check_trajectory(sc, res.trajectory.waypoints)
    assert rep.valid, rep.reason


@pytest.mark.parametrize("seed", [1, pytest.param(2, marks=pytest.mark.slow)])  # roadmap seed 2: `make slow`
def test_an_l_footprint_works_its_arm_into_an_l_obstacles_corner(seed, lfoot_roadmap):
    """The L footprint parked in the inner corner of the L obstacle, its arm 5 cm from the
    obstacle's upright, heading north: it arrives heading about 318 degrees and turns 132
    degrees in place, nearly all of the 136.6 its walls leave it there (an independent
    brute force found that way; a witness passes ``gfuzzy check``). The goal's tilts took
    3/4 of the free turn and never reached that heading: ``no_path`` on seeds 1-3 (the
    unseen scene ``lfoot``, query ``into-the-l``); 0.99 of it (``TILT_SHARES``) finds it."""
    sc, rm = lfoot_roadmap(seed)
    res = Planner(sc, rm).plan([1.0, 1.0, 0.0], [5.85, 1.75, math.pi / 2], 0.0, PlanOptions())
    assert res.solved, res.message
    rep = check_trajectory(sc, res.trajectory.waypoints)
    assert rep.valid, rep.reason


@pytest.mark.parametrize(
    "reverse, start, goal",
    [
        (True, [4.0, 3.0, 0.0], [0.42, 0.27, math.pi]),  # park nose into the corner, beside the wall
        (True, [0.42, 0.27, math.pi], [4.0, 3.0, 0.0]),  # and leave it (backwards first)
        (False, [4.0, 1.0, math.pi], [4.73, 3.58, math.pi / 2]),  # park nose up in the other corner
    ],
)
def test_parking_beside_a_wall_with_2_cm_to_spare_tilts_in_small_turns(reverse, start, goal):
    """A 0.8 x 0.5 box parked in a room's corner, 2 cm from both walls: on the line beside
    the wall it can turn by at most 0.05 rad, so it gets there in a chain of small turns
    (coming down at 0.3 rad, then 0.04, then straight: a witness built by hand passes
    ``gfuzzy check``). The end tilts by part of the turn its walls leave it and follows the
    new heading's line (``_Extras.along``); before, only the end's own line was tried and
    all three were no_path (the unseen scene ``corner-park``, issue 18's review)."""
    robot = {"box": [0.8, 0.5], "vmax": 1.0, "kinematics": "unicycle", "reverse": reverse}
    sc = parse_scene(doc(robot, bounds=(0, 0, 5, 4)))
    verts = np.array([[2.0, 2.3], [1.5, 1.0], [3.5, 1.2], [3.8, 2.8]])
    edges = np.array([[0, 1], [1, 2], [0, 2], [2, 3], [0, 3]])
    rm = Roadmap(verts, edges, np.hypot(*(verts[edges[:, 1]] - verts[edges[:, 0]]).T), sc.name, sc.static_hash,
                 sc.robot.circumradius)  # fmt: skip
    res = Planner(sc, rm).plan(start, goal, 0.0, PlanOptions(dt=0.1))
    assert res.solved, res.message
    rep = check_trajectory(sc, res.trajectory.waypoints)
    assert rep.valid, rep.reason


def test_every_move_of_a_query_graph_keeps_its_heading_within_the_checks_tolerance():
    """A start at heading 0 whose lane to a vertex runs at -7e-10 rad, where the vertex's
    copy (from its lane on) is at -1.15e-9: every one-step move of the query's graph that
    changes position keeps its heading within the 1e-9 rad ``gfuzzy check`` allows. Before,
    the start drove that lane without turning (7e-10 counted as no turn) into that copy (its
    heading within 1e-9 of the lane's), 1.15e-9 off its own: two unseen answers (a corridor,
    a dead end, roadmap seed 1) "turned while moving"."""
    from gfuzzy.timespace.unicycle import build_graph

    robot = {"box": [0.6, 0.4], "vmax": 1.0, "kinematics": "unicycle"}
    sc = parse_scene(doc(robot))
    verts = np.array([[2.0, 2.0 - 7e-10], [3.0, 2.0 - 7e-10 - 1.15e-9], [4.0, 2.0]])
    edges = np.array([[0, 1], [1, 2]])
    rm = Roadmap(verts, edges, np.hypot(*(verts[edges[:, 1]] - verts[edges[:, 0]]).T), sc.name, sc.static_hash,
                 sc.robot.circumradius)  # fmt: skip
    planner = Planner(sc, rm)
    g = build_graph(planner, np.array([1.0, 2.0, 0.0]), np.array([5.0, 2.5, 0.5]), 0.07, 1.0).graph
    src = np.repeat(np.arange(len(g.indptr) - 1), np.diff(g.indptr))
    dst = np.asarray(g.neighbors)
    p = np.asarray(g.poses)
    moves = np.hypot(*(p[dst, :2] - p[src, :2]).T) > 1e-9
    dh = np.abs(np.angle(np.exp(1j * (p[dst, 2] - p[src, 2]))))[moves]
    assert moves.sum() > 100
    assert dh.max() <= 1e-9, dh.max()


@pytest.mark.parametrize("kinematics", ["unicycle", "holonomic"])
def test_a_disc_touching_a_wall_by_a_rounding_drives_off(kinematics):
    """A disc of radius 0.2 at x = 1.6 touches a wall whose face is at 1.8 on paper, and lies
    a few 1e-17 m into it in floating point: ``gfuzzy check`` (1e-9 tolerance) accepts the
    pose, so the planner takes it for touching (its distance measured exactly at contact,
    not by FCL's collision test) and drives off it, the motion away measured exactly too.
    Before: ``invalid_query`` ("collides with a static obstacle"; the unseen scene
    ``disc-uturn``). A motion into the wall from there, or a start 1e-6 m into it, is still
    refused."""
    from gfuzzy.collision.geometry import StaticGeometry

    robot = {"disc": 0.2, "vmax": 0.5, "kinematics": kinematics, **({"wmax": 0.3} if kinematics == "unicycle" else {})}
    sc = parse_scene(doc(robot, obstacles=[{"box": {"center": [2.0, 2.5], "size": [0.4, 1.0]}}], bounds=(0, 0, 4, 3)))
    geo = StaticGeometry(sc)
    start, goal = ([1.6, 2.5, math.pi], [0.8, 2.5, math.pi]) if kinematics == "unicycle" else ([1.6, 2.5], [0.8, 2.5])
    verts = np.array([[1.0, 1.0], [3.0, 1.0], [0.5, 2.0]])
    rm = Roadmap(verts, np.array([[0, 1], [0, 2]]), np.hypot(*(verts[[1, 2]] - verts[0]).T), sc.name, sc.static_hash,
                 sc.robot.circumradius)  # fmt: skip
    res = Planner(sc, rm).plan(start, goal, 0.0, PlanOptions())
    assert res.solved, res.message
    rep = check_trajectory(sc, res.trajectory.waypoints)
    assert rep.valid, rep.reason
    assert geo.clearance1([1.6, 2.5]) == 0.0
    assert not geo.motion_free([1.6, 2.5], [1.7, 2.5])  # into the wall
    assert geo.motion_free([1.6, 2.5], [1.6, 2.2])  # along it, touching: allowed
    assert not geo.motion_free([1.6, 2.5], [1.65, 2.2])  # along it, but into it
    deep = Planner(sc, rm).plan([1.600001, 2.5, math.pi] if kinematics == "unicycle" else [1.600001, 2.5], goal)
    assert deep.status.value == "invalid_query"


@pytest.mark.parametrize("kinematics", ["holonomic", "unicycle"])
def test_a_disc_a_little_into_a_polygon_is_not_a_start(kinematics):
    """A disc 3e-9 to 3e-7 m into a polygon's face: FCL's collision test misses such
    penetrations, and the exact measure queried the obstacles with a buffer's polygon (inside
    the segment's round ends: the polygon was not returned, the gap read +1.51 m), so the
    planner certified motions off the start and answered trajectories `gfuzzy check`
    rejects (a reviewer's scene). Measured exactly at contact, the start is refused, and
    every answer from a start within the tolerance passes the check."""
    robot = {"disc": 0.2, "vmax": 0.5, "kinematics": kinematics, **({"wmax": 0.3} if kinematics == "unicycle" else {})}
    poly = [[4.5, 2.5], [5.6, 2.5], [5.6, 3.6], [5.2, 3.6], [5.2, 2.9], [4.5, 2.9]]
    sc = parse_scene(doc(robot, obstacles=[{"polygon": poly}], bounds=(0, 0, 6, 4)))
    verts = np.array([[4.0, 1.0], [2.0, 1.0], [1.0, 3.0]])
    rm = Roadmap(verts, np.array([[0, 1], [1, 2]]), np.hypot(*(verts[[1, 2]] - verts[[0, 1]]).T), sc.name,
                 sc.static_hash, sc.robot.circumradius)  # fmt: skip
    goal = [1.0, 3.0, 0.0] if kinematics == "unicycle" else [1.0, 3.0]
    for depth in (0.0, 0.3e-9, 0.7e-9, 3e-9, 3e-8, 1e-7, 3e-7):  # touching: up to half the check's 1e-9
        s = [5.329434871600707, 2.3 + depth]
        start = [*s, math.atan2(1.0 - s[1], 4.0 - s[0])] if kinematics == "unicycle" else s
        res = Planner(sc, rm).plan(start, goal, 0.0, PlanOptions())
        if depth > 0.5e-9:
            assert res.status.value == "invalid_query", (depth, res.status)
        else:
            assert res.solved, res.message
            assert check_trajectory(sc, res.trajectory.waypoints).valid


def test_the_exact_disc_gap_against_every_obstacle():
    """``_ExactDisc.gap`` of straight motions near a polygon's faces and corners against the
    distance to every obstacle (no spatial index): the index was asked with the buffer of
    the motion, a polygon inside its round ends, and left out obstacles the disc reaches."""
    import shapely

    from gfuzzy.collision.exact import ExactDisc as _ExactDisc

    poly = [[4.5, 2.5], [5.6, 2.5], [5.6, 3.6], [5.2, 3.6], [5.2, 2.9], [4.5, 2.9]]
    sc = parse_scene(doc({"disc": 0.2, "vmax": 0.5}, obstacles=[{"polygon": poly}, {"box": {"center": [2.0, 2.0], "size": [0.4, 1.0]}}], bounds=(0, 0, 6, 4)))  # fmt: skip
    exact = _ExactDisc(sc)
    shapes = [shapely.Polygon(poly), shapely.box(1.8, 1.5, 2.2, 2.5)]
    rng = np.random.default_rng(5)
    corners = np.array(poly + [[1.8, 1.5], [2.2, 2.5], [1.8, 2.5], [2.2, 1.5]], float)
    starts = []
    for _ in range(200):  # the disc a little into a corner, the motion leaving it
        c = corners[rng.integers(len(corners))]
        u = np.array([math.cos(phi := rng.uniform(-math.pi, math.pi)), math.sin(phi)])
        starts.append((c + u * (0.2 - 10.0 ** rng.uniform(-9, -3.5)), u))
    for _ in range(200):  # a little into the polygon's lower face, leaving it at a slant
        u = np.array([math.cos(phi := rng.uniform(-2.8, -0.35)), math.sin(phi)])
        starts.append((np.array([rng.uniform(4.6, 5.5), 2.3 + 10.0 ** rng.uniform(-9, -4)]), u))
    for a, u in starts:
        b = a + u * rng.uniform(0.0, 2.0) * rng.integers(0, 2)
        seg = shapely.LineString([a, b]) if np.any(a != b) else shapely.Point(a)
        want = min(s.distance(seg) for s in shapes) - 0.2
        assert want < 0.0
        assert exact.gap(a, b) == pytest.approx(want, abs=1e-12), (a, b)


def test_the_fan_turns_where_headings_differ_beyond_the_merge():
    """The navigator's fan (straight moves from the robot, then a turn and a lane to the
    goal) took headings within 1e-9 rad for the same, and a lane on to a goal 1.4e-9 rad off
    its own heading turned while moving by that much (`gfuzzy check` rejects it)."""
    from gfuzzy.timespace.drive import Fan
    from gfuzzy.timespace.unicycle import prepare_goal

    sc = parse_scene(doc({"box": [0.6, 0.4], "vmax": 1.0, "kinematics": "unicycle"}))
    verts = np.array([[5.0, 3.5], [5.5, 3.5]])
    rm = Roadmap(verts, np.array([[0, 1]]), np.array([0.5]), sc.name, sc.static_hash, sc.robot.circumradius)
    pl = Planner(sc, rm)
    kept = prepare_goal(pl, np.array([3.0, 2.0 + 0.7e-9, 1.4e-9]), 0.07, 1.0)
    g = kept.splice(pl, np.array([1.0, 2.0, 0.0]), fan_options=Fan(offsets=(0.0,), distances=(1.0,))).graph
    src = np.repeat(np.arange(len(g.indptr) - 1), np.diff(g.indptr))
    dst, p = np.asarray(g.neighbors), np.asarray(g.poses)
    moves = np.hypot(*(p[dst, :2] - p[src, :2]).T) > 1e-9
    assert moves.sum() > 0
    dh = np.abs(np.angle(np.exp(1j * (p[dst, 2] - p[src, 2]))))[moves]
    assert dh.max() <= 0.5e-9, dh.max()


@pytest.mark.parametrize("robot, tilts", [({"disc": 0.2}, False), ({"box": [0.6, 0.4]}, True)])
def test_a_disc_never_asks_for_tilts(robot, tilts, monkeypatch):
    """A query whose ends are not joined asks again with tilts for a box (or footprint)
    unicycle, never for a disc: a disc turns round wherever it stands, so its goal would
    be prepared a second time for nothing (``Planner.plan``). (A box's lanes prove this
    wall's ends apart before any graph is prepared, ``tests/test_unireach.py``: that proof
    is left out here, so the graph's own way is measured.)"""
    import gfuzzy.timespace.unireach as unireach
    from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap

    wall = {"box": {"center": [3.0, 2.0], "size": [0.4, 4.0]}}  # from bound to bound: sealed off
    sc = parse_scene(doc({**robot, "vmax": 1.0, "kinematics": "unicycle"}, obstacles=[wall]))
    rm = build_roadmap(sc, RoadmapOptions(vertices=60, seed=1))
    asked = []
    prepare = Planner.prepare

    def spy(self, goal, options=None, _tilts=False, **kw):
        asked.append(_tilts)
        return prepare(self, goal, options, _tilts, **kw)

    monkeypatch.setattr(Planner, "prepare", spy)
    monkeypatch.setattr(unireach, "ends_apart", lambda *a, **k: False)
    res = Planner(sc, rm).plan([1.0, 2.0, 0.0], [5.0, 2.0, 0.0], 0.0, PlanOptions())
    assert res.status.value == "no_path"
    assert asked == ([False, True] if tilts else [False])


def test_the_time_limit_bounds_the_lanes_too():
    """``PlanOptions.time_limit`` bounds the whole plan: a box unicycle's lanes and rings,
    built before the search, stop at the deadline and the answer is ``timeout``, never a
    late ``no_path`` (the unseen bent corridor answered ``no_path`` after 68.8 s against a
    limit of 60: its lanes alone took 46 s). Nothing half-built is kept: the next plan
    answers as a fresh one."""
    from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap

    wall = {"box": {"center": [3.0, 2.0], "size": [0.4, 4.0]}}  # sealed off: no_path
    sc = parse_scene(doc({"box": [0.6, 0.4], "vmax": 1.0, "kinematics": "unicycle"}, obstacles=[wall]))
    rm = build_roadmap(sc, RoadmapOptions(vertices=60, seed=1))
    pl = Planner(sc, rm)
    res = pl.plan([1.0, 2.0, 0.0], [5.0, 2.0, 0.0], 0.0, PlanOptions(time_limit=1e-6))
    assert res.status.value == "timeout", res.status
    assert "time_limit" in res.message
    assert not any(k[0].startswith("unicycle") for k in rm._derived if isinstance(k, tuple))
    res = pl.plan([1.0, 2.0, 0.0], [5.0, 2.0, 0.0], 0.0, PlanOptions())
    assert res.status.value == "no_path"


@pytest.mark.parametrize("backend", ["compiled", "reference"])
def test_a_turn_in_place_is_judged_with_the_body_where_the_disc_is_not_safe(backend):
    """A turn in place was judged against movers with the robot's circumscribed disc: a cart
    whose reference point is at its rear (circumradius 1.07 m) could not turn while a mover
    passed 0.7 m behind it, where its body never goes (the unseen door scene with a mover
    looping over the goal: ``no_path`` within a 600 s horizon, a witness waiting 6 s passes
    ``check``). Where the disc is not safe all through, the turn's points are judged one by
    one with the body: it turns at once, as without the mover."""
    robot = {"footprint": [[-0.05, -0.2], [1.0, -0.2], [1.0, 0.2], [-0.05, 0.2]], "vmax": 0.5,
             "kinematics": "unicycle", "wmax": 0.45}  # fmt: skip
    mover = {"name": "m", "disc": 0.1, "speed": 0.3, "path": [[0.3, 0.8], [0.3, 3.9]], "mode": "once"}
    start, goal = [1.0, 2.0, 0.0], [1.0, 2.0, 0.5 * math.pi]
    answers = []
    for movers in ([], [mover]):
        sc = parse_scene(doc(robot, movers=movers))
        res = Planner(sc, _far_roadmap(sc)).plan(start, goal, 0.0, PlanOptions(backend=backend))
        assert res.solved, res.message
        rep = check_trajectory(sc, res.trajectory.waypoints)
        assert rep.valid, rep.reason
        answers.append(res.duration)
    assert answers[1] == pytest.approx(answers[0], abs=1e-9)


def _turn_scene(seed):
    """A random off-centre footprint (rectangle or L) turning in place at (3, 2) among 1-3
    movers that pass near it (a reviewer's brute force of turns judged with the body)."""
    rng = np.random.default_rng(seed)
    length, width, back = rng.uniform(0.6, 1.3), rng.uniform(0.2, 0.5), rng.uniform(-0.1, 0.2)
    if rng.random() < 0.5:
        fp = [[-back, -width / 2], [length, -width / 2], [length, width / 2], [-back, width / 2]]
    else:
        fp = [[-back, -width / 2], [length, -width / 2], [length, width / 2], [length / 2, width / 2],
              [length / 2, 1.5 * width], [-back, 1.5 * width]]  # fmt: skip
    robot = {"footprint": fp, "vmax": float(rng.choice([0.3, 0.5])), "kinematics": "unicycle", "wmax": float(rng.choice([3.0, 1.0]))}
    if rng.random() < 0.3:
        robot["reverse"] = True
    c, movers = np.array([3.0, 2.0]), []
    for k in range(rng.integers(1, 4)):
        ang, off = rng.uniform(0, 2 * math.pi), rng.uniform(0.2, 1.4)
        p0 = c + rng.uniform(-2, 2, 2)
        p1 = c + off * np.array([math.cos(ang), math.sin(ang)]) + rng.uniform(-0.3, 0.3, 2)
        path = [p0.tolist(), p1.tolist(), (2 * p1 - p0).tolist()]
        mode = str(rng.choice(["loop", "bounce", "once"]))
        m = {"name": f"m{k}", "speed": float(rng.uniform(0.1, 0.8)), "mode": mode, "offset": float(rng.uniform(0, 5)),
             "path": path + [path[0]] if mode == "loop" else path}  # fmt: skip
        if rng.random() < 0.5:
            m["disc"] = float(rng.uniform(0.05, 0.3))
        else:
            m["box"] = [float(rng.uniform(0.1, 0.5)), float(rng.uniform(0.1, 0.5))]
        movers.append(m)
    h0 = rng.uniform(-math.pi, math.pi)
    h1 = math.remainder(h0 + rng.uniform(-math.pi, math.pi), 2 * math.pi)
    return parse_scene(doc(robot, movers)), [3.0, 2.0, h0], [3.0, 2.0, h1], float(rng.choice([0.1, 0.2, 0.25]))


@pytest.mark.parametrize("backend", ["compiled", "reference"])
def test_turns_in_place_among_movers_judged_with_the_body_pass_the_check(backend):
    """Turn points re-judged with the body at their own heading where the circumscribed
    disc is not safe: every answer passes the check. Judging them at heading 0 or at the
    turn's first heading gave answers the check rejects on these seeds (108, 140, 141,
    147, 285, 293 of a brute force over 500)."""
    solved = 0
    for seed in (108, 140, 141, 147, 285, 293):
        scene, start, goal, dt = _turn_scene(seed)
        res = Planner(scene, _far_roadmap(scene)).plan(start, goal, 0.0, PlanOptions(backend=backend, dt=dt, time_limit=20))
        if res.solved:
            solved += 1
            rep = check_trajectory(scene, res.trajectory.waypoints)
            assert rep.valid, (seed, rep.reason)
    assert solved >= 2, solved  # (the others: no_path, the movers leave no turn)


def test_an_answer_found_after_the_time_limit_is_a_timeout(monkeypatch):
    """A search that ends after ``time_limit`` (here made to sleep 0.3 s against 0.2 s) does
    not answer ``solved``: ``timeout``, said as such."""
    import time

    from gfuzzy.planner import planner as planner_module

    sc = parse_scene(doc({"box": [0.6, 0.4], "vmax": 1.0, "kinematics": "unicycle"}))
    pl = Planner(sc, _far_roadmap(sc))
    assert pl.plan([1.0, 2.0, 0.0], [1.0, 2.0, 1.0], 0.0, PlanOptions(time_limit=5)).solved
    search = planner_module.Planner._search_rounds

    def slow(self, *args, **kwargs):
        out = search(self, *args, **kwargs)
        time.sleep(0.3)
        return out

    monkeypatch.setattr(planner_module.Planner, "_search_rounds", slow)
    res = pl.plan([1.0, 2.0, 0.0], [1.0, 2.0, 1.0], 0.0, PlanOptions(time_limit=0.2))
    assert res.status.value == "timeout", res.message


def test_a_disc_drives_ends_join_on_the_vertex_clearances_every_query_shares(monkeypatch):
    # the drive kept a second, lazily filled table of its vertices' clearances beside the
    # roadmap's (roadgraph.vertex_clearances, which its lanes fill): one table now
    from pathlib import Path

    import gfuzzy.timespace.unicycle as uni
    import gfuzzy.timespace.uniends as ends
    from gfuzzy.roadmap.roadmap import load_roadmap
    from gfuzzy.scene.scene import load_scene
    from gfuzzy.timespace.roadgraph import vertex_clearances

    root = Path(__file__).resolve().parent.parent
    scene = load_scene(root / "scenes" / "tb3-arena-unicycle.yaml")
    roadmap = load_roadmap(root / "roadmaps" / "tb3-arena-unicycle.json", scene)
    planner = Planner(scene, roadmap)
    first, second = scene.queries[:2]
    assert planner.plan(first.start, first.goal, first.t0).status.value == "solved"
    table = vertex_clearances(roadmap, planner.geometry)
    base = next(v for k, v in roadmap._derived.items() if k[0] == "unicycle-base")
    assert base.clearance is table and not np.isnan(table).any()
    table -= 1e-3  # marked: what the joins read must be these
    seen = []
    real = uni._drive

    def drive(geo, robot, ax, ay, bx, by, back, ca=None, cb=None):
        seen.extend([((ax, ay), ca), ((bx, by), cb)])
        return real(geo, robot, ax, ay, bx, by, back, ca, cb)

    monkeypatch.setattr(uni, "_drive", drive)
    monkeypatch.setattr(ends, "_drive", drive)  # the ends' joins (uniends) drive too
    planner.plan(second.start, second.goal, second.t0)
    at = {(float(x), float(y)): i for i, (x, y) in enumerate(roadmap.vertices[:, :2])}
    read = [(at[xy], c) for xy, c in seen if xy in at]
    assert read and all(c == table[i] for i, c in read)
