"""The component join of a box or footprint robot's roadmap (gfuzzy.roadmap.join).

A PRM of a box robot can come out in pieces although the robot fits between them (a door
with 3 cm per side). The join adds certified vertices and edges between the pieces within a
budget of collision checks; in a sealed room it gives up within that budget. The oracle of the
added edges is written here: the box's rectangle at fine steps along each edge, against the
walls' rectangles with shapely, and the independent checker (gfuzzy.check.check).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import shapely
import yaml
from helpers import run_main
from shapely import affinity

from gfuzzy.check.check import check_trajectory
from gfuzzy.collision.geometry import StaticGeometry
from gfuzzy.planner.planner import Planner, PlanOptions
from gfuzzy.roadmap.join import (
    CHECKS_PER_VERTEX,
    CLOSEST_PAIRS,
    PIECE_CHECKS_PER_VERTEX,
    door_headings,
    join_components,
)
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap, load_roadmap, roadmap_digest
from gfuzzy.scene import load_scene
from gfuzzy.scene.scene import parse_scene

BOX = (0.8, 0.4)


def _wall(cx, cy, w, h) -> dict:
    return {"box": {"center": [cx, cy], "size": [w, h], "angle": 0.0}}


def door_doc(door: float = 0.46) -> dict:
    """A 6 x 4 floor split by a wall at x = 3 with a door ``door`` wide (the box: 0.4)."""
    y0 = 2.0 - door / 2
    walls = [_wall(3.0, y0 / 2, 0.1, y0), _wall(3.0, 4 - y0 / 2, 0.1, y0)]
    return {
        "version": 1,
        "name": "box-door",
        "bounds": [0, 0, 6, 4],
        "robot": {"box": list(BOX), "vmax": 1.0},
        "obstacles": walls,
    }


def sealed_doc() -> dict:
    """The door closed: a room 2 x 2 inside the floor with no way in."""
    doc = door_doc()
    doc["name"] = "box-sealed"
    doc["obstacles"] = [
        _wall(4.0, 1.0, 2.1, 0.1),
        _wall(4.0, 3.0, 2.1, 0.1),
        _wall(3.0, 2.0, 0.1, 2.1),
        _wall(5.0, 2.0, 0.1, 2.1),
    ]
    return doc


def _walls(doc) -> list:
    out = []
    for ob in doc["obstacles"]:
        (cx, cy), (w, h) = ob["box"]["center"], ob["box"]["size"]
        out.append(shapely.box(cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2))
    return out


def _body(pose) -> shapely.Polygon:
    w, h = BOX
    body = shapely.box(-w / 2, -h / 2, w / 2, h / 2)
    return affinity.translate(affinity.rotate(body, pose[2], origin=(0, 0), use_radians=True), pose[0], pose[1])


def _free_along(doc, a, b, steps: int = 200) -> bool:
    """The box is inside the bounds and overlaps no wall at ``steps`` poses along a -> b."""
    walls = _walls(doc)
    x0, y0, x1, y1 = doc["bounds"]
    inside = shapely.box(x0, y0, x1, y1).buffer(1e-9)
    turn = math.remainder(b[2] - a[2], 2 * math.pi)
    for f in np.linspace(0.0, 1.0, steps):
        pose = (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * turn)
        body = _body(pose)
        if not inside.contains(body) or any(body.intersection(w).area > 1e-9 for w in walls):
            return False
    return True


def test_join_makes_a_box_roadmap_in_pieces_whole_with_certified_edges():
    """Uniform PRM, 30 vertices, seed 6: two pieces either side of the door; the join
    makes one, and every added edge is free (shapely, the checker)."""
    doc = door_doc()
    scene = parse_scene(doc)
    opts = {"vertices": 30, "seed": 6, "sampler": "uniform"}
    plain = build_roadmap(scene, RoadmapOptions(**opts, join=False))
    rm = build_roadmap(scene, RoadmapOptions(**opts))
    assert plain.info.components == 2 and not plain.info.join and "join" not in plain.info.to_dict()
    assert rm.info.components == 1
    rep = rm.info.join
    assert rep["components_before"] == 2 and rep["components_after"] == 1
    assert rep["added_vertices"] == len(rm) - 30 > 0 and rep["added_edges"] == len(rm.edges) - len(plain.edges)
    assert rep["checks"] <= rep["budget"] == CHECKS_PER_VERTEX * 30
    np.testing.assert_array_equal(rm.vertices[:30], plain.vertices)
    np.testing.assert_array_equal(rm.edges[: len(plain.edges)], plain.edges)
    added = rm.edges[len(plain.edges) :]
    crosses = 0
    for a, b in added:
        pa, pb = rm.vertices[a], rm.vertices[b]
        assert _free_along(doc, pa, pb), (pa, pb)
        rows = np.array([[0.0, *pa], [10.0, *pb]])
        assert check_trajectory(scene, rows).valid
        crosses += (pa[0] - 3.0) * (pb[0] - 3.0) <= 0
    assert crosses >= 1  # the added path goes through the door
    again = build_roadmap(scene, RoadmapOptions(**opts))  # same seed, same roadmap
    assert roadmap_digest(again) == roadmap_digest(rm) and again.info.join["checks"] == rep["checks"]


def test_join_gives_up_in_a_sealed_room_without_a_check():
    """The robot's inscribed disc cannot leave the room: the pieces are proven apart."""
    offset = [[0.1, -0.2], [0.9, -0.2], [0.9, 0.2], [0.1, 0.2]]  # the reference point outside the body
    for robot, n in (({"box": list(BOX), "vmax": 1.0}, 40), ({"box": list(BOX), "vmax": 1.0}, 60), ({"footprint": offset, "vmax": 1.0}, 40)):
        doc = sealed_doc()
        doc["robot"] = robot
        rm = build_roadmap(parse_scene(doc), RoadmapOptions(vertices=n, seed=2))  # seed 2: vertices in and out
        rep = rm.info.join
        assert rm.info.components == rep["components_before"] == rep["components_after"] == 2
        assert rep["components_apart"] == 1 and rep["checks"] == 0 and rep["budget"] == CHECKS_PER_VERTEX * n
        assert rep["added_vertices"] == rep["added_edges"] == 0 and len(rm) == n


def test_join_spends_at_most_its_budget():
    """Seed 1's pieces share the door (not proven apart) and are not joined in 50 checks."""
    scene = parse_scene(door_doc())
    plain = build_roadmap(scene, RoadmapOptions(vertices=30, seed=1, sampler="uniform", join=False))
    j = join_components(StaticGeometry(scene), plain.vertices, plain.edges, seed=1, budget=50)
    assert (j.before, j.after, j.checks, j.budget, j.apart) == (2, 2, 50, 50, 0)
    assert j.added_vertices == j.added_edges == 0 and len(j.edges) == len(plain.edges)


def test_old_files_load_without_the_join_and_the_cli_reports_it(tmp_path, capsys):
    # the command in process: ``gfuzzy roadmap``'s own process is tested in test_scene
    scene = parse_scene(door_doc())
    rm = build_roadmap(scene, RoadmapOptions(vertices=30, seed=6, sampler="uniform"))
    out = tmp_path / "rm.json"
    rm.save(out)
    assert load_roadmap(out, scene).options.join is True
    doc = json.loads(out.read_text())
    del doc["options"]["join"]
    out.write_text(json.dumps(doc))
    assert load_roadmap(out, scene).options.join is False  # as built before the join
    path = tmp_path / "sealed.yaml"
    path.write_text(yaml.safe_dump(sealed_doc()), encoding="utf-8")
    rc, stdout, stderr = run_main(capsys, "roadmap", path, "-n", "40", "--seed", "2", "-o", out)
    assert rc == 0, stderr
    said = "component join: 2 -> 2 component(s), 0 vertices beyond -n 40 (0 of 400 collision checks; "
    assert said + "1 proven apart: the robot's inscribed disc cannot get out; " in stdout
    assert json.loads(out.read_text())["info"]["join"]["components_after"] == 2
    rc, stdout, _ = run_main(capsys, "roadmap", path, "-n", "40", "--seed", "2", "--no-join", "-o", out)
    assert rc == 0 and "component join" not in stdout
    doc = json.loads(out.read_text())
    assert doc["options"]["join"] is False and "join" not in doc["info"]


def test_a_door_is_reached_from_a_node_beside_it_without_going_out_and_back():
    """``_reach`` joins a door pose to a tree node by a turn, a translation onto the door's
    axis and one along it. The pose on the axis was always a span (two circumradii) before
    the door, beyond a node nearer than that: the path went out there and back (unseen room
    seed 1 case 51: an L crossing a door a mover walks through, 2 m longer, missed among
    the mover). It is now abreast of the node when that is certified."""
    from gfuzzy.roadmap.join import _Search, _Tree

    scene = parse_scene(door_doc())
    geometry = StaticGeometry(scene)
    node = np.array([2.4, 1.6, 0.0])  # 0.6 m before the door's middle along its axis, 0.4 m aside
    search = _Search(geometry, node[None, :], np.zeros((0, 2), dtype=np.int64), budget=100, seed=1)
    tree = _Tree(np.array(search.verts), np.array([True]))
    door = np.array([3.0, 2.0, 0.0])
    got = search._reach(tree, door)
    assert got is not None and np.array_equal(tree.poses[got], door)
    path = [np.asarray(p) for p in tree.poses]
    assert min(p[0] for p in path) >= node[0] - 1e-12  # never farther from the door than the node
    assert all(geometry.motion_free(tree.poses[tree.parent[i]], tree.poses[i]) for i in range(1, len(path)))


#: A U opening forward, 0.8 long and 0.9 wide: through a 0.9 door only sideways (5 cm per side).
U = [[0.4, -0.45], [0.4, -0.25], [-0.1, -0.25], [-0.1, 0.25], [0.4, 0.25], [0.4, 0.45], [-0.4, 0.45], [-0.4, -0.45]]


def test_door_headings_narrowest_across_first_and_none_too_wide():
    body = np.array(U)
    wrapped = lambda hs: sorted((round(math.cos(h), 9) + 0.0, round(math.sin(h), 9) + 0.0) for h in hs)  # noqa: E731
    # the door's axis north: along it the U is 0.9 wide (no room in a 0.899 door); sideways 0.8
    assert wrapped(door_headings(body, math.pi / 2, 0.899, 4)) == wrapped([0.0, math.pi])
    wide = door_headings(body, math.pi / 2, 0.95, 4)
    assert wrapped(wide[:2]) == wrapped([0.0, math.pi]) and wrapped(wide[2:]) == wrapped([math.pi / 2, -math.pi / 2])
    drive = door_headings(body, math.pi / 2, 0.95, 4, drive=True)  # a differential drive: along the axis only
    assert wrapped(drive) == wrapped([math.pi / 2, -math.pi / 2])
    assert door_headings(body, math.pi / 2, 0.899, 4, drive=True) == []  # it cannot slide through sideways
    assert door_headings(body, 0.0, 0.8 - 1e-6, 4) == []  # 0.8 wide at best


def test_door_headings_keep_a_body_exactly_as_wide_as_the_door():
    """A body exactly as wide as the door crosses it touching both jambs, which the contract
    allows, and a door's width from its corners' coordinates rounds to either side of the
    body's (jambs at 8.75 + 0.75 and 11.2 - 0.8: 0.8999999999999986 apart). A door as wide
    as the body or a rounding narrower was left out (a U drive through five 0.9 doors);
    one narrower by more than a rounding still is."""
    body = np.array(U)
    along = [(0.0, -1.0), (0.0, 1.0)]
    for gap in (0.9, 0.8999999999999986, 0.9000000000000004):
        hs = door_headings(body, math.pi / 2, gap, 4, drive=True)
        assert sorted((round(math.cos(h), 9) + 0.0, round(math.sin(h), 9) + 0.0) for h in hs) == along, gap
    assert door_headings(body, math.pi / 2, 0.9 - 1e-8, 4, drive=True) == []
    assert door_headings(body, math.pi / 2, 0.9 - 2e-9, 4, drive=True) == []  # 4 x the tolerance (5e-10)


def _plan_and_check(scene, rm, start, goal):
    res = Planner(scene, rm).plan(start, goal, 0.0, PlanOptions())
    assert res.solved, res.message
    rep = check_trajectory(scene, res.trajectory.waypoints)
    assert rep.valid, rep.reason


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_join_takes_a_u_footprint_sideways_through_a_door_with_5_cm_per_side(seed):
    """The U crosses the 0.9 door only sideways (its heading across the door's axis): the
    doors step tried the headings along the axis alone and the join spent its whole budget
    in vain (seeds 1-3: 2 components, no_path; the scene ``rooms-u-holonomic-static``: 5
    rooms left apart). It tries the body's narrowest headings across the door, centred."""
    doc = door_doc(0.9)
    doc["robot"] = {"footprint": U, "vmax": 1.0}
    scene = parse_scene(doc)
    rm = build_roadmap(scene, RoadmapOptions(vertices=60, seed=seed, sampler="uniform"))
    assert rm.info.join["components_before"] == 2 and rm.info.components == 1
    assert rm.info.join["checks"] < rm.info.join["budget"] // 2
    _plan_and_check(scene, rm, [1.0, 1.0, 0.0], [5.0, 3.0, 0.0])


@pytest.mark.parametrize("seed", [1, 3, 4])
def test_join_crosses_a_door_both_ways_for_an_off_centre_differential_drive(seed):
    """A differential drive without reverse whose body is off its reference point (0.5 x
    0.6, its middle 0.2 m to the left) through a 0.7 door (5 cm per side): it drives through
    on the door's middle line for its heading, which is another line facing east than facing
    west. The doors step crossed facing one way only (seeds 1, 3, 4: one component, yet
    no_path eastwards); it adds the crossing facing the other way too."""
    doc = door_doc(0.7)
    doc["robot"] = {"footprint": [[0.4, -0.1], [0.4, 0.5], [-0.1, 0.5], [-0.1, -0.1]], "vmax": 1.0,
                    "kinematics": "unicycle"}  # fmt: skip
    scene = parse_scene(doc)
    rm = build_roadmap(scene, RoadmapOptions(vertices=60, seed=seed, sampler="uniform"))
    assert rm.info.join["components_before"] == 2 and rm.info.components == 1
    _plan_and_check(scene, rm, [1.0, 1.0, 0.0], [5.0, 3.0, 0.0])


def test_join_takes_a_differential_drive_through_a_door_along_its_heading_only():
    """An L differential drive (with reverse) through a door 0.65 m wide in a wall 0.2 m
    thick. The doors step tried it sideways too, on the door between the thick wall's
    diagonal corners: a slide it cannot drive, counted as the join, so the doors after it
    were not tried (1 component, every query no_path; a reviewer's case, -n 60 seed 4).
    Along its heading it crosses, and every query is solved and checked."""
    doc = door_doc(0.6517)
    doc["obstacles"] = [_wall(3.0, -1.32585, 0.199, 6.0), _wall(3.0, 5.32585, 0.199, 6.0)]
    doc["robot"] = {"footprint": [[0.3, -0.2], [0.3, 0.0], [0.0, 0.0], [0.0, 0.4], [-0.2, 0.4], [-0.2, -0.2]],
                    "vmax": 1.0, "kinematics": "unicycle", "reverse": True}  # fmt: skip
    scene = parse_scene(doc)
    rm = build_roadmap(scene, RoadmapOptions(vertices=60, seed=4, sampler="uniform"))
    assert rm.info.join["components_before"] == 2 and rm.info.components == 1
    heading = rm.vertices[60:, 2]
    assert np.allclose(np.abs(np.cos(heading)), 1.0), heading  # every pose the join added faces along the axis
    for start, goal in (([1, 1, 0], [5, 3, 0]), ([5, 3, 0], [1, 1, 0]), ([1.2, 3, 0], [4.8, 1, 0])):
        _plan_and_check(scene, rm, start, goal)


@pytest.mark.parametrize("seed", [1])  # (seeds 2 and 3 failed on the same old code as 1: 3 s each)
def test_join_takes_a_differential_drive_exactly_as_wide_as_the_door_through_it(seed):
    """The U as a differential drive through a 0.9 door: 0.9 wide across its heading, it
    crosses only centred and along the door's axis, touching both jambs. The doors step left
    the heading out (not narrower than the door) and FCL's collision test, which calls
    contact a collision, refused the pose in the door (2 components, no_path). The pose in
    the door is measured exactly at contact, as ``gfuzzy check`` measures it."""
    doc = door_doc(0.9)
    doc["robot"] = {"footprint": U, "vmax": 1.0, "kinematics": "unicycle"}
    scene = parse_scene(doc)
    rm = build_roadmap(scene, RoadmapOptions(vertices=60, seed=seed, sampler="uniform"))
    assert rm.info.join["components_before"] == 2 and rm.info.components == 1
    geometry = StaticGeometry(scene)
    assert any(abs(v[0] - 3.0) < 0.4 and geometry.clearance1(v) == 0.0 for v in rm.vertices[60:])  # in the door
    _plan_and_check(scene, rm, [1.0, 1.0, 0.0], [5.0, 3.0, 0.0])
    _plan_and_check(scene, rm, [5.0, 3.0, 0.0], [1.0, 1.0, 0.0])


def test_join_takes_only_a_pose_touching_the_jambs_and_only_as_the_last_leg():
    """The U drive in the 0.9 door, centred along the axis, touches both jambs (clearance
    exactly 0; FCL's collision test calls it a collision): ``valid_touching`` takes it, but
    not the pose 1e-6 m into a jamb, and a path of legs takes it only as its last pose (the
    door pose itself), not as a pose it goes on from."""
    from gfuzzy.roadmap.join import _Search

    doc = door_doc(0.9)
    doc["robot"] = {"footprint": U, "vmax": 1.0, "kinematics": "unicycle"}
    geometry = StaticGeometry(parse_scene(doc))
    search = _Search(geometry, np.array([[1.0, 1.0, 0.0], [5.0, 3.0, 0.0]]), np.zeros((0, 2), dtype=int), 100, 1)
    door, into = np.array([3.0, 2.0, 0.0]), np.array([3.0, 2.0 + 1e-6, 0.0])
    assert geometry.clearance1(door) == 0.0 and not search.valid(door) and search.valid_touching(door)
    assert geometry.clearance1(into) < 0.0 and not search.valid_touching(into)
    before, after = np.array([2.0, 2.0, 0.0]), np.array([4.0, 2.0, 0.0])
    legs = search._legs(before, [door])
    assert legs is not None and np.array_equal(legs[-1], door)
    assert search._legs(before, [door, after]) is None


def rotated_door_doc(body: dict, width: float, angle: float) -> dict:
    """A 10 x 10 floor split through its middle by a wall 0.1 thick whose normal (the door's
    axis) is at ``angle``, with a door ``width`` wide in the middle; ``body`` a drive's shape."""
    u = np.array([-math.sin(angle), math.cos(angle)])  # along the wall
    walls = [{"box": {"center": (5.0 + s * u * (width / 2 + 6.0)).tolist(), "size": [12.0, 0.1],
                      "angle": angle + math.pi / 2}} for s in (-1, 1)]  # fmt: skip
    robot = {**body, "vmax": 1.0, "kinematics": "unicycle"}
    return {"version": 1, "name": "rotated-door", "bounds": [0, 0, 10, 10], "robot": robot, "obstacles": walls}


@pytest.mark.parametrize(
    "body, width",
    [({"box": [0.8, 0.5]}, 0.5), ({"footprint": [[0.4, -0.1], [0.4, 0.5], [-0.1, 0.5], [-0.1, -0.1]]}, 0.6)],
    ids=["box", "off-centre"],
)
def test_join_takes_a_drive_exactly_as_wide_as_a_rotated_door_through_it(body, width):
    """A box and an off-centre footprint, each exactly as wide as a door whose axis is at
    0.5 rad (its corners' coordinates rounded by the rotation): joined and driven through
    both ways, checked."""
    angle = 0.5
    scene = parse_scene(rotated_door_doc(body, width, angle))
    rm = build_roadmap(scene, RoadmapOptions(vertices=60, seed=1, sampler="uniform"))
    assert rm.info.join["components_before"] == 2 and rm.info.components == 1
    n, u = np.array([math.cos(angle), math.sin(angle)]), np.array([-math.sin(angle), math.cos(angle)])
    a, b = 5.0 - 2.5 * n + u, 5.0 + 2.5 * n - u
    _plan_and_check(scene, rm, [*a, angle], [*b, angle])
    _plan_and_check(scene, rm, [*b, angle], [*a, angle])


def cage_doc() -> dict:
    """The floor without its wall, and a cage 0.9 x 0.5 inside with a 0.45 gap in its top and
    bottom sides: the box (0.8 x 0.4) inside cannot turn by more than 0.12 rad nor pass a
    gap, but its inscribed disc (0.4 across) can: the cage is not proven apart."""
    doc = door_doc()
    doc["name"] = "box-cage"
    side = [_wall(4.0 + 0.275 / 2, y, 0.275, 0.05) for y in (1.725, 2.275)]
    side += [_wall(5.0 - 0.275 / 2, y, 0.275, 0.05) for y in (1.725, 2.275)]
    doc["obstacles"] = [_wall(4.025, 2.0, 0.05, 0.6), _wall(4.975, 2.0, 0.05, 0.6), *side]
    return doc


def test_join_gives_a_stray_vertex_in_a_cage_a_small_share_of_the_budget():
    """A vertex in the cage (as PRM leaves one among a table's legs: small-house, -n 600,
    seed 1, where the join spent 5929 of its 6000 checks on one) gets its closest pairs and
    ``PIECE_CHECKS_PER_VERTEX`` checks, not the whole budget."""
    scene = parse_scene(cage_doc())
    plain = build_roadmap(scene, RoadmapOptions(vertices=60, seed=1, sampler="uniform", join=False))
    assert plain.info.components == 1
    geometry = StaticGeometry(scene)
    stray = np.array([4.5, 2.0, 0.0])
    assert geometry.is_valid(stray)
    vertices = np.vstack([plain.vertices, stray])
    j = join_components(geometry, vertices, plain.edges, seed=1)
    assert (j.before, j.after, j.apart, j.budget) == (2, 2, 0, CHECKS_PER_VERTEX * 61)
    assert j.checks <= 5 * CLOSEST_PAIRS + PIECE_CHECKS_PER_VERTEX < j.budget  # a direct join: 5 checks at most


def map_door_scene(folder):
    """The door scene (0.9 door) as an occupancy map of 5 cm cells, the U as its robot."""
    res, (w, h) = 0.05, (120, 80)
    x = (np.arange(w) + 0.5) * res
    y = (np.arange(h)[::-1] + 0.5) * res  # row 0 is the top
    X, Y = np.meshgrid(x, y)
    wall = (np.abs(X - 3.0) < 0.05) & (np.abs(Y - 2.0) > 0.45)
    img = np.where(wall, 0, 254).astype(np.uint8)
    (folder / "door.pgm").write_bytes(b"P5\n%d %d\n255\n" % (w, h) + img.tobytes())
    meta = {"image": "door.pgm", "resolution": res, "origin": [0.0, 0.0, 0.0], "negate": 0,
            "occupied_thresh": 0.65, "free_thresh": 0.196}  # fmt: skip
    (folder / "door.yaml").write_text(yaml.safe_dump(meta), encoding="utf-8")
    doc = {"version": 1, "name": "map-door", "bounds": [0, 0, 6, 4], "robot": {"footprint": U, "vmax": 1.0},
           "obstacles": [{"map": {"file": "door.yaml"}}]}  # fmt: skip
    (folder / "scene.yaml").write_text(yaml.safe_dump(doc), encoding="utf-8")
    return load_scene(folder / "scene.yaml")


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_join_finds_the_doors_of_a_map(tmp_path, seed):
    """A map has no polygon's corners: the doors step had none to try and the RRT alone did
    not find the U's sideways crossing (seeds 1-3: 2 pieces, the whole budget spent; the
    rooms scene as a map, -n 400: 2-6 pieces left on seeds 1-4). The outer corners of its
    blocked cells are the doors' jambs."""
    scene = map_door_scene(tmp_path)
    rm = build_roadmap(scene, RoadmapOptions(vertices=60, seed=seed, sampler="uniform"))
    assert rm.info.join["components_before"] == 2 and rm.info.components == 1
    _plan_and_check(scene, rm, [1.0, 1.0, 0.0], [5.0, 3.0, 0.0])
