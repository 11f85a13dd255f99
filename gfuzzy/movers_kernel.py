"""The movers' safety kernel compiled with numba: phases 2 and 3 of
:meth:`gfuzzy.movers.MoverField.unsafe_pairs` in one loop.

numba is imported only when this module is (``MoverField`` imports it lazily, when its
``compiled`` flag is set); ``cache=True`` keeps the machine code on disk
(``python -m gfuzzy.search_kernel`` warms it with the search loop).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["narrow_phase"]




@njit(cache=True)
def _hypot(x, y):
    return math.hypot(x, y)


@njit(cache=True)
def _box_dist(px, py, hx, hy):
    """:func:`gfuzzy.geometry._point_box_distance` for one point (same operations)."""
    qx = abs(px) - hx
    qy = abs(py) - hy
    outside = math.hypot(max(qx, 0.0), max(qy, 0.0))
    inside = min(max(qx, qy), 0.0)
    return outside + inside


@njit(cache=True)
def narrow_phase(g3, m3, c3, chunk, lo, hi, present, mxy, margin_tab, ptr, xy, p0, seg, inv, seg2, dev,
                 body, extent, circ, robot_kind, robot_r, hx_r, hy_r, cosp, sinp, is_disc, mrad, msize,
                 robot_in, inner):  # fmt: skip
    """Phases 2 and 3 of :meth:`gfuzzy.movers.MoverField.unsafe_pairs` in one loop.

    The same tests in the same floating-point operations, per candidate instead of per
    array. ``robot_kind`` 0: disc robot, 1: box robot (``cosp``, ``sinp``: its headings'
    cosines and sines, computed by numpy as the reference does). The exact distance is
    computed here except for a box robot against a box mover (``dist`` NaN: the caller
    uses the reference's separating-axis code). ``robot_in`` and ``inner``: the inscribed
    radii of the robot and the movers; a pair whose inscribed discs are closer than the
    margin is unsafe without its exact distance (which is at most theirs).

    Returns
    -------
    node, mover, step : (p,) int
        The pairs found unsafe, and those whose distance is left to the caller.
    margin, dist : (p,) float
    evaluations : int  (pairs that passed the cheap tests: the reference's ``evaluations``)
    """
    out_n = []  # five lists, not one tuple of them: numba types each list by its appends
    out_m = []
    out_s = []
    out_mg = []
    out_d = []
    count = 0
    for c in range(len(g3)):
        g, m = g3[c], m3[c]
        a = ptr[g]
        n_g = ptr[g + 1] - a
        for k in range(chunk):
            st = c3[c] * chunk + k
            if st < lo[g] or st > hi[g] or not present[m, st]:
                continue
            qx, qy = mxy[m, st, 0], mxy[m, st, 1]
            tu = ((qx - p0[g, 0]) * seg[g, 0] + (qy - p0[g, 1]) * seg[g, 1]) * inv[g]
            tq = min(max(tu, 0.0), 1.0)
            ex = p0[g, 0] + tq * seg[g, 0] - qx
            ey = p0[g, 1] + tq * seg[g, 1] - qy
            mg = margin_tab[m, st]
            # a cheap superset test first (squares, with slack for rounding), then the
            # reference's own test on what remains
            lim = mg + body[g] + extent[m]
            if lim > 0.0 and ex * ex + ey * ey > lim * lim * (1.0 + 1e-9) + 1e-12:
                continue  # far outside: the test below fails too
            dq = math.hypot(ex, ey)
            if not (dq - body[g] - extent[m] < mg):
                continue
            first = 0
            last = n_g - 1
            if dev[g] < 1e-9 and n_g > 1:
                length = math.sqrt(seg2[g])
                fx = p0[g, 0] + tu * seg[g, 0]
                fy = p0[g, 1] + tu * seg[g, 1]
                perp2 = (qx - fx) ** 2 + (qy - fy) ** 2
                reach = circ + extent[m] + mg
                w = math.sqrt(max(reach**2 - perp2, 0.0))
                spacing = length / (n_g - 1)
                first = max(0, np.int64(math.ceil((tu * length - w) / spacing - 1e-9)))
                last = min(n_g - 1, np.int64(math.floor((tu * length + w) / spacing + 1e-9)))
            for i in range(first, last + 1):
                node = a + i
                rx = qx - xy[node, 0]
                ry = qy - xy[node, 1]
                lim = mg + circ + extent[m]
                if lim > 0.0 and rx * rx + ry * ry > lim * lim * (1.0 + 1e-9) + 1e-12:
                    continue  # far outside: the test below fails too
                hc = math.hypot(rx, ry)
                if not (hc - circ - extent[m] < mg):
                    continue
                if hc - robot_in - inner[m] < mg - 1e-9:
                    # the shapes' inscribed discs are closer than the margin, so the exact
                    # distance (or the separating-axis gap, a lower bound) is too
                    d = -np.inf
                elif robot_kind == 0:
                    if is_disc[m]:
                        d = math.hypot(rx, ry) - robot_r - mrad[m]
                    else:
                        d = _box_dist(rx, ry, 0.5 * msize[m, 0], 0.5 * msize[m, 1]) - robot_r
                elif is_disc[m]:
                    cc, ss = cosp[node], sinp[node]
                    d = _box_dist(cc * rx + ss * ry, -ss * rx + cc * ry, hx_r, hy_r) - mrad[m]
                else:
                    d = np.nan
                count += 1
                if d >= mg:  # safe (NaN never is: left to the caller)
                    continue
                out_n.append(node)
                out_m.append(m)
                out_s.append(st)
                out_mg.append(mg)
                out_d.append(d)
    return (
        np.array(out_n, dtype=np.int64),
        np.array(out_m, dtype=np.int64),
        np.array(out_s, dtype=np.int64),
        np.array(out_mg, dtype=np.float64),
        np.array(out_d, dtype=np.float64),
        count,
    )
