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
