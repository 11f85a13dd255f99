"""The movers on the time grid: where they are, and which robot poses they make unsafe.

:class:`MoverField` samples every mover at ``t_n = t0 + n * dt`` and answers the safety
questions of the safe-interval search (:mod:`gfuzzy.timespace.timespace`): which (point, step) pairs
are unsafe (``unsafe_pairs``: a broad phase on chunks of steps, then the exact distances;
the numpy reference, or the compiled kernel of :mod:`gfuzzy.timespace.movers_kernel` when the
``compiled`` flag is set), the same answer as safe intervals (``safe_intervals``, always
compiled: what the compiled search consumes), and whether one motion is safe over a whole
step (``motion_safe``). The safety rule itself (the margin
``(vmax + v_mover) * dt / 2 + clearance``) is explained in :mod:`gfuzzy.timespace.timespace`.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from ..collision.geometry import metric_distance, mover_distance
from ..collision.shapes import shape_of
from ..poses import interpolate_segment
from ..scene.scene import Robot, Scene
from ..typed import BoolArray, FloatArray, IntArray

__all__ = ["MoverField", "CHUNK", "whole_windows"]

#: Steps per chunk of the movers' broad phase.
CHUNK = 8

#: Metres a point on a group's segment may lie from its evenly spaced place for phase 3 of
#: :meth:`MoverField.unsafe_pairs` to examine only the points in reach of a mover (the
#: compiled kernel keeps the same value).
EVEN_TOL = 1e-9

#: Up to this many (group, chunk, mover) box tests the compiled kernel tests them all;
#: above, it finds the overlapping boxes through a grid (:func:`gfuzzy.timespace.movers_kernel.grid_candidates`).
DENSE_BROAD_PHASE = 2_000_000


def _uneven(tt: FloatArray, seg2: FloatArray, ptr: IntArray, gid: IntArray, sizes: IntArray):
    """(g,) True for each group whose points are not evenly spaced on its segment (an edge's
    split points are; a re-timed chain that accelerates is not): phase 3's shortcut of
    :meth:`MoverField.unsafe_pairs` holds for evenly spaced points only. ``tt`` (k,) is each
    point's place along its group's segment (0 to 1), ``seg2`` (g,) the segments' squared lengths."""
    length = np.sqrt(seg2)
    place = (np.arange(len(tt)) - ptr[gid]) * (length / np.maximum(sizes - 1, 1))[gid]
    return np.maximum.reduceat(np.abs(tt * length[gid] - place), ptr[:-1]) > EVEN_TOL


def whole_windows(ptr: IntArray, lo: IntArray, hi: IntArray):
    """:meth:`MoverField.safe_intervals` of a field without movers: every point's window
    ``lo..hi`` of its group is one interval (none when empty), as :func:`gfuzzy.timespace.movers_kernel.safe_runs`
    finds in a table of safe steps, without the table."""
    sizes = np.diff(ptr)
    lo_n, hi_n = np.repeat(lo, sizes), np.repeat(hi, sizes)
    some = lo_n <= hi_n
    sp = np.zeros(len(lo_n) + 1, dtype=np.int64)
    np.cumsum(some, out=sp[1:])
    return lo_n[some], hi_n[some], sp


class MoverField:
    """The movers sampled on the time grid ``t_n = t0 + n * dt``, ``n = 0..steps``.

    Parameters
    ----------
    scene : Scene
    t0, dt : float
    steps : int
        Horizon in steps.
    vrobot : float
        Bound on the speed of any point of the robot (vmax).
    clearance : float, optional
        Distance kept from every present mover (default: the scene's
        ``robot.mover_clearance``); it is added to every entry of :attr:`margin`.

    Attributes
    ----------
    margin : (movers, steps + 1) float
        Smallest robot-mover distance at which a point is safe at a step.

    Notes
    -----
    Memory is about ``32 * movers * steps`` bytes.
    """

    def __init__(
        self, scene: Scene, t0: float, dt: float, steps: int, vrobot: float, clearance: float | None = None
    ):
        self.robot: Robot = scene.robot
        self.keep = float(scene.robot.mover_clearance if clearance is None else clearance)
        self.vrobot = float(vrobot)
        self.movers = scene.movers
        self.t0, self.dt, self.steps = float(t0), float(dt), int(steps)
        n = self.steps + 1
        m = len(self.movers)
        times = self.t0 + self.dt * np.arange(n)
        self.times = times
        self.xy = np.empty((m, n, 2))
        self.present = np.zeros((m, n), dtype=bool)
        self.margin = np.empty((m, n))
        half = 0.5 * self.dt
        straight = _straight_samples(self.movers, times, half)
        if straight is not None:  # all walk straight (a navigator's predictions): no loop over them
            self.xy, self.present, speed = straight
            self.margin[:] = (vrobot + speed) * half + self.keep
        for i, mv in enumerate(self.movers if straight is None else ()):
            ta, tb = mv.time_range
            tc = np.clip(times, ta, tb)
            self.xy[i], _ = mv.state(tc)
            self.present[i] = (times + half >= ta) & (times - half <= tb)
            self.margin[i] = (vrobot + _local_speed(mv, times, half)) * half + self.keep
        self._boxes()
        self.evaluations = 0
        self._extent = np.array([mv.extent for mv in self.movers])
        self._is_disc = np.array([mv.shape == "disc" for mv in self.movers], dtype=bool)
        self._radius = np.array([mv.radius for mv in self.movers])
        self._size = np.array([mv.size for mv in self.movers], dtype=float).reshape(-1, 2)
        self._inner = np.where(self._is_disc, self._radius, 0.5 * self._size.min(axis=1, initial=np.inf))
        #: Phases 2 and 3 of unsafe_pairs compiled (gfuzzy.timespace.search_kernel); the same answers.
        self.compiled = False

    def _boxes(self) -> None:
        """The broad phase's boxes (:attr:`bbox`, :attr:`nc`) from the samples."""
        m, n = self.xy.shape[0], self.steps + 1
        # broad phase: per mover and chunk, the box of reference points inflated by reach
        nc = (n + CHUNK - 1) // CHUNK
        pad = nc * CHUNK - n
        reach = (
            np.array([mv.extent for mv in self.movers]).reshape(m, 1)
            + self.robot.circumradius
            + self.margin.max(axis=1, initial=0.0, keepdims=True)
        )
        x = np.pad(self.xy[..., 0], ((0, 0), (0, pad)), mode="edge").reshape(m, nc, CHUNK)
        y = np.pad(self.xy[..., 1], ((0, 0), (0, pad)), mode="edge").reshape(m, nc, CHUNK)
        pres = np.pad(self.present, ((0, 0), (0, pad))).reshape(m, nc, CHUNK)
        big = np.inf
        self.bbox = np.stack(
            [
                np.where(pres, x, big).min(-1) - reach,
                np.where(pres, y, big).min(-1) - reach,
                np.where(pres, x, -big).max(-1) + reach,
                np.where(pres, y, -big).max(-1) + reach,
            ],
            axis=-1,
        )  # (m, nc, 4); empty (inf/-inf) where absent
        self.nc = nc
        self._bbox_keep = self.keep  # the clearance the boxes were built with (a caller may lower keep)

    def prefix(self, steps: int) -> MoverField:
        """This field over its first ``steps`` steps only: the field ``MoverField(scene, t0,
        dt, steps, vrobot, clearance)`` would build, equal to the last bit (every sample and
        margin depends on its own time only; the boxes are built again), without sampling
        the movers again. A field a caller changed (``keep``) is not to be cut."""
        if not 0 <= steps <= self.steps:
            raise ValueError(f"a prefix of {steps} steps of a field of {self.steps}")
        out = copy.copy(self)
        n = steps + 1
        out.steps = int(steps)
        # copies, C-contiguous as a field's own arrays: the precompiled kernels take only those
        # (a view of the longer field would send every call to numba, compiled at first use)
        cut = (np.ascontiguousarray(a) for a in (self.times[:n], self.xy[:, :n], self.present[:, :n], self.margin[:, :n]))
        out.times, out.xy, out.present, out.margin = cut
        out._boxes()
        out.evaluations = 0
        return out

    def unsafe(self, poses: FloatArray, lo: int = 0, hi: int | None = None) -> BoolArray:
        """Steps at which the robot at each of ``poses`` is not safe (one group; dense, for
        tests and baselines: the search uses :meth:`unsafe_pairs`).

        Parameters
        ----------
        poses : (k, d) float
        lo, hi : int
            Only steps ``lo..hi`` are examined; the others are reported unsafe.

        Returns
        -------
        (k, steps + 1) bool
        """
        poses = np.atleast_2d(np.asarray(poses, dtype=float))
        hi = self.steps if hi is None else hi
        tgrid = np.arange(self.steps + 1)
        out = np.broadcast_to((tgrid < lo) | (tgrid > hi), (len(poses), tgrid.size)).copy()
        node, step = self.unsafe_pairs(poses, np.array([0, len(poses)]), np.array([lo]), np.array([hi]))
        out[node, step] = True
        return out

    def unsafe_pairs(self, poses: FloatArray, ptr: IntArray, lo: IntArray, hi: IntArray):
        """Unsafe (point, step) pairs of many groups of poses at once (no Python loop).

        Parameters
        ----------
        poses : (k, d) float
            Group j is ``poses[ptr[j]:ptr[j+1]]``, typically the points of one roadmap
            edge, which lie close to the segment between its first and last point.
        ptr : (g+1,) int
        lo, hi : (g,) int
            Steps examined per group; the others are reported unsafe.

        Returns
        -------
        node, step : (p,) int
            The unsafe pairs inside the groups' windows (possibly repeated).

        Notes
        -----
        Three phases: each group's box against each mover's box per chunk of steps; then
        each candidate (group, mover, step) by the distance of the mover to the group's
        segment; then the exact robot-mover distance for each point of the surviving groups.
        """
        poses = np.asarray(poses, dtype=float)
        ptr = np.asarray(ptr, dtype=np.int64)
        G, K = len(ptr) - 1, len(poses)
        lo = np.clip(np.asarray(lo, dtype=np.int64), 0, None)
        hi = np.minimum(np.asarray(hi, dtype=np.int64), self.steps)
        sizes = np.diff(ptr)
        gid = np.repeat(np.arange(G), sizes)
        none = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64))
        if not self.movers or K == 0:
            return none
        if self.compiled:
            return self._pairs_compiled(poses, ptr, lo, hi)
        xy = poses[:, :2]
        starts = ptr[:-1]
        gmin = np.minimum.reduceat(xy, starts, axis=0)
        gmax = np.maximum.reduceat(xy, starts, axis=0)
        p0, p1 = xy[starts], xy[ptr[1:] - 1]
        seg = p1 - p0
        seg2 = np.einsum("ij,ij->i", seg, seg)
        inv = np.where(seg2 > 0, 1.0 / np.where(seg2 > 0, seg2, 1.0), 0.0)
        tt = np.clip(np.einsum("ij,ij->i", xy - p0[gid], seg[gid]) * inv[gid], 0.0, 1.0)
        dev = np.maximum.reduceat(np.hypot(*(p0[gid] + tt[:, None] * seg[gid] - xy).T), starts)
        body = self.robot.circumradius + dev
        dev = np.where(_uneven(tt, seg2, ptr, gid, sizes) & (dev < 1e-9), np.inf, dev)

        # 1. broad phase: (group, mover, chunk) whose boxes overlap
        g3, m3, c3 = self._broad_phase(gmin, gmax, lo // CHUNK, hi // CHUNK)
        if g3.size == 0:
            return none
        # 2. mid phase: every step of those chunks, mover against the group's segment
        st = (c3[:, None] * CHUNK + np.arange(CHUNK)).ravel()
        g3 = np.repeat(g3, CHUNK)
        m3 = np.repeat(m3, CHUNK)
        keep = (st >= lo[g3]) & (st <= hi[g3])
        g3, m3, st = g3[keep], m3[keep], st[keep]
        keep = self.present[m3, st]
        g3, m3, st = g3[keep], m3[keep], st[keep]
        q = self.xy[m3, st]
        tu = np.einsum("ij,ij->i", q - p0[g3], seg[g3]) * inv[g3]  # unclipped
        tq = np.clip(tu, 0.0, 1.0)
        dq = np.hypot(*(p0[g3] + tq[:, None] * seg[g3] - q).T)
        margin = self.margin[m3, st]
        keep = dq - body[g3] - self._extent[m3] < margin
        g3, m3, st, margin, tu = g3[keep], m3[keep], st[keep], margin[keep], tu[keep]
        if g3.size == 0:
            return none
        # 3. exact distance for the points of each surviving group that can be in reach: on
        #    an edge (points evenly spaced on the segment) only those whose position along
        #    it is within sqrt(reach^2 - distance to the line^2) of the mover's projection
        n_g = sizes[g3]
        first = np.zeros(len(g3), dtype=np.int64)
        last = n_g - 1
        line = (dev[g3] < 1e-9) & (n_g > 1) & (seg2[g3] > 0)
        if line.any():
            gl = g3[line]
            length = np.sqrt(seg2[gl])
            foot = p0[gl] + tu[line][:, None] * seg[gl]
            perp2 = ((self.xy[m3[line], st[line]] - foot) ** 2).sum(-1)
            reach = self.robot.circumradius + self._extent[m3[line]] + margin[line]
            w = np.sqrt(np.maximum(reach**2 - perp2, 0.0))
            spacing = length / (n_g[line] - 1)
            first[line] = np.maximum(0, np.ceil((tu[line] * length - w) / spacing - 1e-9)).astype(np.int64)
            last[line] = np.minimum(n_g[line] - 1, np.floor((tu[line] * length + w) / spacing + 1e-9)).astype(np.int64)
        cnt = np.maximum(last - first + 1, 0)
        node = np.repeat(ptr[g3] + first, cnt) + (np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt))
        m4 = np.repeat(m3, cnt)
        st4 = np.repeat(st, cnt)
        margin = np.repeat(margin, cnt)
        q = self.xy[m4, st4]
        # centre distance bounds the body distance from below: most points drop here
        keep = np.hypot(*(q - xy[node]).T) - self.robot.circumradius - self._extent[m4] < margin
        node, m4, st4, q, margin = node[keep], m4[keep], st4[keep], q[keep], margin[keep]
        d = self._distance(poses[node], m4, q)
        self.evaluations += d.size
        bad = d < margin
        return node[bad], st4[bad]

    def safe_intervals(self, poses: FloatArray, ptr: IntArray, lo: IntArray, hi: IntArray):
        """Safe intervals of many groups of poses (the compiled kernel; see :meth:`unsafe_pairs`).

        Parameters
        ----------
        poses : (k, d) float ; ptr : (g+1,) int ; lo, hi : (g,) int
            As :meth:`unsafe_pairs`; only steps ``lo..hi`` of each group are examined
            (clipped to ``0..steps``).

        Returns
        -------
        starts, ends : (q,) int
            Maximal runs of safe steps inside each point's window (inclusive), point by
            point, in time order.
        sp : (k+1,) int
            Point i's intervals are ``starts[sp[i]:sp[i+1]]``.
        """
        from .movers_kernel import safe_runs

        poses = np.asarray(poses, dtype=float)
        ptr = np.asarray(ptr, dtype=np.int64)
        lo = np.clip(np.asarray(lo, dtype=np.int64), 0, None)
        hi = np.minimum(np.asarray(hi, dtype=np.int64), self.steps)
        if not self.movers:  # nobody: each point's whole window, without a table of its steps
            return whole_windows(ptr, lo, hi)
        buf, row_off, lo_node = self._mark(poses, ptr, lo, hi)
        return safe_runs(buf, row_off, lo_node)

    def _pairs_compiled(self, poses, ptr, lo, hi):
        """:meth:`unsafe_pairs` by the compiled kernel: its dense table read back as pairs."""
        buf, row_off, lo_node = self._mark(poses, ptr, lo, hi)
        cells = np.flatnonzero(buf)
        node = np.searchsorted(row_off, cells, side="right") - 1
        return node, lo_node[node] + cells - row_off[node]

    def _mark(self, poses, ptr, lo, hi):
        """Unsafe steps of every point as a dense table (:func:`gfuzzy.timespace.movers_kernel.mark_unsafe`).

        Returns
        -------
        buf : (row_off[-1],) bool ; row_off : (k+1,) int ; lo_node : (k,) int
            Point i's steps ``lo_node[i]..`` are ``buf[row_off[i]:row_off[i+1]]`` (True: unsafe).
        """
        from .movers_kernel import mark_unsafe

        sizes = np.diff(ptr)
        lo_node = np.repeat(lo, sizes)
        row_off = np.zeros(len(poses) + 1, dtype=np.int64)
        np.cumsum(np.repeat(np.maximum(hi - lo + 1, 0), sizes), out=row_off[1:])
        buf = np.zeros(int(row_off[-1]), dtype=np.bool_)
        if not self.movers or len(poses) == 0:
            return buf, row_off, lo_node
        robot = self.robot
        box = robot.shape != "disc"
        cosp = np.cos(poses[:, 2]) if box else np.zeros(0)
        sinp = np.sin(poses[:, 2]) if box else np.zeros(0)
        half = 0.5 * np.asarray(robot.size, dtype=float) if box else np.zeros(2)
        kind = {"disc": 0, "box": 1, "footprint": 2}[robot.shape]
        inner = float(robot.inradius)
        if kind == 2:
            pieces, counts = shape_of(robot).padded()
            if not shape_of(robot).origin_inside:  # no disc about the reference point is inside
                inner = -math.inf
        else:
            pieces, counts = np.zeros((1, 1, 2)), np.zeros(1, dtype=np.int64)
        xy = np.ascontiguousarray(poses[:, :2])
        chunks = np.maximum(np.minimum(hi // CHUNK, self.nc - 1) - np.maximum(lo // CHUNK, 0) + 1, 0)
        grid = int(chunks.sum()) * len(self.movers) > DENSE_BROAD_PHASE  # many movers: a grid finds the pairs
        count = mark_unsafe(
            grid, ptr, lo, hi, xy, cosp, sinp, row_off, buf, self.present, self.xy, self.margin, self.bbox,
            CHUNK, self._extent, self._is_disc, self._radius, self._size, self._inner, kind,
            float(robot.circumradius), float(robot.radius), float(half[0]), float(half[1]), inner,
            pieces, counts,
        )  # fmt: skip
        self.evaluations += count
        return buf, row_off, lo_node

    def _broad_phase(self, gmin, gmax, c_lo, c_hi):
        """(group, mover, chunk) triples whose boxes overlap, chunk within the group's range.

        A join on (grid cell, chunk) rather than a dense groups x movers x chunks test, so
        the work grows with the candidates, not with the product (200 movers, 10,000s of
        edges).
        """
        empty = (np.zeros(0, np.int64),) * 3
        c_lo = np.maximum(c_lo, 0)
        c_hi = np.minimum(c_hi, self.nc - 1)
        ok = c_lo <= c_hi
        if not ok.any():
            return empty
        c0, c1 = int(c_lo[ok].min()), int(c_hi[ok].max())
        bb = self.bbox[:, c0 : c1 + 1]  # (M, nc', 4)
        m1, cc = np.nonzero(np.isfinite(bb[..., 0]))
        if m1.size == 0:
            return empty
        boxes = bb[m1, cc]
        c1_ = cc + c0
        # grid: cells about the size of a mover's box over one chunk
        widths = np.maximum(boxes[:, 2] - boxes[:, 0], boxes[:, 3] - boxes[:, 1])
        x0 = min(boxes[:, 0].min(), gmin[:, 0].min())
        y0 = min(boxes[:, 1].min(), gmin[:, 1].min())
        x1 = max(boxes[:, 2].max(), gmax[:, 0].max())
        y1 = max(boxes[:, 3].max(), gmax[:, 1].max())
        cell = max(float(np.median(widths)), 1e-3)
        cell = max(cell, math.sqrt((x1 - x0) * (y1 - y0) / 250_000.0))  # at most ~250k cells
        nx = int((x1 - x0) / cell) + 1
        ny = int((y1 - y0) / cell) + 1
        nct = self.nc

        def cells(b):
            ix0 = np.clip(((b[:, 0] - x0) / cell).astype(np.int64), 0, nx - 1)
            ix1 = np.clip(((b[:, 2] - x0) / cell).astype(np.int64), 0, nx - 1)
            iy0 = np.clip(((b[:, 1] - y0) / cell).astype(np.int64), 0, ny - 1)
            iy1 = np.clip(((b[:, 3] - y0) / cell).astype(np.int64), 0, ny - 1)
            wx, wy = ix1 - ix0 + 1, iy1 - iy0 + 1
            cnt = wx * wy
            owner = np.repeat(np.arange(len(b)), cnt)
            k = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
            return owner, (iy0[owner] + k // wx[owner]) * nx + ix0[owner] + k % wx[owner]

        # movers: (box, cell) keyed by (cell, chunk)
        own1, cell1 = cells(boxes)
        key1 = cell1 * nct + c1_[own1]
        order = np.argsort(key1, kind="stable")
        key1, own1 = key1[order], own1[order]
        # groups: (group, cell, chunk) for every chunk of the group's range
        gidx = np.nonzero(ok)[0]
        own2, cell2 = cells(np.column_stack([gmin[gidx], gmax[gidx]]))
        g2 = gidx[own2]
        nchunk = c_hi[g2] - c_lo[g2] + 1
        g2r = np.repeat(g2, nchunk)
        ch = c_lo[g2r] + (np.arange(nchunk.sum()) - np.repeat(np.cumsum(nchunk) - nchunk, nchunk))
        key2 = np.repeat(cell2, nchunk) * nct + ch
        a = np.searchsorted(key1, key2, side="left")
        b = np.searchsorted(key1, key2, side="right")
        cnt = b - a
        if cnt.sum() == 0:
            return empty
        g3 = np.repeat(g2r, cnt)
        box3 = own1[np.repeat(a, cnt) + (np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt))]
        bx = boxes[box3]
        hit = (bx[:, 0] <= gmax[g3, 0]) & (gmin[g3, 0] <= bx[:, 2]) & (bx[:, 1] <= gmax[g3, 1]) & (gmin[g3, 1] <= bx[:, 3])
        g3, box3 = g3[hit], box3[hit]
        # a pair seen in several shared cells counts once
        key = np.unique(g3 * len(boxes) + box3)
        g3, box3 = key // len(boxes), key % len(boxes)
        return g3, m1[box3], c1_[box3]

    def _distance(self, poses: FloatArray, movers: IntArray, xy: FloatArray) -> FloatArray:
        """Robot-mover distance for aligned arrays of poses, mover indices and positions."""
        if self._is_disc.all() or not self._is_disc.any():  # one shape: no masks to copy through
            shape = "disc" if self._is_disc.all() else "box"
            return mover_distance(
                self.robot, poses, shape, self._radius[movers], self._size[movers], xy, exact=False
            )
        d = np.empty(len(poses))
        disc = self._is_disc[movers]
        for mask, shape in ((disc, "disc"), (~disc, "box")):
            if not mask.any():
                continue
            mm = movers[mask]
            d[mask] = mover_distance(
                self.robot, poses[mask], shape, self._radius[mm], self._size[mm], xy[mask], exact=False
            )
        return d

    def collides_at(self, pose: FloatArray, step: int, clearance: float = 0.0) -> str | None:
        """Name of a mover closer than ``clearance`` to the robot at ``pose`` exactly at
        step ``step`` (0: overlapping it), if any."""
        t = self.t0 + step * self.dt
        for mv in self.movers:
            xy, present = mv.state(np.array([t]))
            if present[0] and mover_distance(self.robot, np.asarray(pose, float), mv.shape, mv.radius, mv.size, xy[0]) < clearance:
                return mv.name
        return None

    def motion_safe(self, a: FloatArray, b: FloatArray, step: int, min_interval: float = 1e-6) -> bool:
        """True when the straight motion a -> b over ``[t_step, t_step + dt]`` keeps
        :attr:`keep` from every mover at every instant (a = b: waiting).

        Lipschitz argument: the robot-mover distance changes no faster than the robot's
        speed plus the mover's largest speed in the step, L; a sub-interval whose ends'
        excesses over the clearance add up to at least L times its length is clear, any
        other is bisected. A mover that appears or vanishes within the step is taken as
        present over the whole step, at its first or last position (conservative).
        Undecided sub-intervals shorter than ``min_interval`` seconds count as unsafe.

        Parameters
        ----------
        a, b : (d,) float
            Poses; the metric length of a -> b must be at most ``vrobot * dt``.
        step : int

        Returns
        -------
        bool
        """
        a = np.asarray(a, dtype=float)
        b = np.asarray(b, dtype=float)
        ta = self.t0 + step * self.dt
        tb = ta + self.dt
        vr = float(metric_distance(a, b, self.robot.circumradius)) / self.dt
        for i in self._near_motion(a, b, step):
            mv = self.movers[i]
            lo, hi = mv.time_range
            if tb < lo or ta > hi:
                continue
            vm = float(_local_speed(mv, np.array([ta + 0.5 * self.dt]), 0.5 * self.dt)[0])
            lip = vr + vm

            def excess(times, mv=mv):
                poses = interpolate_segment(a, b, (times - ta) / self.dt)
                xy, _ = mv.state(times)  # clamped to the first/last row outside its range
                return mover_distance(self.robot, poses, mv.shape, mv.radius, mv.size, xy) - self.keep

            s_t = np.linspace(ta, tb, 9)
            g = excess(s_t)
            if np.any(g < 0):
                return False
            lo_t, hi_t, lo_g, hi_g = s_t[:-1], s_t[1:], g[:-1], g[1:]
            while lo_t.size:
                need = lo_g + hi_g < lip * (hi_t - lo_t)
                lo_t, hi_t, lo_g, hi_g = lo_t[need], hi_t[need], lo_g[need], hi_g[need]
                if lo_t.size == 0:
                    break
                if np.any(hi_t - lo_t < min_interval) or lo_t.size > 100_000:
                    return False
                mid = 0.5 * (lo_t + hi_t)
                gm = excess(mid)
                if np.any(gm < 0):
                    return False
                lo_t, hi_t = np.concatenate([lo_t, mid]), np.concatenate([mid, hi_t])
                lo_g, hi_g = np.concatenate([lo_g, gm]), np.concatenate([gm, hi_g])
        return True


    def _near_motion(self, a: FloatArray, b: FloatArray, step: int) -> IntArray:
        """Indices of the movers that :meth:`motion_safe` must examine for a -> b over step
        ``step``: those whose broad-phase box at step ``step`` or ``step + 1`` meets the
        box of the motion's reference points.

        At any instant of the step a mover is within its largest speed times half a step
        of where it is at the nearer of the two steps (a mover that appears or vanishes
        in the step: of its first or last position), and its box there holds that point
        inflated by its extent, the robot's circumradius and the largest margin (which
        holds that half step of motion plus the clearance the boxes were built with). A
        mover whose boxes miss the motion's is so farther than its extent plus the
        circumradius plus :attr:`keep` from every reference point of the motion at every
        instant: it cannot make the motion unsafe. Among many people the exact check
        then looks at the few near the robot instead of at all of them.
        """
        grow = max(self.keep - self._bbox_keep, 0.0)  # keep raised after the boxes were built
        lo = np.minimum(a[:2], b[:2]) - grow
        hi = np.maximum(a[:2], b[:2]) + grow
        chunks = np.minimum(np.array([step, step + 1]) // CHUNK, self.nc - 1)
        bb = self.bbox[:, chunks]  # (movers, 2, 4)
        meet = (bb[..., 0] <= hi[0]) & (bb[..., 2] >= lo[0]) & (bb[..., 1] <= hi[1]) & (bb[..., 3] >= lo[1])
        return np.flatnonzero(meet.any(axis=1))


def _straight_samples(movers, times: FloatArray, half: float):
    """(xy (m, n, 2), present (m, n), speed (m, 1)) of movers that are each one straight
    trajectory row to row (two rows, the second later), sampled at ``times`` as the loop of
    :class:`MoverField` samples each (``np.interp`` of the clipped times, the same numbers);
    None when any is not."""
    if not movers or any(mv.trajectory is None or len(mv.trajectory) != 2 for mv in movers):
        return None
    tr = np.stack([mv.trajectory for mv in movers])  # (m, 2, 3)
    t0, t1 = tr[:, 0, 0:1], tr[:, 1, 0:1]
    if not (np.isfinite(tr).all() and (t1 > t0).all()):
        return None
    tc = np.clip(times, t0, t1)
    xy = np.empty((len(movers), len(times), 2))
    for c in (1, 2):  # np.interp's own arithmetic: the ends exact, slope * (t - t0) + y0 between
        y0, y1 = tr[:, 0, c : c + 1], tr[:, 1, c : c + 1]
        xy[..., c - 1] = np.where(tc >= t1, y1, np.where(tc == t0, y0, (y1 - y0) / (t1 - t0) * (tc - t0) + y0))
    present = (times + half >= t0) & (times - half <= t1)
    speed = np.hypot(tr[:, 1, 1] - tr[:, 0, 1], tr[:, 1, 2] - tr[:, 0, 2])[:, None] / (t1 - t0)
    return xy, present, speed


def _local_speed(mv, times: FloatArray, half: float) -> FloatArray:
    """Largest speed of a mover within ``[t - half, t + half]`` for each t."""
    if mv.trajectory is None:
        return np.full(times.shape, mv.speed)
    tr = mv.trajectory
    if len(tr) < 2:
        return np.zeros(times.shape)
    seg_v = np.hypot(*np.diff(tr[:, 1:], axis=0).T) / np.diff(tr[:, 0])
    last = len(seg_v) - 1
    i0 = np.clip(np.searchsorted(tr[:, 0], times - half, side="right") - 1, 0, last)
    i1 = np.clip(np.searchsorted(tr[:, 0], times + half, side="left") - 1, 0, last)
    i1 = np.maximum(i1, i0)
    span = int((i1 - i0).max(initial=0))
    v = seg_v[i0]
    for k in range(1, span + 1):
        v = np.maximum(v, seg_v[np.minimum(i0 + k, i1)])
    return v
