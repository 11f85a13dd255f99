"""tools/bench_replays.py: windows of pedestrian recordings cut, driven and checked."""

from __future__ import annotations

import sys

import numpy as np
from conftest import ROOT

sys.path.insert(0, str(ROOT))

from gfuzzy.scene.trackfiles import Track, Tracks  # noqa: E402
from tools.bench_replays import crossing, main  # noqa: E402


def _street(people: int = 12) -> Tracks:
    """People walking both ways along x (a street 4 m wide), 0.4 s apart, for 20 s."""
    rng = np.random.default_rng(2)
    tracks = []
    for i in range(people):
        t = np.arange(0.0, 20.0, 0.4)
        way = 1 if i % 2 else -1
        x = 10.0 - way * 8.0 + way * 1.2 * t
        y = np.full(len(t), rng.uniform(1.0, 5.0))
        tracks.append(Track(str(i), np.column_stack([t, x, y])))
    return Tracks("street.txt", "eth", 2.5, 1, tuple(tracks))


def test_the_crossing_goes_across_the_flow_from_a_clear_start():
    tracks = _street()
    c = crossing(tracks, ROOT / "street.txt", 0.0, 15.0, flip=False)
    (x0, y0), (x1, y1) = c.start, c.goal
    assert abs(x1 - x0) < 0.3 and abs(y1 - y0) >= 4.0  # across the street, its whole width
    r = c.region
    assert r[0] <= min(x0, x1) and max(x0, x1) <= r[2] and r[1] <= min(y0, y1) and max(y0, y1) <= r[3]
    for tr in tracks.tracks:  # nobody within START_GAP of the start over the first second
        for t in np.linspace(0.0, 1.0, 11):
            p = [np.interp(t, tr.rows[:, 0], tr.rows[:, k]) for k in (1, 2)]
            assert np.hypot(p[0] - x0, p[1] - y0) > 1.5 - 1e-9
    flipped = crossing(tracks, ROOT / "street.txt", 0.0, 15.0, flip=True)
    assert (flipped.start[1] - flipped.goal[1]) * (y0 - y1) < 0  # the other way


def test_a_window_of_the_bundled_excerpt_is_driven_and_checked(capsys):
    argv = [str(ROOT / "data" / "pedestrians"), "--files", "crowds_zara01", "--starts", "210", "--duration", "12",
            "--vertices", "120"]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    rows = [line for line in out.splitlines() if line.startswith("| crowds_zara01@210 ")]
    assert len(rows) == 1, out
    cells = [c.strip() for c in rows[0].strip("|").split("|")]
    assert cells[1:4] == ["disc", "estimated", "solved"] and cells[7] == "valid", out
    assert "| disc | estimated | 1 | 1 | 0 | 0 (0) |" in out


def test_a_folder_without_recordings_is_refused(tmp_path, capsys):
    assert main([str(tmp_path)]) == 2
    assert "no recordings" in capsys.readouterr().err
