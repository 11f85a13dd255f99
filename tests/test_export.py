"""gfuzzy export: MCAP files read back with the mcap library, Nav2 maps read back and
checked against the obstacles by sampling, the scene JSON Schema (contract section 8)."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import jsonschema
import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader
from test_scene import scene_docs

from gfuzzy.cli import main
from gfuzzy.errors import InputError
from gfuzzy.export.export import ExportOptions, export_mcap
from gfuzzy.export.mapexport import export_nav2_map, rasterise
from gfuzzy.scene.scene import Box, Disc, Polygon, load_scene, parse_scene
from gfuzzy.trajectory import Trajectory

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes"


def read_mcap(path):
    """topic -> list of (log_time, publish_time, decoded message); topic -> (schema name,
    schema encoding, schema dict, message encoding)."""
    msgs: dict = {}
    kinds: dict = {}
    with open(path, "rb") as fh:
        reader = make_reader(fh)
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            msgs.setdefault(channel.topic, []).append((message.log_time, message.publish_time, json.loads(message.data)))
            kinds[channel.topic] = (schema.name, schema.encoding, json.loads(schema.data), channel.message_encoding)
    return msgs, kinds


def expected_times(t0, t1, step):
    """The contract's time steps, computed here on their own: t0 + k step below t1, then t1."""
    out = []
    k = 0
    while t0 + k * step < t1 - 1e-9:
        out.append(t0 + k * step)
        k += 1
    out.append(t1)
    return out


def yaw_of(q):
    assert abs(q["x"]) < 1e-12 and abs(q["y"]) < 1e-12
    assert math.isclose(q["x"] ** 2 + q["y"] ** 2 + q["z"] ** 2 + q["w"] ** 2, 1.0, rel_tol=1e-9)
    return 2.0 * math.atan2(q["z"], q["w"])


def angle_diff(a, b):
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)


def validate_all(msgs, kinds):
    for topic, rows in msgs.items():
        schema = kinds[topic][2]
        jsonschema.Draft7Validator.check_schema(schema)
        validator = jsonschema.Draft7Validator(schema)
        for _, _, msg in rows:
            validator.validate(msg)


# --------------------------------------------------------------------------- MCAP


def _box_rows():
    """A box-robot trajectory with turns, a wait and a non-grid end time."""
    return np.array(
        [
            [0.5, 1.0, 1.0, 0.0],
            [1.7, 2.0, 1.5, 0.6],
            [2.4, 2.0, 1.5, 0.6],  # a wait
            [4.03, 3.5, 3.0, -2.9],  # the shorter arc crosses pi
            [6.111, 6.0, 3.5, 3.0],
        ]
    )


def test_mcap_topics_schemas_counts_times_and_poses(tmp_path):
    scene = load_scene(SCENES / "building-floor.yaml")
    rows = _box_rows()
    out = tmp_path / "plan.mcap"
    report = export_mcap(scene, out, rows, options=ExportOptions(step=0.25))
    msgs, kinds = read_mcap(out)

    assert set(msgs) == {"/scene", "/movers", "/robot", "/path", "/robot_body"}
    want_schema = {
        "/scene": "foxglove.SceneUpdate",
        "/movers": "foxglove.SceneUpdate",
        "/robot": "foxglove.PoseInFrame",
        "/path": "foxglove.PosesInFrame",
        "/robot_body": "foxglove.SceneUpdate",
    }
    for topic, name in want_schema.items():
        assert kinds[topic][0] == name
        assert kinds[topic][1] == "jsonschema"
        assert kinds[topic][3] == "json"
        assert kinds[topic][2]["title"] == name
    times = expected_times(0.5, 6.111, 0.25)
    assert len(msgs["/scene"]) == 1 and len(msgs["/path"]) == 1
    assert len(msgs["/robot"]) == len(msgs["/movers"]) == len(times) == report.counts["/robot"]
    ns = [round(t * 1e9) for t in times]
    assert [m[0] for m in msgs["/robot"]] == ns
    assert [m[0] for m in msgs["/movers"]] == ns
    assert msgs["/scene"][0][0] == ns[0] and msgs["/path"][0][0] == ns[0]
    assert [m[0] for m in msgs["/robot_body"]] == ns

    traj = Trajectory(rows)
    for (log_time, publish_time, msg), t in zip(msgs["/robot"], times, strict=True):
        assert publish_time == log_time
        assert msg["frame_id"] == "map"
        assert msg["timestamp"]["sec"] * 10**9 + msg["timestamp"]["nsec"] == log_time
        want = traj.at(t)
        p = msg["pose"]["position"]
        assert p["x"] == pytest.approx(want[0], abs=1e-12) and p["y"] == pytest.approx(want[1], abs=1e-12)
        assert p["z"] == 0.0
        assert angle_diff(yaw_of(msg["pose"]["orientation"]), want[2]) < 1e-9
    for (_, _, msg), (_, _, body) in zip(msgs["/robot"], msgs["/robot_body"], strict=True):
        (cube,) = body["entities"][0]["cubes"]  # the box robot's body, at the same pose
        assert cube["pose"]["orientation"] == msg["pose"]["orientation"]
        assert (cube["pose"]["position"]["x"], cube["pose"]["position"]["y"]) == (msg["pose"]["position"]["x"], msg["pose"]["position"]["y"])
        assert (cube["size"]["x"], cube["size"]["y"]) == scene.robot.size

    path = msgs["/path"][0][2]
    assert path["frame_id"] == "map" and len(path["poses"]) == len(rows)
    for pose, row in zip(path["poses"], rows, strict=True):
        assert (pose["position"]["x"], pose["position"]["y"]) == (row[1], row[2])
        assert angle_diff(yaw_of(pose["orientation"]), row[3]) < 1e-9
    validate_all(msgs, kinds)


def test_mcap_movers_are_where_the_scene_says(tmp_path):
    """office-polygons: loop, bounce and once movers and a timed one that appears at t=2 and
    leaves at t=16; every /movers message holds exactly the present ones, where they are."""
    scene = load_scene(SCENES / "office-polygons.yaml")
    out = tmp_path / "movers.mcap"
    export_mcap(scene, out, options=ExportOptions(step=0.5, span=20.0))
    msgs, kinds = read_mcap(out)
    assert set(msgs) == {"/scene", "/movers"}  # no trajectory: no robot, no path
    times = expected_times(0.0, 20.0, 0.5)
    assert [m[0] for m in msgs["/movers"]] == [round(t * 1e9) for t in times]
    seen_absent = False
    for (_, _, msg), t in zip(msgs["/movers"], times, strict=True):
        assert [d["type"] for d in msg["deletions"]] == [1]  # each message a whole snapshot
        by_id = {e["id"]: e for e in msg["entities"]}
        present = {}
        for mv in scene.movers:
            xy, here = mv.state(np.array([t]))
            if here[0]:
                present[f"mover-{mv.name}"] = (mv, xy[0])
        seen_absent |= len(present) < len(scene.movers)
        assert set(by_id) == set(present)
        for eid, (mv, xy) in present.items():
            ent = by_id[eid]
            prim = (ent["cylinders"] if mv.shape == "disc" else ent["cubes"])[0]
            assert prim["pose"]["position"]["x"] == pytest.approx(xy[0], abs=1e-12)
            assert prim["pose"]["position"]["y"] == pytest.approx(xy[1], abs=1e-12)
            if mv.shape == "disc":
                assert prim["size"]["x"] == pytest.approx(2 * mv.radius)
    assert seen_absent
    # the static scene: bounds and one entity per obstacle
    scene_msg = msgs["/scene"][0][2]
    ids = [e["id"] for e in scene_msg["entities"]]
    assert ids == ["bounds"] + [f"obstacle-{i}" for i in range(len(scene.obstacles))]
    validate_all(msgs, kinds)


def test_mcap_polygon_prism_covers_the_polygon(tmp_path):
    """A non-convex polygon's top face: its triangles' areas add up to the polygon's."""
    scene = load_scene(SCENES / "office-polygons.yaml")
    out = tmp_path / "s.mcap"
    export_mcap(scene, out, options=ExportOptions(span=1.0, obstacle_height=0.7))
    msgs, _ = read_mcap(out)
    ents = {e["id"]: e for e in msgs["/scene"][0][2]["entities"]}
    checked = 0
    for i, ob in enumerate(scene.obstacles):
        if not isinstance(ob, Polygon):
            continue
        pts = np.array([[p["x"], p["y"], p["z"]] for p in ents[f"obstacle-{i}"]["triangles"][0]["points"]]).reshape(-1, 3, 3)
        top = pts[np.all(pts[:, :, 2] == 0.7, axis=1)]
        a, b, c = top[:, 0, :2], top[:, 1, :2], top[:, 2, :2]
        area = 0.5 * np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1]))
        x, y = ob.points[:, 0], ob.points[:, 1]
        shoelace = 0.5 * abs(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
        assert area.sum() == pytest.approx(shoelace, rel=1e-9)
        checked += 1
    assert checked >= 3


def _navigate_doc(rows):
    log = [
        {"t": 0.0, "pose": rows[0, 1:].tolist(), "mode": "plan", "predicted": [[3.0, 2.0, 0.5, 0.0, 0.3], [5.0, 1.0, 0.0, 0.0, 0.25]], "plan": rows[:, :3].tolist()},
        {"t": 1.0, "pose": [1.5, 1.2], "mode": "evade", "predicted": [], "plan": rows[1:, :3].tolist()},
        {"t": 2.0, "pose": [2.0, 1.5], "mode": "plan", "predicted": [[3.5, 2.0, -0.2, 0.1, 0.3]], "plan": []},
    ]
    return {
        "version": 1,
        "scene": "office-polygons",
        "query": "sw-to-ne",
        "status": "timeout",
        "message": "did not arrive",
        "duration": None,
        "roadmap_distance": None,
        "delay_factor": None,
        "planning_seconds": 0.0,
        "executed": rows.tolist(),
        "replan_log": log,
    }


def test_cli_navigate_file_adds_predictions(tmp_path, capsys):
    rows = np.array([[0.0, 0.5, 0.5], [1.0, 1.5, 1.2], [2.0, 2.0, 1.5], [2.0 + 1 / 3, 2.0, 1.5]])
    nav = tmp_path / "nav.json"
    nav.write_text(json.dumps(_navigate_doc(rows)), encoding="utf-8")
    out = tmp_path / "nav.mcap"
    assert main(["export", str(SCENES / "office-polygons.yaml"), str(nav), "-o", str(out), "--step", "0.2"]) == 0
    assert "wrote" in capsys.readouterr().out
    msgs, kinds = read_mcap(out)
    assert set(msgs) == {"/scene", "/movers", "/robot", "/path", "/robot_body", "/predictions"}
    assert kinds["/predictions"][0] == "foxglove.SceneUpdate"
    assert [m[0] for m in msgs["/predictions"]] == [0, 10**9, 2 * 10**9]
    first = {e["id"]: e for e in msgs["/predictions"][0][2]["entities"]}
    assert set(first) == {"predicted-0", "predicted-1", "plan"}
    assert first["predicted-0"]["cylinders"][0]["size"]["x"] == pytest.approx(0.6)
    assert first["predicted-0"]["arrows"][0]["shaft_length"] == pytest.approx(0.5)  # 1 s at its velocity
    assert "arrows" not in first["predicted-1"]  # standing still
    assert len(first["plan"]["lines"][0]["points"]) == len(rows)
    assert [e["id"] for e in msgs["/predictions"][2][2]["entities"]] == ["predicted-0"]
    # the executed rows (the run did not arrive) are the robot's
    times = expected_times(0.0, 2.0 + 1 / 3, 0.2)
    assert [m[0] for m in msgs["/robot"]] == [round(t * 1e9) for t in times]
    traj = Trajectory(rows)
    for (_, _, msg), t in zip(msgs["/robot"], times, strict=True):
        assert [msg["pose"]["position"]["x"], msg["pose"]["position"]["y"]] == pytest.approx(traj.at(t).tolist(), abs=1e-12)
    validate_all(msgs, kinds)


def test_cli_real_navigate_run(tmp_path, capsys):
    """What `gfuzzy navigate` really writes: one /predictions message per logged replan."""
    nav = tmp_path / "nav.json"
    scene = SCENES / "office-polygons.yaml"
    assert main(["navigate", str(scene), "-o", str(nav), "--log-every", "8"]) in (0, 1)
    doc = json.loads(nav.read_text(encoding="utf-8"))
    out = tmp_path / "nav.mcap"
    assert main(["export", str(scene), str(nav), "-o", str(out)]) == 0
    capsys.readouterr()
    msgs, kinds = read_mcap(out)
    log = doc["replan_log"]
    assert len(log) >= 2
    assert [m[0] for m in msgs["/predictions"]] == [round(e["t"] * 1e9) for e in log]
    for (_, _, msg), entry in zip(msgs["/predictions"], log, strict=True):
        discs = [e for e in msg["entities"] if e["id"].startswith("predicted-")]
        assert len(discs) == len(entry["predicted"])
    rows = np.asarray(doc.get("waypoints") or doc["executed"], dtype=float)
    assert msgs["/path"][0][2]["poses"][-1]["position"]["x"] == rows[-1, 1]
    validate_all(msgs, kinds)


def test_footprint_robot_body(tmp_path):
    """A footprint robot's body: its polygon (top face of the right area) at each pose."""
    scene = load_scene(SCENES / "footprint-office.yaml")
    rows = np.array([[0.0, 1.0, 1.0, 0.0], [2.0, 2.0, 1.5, 1.2]])
    out = tmp_path / "f.mcap"
    export_mcap(scene, out, rows, options=ExportOptions(step=0.5, robot_height=0.3))
    msgs, kinds = read_mcap(out)
    fp = np.asarray(scene.robot.footprint)
    area = 0.5 * abs(np.sum(fp[:, 0] * np.roll(fp[:, 1], -1) - np.roll(fp[:, 0], -1) * fp[:, 1]))
    for (_, _, robot), (_, _, body) in zip(msgs["/robot"], msgs["/robot_body"], strict=True):
        (tri,) = body["entities"][0]["triangles"]
        assert tri["pose"] == robot["pose"]
        pts = np.array([[p["x"], p["y"], p["z"]] for p in tri["points"]]).reshape(-1, 3, 3)
        top = pts[np.all(pts[:, :, 2] == 0.3, axis=1)]
        a, b, c = top[:, 0, :2], top[:, 1, :2], top[:, 2, :2]
        got = 0.5 * np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1]))
        assert got.sum() == pytest.approx(area, rel=1e-9)
    validate_all(msgs, kinds)


def test_disc_robot_faces_where_it_goes(tmp_path):
    scene = load_scene(SCENES / "office-polygons.yaml")
    rows = np.array([[0.0, 0.5, 0.5], [1.0, 0.5, 0.5], [2.0, 1.5, 0.5], [3.0, 1.5, 0.5], [4.0, 1.5, 1.5]])
    out = tmp_path / "d.mcap"
    export_mcap(scene, out, rows, options=ExportOptions(step=0.5))
    msgs, _ = read_mcap(out)
    yaws = [yaw_of(m[2]["pose"]["orientation"]) for m in msgs["/robot"]]
    # before the first motion and through it: +x; through the wait: still +x; then +y
    assert yaws == pytest.approx([0.0] * 6 + [math.pi / 2] * 3, abs=1e-12)


def test_mcap_export_failing_midway_leaves_nothing(tmp_path, monkeypatch):
    from mcap.writer import Writer

    scene = load_scene(SCENES / "office-polygons.yaml")
    calls = {"n": 0}
    real = Writer.add_message

    def flaky(self, *a, **kw):
        calls["n"] += 1
        if calls["n"] > 5:
            raise OSError(28, "No space left on device")
        return real(self, *a, **kw)

    monkeypatch.setattr(Writer, "add_message", flaky)
    out = tmp_path / "x.mcap"
    with pytest.raises(OSError):
        export_mcap(scene, out, options=ExportOptions(span=5.0))
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "args, needle",
    [
        (["-o", "OUT.png"], "must end in .mcap"),
        ([], "exactly one of"),
        (["-o", "OUT.mcap", "--map", "OUT.yaml"], "exactly one of"),
        (["-o", "OUT.mcap", "--step", "0"], "--step"),
        (["-o", "OUT.mcap", "--step", "nan"], "--step"),
        (["-o", "OUT.mcap", "--resolution", "0.1"], "--resolution is for --map"),
        (["--map", "OUT.yaml", "--resolution", "-1"], "--resolution"),
        (["--map", "OUT.yaml", "--resolution", "inf"], "--resolution"),
        (["--map", "OUT.yaml", "--resolution", "0.0001"], "at most"),
        (["--map", "OUT.pgm"], "must end in .yaml"),
        (["--map", "OUT.yaml", "--step", "1"], "not --map"),
        (["-o", "OUT.mcap", "--step", "1e-12"], "time steps"),
        (["-o", "missing/OUT.mcap"], "does not exist"),
    ],
)
def test_cli_bad_arguments(tmp_path, capsys, args, needle):
    args = [a.replace("OUT", str(tmp_path / "out")) if a.startswith(("OUT", "missing")) else a for a in args]
    args = [str(tmp_path / a) if a.startswith("missing") else a for a in args]
    rc = main(["export", str(SCENES / "office-polygons.yaml"), *args])
    err = capsys.readouterr().err
    assert rc == 2
    assert needle in err and err.count("\n") == 1, err
    assert list(tmp_path.iterdir()) == []


def test_cli_bad_trajectory_files(tmp_path, capsys):
    scene = SCENES / "office-polygons.yaml"
    before = tmp_path / "before.json"
    doc = _navigate_doc(np.array([[-1.0, 0.5, 0.5], [1.0, 1.5, 1.2]]))
    doc.update(status="solved", waypoints=doc["executed"])
    before.write_text(json.dumps(doc), encoding="utf-8")
    box = tmp_path / "box.json"
    doc.update(waypoints=[[0.0, 1.0, 1.0, 0.0], [1.0, 2.0, 1.0, 0.0]])
    box.write_text(json.dumps(doc), encoding="utf-8")
    for traj, needle in ((before, "t >= 0"), (box, "disc robot"), (tmp_path / "none.json", "cannot read")):
        rc = main(["export", str(scene), str(traj), "-o", str(tmp_path / "o.mcap")])
        err = capsys.readouterr().err
        assert rc == 2 and needle in err and err.count("\n") == 1, err
        assert not (tmp_path / "o.mcap").exists()
    ragged = tmp_path / "ragged.json"
    doc = _navigate_doc(np.array([[0.0, 0.5, 0.5], [1.0, 1.5, 1.2]]))
    doc["replan_log"][1]["plan"] = [[0.0, 1.0, 1.0], [1.0, 2.0]]
    ragged.write_text(json.dumps(doc), encoding="utf-8")
    rc = main(["export", str(scene), str(ragged), "-o", str(tmp_path / "o.mcap")])
    err = capsys.readouterr().err
    assert rc == 2 and "replan_log[1]" in err and err.count("\n") == 1, err
    assert not (tmp_path / "o.mcap").exists()
    with pytest.raises(InputError):
        ExportOptions(step=-1)



@pytest.mark.parametrize(
    "edit, place",
    [
        (lambda log: log[1].update(predicted="oops"), "replan_log[1].predicted"),  # render: a ValueError traceback
        (lambda log: log[1].update(predicted=[[1.0, 2.0]]), "replan_log[1].predicted[0]"),  # render: a traceback
        (lambda log: log[0]["predicted"][1].__setitem__(2, float("nan")), "replan_log[0].predicted[1][2]"),  # render drew it
        (lambda log: log[0]["predicted"][0].__setitem__(4, -0.3), "replan_log[0].predicted[0][4]"),  # a negative radius
        (lambda log: log[1].update(t=1e300), "replan_log[1].t"),  # export: an OverflowError traceback
        (lambda log: log[1].update(t=10**400), "replan_log[1].t"),  # a JSON integer past a float: OverflowError
        (lambda log: log[1].update(plan=[[0.0, 1.0, 1.0], [1.0, 1.0, 1.0, 0.0]]), "replan_log[1].plan[1]"),  # widths
        (lambda log: log[1].update(t="1.0"), "replan_log[1].t"),  # both: silently dropped
        (lambda log: log.__setitem__(2, 5), "replan_log[2]"),  # both: silently dropped
        (lambda log: log[1].update(plan=[[0.0, 1.0, 1.0], [1.0, True, 2.0]]), "replan_log[1].plan[1][1]"),
    ],
)
def test_cli_render_and_export_name_the_broken_replan_log_entry(tmp_path, capsys, edit, place):
    """A navigate file's replan log (the predictions a GIF and an MCAP file draw) is read by one
    set of rules: a broken entry is one line naming the file and the entry, exit 2, nothing
    written; never a traceback, never an entry dropped without a word."""
    doc = _navigate_doc(np.array([[0.0, 0.5, 0.5], [1.0, 1.5, 1.2], [2.0, 2.0, 1.5]]))
    edit(doc["replan_log"])
    nav = tmp_path / "nav.json"
    nav.write_text(json.dumps(doc), encoding="utf-8")
    scene = str(SCENES / "office-polygons.yaml")
    for args in (["render", scene, str(nav), "-o", str(tmp_path / "o.gif")], ["export", scene, str(nav), "-o", str(tmp_path / "o.mcap")]):
        rc = main(args)
        err = capsys.readouterr().err
        assert rc == 2 and err.startswith(f"{nav}: {place}:") and err.count("\n") == 1, (args[0], err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["nav.json"]
    doc["replan_log"] = 5
    nav.write_text(json.dumps(doc), encoding="utf-8")
    assert main(["export", scene, str(nav), "-o", str(tmp_path / "o.mcap")]) == 2
    assert capsys.readouterr().err.startswith(f"{nav}: replan_log: expected a list")


def test_mcap_times_beyond_its_nanoseconds_are_bad_input(tmp_path, capsys):
    """MCAP log times are unsigned 64-bit nanoseconds (at most 1.8e10 s): a row or a replan
    later than the 1e9 s gfuzzy's numbers stay within is refused in one line, not a
    struct.error (rows) or OverflowError (a replan) traceback."""
    scene = load_scene(SCENES / "office-polygons.yaml")
    far = [[0.0, 0.5, 0.5], [2e10, 1.5, 1.2]]
    with pytest.raises(InputError, match="at most 1e"):
        export_mcap(scene, tmp_path / "far.mcap", far, options=ExportOptions(step=1e9))
    doc = _navigate_doc(np.array([[0.0, 0.5, 0.5], [1.0, 1.5, 1.2]]))
    doc.update(status="solved", waypoints=far)
    nav = tmp_path / "nav.json"
    nav.write_text(json.dumps(doc), encoding="utf-8")
    rc = main(["export", str(SCENES / "office-polygons.yaml"), str(nav), "-o", str(tmp_path / "o.mcap"), "--step", "1e9"])
    err = capsys.readouterr().err
    assert rc == 2 and "at most 1e" in err and err.count("\n") == 1, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["nav.json"]


# --------------------------------------------------------------------------- Nav2 maps


def read_nav2_map(yaml_path):
    """An independent reader (contract section 6): blocked squares (x0, y0, x1, y1)."""
    meta = yaml.safe_load(Path(yaml_path).read_text(encoding="utf-8"))
    raw = (Path(yaml_path).parent / meta["image"]).read_bytes()
    parts = raw.split(b"\n", 4)  # P5, comment, size, maxval, pixels
    assert parts[0] == b"P5" and parts[1].startswith(b"#") and parts[3] == b"255"
    w, h = map(int, parts[2].split())
    shade = np.frombuffer(parts[4], dtype=np.uint8)
    assert shade.size == w * h
    shade = shade.reshape(h, w)
    p = 1.0 - shade / 255.0
    occupied = p >= meta["occupied_thresh"]
    free = p <= meta["free_thresh"]
    assert np.all(occupied | free)  # trinary, no unknown
    assert meta["mode"] == "trinary" and meta["negate"] == 0 and meta["origin"][2] == 0
    return occupied, float(meta["resolution"]), tuple(meta["origin"][:2])


def cell_of(points, res, origin, h):
    """Row (0 at the top) and column of each point's cell."""
    j = np.floor((points[:, 0] - origin[0]) / res).astype(int)
    k = np.floor((points[:, 1] - origin[1]) / res).astype(int)
    return h - 1 - k, j


def samples_inside(ob, rng, n=400):
    """Points strictly inside an obstacle, drawn independently of the rasteriser."""
    import shapely

    if isinstance(ob, Disc):
        r = ob.radius * np.sqrt(rng.uniform(0, 1, n)) * (1 - 1e-9)
        a = rng.uniform(0, 2 * np.pi, n)
        pts = np.column_stack([ob.center[0] + r * np.cos(a), ob.center[1] + r * np.sin(a)])
        return np.vstack([pts, [ob.center]])
    if isinstance(ob, Box):
        u = rng.uniform(-0.5, 0.5, (n, 2)) * np.asarray(ob.size) * (1 - 1e-9)
        c, s = math.cos(ob.angle), math.sin(ob.angle)
        return u @ np.array([[c, s], [-s, c]]) + np.asarray(ob.center)
    poly = shapely.Polygon(ob.points, list(ob.holes))
    lo, hi = np.asarray(poly.bounds[:2]), np.asarray(poly.bounds[2:])
    pts = rng.uniform(lo, hi, (20 * n, 2))
    inside = shapely.contains_xy(poly, pts[:, 0], pts[:, 1])
    return pts[inside][:n]


@pytest.mark.parametrize("name, res", [("office-polygons", 0.05), ("office-polygons", 0.173), ("warehouse-mesh", 0.1), ("building-floor", 0.05)])
def test_map_covers_every_obstacle(tmp_path, name, res):
    scene = load_scene(SCENES / f"{name}.yaml")
    out = tmp_path / "m.yaml"
    grid = export_nav2_map(scene, out, res)
    occupied, r, origin = read_nav2_map(out)
    assert r == res and origin == scene.bounds[:2]
    np.testing.assert_array_equal(occupied, grid.occupied)
    h, w = occupied.shape
    assert w * res >= scene.bounds[2] - scene.bounds[0] - 1e-9 and h * res >= scene.bounds[3] - scene.bounds[1] - 1e-9
    rng = np.random.default_rng(7)
    for ob in scene.obstacles:
        pts = samples_inside(ob, rng)
        x0, y0, x1, y1 = scene.bounds
        pts = pts[(pts[:, 0] > x0) & (pts[:, 0] < x1) & (pts[:, 1] > y0) & (pts[:, 1] < y1)]
        assert len(pts) > 0
        i, j = cell_of(pts, res, origin, h)
        assert occupied[i, j].all(), f"{ob} has a sample in a free cell"


def test_map_marks_no_cell_away_from_the_obstacles(tmp_path):
    """Not over-conservative: a cell at a positive distance from every obstacle is free."""
    import shapely

    scene = load_scene(SCENES / "office-polygons.yaml")
    grid = rasterise(scene, 0.1)
    shapes = []
    for ob in scene.obstacles:
        if isinstance(ob, Disc):
            shapes.append(shapely.Point(ob.center).buffer(ob.radius * 1.0001, 256))  # circumscribing margin
        elif isinstance(ob, Box):
            shapes.append(shapely.Polygon(ob.vertices()))
        else:
            shapes.append(shapely.Polygon(ob.points, list(ob.holes)))
    union = shapely.union_all(shapes)
    h, w = grid.shape
    boxes = np.array([[grid.cell_box(i, j) for j in range(w)] for i in range(h)])
    cells = shapely.box(boxes[..., 0], boxes[..., 1], boxes[..., 2], boxes[..., 3])
    far = shapely.distance(cells, union) > 1e-9
    assert far.sum() > 0.3 * far.size
    assert not grid.occupied[far].any()


@pytest.mark.parametrize(
    "obstacle, cells",
    [
        # a box whose edges lie exactly on cell borders: exactly its 2 x 2 cells
        ({"box": {"center": [1.0, 1.0], "size": [0.5, 0.5]}}, {(3, 3), (3, 4), (4, 3), (4, 4)}),
        # a disc centred on a cell corner: the four cells around it, not the ones it only touches
        ({"disc": {"center": [0.5, 0.5], "radius": 0.25}}, {(1, 1), (1, 2), (2, 1), (2, 2)}),
        # a sliver 1e-6 m into a cell marks it
        ({"box": {"center": [0.5, 0.625], "size": [0.5 + 2e-6, 0.25]}}, {(2, 0), (2, 1), (2, 2), (2, 3)}),
        # a triangle whose hypotenuse runs through cell corners: the cells under the diagonal
        ({"polygon": [[0, 0], [0.75, 0], [0, 0.75]]}, {(0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (2, 0)}),
    ],
)
def test_map_hand_computed_cells(obstacle, cells):
    doc = {"version": 1, "name": "t", "bounds": [0, 0, 2, 2], "robot": {"disc": 0.1, "vmax": 1}, "obstacles": [obstacle]}
    grid = rasterise(parse_scene(doc), 0.25)
    h = grid.shape[0]
    got = {(h - 1 - i, j) for i, j in zip(*np.nonzero(grid.occupied), strict=True)}  # (y index, x index)
    assert got == cells


#: What ``gfuzzy check`` tolerates as touching (m): an obstacle reaching this far or less
#: into a cell does not mark it, unless it reaches that far into no cell at all (the
#: oracle's own copy of the rule).
_TOUCH = 0.5e-9


def _oracle_cells(scene, res):
    """Every cell of the grid tested on its own (no bounding boxes, no boundary tracing):
    the DE-9IM interior test for polygons and boxes, exact rational arithmetic for discs,
    on each cell shrunk by the touching tolerance (an obstacle must reach more than that in)."""
    from fractions import Fraction

    import shapely

    x0, y0, x1, y1 = scene.bounds
    w, h = math.ceil((x1 - x0) / res - 1e-9), math.ceil((y1 - y0) / res - 1e-9)
    j, k = np.meshgrid(np.arange(w), np.arange(h))

    def marks(ob, e):
        if isinstance(ob, Disc):
            cx, cy, r = (Fraction(v) for v in (*ob.center, ob.radius))
            fe = Fraction(e)
            out = np.zeros((h, w), dtype=bool)
            for kk in range(h):
                for jj in range(w):
                    # the nearest point of the closed (shrunk) square, exactly
                    nx = min(max(cx, Fraction(x0 + jj * res) + fe), Fraction(x0 + (jj + 1) * res) - fe)
                    ny = min(max(cy, Fraction(y0 + kk * res) + fe), Fraction(y0 + (kk + 1) * res) - fe)
                    out[kk, jj] = (nx - cx) ** 2 + (ny - cy) ** 2 < r * r
            return out
        cells = shapely.box(x0 + j * res + e, y0 + k * res + e, x0 + (j + 1) * res - e, y0 + (k + 1) * res - e)
        shape = shapely.Polygon(ob.vertices()) if isinstance(ob, Box) else shapely.Polygon(ob.points, list(ob.holes))
        return shapely.relate_pattern(cells, shape, "T********")

    occ = np.zeros((h, w), dtype=bool)
    for ob in scene.obstacles:
        got = marks(ob, _TOUCH)
        occ |= got if got.any() else marks(ob, 0.0)  # one reaching that far into no cell: every cell it overlaps
    return occ[::-1]


def _snapped(draw, lo, hi, res):
    """A coordinate, half the time on a cell border (where rasterisers go wrong)."""
    if draw(st.booleans()):
        return res * draw(st.integers(int(lo / res), int(hi / res)))
    return draw(st.floats(lo, hi, allow_nan=False))


@st.composite
def small_scenes(draw):
    res = draw(st.sampled_from([0.25, 0.1, 0.3]))
    obs = []
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["box", "disc", "polygon"]))
        c = [_snapped(draw, 0.5, 4.5, res), _snapped(draw, 0.5, 3.5, res)]
        if kind == "box":
            size = [max(0.01, _snapped(draw, 0.01, 2.0, res)) for _ in range(2)]
            obs.append({"box": {"center": c, "size": size, "angle": draw(st.sampled_from([0.0, 0.3, math.pi / 4, 1.0]))}})
        elif kind == "disc":
            obs.append({"disc": {"center": c, "radius": max(0.01, _snapped(draw, 0.01, 1.5, res))}})
        else:
            n = draw(st.integers(3, 6))
            r = draw(st.floats(0.05, 1.5))
            angles = np.sort(draw(st.lists(st.floats(0, 2 * math.pi), min_size=n, max_size=n, unique=True)))
            pts = [[c[0] + r * math.cos(a), c[1] + r * math.sin(a)] for a in angles]
            shoelace = 0.5 * sum(p[0] * q[1] - q[0] * p[1] for p, q in zip(pts, pts[1:] + pts[:1], strict=True))
            if shoelace < 1e-3:
                continue
            obs.append({"polygon": pts})
    doc = {"version": 1, "name": "r", "bounds": [0, 0, 5, 4], "robot": {"disc": 0.1, "vmax": 1}, "obstacles": obs}
    return parse_scene(doc), res


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(case=small_scenes())
def test_map_equals_the_cell_by_cell_oracle(case):
    scene, res = case
    np.testing.assert_array_equal(rasterise(scene, res).occupied, _oracle_cells(scene, res))


def test_map_disc_one_ulp_into_a_cell():
    """Found by the oracle test: the disc's top, 0.6000000000000001 + 0.7000000000000001, lies
    2.2e-16 m above the cell border 13 x 0.1: a rounding, touching (``gfuzzy check``
    tolerates 1e-9 m), so the cell above is free; a disc 1e-6 m higher marks it (the rule is
    the touching tolerance, not the float that happens to come out)."""
    doc = {"version": 1, "name": "u", "bounds": [0, 0, 5, 4], "robot": {"disc": 0.1, "vmax": 1}}
    doc["obstacles"] = [{"disc": {"center": [0.75, 0.6000000000000001], "radius": 0.7000000000000001}}]
    grid = rasterise(parse_scene(doc), 0.1)
    assert grid.occupied[grid.shape[0] - 1 - 12, 7]
    assert not grid.occupied[grid.shape[0] - 1 - 13, 7]
    doc["obstacles"] = [{"disc": {"center": [0.75, 0.600001], "radius": 0.7}}]
    grid = rasterise(parse_scene(doc), 0.1)
    assert grid.occupied[grid.shape[0] - 1 - 13, 7]
    assert not grid.occupied[grid.shape[0] - 1 - 14, 7]


def _cells(doc, res):
    grid = rasterise(parse_scene(doc), res)
    h = grid.shape[0]
    return {(h - 1 - i, j) for i, j in zip(*np.nonzero(grid.occupied), strict=True)}  # (y index, x index)


@pytest.mark.parametrize(
    "obstacle, cells",
    [
        # a wall 0.8e-9 m thick centred on the border x = 1: it reaches 0.4e-9 m into each side
        ({"box": {"center": [1.0, 1.0], "size": [0.8e-9, 1.0]}}, {(k, j) for k in range(2, 6) for j in (3, 4)}),
        ({"polygon": [[1.0 - 0.4e-9, 0.5], [1.0 + 0.4e-9, 0.5], [1.0 + 0.4e-9, 1.5], [1.0 - 0.4e-9, 1.5]]},
         {(k, j) for k in range(2, 6) for j in (3, 4)}),
        # a disc of radius 0.4e-9 m on a cell corner: the four cells around it
        ({"disc": {"center": [1.0, 1.0], "radius": 0.4e-9}}, {(3, 3), (3, 4), (4, 3), (4, 4)}),
    ],
)  # fmt: skip
def test_map_never_loses_an_obstacle_thinner_than_the_tolerance(obstacle, cells):
    """An obstacle reaching no more than the touching tolerance into any cell (thinner than
    1e-9 m, on a cell border) marked no cell at all: the map lost it (docs/export.md says it
    never does). It marks every cell it overlaps instead; a thicker neighbour keeps the rule."""
    doc = {"version": 1, "name": "t", "bounds": [0, 0, 2, 2], "robot": {"disc": 0.1, "vmax": 1}, "obstacles": [obstacle]}
    assert _cells(doc, 0.25) == cells
    doc["obstacles"].append({"box": {"center": [0.25, 0.25], "size": [0.5 + 0.8e-9, 0.5 + 0.8e-9]}})
    assert _cells(doc, 0.25) == cells | {(0, 0), (0, 1), (1, 0), (1, 1)}  # the rule, not the fallback


@pytest.mark.parametrize("radius", [0.2, 2.0])  # decided by the floats, and exactly (within 1e-9 r^2)
@pytest.mark.parametrize("axis", [0, 1])
def test_map_disc_reaching_just_under_or_over_the_tolerance_into_a_cell(radius, axis):
    """A disc whose edge reaches 0.4e-9 m past the border 3.0 into the cell beyond leaves it
    free (touching, as `gfuzzy check` sees it); 0.6e-9 m marks it; along x and along y."""
    doc = {"version": 1, "name": "t", "bounds": [0, 0, 6, 6], "robot": {"disc": 0.1, "vmax": 1}}
    beyond, before = (12, 12), ((12, 11) if axis == 0 else (11, 12))  # (y index, x index): the cell [3, 3.25]^2, the one before it
    for reach, marked in ((0.4e-9, False), (0.6e-9, True)):
        centre = [3.125, 3.125]
        centre[axis] = 3.0 - radius + reach
        doc["obstacles"] = [{"disc": {"center": centre, "radius": radius}}]
        got = _cells(doc, 0.25)
        assert before in got
        assert (beyond in got) == marked, (reach, radius, axis)


def test_map_pair_written_together_or_not_at_all(tmp_path, monkeypatch):
    scene = load_scene(SCENES / "office-polygons.yaml")
    out = tmp_path / "m.yaml"
    real = os.replace

    def fail_on_yaml(src, dst):
        if str(dst).endswith(".yaml"):
            raise OSError(28, "No space left on device", str(dst))
        return real(src, dst)

    monkeypatch.setattr(os, "replace", fail_on_yaml)
    with pytest.raises(OSError):
        export_nav2_map(scene, out, 0.1)
    assert list(tmp_path.iterdir()) == []
    monkeypatch.setattr(os, "replace", real)
    export_nav2_map(scene, out, 0.1)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.pgm", "m.yaml"]


def _read_back(tmp_path, map_yaml):
    """The exported map read by gfuzzy's own map reader, as a scene's map obstacle."""
    from gfuzzy.scene.maps import MapObstacle

    scene_file = tmp_path / "back.yaml"
    scene_file.write_text(
        f"version: 1\nname: back\nrobot: {{disc: 0.1, vmax: 1}}\nobstacles:\n  - map: {{file: {map_yaml.name}}}\n", encoding="utf-8"
    )
    scene = load_scene(scene_file)
    (grid,) = [o for o in scene.obstacles if isinstance(o, MapObstacle)]
    return scene, grid


@pytest.mark.parametrize("name, res", [("office-polygons", 0.05), ("warehouse-mesh", 0.07)])
def test_map_read_back_by_gfuzzy_covers_every_obstacle(tmp_path, name, res):
    scene = load_scene(SCENES / f"{name}.yaml")
    out = tmp_path / "m.yaml"
    written = export_nav2_map(scene, out, res)
    back, grid = _read_back(tmp_path, out)
    np.testing.assert_array_equal(grid.blocked, written.occupied)
    assert back.bounds[:2] == scene.bounds[:2]
    rng = np.random.default_rng(3)
    for ob in scene.obstacles:
        rows, cols, on_grid = grid.cells_of(samples_inside(ob, rng))
        assert on_grid.all() and grid.blocked[rows, cols].all()


def test_map_file_name_that_yaml_would_misread(tmp_path):
    scene = load_scene(SCENES / "office-polygons.yaml")
    out = tmp_path / "#1 & map: x.yaml"
    written = export_nav2_map(scene, out, 0.2)
    meta = yaml.safe_load(out.read_text(encoding="utf-8"))
    assert meta["image"] == "#1 & map: x.pgm" and (tmp_path / meta["image"]).is_file()
    occupied, _, _ = read_nav2_map(out)
    np.testing.assert_array_equal(occupied, written.occupied)


def test_map_scene_round_trips_exactly(tmp_path):
    """A scene on a map, exported at the map's resolution on the map's own grid: the very
    same blocked cells (cells are rectangles, and the grid is aligned)."""
    from gfuzzy.scene.maps import MapObstacle

    scene = load_scene(SCENES / "depot.yaml")
    (original,) = [o for o in scene.obstacles if isinstance(o, MapObstacle)]
    out = tmp_path / "depot.yaml"
    export_nav2_map(scene, out, original.resolution)
    _, grid = _read_back(tmp_path, out)
    assert grid.shape == original.shape
    np.testing.assert_array_equal(grid.blocked, original.blocked)


@pytest.mark.parametrize("name", ["small-house", "tb3-arena"])
def test_map_scene_off_the_origin_round_trips_exactly(tmp_path, name):
    """A map whose origin is not 0 (small-house: -12.5) under bounds a whole number of cells
    in: the grid's cell borders (-9.55 + k 0.05) and the map's (-12.5 + j 0.05) are the same
    lines computed apart, a few ulps off; the old export took that rounding for overlap and
    thickened walls by a cell (small-house 771 cells, tb3-arena 212)."""
    from gfuzzy.scene.maps import MapObstacle

    scene = load_scene(SCENES / f"{name}.yaml")
    (original,) = [o for o in scene.obstacles if isinstance(o, MapObstacle)]
    res = original.resolution
    written = export_nav2_map(scene, tmp_path / "m.yaml", res)
    h, w = written.shape
    j0 = round((written.origin[0] - original.origin[0]) / res)
    k0 = round((written.origin[1] - original.origin[1]) / res)
    rows = original.shape[0] - 1 - (h - 1 - np.arange(h) + k0)  # the same cells, row 0 at the top
    np.testing.assert_array_equal(written.occupied, original.blocked[rows][:, j0 : j0 + w])


def test_obstacle_edges_on_cell_borders_of_an_offset_grid():
    """Walls 0.15 m thick whose edges lie on cell borders of a grid from -4.35 (as written in
    decimals): three columns each, box or polygon, not four (3.7 = -4.35 + 161 * 0.05 in
    decimals; the floats differ by an ulp)."""
    doc = {
        "version": 1, "name": "walls", "bounds": [-4.35, -1.15, 15.75, 10.95], "robot": {"disc": 0.2, "vmax": 1.0},
        "obstacles": [
            {"box": {"center": [3.775, 2.0], "size": [0.15, 4.0]}},
            {"box": {"center": [7.775, 2.0], "size": [0.15, 4.0]}},
            {"polygon": [[11.7, 5.0], [11.85, 5.0], [11.85, 9.0], [11.7, 9.0]]},
            {"disc": {"center": [0.5, 8.05], "radius": 0.05}},  # touches the borders at 0.45, 0.55, 8.0, 8.1
        ],
    }  # fmt: skip
    grid = rasterise(parse_scene(doc), 0.05)
    cols = np.nonzero(grid.occupied.any(axis=0))[0].tolist()
    assert cols == [96, 97, 161, 162, 163, 241, 242, 243, 321, 322, 323]
    rows = np.nonzero(grid.occupied[:, 161])[0]
    assert len(rows) == 80  # y from 0 to 4: 80 cells, not 81
    assert grid.occupied[:, 96].sum() == grid.occupied[:, 97].sum() == 2  # the disc: its 2 x 2 cells


def test_mcap_map_scene_draws_the_blocked_cells(tmp_path):
    from gfuzzy.scene.maps import MapObstacle

    scene = load_scene(SCENES / "depot.yaml")
    (i, original), = [(i, o) for i, o in enumerate(scene.obstacles) if isinstance(o, MapObstacle)]
    out = tmp_path / "depot.mcap"
    export_mcap(scene, out, options=ExportOptions(span=2.0, step=0.5))
    msgs, kinds = read_mcap(out)
    ent = {e["id"]: e for e in msgs["/scene"][0][2]["entities"]}[f"obstacle-{i}"]
    cubes = ent["cubes"]
    area = sum(c["size"]["x"] * c["size"]["y"] for c in cubes)
    assert len(cubes) == len(original.rects)
    assert area == pytest.approx(original.blocked.sum() * original.resolution**2, rel=1e-9)
    validate_all(msgs, kinds)


def test_cli_map(tmp_path, capsys):
    out = tmp_path / "floor.yaml"
    assert main(["export", str(SCENES / "building-floor.yaml"), "--map", str(out), "--resolution", "0.1"]) == 0
    assert "occupied" in capsys.readouterr().out
    occupied, res, _ = read_nav2_map(out)
    assert res == 0.1 and occupied.any() and not occupied.all()


def test_cli_map_into_a_folder_that_refuses_names_the_file_asked_for(capsys):
    # /proc refuses new files even to root; the line named the temporary '/proc/.m.x27xxq5v.pgm'
    # (now the folder is tried before any work, and the line names the file asked for)
    assert main(["export", str(SCENES / "building-floor.yaml"), "--map", "/proc/m.yaml"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("/proc/m.yaml: "), err


def test_cli_step_count_is_written_short(tmp_path, capsys):
    traj = tmp_path / "far.json"
    doc = {"version": 1, "scene": "office-polygons", "query": "", "status": "solved", "message": "",
           "waypoints": [[0.0, 0.5, 4.5], [1e300, 0.6, 4.5]]}
    traj.write_text(json.dumps(doc), encoding="utf-8")
    assert main(["export", str(SCENES / "office-polygons.yaml"), str(traj), "-o", str(tmp_path / "o.mcap")]) == 2
    err = capsys.readouterr().err
    assert "ends at t=1e+300" in err and len(err) < 300, err  # beyond MCAP's times, and not a 300-digit number
    doc["waypoints"][1][0] = 1e9
    traj.write_text(json.dumps(doc), encoding="utf-8")
    assert main(["export", str(SCENES / "office-polygons.yaml"), str(traj), "-o", str(tmp_path / "o.mcap"), "--step", "1e-300"]) == 2
    err = capsys.readouterr().err
    assert "gives inf time steps" in err and len(err) < 300, err  # not a 310-digit count
    assert list(tmp_path.iterdir()) == [traj]


# --------------------------------------------------------------------------- the scene schema

SCHEMA_FILE = ROOT / "docs" / "scene.schema.json"
BAD_SCENES = ROOT / "tests" / "bad_scenes"

#: Bad scenes a JSON Schema cannot refuse, and why (the parser does).
BEYOND_A_SCHEMA = {
    "duplicate_mover": "unique names",
    "duplicate_query": "unique names",
    "footprint_bowtie": "self-intersection",
    "footprint_collinear": "area",
    "footprint_nan": "NaN passes every numeric keyword",
    "footprint_tiny": "a polygon's span compares items",
    "inverted_bounds": "xmin < xmax compares two items",
    "mesh_escape": "a relative path that leaves the folder",
    "mesh_garbage": "the file's contents",
    "mesh_missing": "the file system",
    "nan_center": "NaN passes every numeric keyword",
    "nan_mover_clearance": "NaN passes every numeric keyword",
    "nan_trajectory": "NaN passes every numeric keyword",
    "path_zero_length": "a polyline's length",
    "polygon_bowtie": "self-intersection",
    "polygon_collinear": "area",
    "trajectory_backward": "increasing times compare items",
    "trajectory_equal_time": "increasing times compare items",
    "trajectory_jump": "a speed divides two items",
}


@pytest.fixture(scope="module")
def scene_validator():
    schema = json.loads(SCHEMA_FILE.read_text(encoding="utf-8"))
    jsonschema.Draft7Validator.check_schema(schema)
    return jsonschema.Draft7Validator(schema)


def _yaml_doc(path):
    from gfuzzy.scene.yamldoc import _load_yaml

    return _load_yaml(path.read_text(encoding="utf-8"), str(path))


def test_schema_file_is_what_the_tool_writes():
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_scene_schema", ROOT / "tools" / "make_scene_schema.py")
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    assert SCHEMA_FILE.read_text(encoding="utf-8") == tool.render()


def _bundled_scenes() -> list:
    """Every scene file under scenes/ (the map YAMLs under scenes/maps/ are not scenes)."""
    found = [p for p in sorted(SCENES.rglob("*.yaml")) if "robot" in (_yaml_doc(p) or {})]
    assert len(found) >= 10, found
    return found


@pytest.mark.parametrize("path", _bundled_scenes(), ids=lambda p: p.stem)
def test_schema_accepts_every_bundled_scene(scene_validator, path):
    doc = _yaml_doc(path)
    load_scene(path)  # the parser accepts it ...
    errors = [e.message for e in scene_validator.iter_errors(doc)]
    assert not errors, errors  # ... and so does the schema


def test_schema_rejects_the_bad_scenes_a_schema_can(scene_validator):
    from gfuzzy.errors import SceneError

    accepted, refused = set(), 0
    for path in sorted(BAD_SCENES.glob("*.yaml")):
        try:
            doc = _yaml_doc(path)
        except SceneError:
            continue  # not YAML a schema could see (syntax, duplicate keys, aliases, empty)
        with pytest.raises(SceneError):
            load_scene(path)
        if scene_validator.is_valid(doc):
            accepted.add(path.stem)
        else:
            refused += 1
    assert accepted == set(BEYOND_A_SCHEMA)
    assert refused >= 60



@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(doc=scene_docs())
def test_schema_accepts_every_random_valid_scene(scene_validator, doc):
    parse_scene(doc)  # valid by construction: the parser accepts it
    errors = [e.message for e in scene_validator.iter_errors(doc)]
    assert not errors, errors


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(doc=scene_docs(), where=st.sampled_from(["top", "robot", "obstacle", "mover", "query", "expect"]), key=st.sampled_from(["colour", "Vmax", "radius2"]))
def test_schema_and_parser_both_refuse_an_unknown_key(scene_validator, doc, where, key):
    from gfuzzy.errors import SceneError

    targets = {"top": [doc], "robot": [doc["robot"]]}
    targets["obstacle"] = [next(iter(o.values())) for o in doc.get("obstacles") or [] if isinstance(next(iter(o.values())), dict)]
    targets["mover"] = list(doc.get("movers") or [])
    targets["query"] = list(doc.get("queries") or [])
    targets["expect"] = [q["expect"] for q in doc.get("queries") or [] if "expect" in q]
    if not targets[where]:
        return
    targets[where][0][key] = 1.0
    with pytest.raises(SceneError):
        parse_scene(doc)
    assert not scene_validator.is_valid(doc)


def test_schema_pose_length_follows_the_robot(scene_validator):
    base = {"version": 1, "name": "p", "bounds": [0, 0, 4, 3], "queries": [{"name": "q", "start": [1, 1], "goal": [2, 2]}]}
    disc = dict(base, robot={"disc": 0.2, "vmax": 1})
    assert scene_validator.is_valid(disc)
    box = dict(base, robot={"box": [0.4, 0.2], "vmax": 1})
    assert not scene_validator.is_valid(box)
    unicycle = dict(base, robot={"disc": 0.2, "vmax": 1, "kinematics": "unicycle"})
    assert not scene_validator.is_valid(unicycle)
    three = [{"name": "q", "start": [1, 1, 0], "goal": [2, 2, 0]}]
    assert scene_validator.is_valid(dict(box, queries=three))
    assert scene_validator.is_valid(dict(unicycle, queries=three))
    footprint = dict(base, robot={"footprint": [[0.3, 0.2], [-0.2, 0.2], [-0.2, -0.2]], "vmax": 1, "kinematics": "unicycle", "wmax": 1.5, "reverse": True}, queries=three)
    assert scene_validator.is_valid(footprint)
    # bounds may be left out only with a map
    no_bounds = {k: v for k, v in disc.items() if k != "bounds"}
    assert not scene_validator.is_valid(no_bounds)
    assert scene_validator.is_valid(dict(no_bounds, obstacles=[{"map": {"file": "maps/a.yaml", "unknown": "free"}}]))


def test_cli_says_in_one_line_when_mcap_is_missing(tmp_path, capsys, monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "mcap.writer", None)  # as if the package were not installed
    rc = main(["export", str(SCENES / "office-polygons.yaml"), "-o", str(tmp_path / "o.mcap")])
    err = capsys.readouterr().err
    assert rc == 2 and "pip install 'gfuzzy[export]'" in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_cli_export_of_an_invalid_trajectory_says_so(tmp_path, capsys):
    """As render does: a trajectory `gfuzzy check` rejects (here one that drives through the
    office's walls far faster than vmax) is exported, with a note naming why."""
    from helpers import write_trajectory_file

    scene = SCENES / "office-polygons.yaml"
    bad = write_trajectory_file(tmp_path / "bad.json", [[0.0, 0.5, 0.5], [1.0, 11.5, 7.5]], scene="office-polygons")
    out = tmp_path / "bad.mcap"
    assert main(["export", str(scene), str(bad), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert f"note: {bad}: invalid: " in err and "exported anyway" in err, err
    assert out.exists()


def test_predictions_built_in_python_as_arrays_are_read(tmp_path):
    """export_mcap's predictions may be numpy rows (a caller's own log, NavResult.log's
    numbers), as before the replan log's rules; a 0-d array or a long string is named short."""
    scene = load_scene(SCENES / "office-polygons.yaml")
    rows = np.array([[0.0, 0.5, 0.5], [1.0, 1.5, 1.2]])
    log = [{"t": np.float64(0.5), "predicted": np.array([[3.0, 2.0, 0.5, 0.0, 0.3]]), "plan": rows}]
    report = export_mcap(scene, tmp_path / "a.mcap", rows, log, ExportOptions(step=0.5))
    assert report.counts["/predictions"] == 1
    for bad, needle in ((np.float64(1.0), "replan_log[0].predicted: expected a list of rows, got np.float64(1.0)"),
                        ("x" * 500, "replan_log[0].predicted: expected a list of rows, got 'xxx")):
        with pytest.raises(InputError) as err:
            export_mcap(scene, tmp_path / "b.mcap", rows, [{"t": 0.0, "predicted": bad}])
        assert needle in str(err.value) and len(str(err.value)) < 200, str(err.value)
    assert not (tmp_path / "b.mcap").exists()


def test_a_replan_log_out_of_order_is_read_in_time_order():
    """The GIF and the MCAP file draw the predictions in time; a log written out of order
    (a user's merge of two runs' logs) is read sorted by t (a review's surviving mutant
    returned it as written)."""
    from gfuzzy.trajectory import replan_entries

    log = [{"t": t, "predicted": [[1.0, 2.0, 0.0, 0.0, 0.3]], "plan": [[t, 0.0, 0.0]]} for t in (2.0, 0.5, 1.0)]
    assert [e["t"] for e in replan_entries(log, "nav.json")] == [0.5, 1.0, 2.0]
