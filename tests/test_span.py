"""How long a scene is shown without a trajectory (gfuzzy.render.span): the one rule of an
animation and of a recording, against values computed by hand."""

from __future__ import annotations

import pytest
from conftest import run_python

from gfuzzy.export.export import ExportOptions, export_mcap
from gfuzzy.render.animate import _frame_times
from gfuzzy.render.span import default_span
from gfuzzy.scene.scene import parse_scene


def _scene(movers):
    return parse_scene(
        {
            "version": 1,
            "name": "span",
            "bounds": [0, 0, 20, 20],
            "robot": {"disc": 0.2, "vmax": 1.0},
            "movers": movers,
            "queries": [{"name": "q", "start": [1, 1], "goal": [19, 19]}],
        }
    )


SQUARE = [[2, 2], [6, 2], [6, 6], [2, 6]]  # a closed loop of 16 m, an open path of 12 m


@pytest.mark.parametrize(
    "movers, span",
    [
        ([], 10.0),  # nobody moves: the default
        ([{"name": "a", "disc": 0.3, "speed": 2.0, "path": SQUARE, "mode": "loop"}], 8.0),  # 16 m at 2 m/s
        ([{"name": "a", "disc": 0.3, "speed": 1.0, "path": SQUARE, "mode": "bounce"}], 24.0),  # 2 x 12 m
        ([{"name": "a", "disc": 0.3, "speed": 1.0, "path": SQUARE, "mode": "once"}], 10.0),  # no period
        ([{"name": "a", "disc": 0.3, "speed": 0.1, "path": SQUARE, "mode": "loop"}], 60.0),  # 160 s, clipped
        ([{"name": "a", "disc": 0.3, "speed": 40.0, "path": SQUARE, "mode": "loop"}], 1.0),  # 0.4 s, clipped
        (
            [
                {"name": "a", "disc": 0.3, "speed": 2.0, "path": SQUARE, "mode": "loop"},
                {"name": "b", "disc": 0.3, "trajectory": [[3.0, 1, 1], [12.5, 5, 5]]},  # leaves at 12.5 s
            ],
            12.5,
        ),
    ],
)
def test_the_default_span_by_hand(movers, span):
    assert default_span(_scene(movers)) == pytest.approx(span, rel=1e-12)


def test_an_animation_and_a_recording_show_the_same_span(tmp_path):
    scene = _scene([{"name": "a", "disc": 0.3, "speed": 1.0, "path": SQUARE, "mode": "bounce"}])
    times, _ = _frame_times(scene, None, fps=10.0, max_frames=10_000, duration=None)
    assert times[-1] == pytest.approx(24.0)
    out = tmp_path / "s.mcap"
    export_mcap(scene, out, options=ExportOptions(step=0.5))
    from mcap.reader import make_reader

    with open(out, "rb") as f:
        stamps = [m.log_time for _, _, m in make_reader(f).iter_messages(topics=["/movers"])]
    assert (max(stamps) - min(stamps)) / 1e9 == pytest.approx(24.0)


def test_a_recording_does_not_load_matplotlib():
    out = run_python("import sys, gfuzzy.export.export; print('matplotlib' in sys.modules)")
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "False"
