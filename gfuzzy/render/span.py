"""How long a scene is shown when the user gives no time: an animation without a
trajectory (:mod:`gfuzzy.render.animate`) and a recording (:mod:`gfuzzy.export.export`).

Kept apart from the drawing modules so that an export, which draws nothing, does not load
matplotlib for it.
"""

from __future__ import annotations

import math

from ..scene.scene import Scene

__all__ = ["SPAN_MIN", "SPAN_MAX", "SPAN_DEFAULT", "default_span"]

#: The span's bounds (seconds), and the span of a scene whose movers give none.
SPAN_MIN, SPAN_MAX, SPAN_DEFAULT = 1.0, 60.0, 10.0


def default_span(scene: Scene) -> float:
    """Seconds that show the movers' behaviour: the latest end of a mover's timed
    trajectory and the longest period of a loop or bounce mover, whichever is longer,
    clipped to [``SPAN_MIN``, ``SPAN_MAX``]; ``SPAN_DEFAULT`` when no mover has either
    (no movers, ``once`` movers, movers standing still)."""
    spans = []
    for m in scene.movers:
        if m.trajectory is not None:
            spans.append(m.time_range[1])
        elif math.isfinite(m.period):
            spans.append(m.period)
    if not spans:
        return SPAN_DEFAULT
    return float(min(SPAN_MAX, max(SPAN_MIN, max(spans))))
