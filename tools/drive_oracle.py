"""An independent oracle of a differential drive's static solvability: a lattice search.

    python tools/drive_oracle.py SCENE.yaml [--query NAME] [-o TRAJ.json]

It shares no code with gfuzzy's planner: a hybrid A* over (x, y, heading) with the drive's
own moves only (turns in place by one heading bin, straight steps along the heading,
backwards too with ``reverse``), cells of ``cell`` metres and ``bins`` headings for the
duplicates, and collision against a distance field of the scene's static obstacles
(shapely rasterises them at ``res`` metres; scipy's exact Euclidean distance transform).
Movers are ignored: the question is whether a static path exists. The lattices of
``LADDER`` are tried in turn, coarse (5 degree headings, 4 cm cells: open rooms, a few
seconds) to fine (half a degree, 1 cm cells and a 2.5 mm field: passages with 1-2 cm per
side); ``-o`` writes the path as a trajectory file that ``gfuzzy check SCENE FILE`` reads.

**Conservative.** A pose is accepted when every sample of the body's outline (``res``
apart) lies in a cell whose distance to the nearest blocked cell is at least the robot's
clearance plus ``pad``: the rasterisation (a point of an obstacle lies in a blocked cell;
a sample is within half a diagonal of its cell's centre: one diagonal), half the outline's
sample spacing, half of a heading bin swept by the circumradius or half a step, and
``margin``. A body whose outline stays clear while it moves continuously keeps its inside
clear (an obstacle would have to cross the outline), and the start is checked exactly
(shapely). The goal is reached by an analytic join from poses within ``join`` metres:
turn to face the goal's position (or away from it, with ``reverse``), drive there, turn to
the goal's heading, each sampled as the search's moves are. The path found is written as a
trajectory (``[t, x, y, heading]`` rows, at vmax and the turning rate) that
:func:`gfuzzy.check.check.check_trajectory` should accept on the scene without movers:
:func:`solve` returns it only when it does (``verified``), so a found path is a proof.
Not finding one proves nothing (the lattice is a subset of the drive's motions; the
search is capped at ``max_nodes``).
"""

from __future__ import annotations

import argparse
import dataclasses
import heapq
import json
import math
import sys
import time
from pathlib import Path

import numba
import numpy as np
import shapely
from scipy import ndimage

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.check.check import check_trajectory  # noqa: E402
from gfuzzy.scene.scene import Box, Disc, Polygon, load_scene  # noqa: E402


@dataclasses.dataclass(frozen=True)
class OracleOptions:
    res: float = 0.005  # distance field's cell, m
    cell: float = 0.02  # duplicates' cell, m
    step: float = 0.02  # straight step, m
    bins: int = 360  # headings
    margin: float = 0.002  # kept on top of the clearance, m
    join: float = 1.5  # analytic join to the goal within this distance, m
    max_nodes: int = 2_000_000
    weight: float = 2.0  # A* heuristic weight


# --------------------------------------------------------------------------- geometry


def obstacle_geometry(scene):
    """The union of the scene's static obstacles (shapely), map grids as their rectangles."""
    parts = []
    for ob in scene.obstacles:
        if isinstance(ob, Disc):
            parts.append(shapely.Point(ob.center).buffer(ob.radius, quad_segs=64))
        elif isinstance(ob, Box):
            parts.append(shapely.Polygon(ob.vertices()))
        elif isinstance(ob, Polygon):
            parts.append(shapely.Polygon(ob.points, [np.asarray(h) for h in ob.holes]))
        else:  # an occupancy grid (MapObstacle)
            parts.extend(shapely.box(*r) for r in np.asarray(ob.rects))
    return shapely.union_all(parts) if parts else shapely.GeometryCollection()


def body_polygon(robot):
    """The robot's body in its own frame (x forward), shapely."""
    if robot.shape == "disc":
        return shapely.Point(0, 0).buffer(robot.radius, quad_segs=64)
    if robot.shape == "box":
        hl, hw = 0.5 * robot.size[0], 0.5 * robot.size[1]
        return shapely.box(-hl, -hw, hl, hw)
    return shapely.Polygon(robot.footprint)


def outline_samples(robot, spacing: float) -> np.ndarray:
    """(m, 2) points along the body's outline at most ``spacing`` apart (own frame)."""
    if robot.shape == "disc":
        n = max(16, math.ceil(2 * math.pi * robot.radius / spacing))
        a = np.arange(n) * 2 * math.pi / n
        return robot.radius * np.stack([np.cos(a), np.sin(a)], 1)
    ring = np.asarray(body_polygon(robot).exterior.coords)
    out = []
    for p, q in zip(ring[:-1], ring[1:], strict=True):
        n = max(1, math.ceil(np.linalg.norm(q - p) / spacing))
        out.append(p + (q - p) * (np.arange(n)[:, None] / n))
    return np.concatenate(out)


def distance_field(scene, res: float) -> tuple[np.ndarray, tuple[float, float]]:
    """Distance (m) from each cell's centre to the nearest blocked cell's centre, the
    clearance taken off for obstacles (not for the bounds); cells outside the bounds are
    blocked. Returns the field (nx, ny) and its origin (the lower-left corner)."""
    x0, y0, x1, y1 = scene.bounds
    pad = 2
    nx, ny = math.ceil((x1 - x0) / res) + 2 * pad, math.ceil((y1 - y0) / res) + 2 * pad
    ox, oy = x0 - pad * res, y0 - pad * res
    cx = ox + (np.arange(nx) + 0.5) * res
    cy = oy + (np.arange(ny) + 0.5) * res
    gx, gy = np.meshgrid(cx, cy, indexing="ij")
    half = res * math.sqrt(0.5) + 1e-9
    outside = (gx < x0 + half) | (gx > x1 - half) | (gy < y0 + half) | (gy > y1 - half)
    geom = obstacle_geometry(scene)
    blocked = np.zeros((nx, ny), bool)
    if not geom.is_empty:
        shapely.prepare(geom)
        bx0, by0, bx1, by1 = geom.bounds
        near = (
            (gx > bx0 - 2 * half)
            & (gx < bx1 + 2 * half)
            & (gy > by0 - 2 * half)
            & (gy < by1 + 2 * half)
        )
        idx = np.nonzero(near.ravel())[0]
        hit = shapely.dwithin(geom, shapely.points(gx.ravel()[idx], gy.ravel()[idx]), half)
        blocked.ravel()[idx[hit]] = True
    d_obs = (
        ndimage.distance_transform_edt(~blocked, sampling=res)
        if blocked.any()
        else np.full((nx, ny), 1e9)
    )
    d_bnd = ndimage.distance_transform_edt(~outside, sampling=res)
    return np.minimum(d_obs - scene.robot.clearance, d_bnd), (ox, oy)


# --------------------------------------------------------------------------- search


@numba.njit(cache=True)
def _free(field, ox, oy, res, pts_c, pts_s, x, y, k, need):
    """Whether every outline sample at pose (x, y, heading bin k) has ``need`` clearance."""
    nx, ny = field.shape
    c, s = pts_c[k], pts_s[k]
    for m in range(c.shape[0]):
        i = int((x + c[m] - ox) / res)
        j = int((y + s[m] - oy) / res)
        if i < 0 or j < 0 or i >= nx or j >= ny or field[i, j] < need:
            return False
    return True


@numba.njit(cache=True)
def _rot_free(field, ox, oy, res, pc, ps, x, y, k0, dk, n, bins, need):
    """Turn in place from bin k0 by n bins in direction dk (every bin passed checked)."""
    for t in range(1, n + 1):
        if not _free(field, ox, oy, res, pc, ps, x, y, (k0 + dk * t) % bins, need):
            return False
    return True


@numba.njit(cache=True)
def _line_free(field, ox, oy, res, pc, ps, x, y, k, dx, dy, length, step, need):
    n = int(math.ceil(length / step))
    for t in range(1, n + 1):
        f = min(t * step, length)
        if not _free(field, ox, oy, res, pc, ps, x + dx * f, y + dy * f, k, need):
            return False
    return True


@numba.njit(cache=True)
def _search(
    field,
    ox,
    oy,
    res,
    pc,
    ps,
    heads,
    start,
    goal_xy,
    goal_k,
    cell,
    step,
    reverse,
    need,
    join,
    weight,
    t_step,
    t_turn,
    max_nodes,
    bins,
):
    """Hybrid A*: returns (node arrays, the last node, its join mode) or last -1."""
    nx, ny = field.shape
    cx = int(nx * res / cell) + 2
    cy = int(ny * res / cell) + 2
    seen = np.zeros(cx * cy * bins, np.bool_)
    X = np.empty(max_nodes)
    Y = np.empty(max_nodes)
    K = np.empty(max_nodes, np.int32)
    P = np.empty(max_nodes, np.int64)
    G = np.empty(max_nodes)
    X[0], Y[0], K[0], P[0], G[0] = start[0], start[1], 0, -1, 0.0
    n = 1
    heap = [(0.0, 0)]
    gx, gy = goal_xy[0], goal_xy[1]
    while len(heap) > 0:
        f, u = heapq.heappop(heap)
        x, y, k = X[u], Y[u], K[u]
        key = ((int((x - ox) / cell)) * cy + int((y - oy) / cell)) * bins + k
        if seen[key]:
            continue
        seen[key] = True
        d = math.hypot(gx - x, gy - y)
        if d <= join:
            mode = _try_join(
                field,
                ox,
                oy,
                res,
                pc,
                ps,
                heads,
                x,
                y,
                k,
                gx,
                gy,
                goal_k,
                d,
                step,
                reverse,
                need,
                bins,
            )
            if mode >= 0:
                return X[:n], Y[:n], K[:n], P[:n], u, mode
        for mv in range(4):
            if mv < 2:
                kk = (k + (1 if mv == 0 else bins - 1)) % bins
                xx, yy, cost = x, y, t_turn
            else:
                if mv == 3 and not reverse:
                    continue
                sg = 1.0 if mv == 2 else -1.0
                kk = k
                xx, yy, cost = (
                    x + sg * step * math.cos(heads[k]),
                    y + sg * step * math.sin(heads[k]),
                    t_step,
                )
            key2 = ((int((xx - ox) / cell)) * cy + int((yy - oy) / cell)) * bins + kk
            if xx < ox or yy < oy or seen[key2]:
                continue
            if mv >= 2:
                mid = 0.5
                if not _free(
                    field, ox, oy, res, pc, ps, x + (xx - x) * mid, y + (yy - y) * mid, kk, need
                ):
                    continue
            if not _free(field, ox, oy, res, pc, ps, xx, yy, kk, need):
                continue
            if n >= max_nodes:
                return X[:n], Y[:n], K[:n], P[:n], -1, -1
            X[n], Y[n], K[n], P[n], G[n] = xx, yy, kk, u, G[u] + cost
            h = weight * math.hypot(gx - xx, gy - yy) / step * t_step
            heapq.heappush(heap, (G[n] + h, n))
            n += 1
    return X[:n], Y[:n], K[:n], P[:n], -1, -1


@numba.njit(cache=True)
def _bin_of(h, heads, bins):
    d = (h - heads[0]) % (2 * math.pi)
    return int(round(d / (2 * math.pi / bins))) % bins


@numba.njit(cache=True)
def _turn_bins(k0, k1, bins):
    """Shorter turn from bin k0 to k1: (direction, count)."""
    up = (k1 - k0) % bins
    return (1, up) if up <= bins - up else (-1, bins - up)


@numba.njit(cache=True)
def _try_join(
    field, ox, oy, res, pc, ps, heads, x, y, k, gx, gy, goal_k, d, step, reverse, need, bins
):
    """Analytic join: 0 forward, 1 backward, -1 none. The facing heading is a bin's, the
    drive then along the exact direction to the goal (checked at the nearest bin)."""
    if d < 1e-9:
        dk, nt = _turn_bins(k, goal_k, bins)
        return 0 if _rot_free(field, ox, oy, res, pc, ps, x, y, k, dk, nt, bins, need) else -1
    face = math.atan2(gy - y, gx - x)
    for mode in range(2 if reverse else 1):
        h = face if mode == 0 else face + math.pi
        kf = _bin_of(h, heads, bins)
        if not _line_free(
            field, ox, oy, res, pc, ps, x, y, kf, (gx - x) / d, (gy - y) / d, d, 0.5 * step, need
        ):
            continue
        dk, nt = _turn_bins(kf, goal_k, bins)
        if not _rot_free(field, ox, oy, res, pc, ps, gx, gy, kf, dk, nt, bins, need):
            continue
        dk, nt = _turn_bins(k, kf, bins)
        if _rot_free(field, ox, oy, res, pc, ps, x, y, k, dk, nt, bins, need):
            return mode
    return -1


# --------------------------------------------------------------------------- the answer


def _primitives(X, Y, K, P, last, heads, start, goal, mode):
    """The path as poses where the drive changes from turning to driving: [(x, y, h), ...]."""
    chain = []
    u = last
    while u >= 0:
        chain.append(u)
        u = P[u]
    chain.reverse()
    poses = [(float(start[0]), float(start[1]), float(start[2]))]
    for a, b in zip(chain[:-1], chain[1:], strict=True):
        if K[a] != K[b]:  # a turn: a new pose at the same place
            x, y, _ = poses[-1]
            poses.append((x, y, float(heads[K[b]])))
        else:  # a step: exact along the heading from the previous pose
            x, y, h = poses[-1]
            s = math.copysign(
                math.hypot(X[b] - X[a], Y[b] - Y[a]),
                (X[b] - X[a]) * math.cos(h) + (Y[b] - Y[a]) * math.sin(h),
            )
            poses.append((x + s * math.cos(h), y + s * math.sin(h), h))
    x, y, h = poses[-1]
    d = math.hypot(goal[0] - x, goal[1] - y)
    if d > 0:
        face = math.atan2(goal[1] - y, goal[0] - x) + (math.pi if mode == 1 else 0.0)
        poses.append((x, y, face))
        poses.append((float(goal[0]), float(goal[1]), face))
    poses.append((float(goal[0]), float(goal[1]), float(goal[2])))
    return _merge(poses)


def _merge(poses):
    """Drop repeated poses and join runs of turns and runs of steps."""
    out = [poses[0]]
    for p in poses[1:]:
        q = out[-1]
        if p == q:
            continue
        if len(out) >= 2:
            o = out[-2]
            turn_run = o[:2] == q[:2] == p[:2]
            step_run = o[2] == q[2] == p[2] and o[:2] != q[:2]
            if turn_run or (step_run and _same_way(o, q, p)):
                out[-1] = p
                continue
        out.append(p)
    return out


def _same_way(o, q, p) -> bool:
    h = q[2]
    a = (q[0] - o[0]) * math.cos(h) + (q[1] - o[1]) * math.sin(h)
    b = (p[0] - q[0]) * math.cos(h) + (p[1] - q[1]) * math.sin(h)
    return a * b > 0


def to_waypoints(poses, robot, t0: float) -> np.ndarray:
    """Rows ``[t, x, y, heading]`` at 0.999 of vmax and of the turning rate; the heading
    unwrapped so each turn takes the shorter way."""
    r = robot.circumradius
    w = robot.vmax / r if robot.wmax is None else min(robot.wmax, robot.vmax / r)
    rows = [(t0, *poses[0])]
    for p in poses[1:]:
        t, x, y, h = rows[-1]
        dh = (p[2] - h + math.pi) % (2 * math.pi) - math.pi
        dt = max(math.hypot(p[0] - x, p[1] - y) / robot.vmax, abs(dh) / w) / 0.999
        rows.append((t + dt, p[0], p[1], h + dh if p[:2] == (x, y) else h))
    return np.array(rows)


#: the lattices tried in turn: coarse first (open rooms), then fine, then finer (narrow passages)
LADDER = (
    OracleOptions(bins=72, cell=0.04, step=0.04, max_nodes=1_000_000),
    OracleOptions(),
    OracleOptions(res=0.0025, cell=0.01, step=0.01, bins=720, max_nodes=3_000_000, weight=3.0),
)


def solve(scene, query, ladder=LADDER) -> dict:
    """The oracle on one query, each lattice of ``ladder`` in turn until one finds a path
    that the check accepts: ``{"found", "verified", "waypoints", "nodes", "reason",
    "seconds", "lattice"}`` (``lattice`` the index of the one that found it)."""
    c0 = time.process_time()
    out = {}
    for i, opts in enumerate(ladder):
        out = _solve_one(scene, query, opts)
        out["lattice"] = i
        if out["verified"]:
            break
    out["seconds"] = time.process_time() - c0
    return out


def _solve_one(scene, query, opts: OracleOptions) -> dict:
    """One lattice's search (:func:`solve`)."""
    robot = scene.robot
    static = dataclasses.replace(scene, movers=())
    out = {"found": False, "verified": False, "waypoints": None, "reason": "", "seconds": 0.0}
    start = np.asarray(query.start, float)
    goal = np.asarray(query.goal, float)
    if len(start) == 2:
        start, goal = np.append(start, 0.0), np.append(goal, 0.0)
    field, (ox, oy) = distance_field(scene, opts.res)
    r = robot.circumradius
    dtheta = 2 * math.pi / opts.bins
    sp = opts.res
    need = (
        opts.res * math.sqrt(2) + 0.5 * sp + max(0.5 * r * dtheta, 0.25 * opts.step) + opts.margin
    )
    local = outline_samples(robot, sp)
    heads = start[2] + np.arange(opts.bins) * dtheta
    pc = np.stack([np.cos(h) * local[:, 0] - np.sin(h) * local[:, 1] for h in heads])
    ps = np.stack([np.sin(h) * local[:, 0] + np.cos(h) * local[:, 1] for h in heads])
    w = robot.vmax / r if robot.wmax is None else min(robot.wmax, robot.vmax / r)
    goal_k = int(round(((goal[2] - start[2]) % (2 * math.pi)) / dtheta)) % opts.bins
    X, Y, K, P, last, mode = _search(
        field,
        ox,
        oy,
        opts.res,
        pc,
        ps,
        heads,
        start[:2],
        goal[:2],
        goal_k,
        opts.cell,
        opts.step,
        bool(robot.reverse),
        need,
        opts.join,
        opts.weight,
        opts.step / robot.vmax,
        dtheta / w,
        opts.max_nodes,
        opts.bins,
    )
    out["nodes"] = int(len(X))
    if last >= 0:
        poses = _primitives(X, Y, K, P, last, heads, start, goal, mode)
        wp = to_waypoints(poses, robot, query.t0)
        out["found"] = True
        out["waypoints"] = wp
        rep = check_trajectory(static, wp, query)
        out["verified"] = bool(rep.valid)
        out["reason"] = "" if rep.valid else str(rep.reason)
    else:
        out["reason"] = "cap" if len(X) >= opts.max_nodes else "exhausted"
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("--query")
    ap.add_argument("-o", "--out", help="write the path as a trajectory JSON")
    ap.add_argument(
        "--bins", type=int, help="one lattice of this many headings (default: the ladder)"
    )
    ap.add_argument("--res", type=float, default=OracleOptions.res)
    args = ap.parse_args(argv)
    scene = load_scene(args.scene)
    q = scene.query(args.query) if args.query else scene.queries[0]
    ladder = (
        LADDER
        if args.bins is None
        else (dataclasses.replace(OracleOptions(), bins=args.bins, res=args.res),)
    )
    res = solve(scene, q, ladder)
    print(
        f"{q.name}: found {res['found']} verified {res['verified']} nodes {res['nodes']} "
        f"cpu {res['seconds']:.2f} s {res['reason']}"
    )
    if args.out and res["found"]:
        wp = res["waypoints"]
        doc = {
            "version": 1,
            "scene": scene.name,
            "query": q.name,
            "status": "solved",
            "message": "tools/drive_oracle.py",
            "duration": float(wp[-1, 0] - wp[0, 0]),
            "waypoints": wp.tolist(),
        }
        Path(args.out).write_text(json.dumps(doc))
    return 0 if res["verified"] else 1


if __name__ == "__main__":
    sys.exit(main())
