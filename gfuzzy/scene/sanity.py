"""Warnings about a scene that parses but may not say what its author meant.

Neither is an error: the scene is planned as written; the warning says what gfuzzy
will take it to mean.
"""

from __future__ import annotations

import logging

log = logging.getLogger(__name__)

#: A speed bound (m/s) beyond which a scene is most likely written in other units than
#: metres and seconds (a mobile robot at 72 km/h; a scene in millimetres has vmax ~1000).
UNITS_VMAX = 20.0


def warn_units(file: str, robot) -> None:
    """Warn when the robot's speed bound suggests a scene not in metres and seconds: the
    plan scales with the units, but the navigator's distances (personal space 0.2 m, the
    safety buffer) and the speed layer's bounds are in metres."""
    if robot.vmax > UNITS_VMAX:
        log.warning(
            "%s: robot.vmax %g m/s: gfuzzy's units are metres and seconds (a scene in millimetres plans, "
            "but the navigator's distances and the speed layer assume metres)",
            file, robot.vmax,
        )


def warn_beyond_maps(file: str, bounds, grids: list) -> None:
    """Warn when explicit ``bounds`` reach beyond every map's image: a map says nothing
    about what lies outside it, so that space is free (no obstacle there), unlike the map's
    unknown cells (docs/formats.md, section 1)."""
    if not grids:
        return
    import shapely

    inside = shapely.union_all([shapely.box(*g.extent) for g in grids])
    outside = shapely.box(*bounds).difference(inside)
    if outside.area > 1e-9 * shapely.box(*bounds).area:
        x0, y0, x1, y1 = outside.bounds
        log.warning(
            "%s: bounds reach %.3g m² beyond the map's image (within [%g, %g] x [%g, %g]): "
            "that space is free, the map knows nothing of it (bounds within the map close it)",
            file, outside.area, x0, x1, y0, y1,
        )
