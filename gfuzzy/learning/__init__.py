"""Rule learning and the tracking simulation it scores rule bases with.

Not part of planning: nothing under :mod:`gfuzzy` outside this subpackage imports it
(``tests/test_architecture.py`` checks), so a plan never loads it.
"""

from .learn import LearnOptions, LearnResult, learn_rules
from .tracking import TrackingOptions, TrackingResult, UnicycleLimits, track

__all__ = [
    "LearnOptions",
    "LearnResult",
    "TrackingOptions",
    "TrackingResult",
    "UnicycleLimits",
    "learn_rules",
    "track",
]


def __getattr__(name: str):
    # the package's other modules, loaded on first use (`gfuzzy.learning.drivetracking`)
    from .. import submodule

    return submodule(__name__, name)
