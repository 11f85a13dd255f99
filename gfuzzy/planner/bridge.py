"""Bridges from a query end the roadmap does not reach to the roadmap (holonomic robots).

A start or a goal deep in a dead end barely wider than the robot (an alcove, a dock 1-2 cm
wider than the body) may have no certified straight motion to any of its nearest roadmap
vertices: each of them turns or slides the body into the walls on the way out, and the
PRM, sampling uniformly, seldom puts a vertex inside so tight a dead end. The only
motions that leave it are translations that keep the heading, along its axis.

:func:`bridge` searches from such an end a small tree of those translations,
breadth first and without sampling: from the end and from every pose it reaches, a ray
in each of ``RAYS`` directions of the plane and the robot's four own (ahead, behind, left,
right: a dead end's axis is one of them when the body fits it closely), followed by
conservative advancement (each step as long as the pose's static clearance: the body
cannot meet anything within it) until the clearance falls below ``STUCK`` or the ray
reaches ``REACH`` circumradii. The middle of each ray and its far end (backed off from
what stopped it) are new poses; each tries certified straight motions to its nearest
roadmap vertices in the component the end must join, and the first that connects ends
the search. Every edge of the bridge is certified again
(:meth:`~gfuzzy.collision.geometry.StaticGeometry.motion_free`), so a query's answer
through it passes ``gfuzzy check`` as any other.

:func:`bridged_roadmap` runs it for every end of a query that misses the roadmap's
component the other end (or, failing that, the largest component) lies in, and returns a
copy of the roadmap with the bridges' poses and edges appended: the query's graph only
(the planner plans once more on the copy); the roadmap and its file never change. It runs
only where needed: for a goal with no certified connection when its graph is prepared
(:func:`gfuzzy.planner.prepared.prepare_goal`, so the navigator's kept goal too), and when
a fresh plan finds its ends not joined on the roadmap; other queries pay nothing. Same
roadmap, same query: the same bridges.

The rays advance by :meth:`StaticGeometry.clearance1`, which already leaves out
``robot.clearance``: they keep it, as every certified motion does.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Iterator
from dataclasses import replace

import numpy as np

from ..collision.geometry import StaticGeometry, metric_distance
from ..roadmap.join import component_labels
from ..typed import FloatArray, IntArray

__all__ = ["bridge", "bridged_roadmap", "bridged_planner", "with_chains", "extended", "components", "reached", "RAYS", "REACH", "STUCK", "MAX_POSES", "TRIES"]

log = logging.getLogger(__name__)

#: Directions of the plane a ray is cast in from every pose of the tree (plus the robot's four).
RAYS = 16
#: A ray's longest reach, in circumradii.
REACH = 4.0
#: A ray stops where the pose's clearance falls below this (m).
STUCK = 2e-3
#: Poses of one bridge's tree at most (its root, the end, included).
MAX_POSES = 40
#: Nearest vertices of the target component a new pose tries to connect to.
TRIES = 6
#: Advancement steps per ray at most.
MAX_STEPS = 400


def components(roadmap) -> IntArray:
    """Connected component label of every roadmap vertex, cached on the roadmap."""
    hit = roadmap._derived.get(("components",))
    if hit is None:
        hit = roadmap._derived[("components",)] = component_labels(len(roadmap.vertices), roadmap.edges)
    return hit


def _directions(pose: FloatArray) -> FloatArray:
    """Unit ray directions from ``pose``: the robot's own four (with a heading), then the plane's."""
    ang = 2.0 * np.pi * np.arange(RAYS) / RAYS
    if len(pose) == 3:
        ang = np.r_[float(pose[2]) + 0.5 * np.pi * np.arange(4), ang]
    return np.c_[np.cos(ang), np.sin(ang)]


def _ray(geometry: StaticGeometry, pose: FloatArray, d: FloatArray, reach: float) -> float:
    """How far ``pose`` translates along ``d`` (same heading) before it gets stuck (conservative
    advancement on the static clearance), at most ``reach``. A pose touching a wall or the
    bounds (clearance 0: allowed), or flush with a wall, is first tried a slide of the whole
    ``reach`` (or 1/2, 1/4, 1/8 of it) certified from contact, then a step of ``2 STUCK``."""
    t = 0.0
    p = pose.copy()
    if not geometry.clearance1(p) >= STUCK:
        for f in (1.0, 0.5, 0.25, 0.125):  # flush with a wall: a slide along it, certified whole
            p[:2] = pose[:2] + f * reach * d
            if geometry.motion_free(pose, p):
                return f * reach
        p[:2] = pose[:2] + 2.0 * STUCK * d
        if not geometry.motion_free(pose, p):
            return 0.0
        t = 2.0 * STUCK
    for _ in range(MAX_STEPS):
        p[:2] = pose[:2] + t * d
        c = geometry.clearance1(p)
        if not c >= STUCK:
            break
        t = min(t + c, reach)
        if t >= reach:
            break
    return t


def reached(geometry: StaticGeometry, roadmap, pose: FloatArray, targets: IntArray) -> Iterator[int]:
    """Those of the ``TRIES`` nearest ``targets`` vertices a certified motion from ``pose``
    reaches, nearest first (each motion certified when asked for)."""
    V = roadmap.vertices[targets]
    d = metric_distance(V, pose[None, :], geometry.r)
    c = geometry.clearance1(pose)
    for i in np.argsort(d, kind="stable")[:TRIES].tolist():
        if geometry.motion_free(pose, V[i], ca=c):
            yield int(targets[i])


def _link(geometry: StaticGeometry, roadmap, pose: FloatArray, targets: IntArray) -> int | None:
    """The first of the ``TRIES`` nearest ``targets`` vertices a certified motion from ``pose`` reaches."""
    return next(reached(geometry, roadmap, pose, targets), None)


def bridge(
    geometry: StaticGeometry, roadmap, pose: FloatArray, targets: IntArray, deadline: float = math.inf,
    clock=time.perf_counter,
) -> tuple[list, int] | None:
    """A chain of certified translations from ``pose`` to a pose linked to one of ``targets``.

    Parameters
    ----------
    geometry : StaticGeometry
    roadmap : Roadmap
    pose : (d,) float
        A free query end (heading wrapped for a box robot).
    targets : (m,) int
        Roadmap vertices the chain may end at.

    Returns
    -------
    (poses, vertex) or None
        ``poses``: the chain after ``pose`` (its first pose ``2 STUCK`` from ``pose`` on
        the way out, so the end's own nearest connections find it), each motion certified; ``vertex``: the target it is linked to. None when no chain of at most
        ``MAX_POSES`` poses is found, or none by ``deadline`` (on ``clock``).
    """
    reach = REACH * geometry.r
    tree = [np.asarray(pose, dtype=float)]
    parent = [-1]
    sep = max(4.0 * STUCK, 0.02 * geometry.r)  # poses nearer than this to a tree pose are not added
    i = 0
    while i < len(tree) and len(tree) < MAX_POSES and clock() <= deadline:
        node = tree[i]
        for d in _directions(node):
            length = _ray(geometry, node, d, reach)
            if length < 2.0 * sep:
                continue
            for t in (0.5 * length, length - min(0.25 * length, 0.05 * geometry.r)):
                child = node.copy()
                child[:2] = node[:2] + t * d
                near = metric_distance(np.asarray(tree), child[None, :], geometry.r)
                if float(np.min(near)) < sep or not geometry.motion_free(node, child):
                    continue
                tree.append(child)
                parent.append(i)
                v = _link(geometry, roadmap, child, targets)
                if v is not None:
                    return _chain(geometry, tree, parent, len(tree) - 1, v, roadmap)
                if len(tree) >= MAX_POSES:
                    return None
        i += 1
    return None


def _chain(geometry: StaticGeometry, tree: list, parent: list, last: int, v: int, roadmap) -> tuple[list, int] | None:
    """The poses from the root's first child to ``last``, a pose a step from the root first
    (the end's own connections meet it before any roadmap vertex)."""
    path = []
    j = last
    while j > 0:
        path.append(tree[j])
        j = parent[j]
    path.reverse()
    root = tree[0]
    step = path[0] - root
    gap = float(np.hypot(step[0], step[1]))
    near = root + step * min(0.5, 2.0 * STUCK / gap) if gap > 0 else None
    poses = ([near] if near is not None else []) + path
    prev = root
    for p in [*poses, roadmap.vertices[v]]:  # certified again, end to end
        if not geometry.motion_free(prev, p):
            return None
        prev = p
    return poses, v


def bridged_roadmap(planner, ends: list, k: int, deadline: float = math.inf):
    """A copy of ``planner.roadmap`` with bridges from the ``ends`` (a query's start and goal,
    or a goal alone) that miss the component to join, or None when none is needed or one is
    not found (see the module docstring).

    ``k``: the query's ``connect_k`` (the ends' own connections tell the components they reach).
    """
    rm = planner.roadmap
    if len(rm.vertices) == 0:
        return None
    labels = components(rm)
    reached = [{int(labels[v]) for v, _ in planner._connect(e, k)} for e in ends]
    if set.intersection(*reached) if len(ends) > 1 else reached[0]:
        return None
    sizes = np.bincount(labels, minlength=len(labels))
    touched = sorted(set.union(*reached), key=lambda c: (-sizes[c], c))
    main = touched[0] if touched else int(np.argmax(sizes))
    targets = np.flatnonzero(labels == main)
    chains = []
    for end, got in zip(ends, reached, strict=True):
        if main in got:
            continue
        found = bridge(planner.geometry, rm, end, targets, deadline)
        if found is None:
            return None
        chains.append(found)
    return with_chains(rm, chains)


def with_chains(rm, chains: list):
    """A copy of the roadmap ``rm`` with the ``chains`` (:func:`bridge`'s answers) appended:
    each chain's poses as new vertices, its edges from the first pose to its roadmap vertex.

    The copy's spanners are the roadmap's, each chain edge kept: exactly what
    :meth:`~gfuzzy.roadmap.roadmap.Roadmap.spanner`'s greedy two-edge test gives on the
    copy (a chain is a path hung from one vertex: its edges lie on no triangle, so none is
    dropped and none drops another), without running it again over every edge (most of
    the copy's cost on a large roadmap: 0.06 of 0.1 s at 3000 vertices).
    """
    verts, edges = [rm.vertices], [rm.edges.reshape(-1, 2)]
    n = len(rm.vertices)
    for poses, v in chains:
        ids = list(range(n, n + len(poses)))
        verts.append(np.asarray(poses).reshape(len(poses), -1))
        n += len(poses)
        edges.append(np.asarray([(min(a, b), max(a, b)) for a, b in zip(ids, [*ids[1:], v], strict=True)], dtype=np.int64))
    log.info("query ends bridged to the roadmap: %d poses added", n - len(rm.vertices))
    return extended(rm, np.vstack(verts), np.vstack(edges))


def extended(rm, vertices: FloatArray, edges: IntArray):
    """A copy of the roadmap ``rm`` with ``vertices`` and ``edges`` (its own first, in order,
    then the added ones), whose spanners are the roadmap's with every added edge kept: still
    a spanner of each stretch (a path within the stretch for every edge), without running
    the greedy test again over every edge (0.06 s at 3000 vertices). For bridges
    (:func:`with_chains`) exactly the greedy test's answer on the copy."""
    lengths = metric_distance(vertices[edges[:, 0]], vertices[edges[:, 1]], rm.circumradius)
    spanners = {}
    for stretch, keep in rm._spanners.items():
        spanners[stretch] = np.concatenate([keep, np.ones(len(edges) - len(rm.edges), dtype=bool)])
        spanners[stretch].flags.writeable = False
    return replace(rm, vertices=vertices, edges=edges, lengths=np.asarray(lengths, dtype=float), _spanners=spanners)


def bridged_planner(planner, ends: list, k: int, deadline: float = math.inf):
    """A copy of ``planner`` on :func:`bridged_roadmap`'s copy, or None (the same)."""
    import copy

    rm = bridged_roadmap(planner, ends, k, deadline)
    if rm is None:
        return None
    out = copy.copy(planner)
    out.roadmap = rm
    return out
