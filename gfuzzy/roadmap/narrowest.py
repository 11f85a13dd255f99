"""Why two poses cannot be joined, for a ``no_path`` message: they lie in separate regions
of a disc robot's free space (:mod:`gfuzzy.roadmap.freespace`); the growth of the obstacles
below which they join (bisection) and the narrowest place on the way between them."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..scene.scene import Scene
from ..typed import FloatArray
from .freespace import (
    DELTAS,
    FreeSpace,
    disc_centres,
    free_space,
    inscribed_disc,
    inscribed_free_space,
)

__all__ = ["Separation", "separation", "not_joined", "SEPARATION_MAX_OBSTACLES", "SEPARATION_MAX_RECTS"]

#: Separations are explained by bisection on the obstacles' growth only up to this many
#: obstacles (each step recomputes the free space).
SEPARATION_MAX_OBSTACLES = 400
#: ... and maps of at most this many blocked rectangles in all (a larger map's free space
#: takes seconds each time: a 90 x 60 m one 6 s of CPU, a dozen of them for the bisection).
SEPARATION_MAX_RECTS = 5000


@dataclass(frozen=True)
class Separation:
    """Why two poses cannot be joined: they lie in different free-space regions.

    Attributes
    ----------
    start, goal : (2,) float
        The two positions (a point in each region).
    grown : float
        The obstacles' growth: robot radius + clearance.
    passes_below : float or None
        A growth below which the planner joins them: the low end of the bisection's last
        bracket (to 1e-4 m) less the repair paths' smallest margin (``DELTAS[-1]``, which a
        path keeps from the free space's boundary on both sides), rounded down to 1e-4 m
        (a 1 m door: below 0.4997; a disc of 0.4997 is solved there, 0.49975 not);
        0 when even a point robot cannot pass;
        None when not computed (a scene with many obstacles).
    touching : float or None
        The growth at which a disc touches both sides of the narrowest place, estimated as
        the middle of that bracket plus the free space's ``tolerance`` (by which it grows the
        obstacles more than asked): what "too narrow" is measured from.
    narrowest : (2,) float or None
        Where the two regions come closest: the middle of the shortest segment between
        them, at a growth just above ``passes_below`` (the pinch point), else at ``grown``.
    """

    start: tuple
    goal: tuple
    grown: float
    passes_below: float | None
    narrowest: tuple | None
    touching: float | None = None

    def message(self) -> str:
        msg = (
            "start and goal lie in separate parts of the free space, so no way exists for this robot "
            f"(obstacles grown by radius + clearance = {self.grown:g} m): the start's region around "
            f"({self.start[0]:.3f}, {self.start[1]:.3f}), the goal's around ({self.goal[0]:.3f}, {self.goal[1]:.3f})"
        )
        if self.passes_below == 0.0:
            return msg + "; they are sealed off from each other (the obstacles themselves, not grown, leave no way between them)"
        if self.narrowest is not None:
            msg += f"; the narrowest place between them is near ({self.narrowest[0]:.3f}, {self.narrowest[1]:.3f})"
        if self.passes_below is not None:
            msg += (
                f", {2 * max(0.0, self.grown - (self.touching or self.passes_below)):.3f} m too narrow (radius + clearance "
                f"would have to be below {self.passes_below:.4f} m)"
            )
        return msg


def _joined(scene: Scene, grown: float, ends: FloatArray) -> tuple[bool, FreeSpace | None]:
    fs = free_space(scene, grown)
    if fs is None:
        return False, None
    rs, rg = fs.region_of(ends, slack=0.0).tolist()
    return rs == rg and rs >= 0, fs


def _narrowest(fs: FreeSpace, ends: FloatArray, joined: FreeSpace | None = None) -> tuple | None:
    """The middle of the shortest segment from the start's region to the goal's; with the
    free space ``joined`` in which one region holds both, to the next region on the way
    (:func:`_way`): a way through a corridor is cut at both doors, and the segment straight
    between the rooms named the corridor's middle, 1.85 m wide, for its 0.9 m doors."""
    import shapely

    rs, rg = fs.region_of(ends, slack=0.0).tolist()
    if rs < 0 or rg < 0 or rs == rg:
        return None
    k = -1 if joined is None else int(joined.region_of(ends[:1], slack=0.0)[0])
    rg = rg if k < 0 else _way(fs, rs, rg, joined.regions[k])
    c = np.asarray(shapely.shortest_line(fs.regions[rs], fs.regions[rg]).coords)
    return tuple(float(v) for v in 0.5 * (c[0] + c[1]))


def _way(fs: FreeSpace, rs: int, rg: int, whole) -> int:
    """The region after ``rs`` on the chain of ``fs``'s regions inside ``whole`` from ``rs``
    to ``rg`` whose largest step (the distance between consecutive regions) is least: the
    way through the passages that close first, not through a wall. ``rg`` itself when more
    than ``_WAY_REGIONS`` regions lie inside ``whole``."""
    import shapely

    inside = [k for k, reg in enumerate(fs.regions) if whole.contains(shapely.point_on_surface(reg))]
    if rs not in inside or rg not in inside or len(inside) > _WAY_REGIONS:
        return rg
    worst, first, done = {rs: 0.0}, {rs: rg}, set()
    while (k := min((v for v in worst if v not in done), key=worst.__getitem__)) != rg:
        done.add(k)  # Dijkstra on the largest step instead of the sum
        for j in set(inside) - done:
            w = max(worst[k], fs.regions[k].distance(fs.regions[j]))
            if w < worst.get(j, math.inf):
                worst[j], first[j] = w, j if k == rs else first[k]
    return first[rg]


_WAY_REGIONS = 40  # regions a way is looked for among, at most


def separation(scene: Scene, fs: FreeSpace, start: FloatArray, goal: FloatArray) -> Separation | None:
    """Where and by how much ``start`` and ``goal`` are kept apart (None: one region holds both).

    The growth at which the two regions join is found by bisection (each step a free-space
    computation), and the narrowest place is the shortest segment between the two regions
    just above it.
    """
    ends = np.asarray([start[:2], goal[:2]], dtype=float)
    rs, rg = fs.region_of(ends).tolist()
    if rs == rg and rs >= 0:
        return None
    passes: float | None = None
    touching: float | None = None
    where = _narrowest(fs, ends)
    rects = sum(len(ob.rects) for ob in scene.obstacles if hasattr(ob, "rects"))
    if len(scene.obstacles) <= SEPARATION_MAX_OBSTACLES and rects <= SEPARATION_MAX_RECTS:
        lo, hi = 0.0, fs.grown
        ok, fs_lo = _joined(scene, lo, ends)
        if not ok:
            passes = 0.0
        else:
            fs_hi = fs
            while hi - lo > 1e-4:
                mid = 0.5 * (lo + hi)
                ok, f = _joined(scene, mid, ends)
                if ok:
                    lo, fs_lo = mid, f
                else:
                    hi, fs_hi = mid, f
            # what the planner's paths can use, rounded down: "at most 0.4000" (the bracket
            # plus the tolerance, rounded to the nearest) was said at a 0.8 m door where
            # 0.39995 is not solved
            passes = max(0.0, math.floor((lo - DELTAS[-1]) * 1e4) / 1e4)
            touching = 0.5 * (lo + hi) + fs.tolerance
            where = _narrowest(fs_hi, ends, fs_lo) or where
    return Separation(tuple(ends[0].tolist()), tuple(ends[1].tolist()), fs.grown, passes, where, touching)


def not_joined(scene: Scene, start, goal) -> str:
    """The ``no_path`` message of a box or footprint robot whose roadmap does not join
    ``start`` and ``goal`` (poses ``[x, y, heading]``): a proof that no way exists when the
    disc inside its body (:func:`~gfuzzy.roadmap.freespace.inscribed_free_space`) finds them
    in separate regions (a robot wider than every door: more vertices cannot help, and the
    message said they might), else the roadmap may have missed a passage."""
    got = inscribed_free_space(scene)
    if got is not None:
        centre, fs = got
        rs, rg = fs.region_of(disc_centres(centre, [start, goal]), slack=0.0).tolist()
        if rs >= 0 and rg >= 0 and rs != rg:
            import shapely

            # where the start's part comes nearest another (its narrowest way out: the shortest
            # segment straight to the goal's part named the middle of a room between two doors)
            rest = shapely.union_all([reg for k, reg in enumerate(fs.regions) if k != rs])
            c = np.asarray(shapely.shortest_line(fs.regions[rs], rest).coords)
            where = 0.5 * (c[0] + c[1])
            near = f"; the start's part comes nearest another near ({where[0]:.3f}, {where[1]:.3f})"
            return (
                f"start and goal lie in separate parts of the free space of the disc inside the robot's body "
                f"(radius {inscribed_disc(scene.robot)[1]:.3f} m, clearance {scene.robot.clearance:g} m), so no way "
                f"exists for this robot{near}"
            )
    return ("start and goal are not connected on the roadmap (sealed off, or the roadmap missed "
            "a passage: more vertices, -n, may find it)")  # fmt: skip
