"""Coding of the genes: knots, search lines and level steps along the input path (paper
section 3.1, "reducing dimensions")."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..typed import ArrayLike, BoolArray, FloatArray, IntArray
from .options import REMOVED, StaticClearance, _call_static


@dataclass(frozen=True, eq=False)
class PathCoding:
    """The paper's "reducing dimensions" coding of a path's via-points.

    Parameters
    ----------
    start, goal : (2,) float
        The fixed end points.
    knots : (K, 2) float
        Origins of the search lines, at equal arc length along the input path.
    normals : (K, 2) float
        Unit directions of the search lines, perpendicular to the path at each knot.
    steps : (K,) float
        Offset between two levels on each search line.
    levels : int
        Levels per gene; level ``levels // 2`` is the knot itself.
    """

    start: FloatArray
    goal: FloatArray
    knots: FloatArray
    normals: FloatArray
    steps: FloatArray
    levels: int

    @property
    def n_knots(self) -> int:
        return len(self.knots)

    @property
    def mid(self) -> int:
        """The level of zero offset."""
        return self.levels // 2

    @property
    def arc(self) -> FloatArray:
        """(K + 2,) float: the input's arc-length fraction of start, knots and goal.

        A via-point is reached when the input reached its knot (see
        :meth:`PathEvaluator.evaluate`).
        """
        return np.arange(self.n_knots + 2) / (self.n_knots + 1)

    @classmethod
    def from_path(
        cls, path_xy: ArrayLike, n_knots: int, levels: int, steps: ArrayLike | float
    ) -> PathCoding:
        """Place ``n_knots`` knots and their search lines along a polyline.

        Parameters
        ----------
        path_xy : (n, 2) float
            The input path, n >= 2, with positive length.
        n_knots, levels : int
        steps : float or (n_knots,) float

        Returns
        -------
        PathCoding

        Raises
        ------
        ValueError
            If the path has zero length.
        """
        pts = _dedupe(np.asarray(path_xy, dtype=float))
        if len(pts) < 2:
            raise ValueError("path has zero length: nothing to refine")
        s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
        total = s[-1]
        sk = total * np.arange(1, n_knots + 1) / (n_knots + 1)
        knots = _interp_polyline(pts, s, sk)
        # The central difference over one knot spacing gives the bisector direction at a
        # corner, so the search line there cuts the corner rather than sliding along a leg.
        half = 0.5 * total / (n_knots + 1)
        tangent = _interp_polyline(pts, s, sk + half) - _interp_polyline(pts, s, sk - half)
        tn = np.hypot(tangent[:, 0], tangent[:, 1])
        seg = np.clip(np.searchsorted(s, sk, side="right") - 1, 0, len(pts) - 2)
        seg_dir = pts[seg + 1] - pts[seg]
        bad = tn < 1e-9 * total
        tangent[bad] = seg_dir[bad]
        tangent /= np.hypot(tangent[:, 0], tangent[:, 1])[:, None]
        normals = np.stack([-tangent[:, 1], tangent[:, 0]], axis=1)
        steps = np.broadcast_to(np.asarray(steps, dtype=float), (n_knots,)).copy()
        arrays = [pts[0].copy(), pts[-1].copy(), knots, normals, steps]
        for a in arrays:
            a.setflags(write=False)
        return cls(*arrays, levels=int(levels))

    def offsets(self, chromosomes: ArrayLike) -> FloatArray:
        """Signed offsets along the search lines.

        Parameters
        ----------
        chromosomes : (P, K) int

        Returns
        -------
        (P, K) float
            NaN where the gene is :data:`REMOVED`.
        """
        g = np.asarray(chromosomes)
        off = (g - self.mid) * self.steps
        return np.where(g == REMOVED, np.nan, off)

    def decode(self, chromosomes: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Decode a population into padded paths.

        Parameters
        ----------
        chromosomes : (P, K) int

        Returns
        -------
        points : (P, K + 2, 2) float
            Start, the K via-points (removed ones sit at their knot), goal.
        mask : (P, K + 2) bool
            False where a via-point is removed.
        """
        g = np.asarray(chromosomes)
        P = g.shape[0]
        off = np.where(g == REMOVED, 0, g - self.mid) * self.steps
        pts = np.empty((P, self.n_knots + 2, 2))
        pts[:, 0] = self.start
        pts[:, -1] = self.goal
        pts[:, 1:-1] = self.knots + off[..., None] * self.normals
        mask = np.ones((P, self.n_knots + 2), dtype=bool)
        mask[:, 1:-1] = g != REMOVED
        return pts, mask

    def node_ids(self, chromosomes: ArrayLike) -> IntArray:
        """Lattice node number of every point of the decoded paths (for the segment cache).

        Returns
        -------
        (P, K + 2) int
            0 for the start, ``1 + k * levels + level`` for a via-point, the largest for the goal.
        """
        g = np.asarray(chromosomes, dtype=np.int64)
        P, K = g.shape
        ids = np.empty((P, K + 2), dtype=np.int64)
        ids[:, 0] = 0
        ids[:, -1] = 1 + K * self.levels
        ids[:, 1:-1] = 1 + np.arange(K) * self.levels + np.maximum(g, 0)
        return ids

    def polyline(self, chromosome: ArrayLike) -> FloatArray:
        """The path of one chromosome.

        Parameters
        ----------
        chromosome : (K,) int

        Returns
        -------
        (m, 2) float
            Start, kept via-points, goal.
        """
        pts, mask = self.decode(np.asarray(chromosome)[None])
        return pts[0][mask[0]]


def _dedupe(pts: FloatArray) -> FloatArray:
    keep = np.ones(len(pts), dtype=bool)
    keep[1:] = np.any(np.diff(pts, axis=0) != 0, axis=1)
    return pts[keep]


def _interp_polyline(pts: FloatArray, s: FloatArray, q: FloatArray) -> FloatArray:
    """Points at arc lengths ``q`` (clamped) on the polyline ``pts`` with arc lengths ``s``."""
    return np.stack([np.interp(q, s, pts[:, 0]), np.interp(q, s, pts[:, 1])], axis=1)


def _derive_steps(
    path: FloatArray,
    knots: FloatArray,
    normals: FloatArray,
    levels: int,
    robot_radius: float,
    resolution: float,
    static_clearance: StaticClearance,
) -> FloatArray:
    """One level step per knot from the free width of its search line.

    Each search line is probed on both sides up to ``reach_max`` = the larger of the input's
    largest distance from the start-goal chord (how far the zig-zag strays) and the knot
    spacing. The knot's reach is the farther free extent of the two sides, so the levels
    span the corridor around the knot; ``step = reach / (levels // 2)``.
    """
    start, goal = path[0], path[-1]
    dev = float(np.max(_point_segment_distance(path, start, goal)))
    spacing = float(np.sum(np.hypot(*np.diff(path, axis=0).T))) / (len(knots) + 1)
    reach_max = max(dev, spacing, 2.0 * robot_radius)
    n = int(math.ceil(reach_max / resolution))
    s = np.minimum(np.arange(1, n + 1) * resolution, reach_max)
    K = len(knots)
    probe = (
        knots[:, None, None, :]
        + np.array([1.0, -1.0])[None, :, None, None]
        * s[None, None, :, None]
        * normals[:, None, None, :]
    )
    c = _call_static(static_clearance, probe.reshape(-1, 2)).reshape(K, 2, n)
    blocked = c < 0
    first = np.where(blocked.any(axis=2), blocked.argmax(axis=2), n)  # index of first blocked probe
    extent = np.where(first > 0, s[np.maximum(first - 1, 0)], 0.0)
    extent = np.where(first == n, reach_max, extent)
    reach = np.clip(extent.max(axis=1), resolution, reach_max)
    # a knot inside an obstacle (the resampled input cuts a corner) gets the full reach
    reach = np.where(_call_static(static_clearance, knots) < 0, reach_max, reach)
    return reach / (levels // 2)


def _point_segment_distance(p: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    ab = b - a
    den = float(ab @ ab)
    t = np.zeros(len(p)) if den == 0 else np.clip((p - a) @ ab / den, 0.0, 1.0)
    return np.hypot(*(a + t[:, None] * ab - p).T)
