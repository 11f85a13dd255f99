"""gfuzzy.trajectory: timed trajectories and their files, on hand-made rows."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from conftest import ROOT

from gfuzzy.cli import main
from gfuzzy.errors import SceneError
from gfuzzy.trajectory import Trajectory, TrajectoryFile, load_trajectory

ROWS = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [3.0, 1.0, 0.0], [4.0, 1.0, 1.0]])


def test_figures_of_a_hand_made_trajectory():
    tr = Trajectory(ROWS)
    assert tr.duration == 4.0 and tr.length == 2.0 and tr.xy_length == 2.0
    np.testing.assert_allclose(tr.speeds(), [1.0, 0.0, 1.0])
    assert tr.delay_factor(1.0, 2.0) == 2.0 and tr.delay_factor(1.0, 0.0) == 1.0


def test_at_interpolates_and_clamps():
    tr = Trajectory(ROWS)
    np.testing.assert_allclose(tr.at(0.5), [0.5, 0.0])
    np.testing.assert_allclose(tr.at([2.0, 3.5, -1.0, 9.0]), [[1.0, 0.0], [1.0, 0.5], [0.0, 0.0], [1.0, 1.0]])


def test_heading_turns_the_short_way():
    rows = np.array([[0.0, 0.0, 0.0, 3.0], [1.0, 0.0, 0.0, -3.0]])
    tr = Trajectory(rows, circumradius=1.0)
    assert abs(abs(tr.at(0.5)[2]) - math.pi) < 1e-12
    assert tr.length == pytest.approx(2 * math.pi - 6.0)


def test_json_and_csv_round_trip(tmp_path):
    tf = TrajectoryFile("s", "q", "solved", "", 4.0, 2.0, 2.0, 0.1, ROWS, extra={"stats": {"x": math.inf}})
    tf.save(tmp_path / "a.json")
    doc = json.loads((tmp_path / "a.json").read_text())
    assert doc["stats"]["x"] is None  # JSON has no inf
    back = load_trajectory(tmp_path / "a.json")
    np.testing.assert_array_equal(back.waypoints, ROWS)
    assert back.status == "solved" and back.duration == 4.0
    tf.save(tmp_path / "a.csv")
    assert (tmp_path / "a.csv").read_text().splitlines()[0] == "t,x,y"


def test_an_unsolved_answer_has_no_csv(tmp_path):
    tf = TrajectoryFile("s", "q", "no_path", "blocked", None, None, None, 0.1)
    with pytest.raises(ValueError, match="no waypoints"):
        tf.save(tmp_path / "a.csv")
    assert not (tmp_path / "a.csv").exists()


def test_bad_file_names_the_place(tmp_path):
    p = tmp_path / "bad.json"
    p.write_text(json.dumps({"version": 1, "status": "solved", "waypoints": [[0, 0, 0], [0, 1, 1]]}))
    with pytest.raises(SceneError) as exc:
        load_trajectory(p)
    assert str(p) in str(exc.value)


@pytest.mark.parametrize(("key", "value", "says"), [
    ("query", [1], "query: expected a string, got [1]"),
    ("scene", {"a": 1}, "scene: expected a string, got {'a': 1}"),
    ("message", 3, "message: expected a string, got 3"),
    ("status", [1], "status: unknown status [1]"),
    ("duration", [4.0], "duration: expected a number, got [4.0]"),
    ("planning_seconds", "0.1", "planning_seconds: expected a number, got '0.1'"),
])
def test_a_name_or_number_of_another_type_is_bad_input(tmp_path, capsys, key, value, says):
    # str() read `"query": [1]` as the query "[1]" (check: 'names query '[1]', which scene ...
    # does not have', exit 0); a list status was a TypeError traceback; a list duration was
    # read as none
    doc = {"version": 1, "status": "solved", "scene": "sim-4s1m", "query": "q", "duration": 1.0,
           "waypoints": [[0, 0, 0], [1, 1, 0]], key: value}
    path = tmp_path / "t.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(SceneError, match=rf"t.json: {re.escape(says)}$"):
        load_trajectory(path)
    assert main(["check", str(ROOT / "scenes" / "sim-4s1m.yaml"), str(path)]) == 2
    assert capsys.readouterr().err == f"{path}: {says}\n"
    if key != "status":
        doc[key] = None  # null: as absent (NaN or inf are written so)
        path.write_text(json.dumps(doc))
        assert getattr(load_trajectory(path), key) in ("", None, 0.0)


@pytest.mark.parametrize("command", ["check", "render", "export"])
def test_arrays_nested_past_pythons_stack_are_invalid_json(tmp_path, capsys, command):
    # json raised RecursionError, not JSONDecodeError: `gfuzzy check` printed a traceback
    path = tmp_path / "deep.json"
    path.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(SceneError, match="invalid JSON"):
        load_trajectory(path)
    out = {"check": [], "render": ["-o", str(tmp_path / "a.png")], "export": ["-o", str(tmp_path / "a.mcap")]}[command]
    assert main([command, str(ROOT / "scenes" / "sim-4s1m.yaml"), str(path), *out]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"{path}: invalid JSON")
    assert list(tmp_path.iterdir()) == [path]


def test_a_bom_is_read_past_and_bytes_not_utf8_are_named(tmp_path):
    # a scene or a tracks file with a BOM (Windows editors write one) loaded; a trajectory or
    # a roadmap JSON with one was bad input ('invalid JSON: Unexpected UTF-8 BOM'), and a
    # stray byte said "'utf-8' codec can't decode byte 0xe9 in position 42" instead of where
    from gfuzzy.roadmap.roadmap import load_roadmap, roadmap_digest

    doc = {"version": 1, "status": "solved", "scene": "s", "query": "q", "waypoints": [[0, 0, 0], [1, 1, 0]]}
    path = tmp_path / "bom.json"
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps(doc).encode())
    np.testing.assert_array_equal(load_trajectory(path).waypoints, doc["waypoints"])
    path.write_bytes(json.dumps(doc).replace('"q"', '"caf\xe9"', 1).encode("latin-1"))
    with pytest.raises(SceneError, match=r"bom.json: not UTF-8 text \(line 1, column \d+: byte 0xe9\)$"):
        load_trajectory(path)
    saved = ROOT / "roadmaps" / "sim-4s1m.json"
    path.write_bytes(b"\xef\xbb\xbf" + saved.read_bytes())
    assert roadmap_digest(load_roadmap(path)) == roadmap_digest(load_roadmap(saved))
    path.write_bytes(b"\xff" + saved.read_bytes())
    with pytest.raises(SceneError, match=r"bom.json: not a roadmap file \(not UTF-8 text \(line 1, column 1: byte 0xff\)\)$"):
        load_roadmap(path)


def test_trajectories_with_other_waypoints_are_not_equal():
    a = Trajectory(np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 0.0]]), circumradius=0.3)
    same = Trajectory(a.waypoints.copy(), circumradius=0.3)
    other = Trajectory(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 1.0]]), circumradius=0.3)
    assert a == same
    assert a != other
    assert a != Trajectory(a.waypoints.copy(), circumradius=0.5)


def test_trajectory_files_with_other_waypoints_or_extras_are_not_equal():
    def doc(rows, **extra):
        return TrajectoryFile("s", "q", "solved", "", 1.0, 1.0, 1.0, 0.0, np.array(rows), extra)

    rows = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0]]
    assert doc(rows) == doc([r[:] for r in rows])
    assert doc(rows) != doc([[0.0, 0.0, 0.0], [1.0, 0.0, 1.0]])
    assert doc(rows) != doc(rows, replans=3)
    no_rows = TrajectoryFile("s", "q", "no_path", "x", None, None, None, 0.0)
    assert no_rows == TrajectoryFile("s", "q", "no_path", "x", None, None, None, 0.0)
    assert no_rows != doc(rows)


@pytest.mark.parametrize("heading", [False, True])
def test_at_keeps_the_shape_of_the_times(heading):
    # a (2, 2) array of times gave a (2, 2, 2) array whose rows were not the poses at those
    # times (a disc robot), or an IndexError (a robot with a heading)
    rows = np.c_[ROWS, [0.0, 0.5, 1.0, 1.5]] if heading else ROWS
    tr = Trajectory(rows)
    times = np.array([[0.5, 2.0], [3.5, 9.0]])
    got = tr.at(times)
    assert got.shape == (2, 2, rows.shape[1] - 1)
    np.testing.assert_allclose(got.reshape(4, -1), tr.at(times.reshape(-1)))
    np.testing.assert_allclose(got[1, 0, :2], [1.0, 0.5])
    assert tr.at(2.0).shape == (rows.shape[1] - 1,) and tr.at([]).shape == (0, rows.shape[1] - 1)
    # one row: the same shapes (only a 4-row trajectory was tried)
    one = Trajectory(rows[:1])
    assert one.at(times).shape == (2, 2, rows.shape[1] - 1) and one.at(7.0).shape == (rows.shape[1] - 1,)
    np.testing.assert_array_equal(one.at(times)[1, 1], rows[0, 1:])


def test_rows_given_as_lists_make_a_trajectory_and_no_rows_are_refused():
    # Trajectory([[...]]) was kept as a list: .duration raised "list indices must be integers";
    # no rows raised IndexError at the first use, far from the mistake
    tr = Trajectory([[0, 0, 0], [1, 1, 0]])
    assert tr.duration == 1.0 and tr.waypoints.dtype == float and tr == Trajectory(np.array([[0.0, 0, 0], [1, 1, 0]]))
    for bad in (np.zeros((0, 3)), [[0, 1], [1, 2]], [0, 1, 2], [[[0, 0, 0]]]):
        with pytest.raises(ValueError, match=r"waypoints: expected rows \[t, x, y\] or \[t, x, y, heading\]"):
            Trajectory(bad)



def test_rows_of_strings_or_booleans_are_no_trajectory():
    # numpy made ["0", "1", "1"] and True numbers (plan and load_trajectory refuse both)
    for bad in ([["0", "1", "1"], ["1", "2", "1"]], np.ones((2, 3), dtype=bool), [[0, 1, 1], [True, 2, 1]], [[0, 1, 1], [1, 2]]):
        with pytest.raises(ValueError, match=r"^waypoints: expected rows of numbers \[t, x, y\(, heading\)\] of one width"):
            Trajectory(bad)


def test_a_saved_file_loads_back_equal_with_its_other_keys(tmp_path):
    # load_trajectory kept the contract's keys only: a plan's `stats` and a navigate run's
    # `replans`, `min_separation`, `executed` ... were lost, and nothing saved loaded back equal
    extra = {"stats": {"expansions": 12, "horizon": 4.5}, "replans": 3, "min_separation": 0.25,
             "executed": [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0]]}
    tf = TrajectoryFile("s", "q", "solved", "", 4.0, 2.0, 2.0, 0.1, ROWS, extra=extra)
    tf.save(tmp_path / "a.json")
    back = load_trajectory(tmp_path / "a.json")
    assert back.extra == extra and back == tf
    no_rows = TrajectoryFile("s", "q", "timeout", "not there", None, None, None, 0.0, extra={"replans": 9})
    no_rows.save(tmp_path / "b.json")
    assert load_trajectory(tmp_path / "b.json") == no_rows
