"""tools/bench_nav_budget.py: its ``--opt key=value`` settings."""

from __future__ import annotations

import sys

import pytest
from conftest import ROOT

sys.path.insert(0, str(ROOT))

from tools.bench_nav_budget import parse_opts  # noqa: E402


def test_opt_values_take_the_settings_types():
    opts = parse_opts(["fan=false", "full_speed=True", "time_budget=0.2", "dt=0.05"])
    assert opts == {"fan": False, "full_speed": True, "time_budget": 0.2, "dt": 0.05}


def test_a_bool_opt_that_is_not_one_is_refused():
    with pytest.raises(SystemExit, match="fan=maybe"):
        parse_opts(["fan=maybe"])
