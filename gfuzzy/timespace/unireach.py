"""Whether a differential drive's graph can join a query's ends, asked before its rings.

A footprint or box drive's graph (:mod:`gfuzzy.timespace.unicycle`) costs most in its
turning rings (a turn in place certified every turning step at every vertex: 60 of 70 s of
CPU on an unseen crop of a map, ``tools/bench_unseen_drives.py``); an unsolvable query paid
for them before the graph said its ends were apart. :func:`ends_apart` proves from the
lanes alone (:func:`gfuzzy.timespace.unilanes.lanes`, which the graph is made of anyway)
that the graph cannot join the ends: an over-approximation of it in the plane, in which

* each vertex with a copy is one node, every certified lane an undirected edge (the graph's
  copies at a vertex are joined only by its rings and turns, which stay at the vertex);
* each end is one node joined to every vertex the graph's own code would join it to or to
  one of its points on a heading line, tilts included (:meth:`_Extras.join`,
  :meth:`_Extras.along` run as the graph runs them, the copy of a vertex not built);
* the two ends joined when the straight drive from one to the other is free (as
  :meth:`gfuzzy.timespace.unicycle.UnicycleGoal.splice` joins them).

When the ends lie in different components of that graph, no path of the real one joins
them: ``no_path`` without building the rings.
"""

from __future__ import annotations

import math

import numpy as np

from ..poses import wrap_angle
from ..typed import FloatArray
from .uniends import _drive, _Extras
from .unilanes import lanes

__all__ = ["ends_apart"]


class _Reach:
    """The base the ends' joins read (:class:`gfuzzy.timespace.unicycle._Base`'s fields
    :meth:`_Extras.join` uses) from the lanes alone."""

    def __init__(self, xy: FloatArray, with_copy: np.ndarray, roadmap_vertices: int):
        self.vertex_xy = xy
        self.vertex = np.nonzero(with_copy)[0]
        self.roadmap_vertices = roadmap_vertices
        self.clearance = None  # a disc's only (never asked here)


class _Met(Exception):
    """The end joined a component the other end joins: the ends may be joined."""


class _Joins(_Extras):
    """:class:`_Extras` that records the lanes' components an end joins instead of building
    copies. A vertex of a component already reached is not tried (``known``): the loop then
    tries as many vertices as the graph's own or more, so its components are a superset of
    the graph's; reaching one of ``stop`` raises :class:`_Met`."""

    def __init__(self, base: _Reach, geometry, tilts: bool, label: np.ndarray, stop: set):
        super().__init__(base, geometry, 1.0, 0, None, tilts)
        self.label, self.stop, self.reached = label, stop, set()
        self.known = lambda v: int(label[v]) in self.reached

    def copy_at(self, v: int, h: float, out: bool) -> int:
        c = int(self.label[v])
        if c in self.stop:
            raise _Met
        self.reached.add(c)
        return self.node(*self.base.vertex_xy[v], h)


def _reached(base: _Reach, geometry, pose: FloatArray, connect_k: int, outward: bool, tilts: bool,
             label: np.ndarray, stop: set) -> set | None:  # fmt: skip
    """The lanes' components the end at ``pose`` joins (``outward``: the start), as
    :meth:`UnicycleGoal.splice` (a start) or :func:`prepare_goal` (a goal) joins it; None as
    soon as it joins one of ``stop``."""
    ex = _Joins(base, geometry, tilts, label, stop)
    node = ex.node(*pose)
    reverse = bool(geometry.robot.reverse)
    try:
        ex.join(pose, node, connect_k, outward, reverse)
        ex.along(pose, node, connect_k, outward, reverse)
    except _Met:
        return None
    return ex.reached


def ends_apart(planner, start: FloatArray, goal: FloatArray, connect_k: int, stretch: float,
               deadline: float = math.inf, extra=None) -> bool:  # fmt: skip
    """True when the drive's graph of ``planner`` cannot join ``start`` and ``goal``
    (``[x, y, heading]``), proven from its lanes (see the module docstring); False when it
    may (then the graph is built and searched as before). Only a box or footprint drive
    is asked (a disc's rings cost nothing: every heading is free where the disc is).
    ``extra``: a repair's chains' lanes added (:class:`gfuzzy.timespace.unirepair.Chains`).
    :class:`gfuzzy.timespace.unilanes.OutOfTime` past ``deadline`` while the lanes are built."""
    geo, robot, rm = planner.geometry, planner.robot, planner.roadmap
    if robot.shape == "disc":
        return False
    start = np.array(start, dtype=float)
    goal = np.array(goal, dtype=float)
    start[2], goal[2] = wrap_angle(start[2]), wrap_angle(goal[2])
    ln = lanes(rm, geo, stretch, deadline)
    xy, e = (ln.xy, ln.edges) if extra is None else (np.vstack([ln.xy, extra.xy]), np.vstack([ln.edges, extra.edges]))
    n = len(xy)
    with_copy = np.zeros(n, dtype=bool)
    with_copy[e.reshape(-1)] = True
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    graph = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)) if len(e) else coo_matrix((n, n))
    _, label = connected_components(graph, directed=False)
    if len(set(label[with_copy].tolist())) == 1:
        return False  # one component holds every vertex an end can join
    sx, sy, gx, gy = float(start[0]), float(start[1]), float(goal[0]), float(goal[1])
    if math.hypot(gx - sx, gy - sy) <= 1e-9:
        return False  # a turn in place may join them
    for back in (False, True) if robot.reverse else (False,):
        if _drive(geo, robot, sx, sy, gx, gy, back) is not None:
            return False
    base = _Reach(xy, with_copy, len(rm.vertices))
    for tilts in (False, True):  # the graph tilts its ends when it does not join them without
        reached = _reached(base, geo, goal, connect_k, False, tilts, label, set())
        if _reached(base, geo, start, connect_k, True, tilts, label, reached) is None:
            return False
    return True
