"""tools/bench_populated.py: people added to a map scene, every query driven and checked."""

from __future__ import annotations

import sys

from conftest import ROOT

sys.path.insert(0, str(ROOT))

from tools.bench_populated import main  # noqa: E402


def test_every_query_is_driven_once_per_sensing_and_counted(monkeypatch, capsys):
    scene = str(ROOT / "scenes" / "tb3-arena.yaml")  # a SLAM map, three queries, two movers
    # the runs' first 7 s: the whole crossings cost 17 s of CPU for the same counting (on this
    # machine the rows still hold a run that timed out, one that arrived and one that collided)
    argv = ["bench_populated", scene, "--people", "2", "--seeds", "1", "--sensing", "exact", "fov", "--vertices", "100",
            "--max-time", "7"]  # fmt: skip
    monkeypatch.setattr(sys, "argv", argv)
    assert main() == 0
    out = capsys.readouterr().out
    rows = [line for line in out.splitlines() if line.startswith("  seed 1 ")]
    assert len(rows) == 6, out  # 3 queries x 2 sensings
    assert {r.split()[3] for r in rows} == {"exact", "fov"}
    assert all(float(r.split()[5]) <= 7.0 for r in rows), out  # --max-time: each run ends by then
    tally = {line.split()[0]: line.split()[1:] for line in out.split("runs valid:")[1].splitlines() if line.strip()}
    assert set(tally) == {"exact", "fov"}
    for name, (ok, _, n) in tally.items():
        shown = sum(1 for r in rows if r.split()[3] == name and r.rstrip().endswith("valid") and "collides" not in r)
        assert int(n) == 3 and int(ok) == shown, out
