"""A differential drive's graph repaired where its pieces lie close: small-step manoeuvres.

A box or footprint drive turns only at its graph's vertices (:mod:`gfuzzy.timespace.unicycle`).
Where a gap leaves its body a centimetre or two (a curved gap round a post, a T footprint
whose crossbar sweeps wide when it turns) the way through is a chain of turns of a
hundredth of a radian every few centimetres, at places no roadmap vertex is; the graph
then falls into pieces that lie a few centimetres apart (the unseen drives, seed 2 case 6:
the start's and the goal's pieces 0.1 m apart in the middle of the gap, the roadmap itself
one piece; not yet solved by this: ``docs/benchmarks.md``). :func:`drive_graph` joins such pieces, query-independently, by
:func:`drive_chain`: a weighted A* over small moves (drive ``STEP`` m forwards, backwards
with ``robot.reverse``, turn ``TURN`` rad in place), each certified
(:meth:`StaticGeometry.motion_free`, :func:`gfuzzy.timespace.drive.turn_free`), from the
copies of one piece near a vertex to a copy of another piece near a vertex close by, along
the roadmap's own way between them (its heuristic), its last
move a turn, a straight drive onto that vertex and a turn there. The chain becomes lanes
between new points (one where each straight run ends) and explicit turns at them
(:class:`Chains`; the points get no turning ring). The planner asks for it only when the
query's graph does not join its ends, so every query the graph solved is answered as
before. On by default (``PlanOptions.drive_repair``): each certificate is asked once
(:class:`_Cert`) and a repair's attempts share ``TOTAL`` expansions, so a query with no
way pays a bounded few seconds for it.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from ..poses import wrap_angle
from ..settings import SPEED_SAFETY
from ..typed import FloatArray
from . import unireach
from .unicycle import _base
from .unilanes import lanes, on_time

__all__ = ["Chains", "drive_chain", "drive_graph", "STEP", "TURN", "EXPANSIONS", "TOTAL", "PAIRS", "MIN_PIECE"]

#: The manoeuvres' drive step (m) and turn step (rad).
STEP = 0.02
TURN = 0.01
#: The A*'s cells in the plane, in drive steps (a pose in a visited cell at a visited
#: heading is not expanded).
KEY = 0.5
#: The A*'s heuristic weight (the length of the roadmap's way left, :func:`_guide`).
WEIGHT = 2.0
#: A turn step's cost in the A*, in circumradii per radian (the contract's metric; 4 made
#: the box of tests/test_unirepair.py explore its room rather than turn along the curve).
TURN_COST = 1.0
#: How far off a lattice pose's heading a target may lie for a straight drive onto it (rad).
FACING = 0.3
#: A* expansions per attempt between two vertices.
EXPANSIONS = 1500
#: A* expansions per repair in all (an unsolvable query pays for them: on the box
#: corridor of ``docs/benchmarks.md`` about a millisecond each, on a map's crop a few).
TOTAL = 4000
#: Pairs tried per repair in all (an unsolvable query pays for them: on a map's crop an
#: attempt that finds nothing costs up to a minute of CPU).
ATTEMPTS = 6
#: Closest vertex pairs tried per piece (in the plane, at most ``REACH`` spans apart).
PAIRS = 4
REACH = 2.5
#: A pair is tried only where the roadmap joins it within this many times its distance.
DETOUR = 3.0
#: Vertices where the body turns freely that a chain may start or end at, per end.
ENDS = 3
#: Headings a chain may start at from a vertex where the body turns freely, off the
#: direction towards the other end's vertex (rad).
FAN = (-0.2, -0.1, 0.0, 0.1, 0.2)
#: Pieces with fewer vertices are not joined (a stray copy or two in a tight spot).
MIN_PIECE = 3
#: Clearance queries tracing one side of a target's free turns before it counts as blocked.
ARC_STEPS = 200
#: A clearance below this certifies nothing (as :mod:`gfuzzy.collision.geometry`'s tracing).
_EPS = 1e-9


@dataclass
class Chains:
    """Lanes and turns added to a drive's plane roadmap (:func:`gfuzzy.timespace.unicycle._base`'s ``extra``).

    Attributes
    ----------
    xy : (P, 2) float
        New points, numbered after the lanes' points.
    edges : (E, 2) int ; ok : (E, 2) bool
        Lanes as :class:`gfuzzy.timespace.unilanes.Lanes`' (column 0: heading u -> v).
    turns : (T, 3) float
        Turns in place: point, heading from, signed change (certified).
    """

    xy: FloatArray
    edges: np.ndarray
    ok: np.ndarray
    turns: FloatArray


def _facing(p, t, near: float, reverse: bool, roomy: bool = False) -> bool:
    """Whether target ``t`` lies within ``near`` of lattice pose ``p`` and within ``FACING``
    of its heading (or behind it, with ``reverse``), or within three steps or ``roomy``."""
    d = math.hypot(t[0] - p[0], t[1] - p[1])
    if d > near:
        return False
    if roomy:
        return True
    off = abs(float(wrap_angle(math.atan2(t[1] - p[1], t[0] - p[0]) - p[2])))
    return d <= 3.0 * STEP or off <= FACING or (reverse and math.pi - off <= FACING)


class _Cert:
    """The chains' certificates, each clearance asked once (:meth:`StaticGeometry.motion_free`
    given both ends' clearances certifies a small move with no further query when they
    add up to its length: two certified stretches meet, ``motion_clearance``'s argument).

    A pose's clearance: the maps' distance-transform bound of the circumscribed disc
    (:meth:`StaticGeometry.disc_bound`, no FCL query) where it exceeds a drive step, else
    :meth:`StaticGeometry.clearance1`; both lower bounds. A target's turns: the arc of
    headings certified free on each side of its heading, traced lazily as far as asked."""

    def __init__(self, geo):
        self.geo, self.r = geo, float(geo.robot.circumradius)
        self.clear: dict = {}
        self.disc: dict = {}
        self.room: dict = {}
        self.arcs: dict = {}
        self.moves: dict = {}
        self.budget = TOTAL  # A* expansions left to the repair's attempts

    def c(self, p) -> float:
        got = self.clear.get(p)
        if got is None:
            d = self.disc.get(p[:2])
            if d is None:
                d = self.disc[p[:2]] = self.geo.disc_bound(p[0], p[1])
            got = self.clear[p] = d if d > STEP else self.geo.clearance1(list(p))
        return got

    def roomy(self, x: float, y: float) -> bool:
        """Whether every turn in place at (x, y) is free (:meth:`StaticGeometry.sweep_bound`)."""
        got = self.room.get((x, y))
        if got is None:
            got = self.room[(x, y)] = self.geo.sweep_bound(x, y) > 0
        return got

    def move(self, p, q) -> bool:
        """Whether the straight motion p -> q (a drive, or a turn of at most pi / 2) is certified (kept)."""
        got = self.moves.get((p, q))
        if got is None:
            ca = self.c(p)
            total = math.hypot(q[0] - p[0], q[1] - p[1]) + abs(float(wrap_angle(q[2] - p[2]))) * self.r
            if ca > total + _EPS:  # p's clearance alone certifies it (no pose moves farther than total)
                got = True
            else:
                cb = self.c(q) if ca >= 0 else -1.0
                got = bool(cb >= 0 and self.geo.motion_free(list(p), list(q), ca=ca, cb=cb))
            self.moves[(p, q)] = got
        return got

    def turn(self, p, dh: float) -> bool:
        """Whether turning in place from pose ``p`` by ``dh`` (|dh| <= pi / 2) is certified."""
        if abs(dh) <= 1e-12 or self.roomy(p[0], p[1]):
            return self.c(p) >= 0
        return self.move(p, (p[0], p[1], float(wrap_angle(p[2] + dh))))

    def arc(self, p, dh: float) -> bool:
        """Whether turning in place from pose ``p`` by ``dh`` (any size) is certified: the
        arc free on that side of ``p``, traced by clearance (sphere tracing, each step
        certified by the clearance at its start) and kept."""
        if abs(dh) <= 1e-12 or self.roomy(p[0], p[1]):
            return self.c(p) >= 0
        side = 1.0 if dh > 0 else -1.0
        done, blocked = self.arcs.get((p, side), (0.0, False))
        steps = 0
        while done < abs(dh) and not blocked:
            c = self.geo.clearance1([p[0], p[1], float(wrap_angle(p[2] + side * done))])
            steps += 1
            if c < _EPS or steps > ARC_STEPS:
                blocked = True
            else:
                done += c / self.r
        self.arcs[(p, side)] = (done, blocked)
        return done >= abs(dh)


def _finish(cert: _Cert, node, target, reverse: bool):
    """Moves from lattice pose ``node`` onto ``target`` (x, y, h): turn, straight, turn."""
    x, y, h = node
    tx, ty, th = target
    d = math.hypot(tx - x, ty - y)
    if d <= 1e-9:  # (the chain must end on the vertex itself)
        return None
    for back in (False, True) if reverse else (False,):
        hc = float(wrap_angle(math.atan2(ty - y, tx - x) + (math.pi if back else 0.0)))
        a, b = float(wrap_angle(hc - h)), float(wrap_angle(th - hc))
        if cert.arc(target, -b) and cert.move((x, y, hc), (tx, ty, hc)) and cert.arc(node, a):
            return [("T", a), ("D", d * (-1.0 if back else 1.0)), ("T", b)]
    return None


def drive_chain(geo, sources: list, targets: list, reverse: bool, budget: int | None = None, guide=None,
                deadline: float = math.inf, cert: _Cert | None = None):  # fmt: skip
    """A certified small-step drive from one of ``sources`` ((x, y, h)) to one of
    ``targets`` ((x, y, h)): (source index, target index, moves), moves ``("T", dh)`` (a
    turn in place) and ``("D", s)`` (a straight drive of s m along the heading, backwards
    when negative); None within ``budget`` expansions (default ``EXPANSIONS``). ``guide``: (points (k, 2), metres
    left from each): a polyline to a target (the roadmap's way, :func:`_guide`) whose
    length from a pose's nearest point is the heuristic; else the nearest target's distance.
    ``cert``: the certificates kept so far (:class:`_Cert`, shared by a repair's attempts).
    :class:`gfuzzy.timespace.unilanes.OutOfTime` past ``deadline``."""
    cert = _Cert(geo) if cert is None else cert
    budget = EXPANSIONS if budget is None else budget
    targets = [(float(t[0]), float(t[1]), float(t[2])) for t in targets]
    tx = np.array([t[:2] for t in targets], dtype=float)
    near = max(3.0 * STEP, 2.0 * float(geo.robot.circumradius))  # where a straight drive onto a target is tried
    gp, left = guide if guide is not None else (tx, np.zeros(len(tx)))

    def h_cost(x, y):
        return float(np.min(np.hypot(gp[:, 0] - x, gp[:, 1] - y) + left))

    key = lambda p: (round(p[0] / (KEY * STEP)), round(p[1] / (KEY * STEP)), round(p[2] / (0.5 * TURN)))  # noqa: E731
    heap, parent, seen = [], {}, set()
    for i, s in enumerate(sources):
        p = (float(s[0]), float(s[1]), float(s[2]))
        parent[p] = (None, None, i)
        heapq.heappush(heap, (WEIGHT * h_cost(*p[:2]), 0.0, p))
    moves = [("D", STEP)] + ([("D", -STEP)] if reverse else []) + [("T", TURN), ("T", -TURN)]
    r = float(geo.robot.circumradius)
    for n in range(budget):
        if n % 64 == 0:
            on_time(deadline)
        if not heap or cert.budget <= 0:
            return None
        cert.budget -= 1
        _, g, p = heapq.heappop(heap)
        if key(p) in seen:
            continue
        seen.add(key(p))
        dist = np.hypot(tx[:, 0] - p[0], tx[:, 1] - p[1])
        if dist.min() <= near:
            roomy = cert.roomy(p[0], p[1])  # any turn free: every target near is tried
            for j in np.argsort(dist, kind="stable").tolist():
                t = targets[j]
                if _facing(p, t, near, reverse, roomy) and (fin := _finish(cert, p, t, reverse)) is not None:
                    path = list(fin)
                    q = p
                    while parent[q][0] is not None:
                        q, mv, _ = parent[q]
                        path.insert(0, mv)
                    return parent[q][2], j, path
        x, y, h = p
        for kind, s in moves:
            if kind == "D":
                c = (x + s * math.cos(h), y + s * math.sin(h), h)
                ok = key(c) not in seen and c not in parent and cert.move(p, c)
                cost = abs(s)
            else:
                c = (x, y, float(wrap_angle(h + s)))
                ok = key(c) not in seen and c not in parent and cert.turn(p, s)
                cost = abs(s) * r * TURN_COST
            if ok:
                parent[c] = (p, (kind, s), None)
                heapq.heappush(heap, (g + cost + WEIGHT * h_cost(*c[:2]), g + cost, c))
    return None


def _components(n: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    return connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)), directed=False)[1]


def _base_pieces(base) -> tuple:
    """(copy poses, their vertices, a piece label per copy) of a drive's base: the weak
    components of its graph (ring points joined in)."""
    k = len(base.poses)
    a = np.where(base.a >= 0, base.a, k - 1 - base.a)
    b = np.where(base.b >= 0, base.b, k - 1 - base.b)
    return base.poses, base.vertex, _components(k + len(base.ring), a, b)[:k]


def _lane_pieces(ln) -> tuple:
    """The same from lanes alone (no ring built): a copy at each end of each certified lane
    direction, labelled by its vertex's component of the lanes' plane graph."""
    xy, e = ln.xy, ln.edges
    label = _components(len(xy), e[:, 0], e[:, 1])
    h = np.arctan2(xy[e[:, 1], 1] - xy[e[:, 0], 1], xy[e[:, 1], 0] - xy[e[:, 0], 0])
    vs, hs = [], []
    for col, hh in ((0, h), (1, wrap_angle(h + math.pi))):
        m = ln.ok[:, col]
        vs += [e[m, 0], e[m, 1]]
        hs += [hh[m], hh[m]]
    v, hh = np.concatenate(vs), np.concatenate(hs)
    return np.column_stack([xy[v], hh]), v, label[v]


class _Builder:
    """Turns :func:`drive_chain`'s moves into new points, lanes and turns."""

    def __init__(self, first: int):
        self.first, self.xy, self.edges, self.turns = first, [], [], []

    def add(self, geo, u: int, pose, moves, v: int, vxy) -> bool:
        """Add the chain of ``moves`` from vertex ``u`` at ``pose`` onto vertex ``v``, its
        merged straight runs certified again as lanes; False (nothing added) when one is not."""
        x, y, h = (float(c) for c in pose)
        cur, run, turn = u, 0.0, 0.0
        n_xy, n_edges, n_turns = len(self.xy), len(self.edges), len(self.turns)
        for i, (kind, s) in enumerate([*moves, ("D", 0.0)]):  # (the last: flushes a last turn)
            if kind == "T":
                turn += s
                continue
            if abs(turn) > 1e-12:  # the turns in a row at a point: one (its copies: the lanes')
                self.turns.append((cur, h, turn))
            h, turn = float(wrap_angle(h + turn)), 0.0
            if i == len(moves):
                break
            run += s
            last = i + 1 >= len(moves) or moves[i + 1][0] != "D" or (moves[i + 1][1] > 0) != (s > 0)
            if not last:
                continue
            ends_at_v = all(m[0] == "T" for m in moves[i + 1 :])
            if ends_at_v:
                nx, ny, nxt = float(vxy[0]), float(vxy[1]), v
            else:
                nx, ny = x + run * math.cos(h), y + run * math.sin(h)
                self.xy.append((nx, ny))
                nxt = self.first + len(self.xy) - 1
            tail, head = ((x, y), (nx, ny)) if run > 0 else ((nx, ny), (x, y))
            hl = math.atan2(head[1] - tail[1], head[0] - tail[0])
            if not geo.motion_free([*tail, hl], [*head, hl]):
                del self.xy[n_xy:], self.edges[n_edges:], self.turns[n_turns:]
                return False
            self.edges.append((cur, nxt) if run > 0 else (nxt, cur))  # column 0: heading tail -> head = h
            x, y, cur, run = nx, ny, nxt, 0.0
        return True

    def chains(self) -> Chains:
        e = np.array(self.edges, dtype=np.int64).reshape(-1, 2)
        ok = np.zeros((len(e), 2), dtype=bool)
        ok[:, 0] = True
        return Chains(np.array(self.xy, dtype=float).reshape(-1, 2), e, ok, np.array(self.turns, dtype=float).reshape(-1, 3))


def _guide(roadmap, u: int, ends: list, d: float):
    """The roadmap's shortest way from ``u`` to the nearest of ``ends`` (vertices of the
    roadmap) when it is at most ``DETOUR`` times ``d`` plus a robot span long (its holonomic
    motions pass there: a drive's small steps may too; else they would get round a wall):
    (points (k, 2), metres left from each), or None."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    n = len(roadmap.vertices)
    ends = [w for w in ends if w < n]
    if u >= n or not ends:
        return None
    key = ("unicycle-repair-graph", n, len(roadmap.edges))
    g = roadmap._derived.get(key)
    if g is None:
        e = np.asarray(roadmap.edges, dtype=np.int64).reshape(-1, 2)
        w = np.hypot(*(roadmap.vertices[e[:, 1], :2] - roadmap.vertices[e[:, 0], :2]).T) + 1e-12
        g = roadmap._derived[key] = coo_matrix((w, (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
    dist, pred = dijkstra(g, directed=False, indices=u, limit=DETOUR * d + 2.0 * roadmap.circumradius,
                          return_predecessors=True)  # fmt: skip
    end = min(ends, key=lambda w: dist[w])
    if not np.isfinite(dist[end]):
        return None
    way = [end]
    while way[-1] != u:
        way.append(int(pred[way[-1]]))
    pts = roadmap.vertices[way, :2].astype(float)  # from the end back to u
    left = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
    return pts, left


def _chains(geo, roadmap, pieces: tuple, xy: FloatArray, deadline: float) -> Chains | None:
    """Chains joining ``pieces`` (:func:`_base_pieces`, :func:`_lane_pieces`) of at least
    ``MIN_PIECE`` vertices (largest first, each to another at its ``PAIRS`` closest vertex
    pairs the roadmap joins nearby: :func:`_guide`), numbered after ``xy``, the
    points so far; None when none was found."""
    poses, vertex, label = pieces
    parent: dict = {}

    def find(c):
        while parent.get(c, c) != c:
            c = parent[c]
        return c

    verts: dict = {}
    at: dict = {}
    for k, (c, v) in enumerate(zip(label.tolist(), vertex.tolist(), strict=True)):
        verts.setdefault(c, set()).add(v)
        at.setdefault(v, []).append(k)
    big = sorted((c for c, vs in verts.items() if len(vs) >= MIN_PIECE), key=lambda c: -len(verts[c]))
    big_set = set(big)
    reverse, span = bool(geo.robot.reverse), 2.0 * float(geo.robot.circumradius)
    out = _Builder(len(xy))
    roomy: dict = {}
    cert = _Cert(geo)
    attempts = 0
    for c in big:
        mine = np.array(sorted(verts[c]))
        other = np.array(sorted({v for d in big if find(d) != find(c) for v in verts[d]}))
        if not len(other):
            continue
        dist = np.hypot(*(xy[mine][:, None, :] - xy[other][None, :, :]).transpose(2, 0, 1))
        tried = 0
        for flat in np.argsort(dist, axis=None, kind="stable")[: 8 * PAIRS].tolist():
            i, j = divmod(flat, len(other))
            if tried >= PAIRS or dist[i, j] > REACH * span:
                break
            u, v = int(mine[i]), int(other[j])
            cu = [k for w in _ends(geo, xy, mine, v, u, span, roomy) for k in at[w] if find(label[k]) == find(c)]
            cv = [k for w in _ends(geo, xy, other, u, v, span, roomy) for k in at[w]
                  if find(label[k]) != find(c) and label[k] in big_set]  # fmt: skip
            guides = [_guide(roadmap, a, _roomy_first(vertex, to, roomy), float(dist[i, j])) if cu and cv else None
                      for a, to in ((u, cv), (v, cu))]  # fmt: skip
            if guides[0] is None:
                continue
            tried += 1
            attempts += 1
            if attempts > ATTEMPTS or cert.budget <= 0:
                return out.chains() if out.edges else None
            if _join(geo, out, (poses, vertex, roomy, cert), cu, cv, reverse, xy, guides, deadline):
                parent[find(c)] = find(label[cv[0]])
                break
    return out.chains() if out.edges else None


def _ends(geo, xy, cands, near: int, own: int, span: float, roomy: dict) -> list:
    """The vertices of ``cands`` a chain may start or end at: ``own`` and the ``ENDS``
    nearest vertex ``near`` within ``REACH`` spans of it where the body turns freely
    (:meth:`StaticGeometry.sweep_bound`: a lattice pose rarely lines up with a vertex in a
    tight spot, and a vertex there has copies at few headings), else ``own`` and those
    within a span of it."""
    far = cands[np.hypot(*(xy[cands] - xy[near]).T) <= REACH * span].tolist()
    for w in far:
        if w not in roomy:
            roomy[w] = geo.sweep_bound(float(xy[w, 0]), float(xy[w, 1])) > 0
    out = sorted((w for w in far if roomy[w] and w != own), key=lambda w: math.hypot(*(xy[w] - xy[near])))[:ENDS]
    return [own, *out] if out else cands[np.hypot(*(xy[cands] - xy[own]).T) <= span].tolist()


def _sources(copies: list, poses, vertex, roomy: dict, towards, reverse: bool) -> list:
    """(copy, turn, pose) the A* starts from: each copy as it is, and at a vertex where the
    body turns freely also the headings ``FAN`` towards point ``towards`` (and away from
    it, with ``reverse``), each a turn from its first copy there."""
    out, fanned = [], set()
    for k in copies:
        out.append((k, 0.0, tuple(float(c) for c in poses[k])))
        w = int(vertex[k])
        x, y, h = (float(c) for c in poses[k])
        if not roomy.get(w) or w in fanned or math.hypot(towards[0] - x, towards[1] - y) < 1e-9:
            continue
        fanned.add(w)
        aim = math.atan2(towards[1] - y, towards[0] - x)
        for off in FAN + tuple(f + math.pi for f in FAN if reverse):
            dh = float(wrap_angle(aim + off - h))
            out.append((k, dh, (x, y, float(wrap_angle(h + dh)))))
    return out


def _roomy_first(vertex, copies: list, roomy: dict) -> list:
    """The vertices of ``copies`` where the body turns freely, else all of them (a tight
    vertex lures the A* into a corner it cannot turn in)."""
    ends = sorted({int(vertex[k]) for k in copies})
    return [w for w in ends if roomy.get(w)] or ends


def _join(geo, out: _Builder, pieces: tuple, one: list, two: list, reverse: bool, xy, guides,
          deadline: float = math.inf) -> bool:  # fmt: skip
    """A chain from a copy of ``one`` to a copy of ``two`` (copy ids; ``pieces``: the
    copies' poses, their vertices, which vertices are roomy and the :class:`_Cert`) along
    ``guides[0]`` (:func:`_guide`: the roadmap's way from ``one``'s vertex to those of
    ``two`` where the body turns freely), and one from ``two`` to ``one`` along
    ``guides[1]``: with ``reverse`` either (a chain is driven both ways; the second is
    searched only when the first is not found), else both (the body facing either way);
    added to ``out`` when found."""
    poses, vertex, roomy, cert = pieces
    found = 0
    for a, b, gd in ((one, two, guides[0]), (two, one, guides[1])):
        if gd is None:
            continue
        src = _sources(a, poses, vertex, roomy, gd[0][-1], reverse)
        got = drive_chain(geo, [p for _, _, p in src], [poses[k] for k in b], reverse, guide=gd, deadline=deadline,
                          cert=cert)  # fmt: skip
        if got is not None:
            k, dh, _ = src[got[0]]
            u, v = int(vertex[k]), int(vertex[b[got[1]]])
            if out.add(geo, u, poses[k], [("T", dh), *got[2]], v, xy[v]):
                found += 1
        if found if reverse else found == 0:
            break
    return found == (1 if reverse else 2)


def _extra(planner, stretch: float, step_len: float, deadline: float, first=None):
    """Chains joining the pieces of the drive's lanes (``first`` None: no ring built) or of
    its base with ``first`` (a :class:`Chains` or False: none) added; cached on the roadmap."""
    geo, robot, rm = planner.geometry, planner.robot, planner.roadmap
    key = ("unicycle-chains", geo.scene.static_hash, float(geo.keep), float(stretch), robot.shape, robot.size,
           bool(robot.reverse), float(robot.turn_rate), float(robot.vmax), float(step_len), "plane" if first is None else bool(first))  # fmt: skip
    if key in rm._derived:
        return rm._derived[key]
    ln = lanes(rm, geo, stretch, deadline)
    if first is None:
        got = _chains(geo, rm, _lane_pieces(ln), ln.xy, deadline)
    else:
        base = _repaired(planner, stretch, step_len, deadline, first)
        got = _chains(geo, rm, _base_pieces(base), base.vertex_xy, deadline)
        if got is not None and first:
            got = Chains(np.vstack([first.xy, got.xy]), np.vstack([first.edges, got.edges]),
                         np.vstack([first.ok, got.ok]), np.vstack([first.turns, got.turns]))  # fmt: skip
    rm._derived[key] = got
    return got


def _repaired(planner, stretch: float, step_len: float, deadline: float, extra):
    """The drive's base with ``extra`` (a :class:`Chains`, or False/None: the plain base),
    cached on the roadmap."""
    geo, robot, rm = planner.geometry, planner.robot, planner.roadmap
    if not extra:
        return _base(rm, geo, stretch, robot.vmax, step_len, deadline)
    key = ("unicycle-repaired", id(extra))
    hit = rm._derived.get(key)
    if hit is None or hit[0] is not extra:
        hit = rm._derived[key] = (extra, _base(rm, geo, stretch, robot.vmax, step_len, deadline, extra=extra))
    return hit[1]


def drive_graph(planner, start, goal, opts, deadline: float = math.inf) -> tuple:
    """(graph, start id, goal id, roadmap distance) of a fresh box or footprint drive's
    query. Where its lanes prove the ends apart (:func:`gfuzzy.timespace.unireach.ends_apart`)
    None and inf, unless ``opts.drive_repair``: then the lanes' pieces are joined by chains
    first (no ring built), and only if still apart None and inf. Else its graph; where that
    does not join the ends, with its ends' tilts; then, with ``opts.drive_repair``, with
    chains joining that graph's pieces (the ends tilting). OutOfTime past ``deadline``."""
    step_len = planner.robot.vmax * SPEED_SAFETY * opts.dt
    args = (start, goal, opts.connect_k, opts.stretch, deadline)
    extra = False
    if unireach.ends_apart(planner, *args):
        if not opts.drive_repair:
            return None, -1, -1, math.inf
        extra = _extra(planner, opts.stretch, step_len, deadline)
        if extra is None or unireach.ends_apart(planner, *args, extra=extra):
            return None, -1, -1, math.inf
    graph = lambda tilts: planner._query_graph(  # noqa: E731
        start, planner.prepare(goal, opts, _tilts=tilts, _deadline=deadline,
                               _base=_repaired(planner, opts.stretch, step_len, deadline, extra) if extra else None))
    got = graph(bool(extra))
    if not math.isfinite(got[3]) and not extra:
        got = graph(True)
    if not math.isfinite(got[3]) and opts.drive_repair:
        more = _extra(planner, opts.stretch, step_len, deadline, extra)
        if more is not None:
            extra = more
            got = graph(True)
    return got
