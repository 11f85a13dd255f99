"""gfuzzy.timespace.drive: the fan of straight lanes out of a unicycle's start."""

from __future__ import annotations

import math

import pytest

from gfuzzy.errors import InputError
from gfuzzy.timespace.drive import Fan


def test_the_default_fan_and_a_custom_one_are_accepted():
    assert Fan().distances == (1.0, 2.0, 3.0)
    assert Fan(offsets=(0.0, 0.5), distances=(0.5, 4.0)).offsets == (0.0, 0.5)


@pytest.mark.parametrize(
    "kwargs, where",
    [
        ({"distances": (-1.0, 2.0)}, r"distances\[0\]"),  # a backward lane
        ({"distances": (1.0, 0.0)}, r"distances\[1\]"),
        ({"distances": (1.0, math.inf)}, r"distances\[1\]"),
        ({"distances": (math.nan,)}, r"distances\[0\]"),
        ({"distances": (2.0, 1.0)}, r"distances\[1\]"),  # not increasing
        ({"offsets": (0.0, math.inf)}, r"offsets\[1\]"),
        ({"offsets": (math.nan,)}, r"offsets\[0\]"),
    ],
)
def test_a_bad_fan_is_refused_naming_the_field(kwargs, where):
    with pytest.raises(InputError, match=where):
        Fan(**kwargs)


@pytest.mark.parametrize(
    "robot, pose",
    [({"disc": 0.3, "vmax": 1.0}, [1.0, 2.0]), ({"box": [0.6, 0.4], "vmax": 1.0}, [1.0, 2.0, 0.0])],
)
def test_the_evasions_reach_the_farthest_free_fraction(robot, pose):
    """:func:`reach_fraction`, the reach of both robots' evasive motions: a wall 2.2 m ahead
    leaves a quarter of a 4 m move and half of a 2.4 m one, the bounds stop a move out of
    the room, and a free move goes all the way."""
    from gfuzzy.collision.geometry import StaticGeometry
    from gfuzzy.scene.scene import parse_scene
    from gfuzzy.timespace.drive import reach_fraction

    doc = {
        "version": 1, "name": "reach", "bounds": [0, 0, 10, 4], "robot": robot,
        "obstacles": [{"box": {"center": [3.7, 2.0], "size": [1.0, 4.0]}}],  # its west face at x = 3.2
    }  # fmt: skip
    geo = StaticGeometry(parse_scene(doc))
    # east (the body reaches 0.3 m ahead of x): 4 m and 2 m hit the wall (x = 3.0 reaches
    # 3.3 > 3.2), 1 m is free; 2.4 m hits it (3.7), 1.2 m is free (2.5)
    assert reach_fraction(geo, pose, [4.0, 0.0]) == 0.25
    assert reach_fraction(geo, pose, [2.4, 0.0]) == 0.5
    assert reach_fraction(geo, pose, [0.0, 1.0]) == 1.0  # north, inside the room
    assert reach_fraction(geo, pose, [-4.0, 0.0]) is None  # west: out of the bounds even a quarter
