"""tools/time_audit.py: an episode's time cut into the straight run and the pieces that add to it."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from conftest import ROOT

sys.path.insert(0, str(ROOT))

from tools.time_audit import audit  # noqa: E402


def test_the_pieces_add_up_to_the_time():
    # 0.25 s steps towards a goal 1.2 m ahead (success within 0.3 m): a full step, a step
    # aside and back (0.2 m of detour each way), a wait, a half step, then two full steps
    poses = np.array([[0.0, 0.0], [0.0, 0.25], [0.2, 0.25], [0.0, 0.25], [0.0, 0.25], [0.0, 0.375],
                      [0.0, 0.625], [0.0, 0.875], [0.0, 1.125]])  # fmt: skip
    got = audit(poses, np.array([0.0, 1.2]), 0.3, 1.0, 0.25)
    assert got["time"] == pytest.approx(2.0)
    assert got["line"] == pytest.approx(0.9)
    assert got["over"] == pytest.approx(0.3 - 0.075)
    assert got["detour"] == pytest.approx(0.4)
    assert got["wait"] == pytest.approx(0.25)
    assert got["slow"] == pytest.approx(0.05 + 0.05 + 0.125)
    total = got["line"] + got["over"] + got["detour"] + got["slow"] + got["wait"]
    assert total == pytest.approx(got["time"])
    assert got["turning"] == pytest.approx(np.pi / 2 + np.pi + np.pi / 2)


def test_the_recorder_hands_the_navigator_who_is_of_unknown_velocity(monkeypatch):
    """The crowd loop calls the navigator's policy with ``Sensor.unknown`` too: the recorder
    passes it on (it was taken for the wrapped call and failed with a TypeError)."""
    from gfuzzy.navigation import crowdpolicies as CP
    from tools.time_audit import _recorder

    for cls in (CP.NavigatorPolicy, CP.OraclePolicy):
        monkeypatch.setattr(cls, "__call__", cls.__call__)  # restored after the test

    class Nav:
        def step(self, t, pose, obs, unknown=None):
            self.unknown = unknown
            return "plan"

    store: list = []
    _recorder(store)
    nav = Nav()
    unknown = np.array([True, False])
    assert CP.NavigatorPolicy(nav)(0.5, np.array([1.0, 2.0]), np.zeros((2, 5)), unknown) == "plan"
    assert nav.unknown is unknown
    assert store[0][0] == 0.5 and store[0][2] == "plan"
    np.testing.assert_array_equal(store[0][1], [1.0, 2.0])
