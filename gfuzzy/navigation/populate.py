"""Walking people for any scene: ``gfuzzy populate`` (a crowd to test a navigator against).

Each person is a disc walking among the scene's static obstacles: the local motion is
ORCA (van den Berg et al. 2011, RVO2 through ``pyrvo``: the people avoid each other and
the obstacles, which RVO2 takes as polygons), the way is a shortest path on a grid of
the free space (cells whose centre is at least the person's radius plus 5 cm from every
obstacle and inside the bounds), shortened where a straight line keeps that clearance.
People walk between random free points of the largest connected free region (a new one
when they arrive), or around the given ``waypoints`` in turn. Their positions every
``dt`` seconds become ``trajectory`` movers; a person whose straight motion between two
samples would come closer to an obstacle than their radius (ORCA is a local method: it
may press someone against a corner) stops being present there, so every mover written
keeps its radius clear of every obstacle at every instant.
"""

from __future__ import annotations

import logging
import math
import numbers
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError, check_number
from ..rng import create_rng
from ..roadmap.freespace import obstacle_shape
from ..scene.scene import Mover, Scene
from ..settings import MAX_MAGNITUDE, MAX_RUN_STEPS
from ..typed import FloatArray

__all__ = ["PopulateOptions", "Populated", "populate", "write_scene", "obstacle_union"]

log = logging.getLogger(__name__)

#: Clearance (m) kept between a person's disc and the obstacles by the grid's free cells.
GRID_MARGIN = 0.05
#: A person's waypoint counts as passed within this distance (m).
WAYPOINT_REACHED = 0.5
#: People start at least this far (m) from every query's start.
START_KEEP = 1.0
#: ORCA's time horizon for obstacles (s; RVO2's ``timeHorizonObst``).
ORCA_OBSTACLE_HORIZON = 1.0


@dataclass(frozen=True)
class PopulateOptions:
    """Settings of :func:`populate`.

    Attributes
    ----------
    people : int
    seed : int
    duration : float
        Seconds of walking recorded (from t = 0).
    radius : float
        The people's radius (m).
    speed : float
        Their preferred speed (m/s).
    waypoints : tuple of (x, y), optional
        Walk around these points in turn (each person from a random one, in a random
        direction) instead of between random free points.
    dt : float
        Sampling of the walks (s), ORCA's time step.
    """

    people: int = 10
    seed: int = 1
    duration: float = 60.0
    radius: float = 0.3
    speed: float = 1.0
    waypoints: tuple | None = None
    dt: float = 0.25

    def __post_init__(self):
        if not 1 <= self.people <= 500:
            raise InputError(f"people must be between 1 and 500, got {self.people}")
        for name in ("duration", "radius", "speed", "dt"):
            check_number(name, getattr(self, name))  # positive, at most 1e9: ORCA's arithmetic overflows beyond
        if self.duration / self.dt > MAX_RUN_STEPS:  # named in seconds: dt is no option of `gfuzzy populate`
            raise InputError(f"duration must be at most {MAX_RUN_STEPS * self.dt:g} s ({MAX_RUN_STEPS} steps of {self.dt:g} s), "
                             f"got {self.duration:g}")
        create_rng(self.seed)  # a negative seed is refused here, before the walk
        if self.duration < self.dt:  # one sample is no walk: nobody would be written
            raise InputError(f"duration must be at least one step of {self.dt:g} s, got {self.duration:g}")
        if self.waypoints is not None and len(self.waypoints) < 2:
            raise InputError(f"waypoints must be at least two points, got {len(self.waypoints)}")
        for i, p in enumerate(self.waypoints or ()):  # a NaN used to reach the grid's lookup
            if len(p) != 2 or not all(isinstance(v, numbers.Real) and math.isfinite(v) and abs(v) <= MAX_MAGNITUDE for v in p):
                raise InputError(f"waypoints[{i}] must be two finite numbers of at most {MAX_MAGNITUDE:g} in magnitude, "
                                 f"got {tuple(p)}")


@dataclass(frozen=True)
class Populated:
    """What :func:`populate` made: the movers (``trajectory`` discs), and how many people
    were cut short (their walk stopped where it would have touched an obstacle)."""

    movers: tuple
    cut: int = 0


def obstacle_union(scene: Scene):
    """The scene's static obstacles as one shapely geometry (None without obstacles)."""
    import shapely

    shapes = [g for g in map(obstacle_shape, scene.obstacles) if g is not None]
    return shapely.union_all(shapes) if shapes else None


class _Grid:
    """Free cells of the scene for a disc of ``radius`` and shortest paths on them."""

    def __init__(self, scene: Scene, radius: float, union):
        import shapely
        from scipy import ndimage

        x0, y0, x1, y1 = scene.bounds
        self.res = res = max(0.05, max(x1 - x0, y1 - y0) / 250.0)
        xs = np.arange(x0 + res / 2, x1, res)
        ys = np.arange(y0 + res / 2, y1, res)
        gx, gy = np.meshgrid(xs, ys, indexing="xy")  # (ny, nx)
        keep = radius + GRID_MARGIN
        free = (gx - x0 >= keep) & (x1 - gx >= keep) & (gy - y0 >= keep) & (y1 - gy >= keep)
        if union is not None and free.any():
            # a prepared geometry answers "within keep?" from an index of its edges; a plain
            # distance walks them all, for every cell (and every line of the walk below)
            shapely.prepare(union)
            free[free] = ~shapely.dwithin(union, shapely.points(gx[free], gy[free]), keep)
        lab, n = ndimage.label(free)
        if n == 0:
            raise InputError(f"{scene.source}: no free space for a person of radius {radius:g} m")
        sizes = np.bincount(lab.ravel())[1:]
        self.free = lab == (int(np.argmax(sizes)) + 1)  # the largest connected region
        self.xs, self.ys, self.x0, self.y0 = xs, ys, x0, y0
        self.union, self.radius, self.bounds = union, radius, scene.bounds
        self._graph = None

    def cells(self) -> FloatArray:
        iy, ix = np.nonzero(self.free)
        return np.column_stack([self.xs[ix], self.ys[iy]])

    def index(self, p) -> tuple[int, int]:
        ix = int(np.clip(np.floor((p[0] - self.x0) / self.res), 0, len(self.xs) - 1))
        iy = int(np.clip(np.floor((p[1] - self.y0) / self.res), 0, len(self.ys) - 1))
        return iy, ix

    def _build(self):
        from scipy.sparse import coo_matrix

        ny, nx = self.free.shape
        ids = np.arange(ny * nx).reshape(ny, nx)
        rows, cols, w = [], [], []
        for dy, dx, c in ((0, 1, 1.0), (1, 0, 1.0), (1, 1, math.sqrt(2)), (1, -1, math.sqrt(2))):
            xa, xb = max(0, -dx), nx - max(0, dx)
            a, ia = self.free[: ny - dy, xa:xb], ids[: ny - dy, xa:xb]
            b, ib = self.free[dy:, xa + dx : xb + dx], ids[dy:, xa + dx : xb + dx]
            m = a & b
            rows.append(ia[m])
            cols.append(ib[m])
            w.append(np.full(int(m.sum()), c * self.res))
        r, c_, ww = np.concatenate(rows), np.concatenate(cols), np.concatenate(w)
        self._graph = coo_matrix((np.r_[ww, ww], (np.r_[r, c_], np.r_[c_, r])), shape=(ny * nx, ny * nx)).tocsr()

    def path(self, a, b) -> list:
        """Waypoints from near ``a`` to ``b`` (b last), shortened by straight lines."""
        from scipy.sparse.csgraph import dijkstra

        if self._graph is None:
            self._build()
        ny, nx = self.free.shape
        ia, ib = self.index(a), self.index(b)
        sa, sb = ia[0] * nx + ia[1], ib[0] * nx + ib[1]
        if not (self.free[ia] and self.free[ib]):
            return [np.asarray(b, float)]
        _, pred = dijkstra(self._graph, directed=False, indices=sb, return_predecessors=True)
        if pred[sa] < 0 and sa != sb:
            return [np.asarray(b, float)]
        chain = []
        v = sa
        while v != sb and v >= 0:
            chain.append(np.array([self.xs[v % nx], self.ys[v // nx]]))
            v = pred[v]
        chain.append(np.asarray(b, float))
        return self._shorten(np.asarray(a, float), chain)

    def clear_point(self, p) -> bool:
        """Is a person at ``p`` inside the bounds and clear of the obstacles (by half the
        grid's margin)? A free cell's centre is; a point elsewhere in it need not be on a
        coarse grid (cells of 0.36 m on a 90 m map)."""
        import shapely

        x0, y0, x1, y1 = self.bounds
        keep = self.radius + GRID_MARGIN / 2
        if not (x0 + keep <= p[0] <= x1 - keep and y0 + keep <= p[1] <= y1 - keep):
            return False
        return self.union is None or not shapely.dwithin(self.union, shapely.Point(p), keep)

    def walkable(self, p) -> bool:
        """Is ``p`` in a free cell of the people's region and itself clear (:meth:`clear_point`)?"""
        return bool(self.free[self.index(p)]) and self.clear_point(p)

    def clear_line(self, a, b) -> bool:
        import shapely

        if self.union is None:
            return True
        return not shapely.dwithin(self.union, shapely.LineString([a, b]), self.radius + GRID_MARGIN / 2)

    def _shorten(self, a, chain) -> list:
        out, cur, i = [], a, 0
        while i < len(chain):
            j = len(chain) - 1
            while j > i and not self.clear_line(cur, chain[j]):
                j = max(i, j - max(1, (j - i) // 2)) if j - i > 8 else j - 1
            out.append(chain[j])
            cur, i = chain[j], j + 1
        return out


def _near_walks(union, grid: _Grid, reach: float):
    """The obstacles ``union`` without the outlines that no free cell of the people's
    region comes within ``reach`` of: a polygon all of whose rings are that far is left
    out, and so is such a hole of a polygon (which fills it: nobody can get there). What
    is kept is kept exactly, within the box of the region's cells grown by ``reach``
    (outside it, a polygon is cut along the box, where nobody can come). None when
    nothing is left.

    RVO2 builds its obstacle tree in time that grows with the square of the edges, and an
    agent only ever looks at the obstacles within ``time_horizon_obst * speed + radius``
    of itself: outlines far from every free cell of the people's region (other buildings,
    rooms they cannot enter, the ragged islands of unknown space) cost time and change
    nothing.
    """
    import shapely

    if union is None:
        return None
    iy, ix = np.nonzero(grid.free)
    cells = shapely.multipoints(np.column_stack([grid.xs[ix], grid.ys[iy]]))
    shapely.prepare(cells)
    # a person may stand anywhere in a free cell: half its diagonal more
    d = reach + grid.res * math.sqrt(0.5)
    # and nothing outside the box of the region's cells grown by as much
    box = shapely.box(grid.xs[ix].min() - d, grid.ys[iy].min() - d, grid.xs[ix].max() + d, grid.ys[iy].max() + d)
    kept = []
    for poly in shapely.get_parts(union):
        if poly.geom_type != "Polygon":
            continue
        near = shapely.dwithin(cells, [poly.exterior, *poly.interiors], d)
        if not near.any():
            continue
        poly = shapely.Polygon(poly.exterior, [h for h, n in zip(poly.interiors, near[1:], strict=True) if n])
        kept += [p for p in shapely.get_parts(poly.intersection(box)) if p.geom_type == "Polygon" and not p.is_empty]
    return shapely.MultiPolygon(kept) if kept else None


def _rvo_obstacles(sim, scene: Scene, union) -> None:
    """The obstacles and the bounds' outside as RVO2 polygons (counter-clockwise)."""
    import shapely

    x0, y0, x1, y1 = scene.bounds
    big = max(x1 - x0, y1 - y0)
    walls = [
        [(x0 - big, y0 - big), (x1 + big, y0 - big), (x1 + big, y0), (x0 - big, y0)],
        [(x1, y0 - big), (x1 + big, y0 - big), (x1 + big, y1 + big), (x1, y1 + big)],
        [(x0 - big, y1), (x1 + big, y1), (x1 + big, y1 + big), (x0 - big, y1 + big)],
        [(x0 - big, y0 - big), (x0, y0 - big), (x0, y1 + big), (x0 - big, y1 + big)],
    ]
    polys = [shapely.Polygon(w) for w in walls]
    if union is not None:
        polys += list(getattr(union, "geoms", [union]))
    for poly in polys:
        # exterior counter-clockwise, holes clockwise: RVO2 keeps agents out of the first and
        # inside the second (the free rooms of a map whose walls and unknown cells enclose them)
        poly = shapely.geometry.polygon.orient(poly, 1.0)
        for ring in (poly.exterior, *poly.interiors):
            pts = [(float(x), float(y)) for x, y in list(ring.coords)[:-1]]
            if len(pts) >= 2:
                sim.add_obstacle(pts)
    sim.process_obstacles()


def populate(scene: Scene, options: PopulateOptions | None = None) -> Populated:
    """Walking people for ``scene`` (its movers are kept; the people are new movers).

    Parameters
    ----------
    scene : Scene
    options : PopulateOptions, optional

    Returns
    -------
    Populated

    Raises
    ------
    InputError
        No free space for the people, too many people for it, or a waypoint that is not
        free.
    """
    from .humans import _rvo, preferred_velocity

    o = options or PopulateOptions()
    rng = create_rng(o.seed)
    union = obstacle_union(scene)
    grid = _Grid(scene, o.radius, union)
    cells = grid.cells()
    starts_q = np.array([q.start[:2] for q in scene.queries], dtype=float).reshape(-1, 2)
    usable = cells
    if len(starts_q):
        far = np.min(np.hypot(*(cells[:, None, :] - starts_q[None, :, :]).transpose(2, 0, 1)), axis=1) >= START_KEEP
        usable = cells[far] if far.any() else cells
    wps = None
    if o.waypoints is not None:
        wps = np.asarray(o.waypoints, dtype=float).reshape(-1, 2)
        x0, y0, x1, y1 = scene.bounds
        for i, p in enumerate(wps):
            # outside the bounds first: the grid's lookup clamps a point to its border cells
            if not (x0 <= p[0] <= x1 and y0 <= p[1] <= y1):
                raise InputError(f"waypoints[{i}] ({p[0]:g}, {p[1]:g}) lies outside the scene's bounds "
                                 f"[{x0:g}, {y0:g}, {x1:g}, {y1:g}]")  # fmt: skip
            if not grid.walkable(p):  # its cell's centre may be free, it not
                raise InputError(f"waypoints[{i}] ({p[0]:g}, {p[1]:g}) is not free for a person of radius {o.radius:g} m "
                                 f"(clear of the obstacles and the bounds by {o.radius + GRID_MARGIN / 2:g} m)")  # fmt: skip

    free_point = _FreePoints(usable, grid, rng)
    starts_a, goals, order = _place(scene, o, grid, free_point, wps, rng)
    pyrvo = _rvo()
    sim = pyrvo.RVOSimulator(o.dt, 5.0, 10, 3.0, ORCA_OBSTACLE_HORIZON, o.radius + 0.01, o.speed)
    ids = [sim.add_agent((float(x), float(y))) for x, y in starts_a]
    # what an agent can see of the obstacles: ORCA's horizon at full speed, its radius,
    # and two cells (a person is anywhere within a free cell, or pushed a little out of it)
    reach = o.radius + 0.01 + ORCA_OBSTACLE_HORIZON * o.speed + 2 * grid.res
    _rvo_obstacles(sim, scene, _near_walks(union, grid, reach))
    routes = [grid.path(starts_a[i], goals[i]) for i in range(o.people)]
    n = int(math.ceil(o.duration / o.dt - 1e-9)) + 1
    track = np.empty((o.people, n, 2))
    track[:, 0] = starts_a
    pos = starts_a.copy()
    for k in range(1, n):
        targets = np.empty_like(pos)
        for i in range(o.people):
            route = routes[i]
            while len(route) > 1 and (np.hypot(*(route[0] - pos[i])) < WAYPOINT_REACHED
                                      or grid.clear_line(pos[i], route[1])):  # fmt: skip
                route.pop(0)
            if np.hypot(*(route[-1] - pos[i])) < o.radius:  # arrived: a new goal
                if wps is None:
                    goals[i] = free_point()
                else:
                    j, d = order[i]
                    j = (j + d) % len(wps)
                    order[i] = (j, d)
                    goals[i] = wps[j].copy()
                routes[i] = route = grid.path(pos[i], goals[i])
            targets[i] = route[0]
        pref = preferred_velocity(pos, targets, o.speed)
        for i, a in enumerate(ids):
            sim.set_agent_pref_velocity(a, (float(pref[i, 0]), float(pref[i, 1])))
        sim.do_step()
        for i, a in enumerate(ids):
            p = sim.get_agent_position(a)
            pos[i] = (p.x, p.y)
        track[:, k] = pos

    movers, cut = _movers(scene, o, track, union)
    if cut:
        log.info("%d of %d people stopped where they would have touched an obstacle", cut, o.people)
    return Populated(tuple(movers), cut)


class _FreePoints:
    """Random free points: a free cell's centre, jittered within the cell (the centre
    itself when the jittered point is not clear of the obstacles)."""

    def __init__(self, cells: FloatArray, grid: _Grid, rng: np.random.Generator):
        self.cells, self.grid, self.rng = cells, grid, rng

    def __call__(self) -> FloatArray:
        c = self.cells[self.rng.integers(len(self.cells))]
        p = c + self.rng.uniform(-0.4, 0.4, 2) * self.grid.res
        return p if self.grid.clear_point(p) else c


def _place(scene: Scene, o: PopulateOptions, grid: _Grid, free_point, wps, rng):
    """The people's starts (K, 2), first goals (list) and, with waypoints, (index, direction)."""
    starts: list = []
    for _ in range(o.people):
        for _try in range(2000):
            p = free_point() if wps is None else wps[rng.integers(len(wps))] + rng.normal(0, 0.5, 2)
            if not grid.walkable(p):
                continue
            if all(np.hypot(*(p - q)) >= 2 * o.radius + 0.1 for q in starts):
                starts.append(p)
                break
        else:
            area = float(grid.free.sum()) * grid.res**2
            gap = 2 * (o.radius + GRID_MARGIN)
            raise InputError(
                f"{scene.source}: no room for {o.people} people of radius {o.radius:g} m in the largest "
                f"free region they can walk ({area:.1f} m²; they cannot pass a gap narrower than {gap:.2f} m): "
                f"give fewer --people or a smaller --radius"
            )
    order: list = [None] * o.people
    goals = []
    for i in range(o.people):
        if wps is None:
            goals.append(free_point())
        else:
            k = int(rng.integers(len(wps)))
            order[i] = (k, 1 if rng.random() < 0.5 else -1)
            goals.append(wps[k].copy())
    return np.array(starts), goals, order


def _movers(scene: Scene, o: PopulateOptions, track: FloatArray, union) -> tuple[list, int]:
    """``trajectory`` movers of the tracks (K, n, 2), each cut before its first motion that
    would come closer than its radius to an obstacle or the bounds; (movers, people cut)."""
    import shapely

    n = track.shape[1]
    times = np.arange(n) * o.dt
    movers, cut = [], 0
    taken = {m.name for m in scene.movers}
    x0, y0, x1, y1 = scene.bounds
    for i in range(o.people):
        tr = track[i]
        segs = shapely.linestrings(np.stack([tr[:-1], tr[1:]], axis=1))
        ok = np.ones(len(tr) - 1, dtype=bool)
        if union is not None:  # exact distances, for the motions the index finds close
            close = shapely.dwithin(union, segs, o.radius)
            ok[close] &= shapely.distance(segs[close], union) >= o.radius
        inside = (tr[:, 0] - x0 >= o.radius) & (x1 - tr[:, 0] >= o.radius) & (tr[:, 1] - y0 >= o.radius) & (
            y1 - tr[:, 1] >= o.radius)  # fmt: skip
        ok &= inside[:-1] & inside[1:]
        last = len(tr) if ok.all() else int(np.argmin(ok)) + 1  # rows kept: up to the bad segment's start
        if last < len(tr):
            cut += 1
        if last < 2:
            continue
        name = f"person{i}"
        while name in taken:
            name += "_"
        taken.add(name)
        rows = np.column_stack([times[:last], np.round(tr[:last], 6)])
        movers.append(Mover(name, "disc", o.radius, (0.0, 0.0), trajectory=rows))
    return movers, cut


def scene_copy(source: str | os.PathLike, out: str | os.PathLike) -> dict:
    """The scene file ``source`` as a document to write at ``out``: relative ``file`` paths of
    its obstacles (meshes, maps) rewritten so that they still point at the same files from
    ``out``'s folder (which must then hold them: a scene's files lie in its folder). Cheap:
    ``gfuzzy populate`` asks before it walks the people (it said so after seconds of work).

    Raises
    ------
    InputError
        ``out``'s folder does not hold a file the scene refers to.
    """
    from ..scene.yamldoc import _load_yaml as load_yaml
    from ..scene.yamldoc import leaves_folder

    src = Path(source)
    doc = load_yaml(src.read_text(), str(src))
    here, there = src.resolve().parent, Path(out).resolve().parent
    for item in doc.get("obstacles") or []:
        if isinstance(item, dict):
            for spec in item.values():
                if isinstance(spec, dict):
                    for key in ("file", "image", "yaml"):
                        f = spec.get(key)
                        if isinstance(f, str) and not os.path.isabs(f):
                            rel = os.path.relpath(here / f, there)
                            if leaves_folder(rel):  # the loader keeps a scene's files in its folder
                                raise InputError(
                                    f"{out}: the scene refers to {f}, which would lie outside the new file's "
                                    f"folder: write it in {here} or a folder above {f}"
                                )
                            spec[key] = rel
    return doc


def write_scene(source: str | os.PathLike, result: Populated, out: str | os.PathLike, doc: dict | None = None) -> None:
    """Write a copy of the scene file ``source`` with ``result``'s movers added, atomically:
    ``doc``, :func:`scene_copy`'s document (made here when not given), its every key kept.

    Raises
    ------
    InputError
        ``out``'s folder does not hold a file the scene refers to.
    """

    from ..atomic import write_atomic
    from ..scene.yamldoc import dump_yaml

    src = Path(source)
    doc = scene_copy(source, out) if doc is None else dict(doc)
    movers = list(doc.get("movers") or [])
    for m in result.movers:
        movers.append({"name": m.name, "disc": float(m.radius),
                       "trajectory": [[float(v) for v in row] for row in m.trajectory]})  # fmt: skip
    doc["movers"] = movers
    head = f"# {src.name} with {len(result.movers)} walking people added by gfuzzy populate\n"
    write_atomic(out, head + dump_yaml(doc, sort_keys=False, default_flow_style=None, width=120))
