"""gfuzzy.timespace.drive: the fan of straight lanes out of a unicycle's start."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gfuzzy.errors import InputError
from gfuzzy.poses import wrap_angle
from gfuzzy.settings import SPEED_SAFETY
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


def test_an_evasive_half_turn_is_checked_along_the_arc_it_turns():
    """A half turn aimed one way may come out the other (the headings' difference wraps to
    -pi where +pi was aimed at): each evasive candidate's turn is certified along the arc its
    rows turn, so a stick-shaped robot beside a post never sweeps it (one candidate did)."""
    from gfuzzy.check.check import check_trajectory
    from gfuzzy.collision.geometry import StaticGeometry
    from gfuzzy.poses import wrap_angle
    from gfuzzy.scene.scene import parse_scene
    from gfuzzy.timespace.drive import evasions

    x = y = 5.0
    heading = -1.1780972450961715  # grid heading 14 of 16 give or take an ulp, as a turn leaves it
    a = math.radians(-157.5)
    doc = {
        "version": 1, "name": "half-turn", "bounds": [0, 0, 10, 10],
        "robot": {"footprint": [[0.0, -0.05], [0.6, -0.05], [0.6, 0.05], [0.0, 0.05]], "vmax": 1.0,
                  "kinematics": "unicycle"},
        "obstacles": [{"disc": {"center": [x + 0.4 * math.cos(a), y + 0.4 * math.sin(a)], "radius": 0.08}}],
    }  # fmt: skip
    scene = parse_scene(doc)
    aimed = 5 * (2 * math.pi / 16)
    turned = float(wrap_angle(heading + float(wrap_angle(aimed - heading))))
    assert float(wrap_angle(aimed - heading)) > 0 > float(wrap_angle(turned - heading))  # the case
    cands = evasions(StaticGeometry(scene), 0.0, [x, y, heading], 3.0, 3.0, 16, 0.5)
    assert len(cands) > 5
    for rows in cands:
        rep = check_trajectory(scene, rows)
        assert rep.valid, (rows[:2], rep.reason)


def test_a_fan_piece_grazing_a_wall_is_decided_within_its_steps():
    """A lane along a wall 1 mm away took the sphere tracing thousands of steps to certify
    (a second of FCL queries in a depot); within the fan it is given ``FAN_TRACE_STEPS``,
    and its swept body (a box's translation sweeps the hull of its two ends) now certifies
    it within them (it was left out)."""
    from gfuzzy.collision.geometry import StaticGeometry
    from gfuzzy.scene.scene import parse_scene
    from gfuzzy.timespace.drive import FAN_TRACE_STEPS, _free

    doc = {
        "version": 1, "name": "graze", "bounds": [0, 0, 10, 4],
        "robot": {"box": [0.6, 0.4], "vmax": 1.0, "kinematics": "unicycle"},
        "obstacles": [{"box": {"center": [5.0, 2.5], "size": [8.0, 1.0]}}],  # its lower face at y = 2
    }  # fmt: skip
    geo = StaticGeometry(parse_scene(doc))
    a, b = (2.0, 1.799, 0.0), (5.0, 1.799, 0.0)  # the box's upper side 1 mm below the wall, 3 m along it
    assert _free(geo, a, b)  # free, as certified without a bound
    c0 = geo.calls
    assert _free(geo, a, b, FAN_TRACE_STEPS)
    assert geo.calls - c0 <= 2 * FAN_TRACE_STEPS + 2
    assert not _free(geo, a, (5.0, 1.801, 0.0), FAN_TRACE_STEPS)  # 1 mm into the wall at its end
    assert _free(geo, (2.0, 1.0, 0.0), (5.0, 1.0, 0.0), FAN_TRACE_STEPS)  # 0.8 m away: within the steps


def test_an_evasion_decides_each_move_along_a_ray_once():
    """A reversing differential drive among a map's walls spent 240 ms of CPU on one evasive
    answer (the depot, 8 people, ``--soft-search``): each heading's ray was traced again for
    every speed, the same moves (half speed all the way, full speed half way) and the parts
    of moves already found free. Now each is decided once, with the same candidates."""
    from gfuzzy.collision.geometry import StaticGeometry
    from gfuzzy.scene.scene import parse_scene
    from gfuzzy.timespace.drive import evasions, reach_fraction

    doc = {  # a box: its moves' ends carry the heading, which tells a forward ray from a reverse one
        "version": 1, "name": "walls", "bounds": [0, 0, 10, 4],
        "robot": {"box": [0.4, 0.3], "vmax": 1.0, "kinematics": "unicycle", "reverse": True},
        "obstacles": [{"box": {"center": [3.7, 2.0], "size": [1.0, 4.0]}}],  # a wall 1.2 m east
    }  # fmt: skip
    geo = StaticGeometry(parse_scene(doc))
    pose, speeds = [2.0, 2.0, 0.3], (1.0, 0.5, 0.25)
    checked = []
    free = geo.motion_free

    def counted(a, b, *args, **kwargs):
        checked.append((tuple(a), tuple(b)))
        return free(a, b, *args, **kwargs)

    geo.motion_free = counted
    cands = evasions(geo, 0.0, pose, 4.0, 4.0, 16, 1.0, speeds)
    assert len(checked) == len(set(checked))  # no move traced twice
    per_ray: dict = {}
    for a, b in checked:  # a part of a move already certified is not traced again
        ray = (round(math.atan2(b[1] - a[1], b[0] - a[0]), 9), a)  # a = (x, y, heading)
        per_ray.setdefault(ray, []).append(math.hypot(b[0] - a[0], b[1] - a[1]))
    for lengths in per_ray.values():
        assert lengths == sorted(lengths, reverse=True)
    geo.motion_free = free
    # the candidates are those of every speed's own reach_fraction, as before
    ends = set()
    for rows in cands[1:]:
        ends.add(tuple(np.round(rows[-1, 1:3], 9)))
    expected = set()
    for h in np.concatenate([[pose[2]], np.arange(16) * (2 * math.pi / 16)]):
        turn = abs(float(wrap_angle(h - pose[2])))
        left = 4.0 - turn / (geo.robot.turn_rate * SPEED_SAFETY)
        if left <= 0:
            continue
        for sign in (1.0, -1.0):
            unit = sign * np.array([math.cos(h), math.sin(h)])
            for speed in speeds:
                f = reach_fraction(geo, [2.0, 2.0, h], unit * speed * left)
                if f is not None:
                    expected.add(tuple(np.round(np.array(pose[:2]) + unit * speed * left * f, 9)))
    # exactly those: a move the walls block is no candidate (the standing one aside)
    assert ends - {tuple(np.round(pose[:2], 9))} == expected
