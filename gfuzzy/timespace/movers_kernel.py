"""The movers' safety kernel compiled with numba: phases 1-3 of
:meth:`gfuzzy.timespace.movers.MoverField.unsafe_pairs` marking a dense table, and the safe
intervals read off that table.

:func:`mark_unsafe` runs the same tests in the same floating-point operations as the
numpy reference (per candidate instead of per array) and marks every unsafe (point, step)
in one bool row per point, instead of listing pairs: a list append per unsafe pair cost
more than the distance itself. :func:`safe_runs` turns the rows into safe intervals (the
gaps between unsafe steps), which is what the search consumes.

``MoverField`` imports this module lazily, when its ``compiled`` flag is set; the kernels
are the precompiled extension's when ``make warm`` built it (:mod:`gfuzzy.timespace.jit`), numba's
otherwise (imported then, ``cache=True`` keeping the machine code on disk).
"""

from __future__ import annotations

import math

import numpy as np

from .jit import njit

__all__ = ["mark_unsafe", "safe_runs", "merge_runs"]


@njit(cache=True)
def _box_dist(px, py, hx, hy):
    """:func:`gfuzzy.collision.shapes._point_box_distance` for one point (same operations)."""
    qx = abs(px) - hx
    qy = abs(py) - hy
    outside = math.hypot(max(qx, 0.0), max(qy, 0.0))
    inside = min(max(qx, qy), 0.0)
    return outside + inside


#: :data:`gfuzzy.collision.geometry.QUAD_EXACT`: beyond it a box-box distance is the circumscribed
#: circles' (kept here so that numba does not import the geometry module).
QUAD_EXACT = 2.0

#: :data:`gfuzzy.timespace.movers.EVEN_TOL`: how far (m) a point on a group's segment may lie
#: from its evenly spaced place for phase 3's shortcut (kept here so numba does not import movers).
EVEN_TOL = 1e-9


@njit(cache=True)
def _box_box_gap(q, px, py, cc, ss, hl, hw, qx, qy, mhx, mhy):
    """:func:`gfuzzy.collision.geometry.mover_distance` (``exact=False``) of a box robot at
    ``(px, py)`` with heading cosine/sine ``cc, ss`` and half sizes ``hl, hw`` against an
    axis-aligned box mover at ``(qx, qy)`` with half sizes ``mhx, mhy``: the same
    floating-point operations as ``Robot.corners`` and ``_quad_distance``. ``q``: a
    (2, 4, 2) scratch array for the corners."""
    for k in range(4):
        lx = hl if k == 0 or k == 3 else -hl
        ly = hw if k < 2 else -hw
        q[0, k, 0] = px + (cc * lx + -ss * ly)
        q[0, k, 1] = py + (ss * lx + cc * ly)
        q[1, k, 0] = qx + mhx * (1.0 if k == 0 or k == 3 else -1.0)
        q[1, k, 1] = qy + mhy * (1.0 if k < 2 else -1.0)
    cx0 = (((q[0, 0, 0] + q[0, 1, 0]) + q[0, 2, 0]) + q[0, 3, 0]) / 4.0
    cy0 = (((q[0, 0, 1] + q[0, 1, 1]) + q[0, 2, 1]) + q[0, 3, 1]) / 4.0
    cx1 = (((q[1, 0, 0] + q[1, 1, 0]) + q[1, 2, 0]) + q[1, 3, 0]) / 4.0
    cy1 = (((q[1, 0, 1] + q[1, 1, 1]) + q[1, 2, 1]) + q[1, 3, 1]) / 4.0
    ra = 0.0
    rb = 0.0
    for k in range(4):
        ra = max(ra, math.sqrt((q[0, k, 0] - cx0) ** 2 + (q[0, k, 1] - cy0) ** 2))
        rb = max(rb, math.sqrt((q[1, k, 0] - cx1) ** 2 + (q[1, k, 1] - cy1) ** 2))
    out = math.hypot(cx0 - cx1, cy0 - cy1) - ra - rb
    if not (out < QUAD_EXACT):
        return out
    gap = -np.inf  # separating-axis test on the edge normals of both boxes (two each)
    for w in range(2):
        for k in range(2):
            nx = -(q[w, k + 1, 1] - q[w, k, 1])
            ny = q[w, k + 1, 0] - q[w, k, 0]
            nn = math.sqrt(nx * nx + ny * ny)
            nx, ny = nx / nn, ny / nn
            p_lo = q_lo = np.inf
            p_hi = q_hi = -np.inf
            for j in range(4):
                pp = q[w, j, 0] * nx + q[w, j, 1] * ny
                qq = q[1 - w, j, 0] * nx + q[1 - w, j, 1] * ny
                p_lo, p_hi = min(p_lo, pp), max(p_hi, pp)
                q_lo, q_hi = min(q_lo, qq), max(q_hi, qq)
            gap = max(gap, max(q_lo - p_hi, p_lo - q_hi))
    return gap


@njit(cache=True)
def _axis_gap(nx, ny, bx, by, piece, m):
    """The gap between the box (corners ``bx``, ``by``) and the convex ``piece`` (its first
    ``m`` vertices) projected on the axis normal to an edge, ``(nx, ny)`` unnormalised:
    positive when the axis separates them (one axis of the separating-axis test)."""
    nn = math.sqrt(nx * nx + ny * ny)
    nx, ny = nx / nn, ny / nn
    p_lo = r_lo = np.inf
    p_hi = r_hi = -np.inf
    for j in range(4):
        pp = bx[j] * nx + by[j] * ny
        p_lo, p_hi = min(p_lo, pp), max(p_hi, pp)
    for j in range(m):
        rr = piece[j, 0] * nx + piece[j, 1] * ny
        r_lo, r_hi = min(r_lo, rr), max(r_hi, rr)
    return max(p_lo - r_hi, r_lo - p_hi)


@njit(cache=True)
def footprint_distance(rx, ry, cc, ss, disc, mrad, mhx, mhy, pieces, counts):
    """:meth:`gfuzzy.collision.shapes.FootprintShape.mover_distance` (``exact=False``) for one pair:
    the mover at ``(rx, ry)`` from the robot's reference point (world axes), the heading's
    cosine and sine ``cc, ss``; a disc mover of radius ``mrad`` or an axis-aligned box of
    half sizes ``mhx, mhy``; the footprint's convex pieces ``pieces`` (P, V, 2) with
    ``counts`` (P,) vertices (the same operations as the numpy reference)."""
    lx = cc * rx + ss * ry  # the mover in the robot's frame
    ly = -ss * rx + cc * ry
    best = np.inf
    if not disc:  # the box's corners in the robot's frame
        bx = np.empty(4)
        by = np.empty(4)
        for j in range(4):
            sx = 1.0 if j == 0 or j == 3 else -1.0
            sy = 1.0 if j < 2 else -1.0
            bx[j] = (lx + (mhx * sx) * cc) + (mhy * sy) * ss
            by[j] = (ly + (mhx * sx) * -ss) + (mhy * sy) * cc
    for p in range(pieces.shape[0]):
        m = counts[p]
        if disc:  # signed distance from the point to the convex piece
            smax = -np.inf
            for k in range(m):
                vx, vy = pieces[p, k, 0], pieces[p, k, 1]
                k1 = k + 1 if k + 1 < m else 0
                nx = pieces[p, k1, 1] - vy
                ny = -(pieces[p, k1, 0] - vx)
                nn = math.sqrt(nx * nx + ny * ny)
                nx, ny = nx / nn, ny / nn
                smax = max(smax, (lx - vx) * nx + (ly - vy) * ny)
            if smax > 0:
                smax = np.inf
                for k in range(m):
                    ax, ay = pieces[p, k, 0], pieces[p, k, 1]
                    k1 = k + 1 if k + 1 < m else 0
                    abx, aby = pieces[p, k1, 0] - ax, pieces[p, k1, 1] - ay
                    apx, apy = lx - ax, ly - ay
                    den = abx * abx + aby * aby
                    t = min(max((apx * abx + apy * aby) / max(den, 1e-300), 0.0), 1.0)
                    dx, dy = apx - t * abx, apy - t * aby
                    smax = min(smax, math.sqrt(dx * dx + dy * dy))
            best = min(best, smax - mrad)
            continue
        gap = -np.inf  # separating-axis gap: the piece's normals, then the box's
        for k in range(m):
            k1 = k + 1 if k + 1 < m else 0
            ex, ey = pieces[p, k1, 0] - pieces[p, k, 0], pieces[p, k1, 1] - pieces[p, k, 1]
            gap = max(gap, _axis_gap(ey, -ex, bx, by, pieces[p], m))
        for k in range(4):
            k1 = k + 1 if k < 3 else 0
            gap = max(gap, _axis_gap(by[k1] - by[k], -(bx[k1] - bx[k]), bx, by, pieces[p], m))
        best = min(best, gap)
    return best


@njit(cache=True)
def _group_geometry(xy, ptr, circ):
    """Per group: bounding box, first point, segment to the last point, 1/|seg|^2, |seg|^2,
    the points' largest deviation from the segment (infinite when the points lie on it but
    not evenly spaced: the shortcut of phase 3 holds for evenly spaced points only) and the
    body radius around it (the numpy reference's reductions, in its operations)."""
    G = len(ptr) - 1
    box = np.empty((G, 4))
    p0 = np.empty((G, 2))
    seg = np.empty((G, 2))
    inv = np.empty(G)
    seg2 = np.empty(G)
    dev = np.empty(G)
    body = np.empty(G)
    for g in range(G):
        a, z = ptr[g], ptr[g + 1]
        if z == a:  # an empty group: nothing is examined, but keep the arrays defined
            box[g] = np.inf
            p0[g], seg[g] = 0.0, 0.0
            inv[g] = seg2[g] = dev[g] = body[g] = 0.0
            continue
        x0, y0 = xy[a, 0], xy[a, 1]
        sx, sy = xy[z - 1, 0] - x0, xy[z - 1, 1] - y0
        s2 = sx * sx + sy * sy
        iv = 1.0 / s2 if s2 > 0 else 0.0
        bx0, by0, bx1, by1 = x0, y0, x0, y0
        worst = 0.0
        for i in range(a, z):
            px, py = xy[i, 0], xy[i, 1]
            bx0, bx1 = min(bx0, px), max(bx1, px)
            by0, by1 = min(by0, py), max(by1, py)
            t = ((px - x0) * sx + (py - y0) * sy) * iv
            t = min(max(t, 0.0), 1.0)
            d = math.hypot(x0 + t * sx - px, y0 + t * sy - py)
            if i == a or d > worst:
                worst = d
        box[g, 0], box[g, 1], box[g, 2], box[g, 3] = bx0, by0, bx1, by1
        p0[g, 0], p0[g, 1] = x0, y0
        seg[g, 0], seg[g, 1] = sx, sy
        body[g] = circ + worst
        if worst < 1e-9 and z - a > 1 and s2 > 0:  # on the segment: evenly spaced too?
            length = math.sqrt(s2)
            spacing = length / (z - a - 1)
            for i in range(a, z):
                t = ((xy[i, 0] - x0) * sx + (xy[i, 1] - y0) * sy) * iv
                t = min(max(t, 0.0), 1.0)
                if abs(t * length - (i - a) * spacing) > EVEN_TOL:
                    worst = math.inf  # not evenly spaced: no shortcut (see mark_unsafe)
                    break
        inv[g], seg2[g], dev[g] = iv, s2, worst
    return box, p0, seg, inv, seg2, dev, body


@njit(cache=True)
def _mark_group(g, cand, c0, c1, a, n_g, lo_g, hi_g, box, p0x, p0y, sx, sy, inv_g, seg2_g, dev_g, body_g, row_off,
                buf, present, mxy, margin_tab, bbox, chunk, xy, cosp, sinp, circ, extent, inner, is_disc, mrad,
                msize, robot_kind, robot_r, hx_r, hy_r, robot_in, scratch, pieces, counts):  # fmt: skip
    """Phases 2 and 3 of :func:`mark_unsafe` for group ``g`` (points ``a..a+n_g-1`` near
    the segment ``p0 + t * s``): its candidates ``cand[c0:c1]``, or with none every mover
    and chunk whose box overlaps the group's ``box``. Returns the evaluations."""
    count = 0
    n_m, nc = bbox.shape[0], bbox.shape[1]
    dense = cand.shape[0] == 0
    for o in range(max(lo_g // chunk, 0) * n_m, (min(hi_g // chunk, nc - 1) + 1) * n_m) if dense else range(c0, c1):
        c, m = (o // n_m, o % n_m) if dense else (cand[o, 2], cand[o, 1])
        if dense and not (bbox[m, c, 0] <= box[2] and box[0] <= bbox[m, c, 2]
                          and bbox[m, c, 1] <= box[3] and box[1] <= bbox[m, c, 3]):  # fmt: skip
            continue
        for st in range(max(c * chunk, lo_g), min(c * chunk + chunk - 1, hi_g) + 1):
            if not present[m, st]:
                continue
            qx, qy = mxy[m, st, 0], mxy[m, st, 1]
            tu = ((qx - p0x) * sx + (qy - p0y) * sy) * inv_g
            tq = min(max(tu, 0.0), 1.0)
            ex = p0x + tq * sx - qx
            ey = p0y + tq * sy - qy
            mg = margin_tab[m, st]
            # a cheap superset test first (squares, with slack for rounding), then the
            # reference's own test on what remains
            lim = mg + body_g + extent[m]
            if lim > 0.0 and ex * ex + ey * ey > lim * lim * (1.0 + 1e-9) + 1e-12:
                continue
            if not (math.hypot(ex, ey) - body_g - extent[m] < mg):
                continue
            first, last = 0, n_g - 1
            if dev_g < 1e-9 and n_g > 1 and seg2_g > 0.0:  # points evenly spaced on a segment: those in reach
                length = math.sqrt(seg2_g)
                perp2 = (qx - (p0x + tu * sx)) ** 2 + (qy - (p0y + tu * sy)) ** 2
                w = math.sqrt(max((circ + extent[m] + mg) ** 2 - perp2, 0.0))
                spacing = length / (n_g - 1)
                first = max(0, np.int64(math.ceil((tu * length - w) / spacing - 1e-9)))
                last = min(n_g - 1, np.int64(math.floor((tu * length + w) / spacing + 1e-9)))
            lim = mg + circ + extent[m]
            # inscribed discs closer than this are unsafe (the test below); squared with
            # slack, it decides most unsafe points without a hypot
            lin = mg - 1e-9 + robot_in + inner[m]
            lin2 = lin * lin * (1.0 - 1e-9) - 1e-12 if lin > 0.0 else -1.0
            for node in range(a + first, a + last + 1):
                cell = row_off[node] + st - lo_g
                rx = qx - xy[node, 0]
                ry = qy - xy[node, 1]
                r2 = rx * rx + ry * ry
                if lim > 0.0 and r2 > lim * lim * (1.0 + 1e-9) + 1e-12:
                    continue
                if r2 < lin2:  # surely inside: both tests below pass (lin < lim)
                    count += 1
                    buf[cell] = True
                    continue
                hc = math.hypot(rx, ry)
                if not (hc - circ - extent[m] < mg):
                    continue
                count += 1
                if buf[cell]:
                    continue  # already unsafe (another mover): nothing to learn
                if hc - robot_in - inner[m] < mg - 1e-9:
                    # the inscribed discs are closer than the margin, so the exact distance
                    # (or the separating-axis gap) is too
                    buf[cell] = True
                elif robot_kind == 2:  # a footprint: its convex pieces
                    buf[cell] = footprint_distance(rx, ry, cosp[node], sinp[node], is_disc[m], mrad[m],
                                                   0.5 * msize[m, 0], 0.5 * msize[m, 1], pieces, counts) < mg  # fmt: skip
                elif robot_kind == 0:
                    if is_disc[m]:
                        d = hc - robot_r - mrad[m]
                    else:
                        d = _box_dist(rx, ry, 0.5 * msize[m, 0], 0.5 * msize[m, 1]) - robot_r
                    buf[cell] = d < mg
                elif is_disc[m]:
                    cc, ss = cosp[node], sinp[node]
                    buf[cell] = _box_dist(cc * rx + ss * ry, -ss * rx + cc * ry, hx_r, hy_r) - mrad[m] < mg
                else:  # box against box: the separating-axis gap
                    buf[cell] = _box_box_gap(scratch, xy[node, 0], xy[node, 1], cosp[node], sinp[node], hx_r, hy_r,
                                             qx, qy, 0.5 * msize[m, 0], 0.5 * msize[m, 1]) < mg  # fmt: skip
    return count


@njit(cache=True)
def _grow(a, n):
    """``a`` with room for at least ``n`` rows (doubled), its rows kept."""
    if n <= a.shape[0]:
        return a
    b = np.empty((max(n, 2 * a.shape[0]),) + a.shape[1:], a.dtype)
    b[: a.shape[0]] = a
    return b


@njit(cache=True)
def grid_candidates(box, lo, hi, bbox, chunk):
    """Phase 1 of :func:`mark_unsafe` for many movers: every (group, mover, chunk) whose
    boxes overlap, the chunk within the group's steps ``lo..hi``, sorted by group; the
    same set as testing every triple, found through a grid of cells rebuilt per chunk.

    Parameters
    ----------
    box : (G, 4) float
        Groups' boxes (x0, y0, x1, y1).
    lo, hi : (G,) int
    bbox : (M, nc, 4) float
        Movers' boxes per chunk (empty, inf/-inf, where absent).
    chunk : int

    Returns
    -------
    (c, 3) int
    """
    G, M, nc = box.shape[0], bbox.shape[0], bbox.shape[1]
    c0, c1 = nc, -1
    x0 = y0 = np.inf
    x1 = y1 = -np.inf
    for g in range(G):
        a, b = max(lo[g] // chunk, 0), min(hi[g] // chunk, nc - 1)
        if a <= b and lo[g] <= hi[g] and box[g, 0] <= box[g, 2]:
            c0, c1 = min(c0, a), max(c1, b)
            x0, y0 = min(x0, box[g, 0]), min(y0, box[g, 1])
            x1, y1 = max(x1, box[g, 2]), max(y1, box[g, 3])
    out = np.empty((1024, 3), np.int64)
    if c1 < c0:
        return out[:0]
    # cells about as wide as a mover's box over a chunk, at most 256 x 256 of them
    wsum, wn = 0.0, 0
    for m in range(M):
        for c in range(c0, c1 + 1, max(1, (c1 - c0) // 8)):
            if bbox[m, c, 0] <= bbox[m, c, 2]:
                wsum += max(bbox[m, c, 2] - bbox[m, c, 0], bbox[m, c, 3] - bbox[m, c, 1])
                wn += 1
    cell = max(1.0 * wsum / max(wn, 1), (x1 - x0) / 256.0, (y1 - y0) / 256.0, 1e-3)
    nx, ny = int((x1 - x0) / cell) + 1, int((y1 - y0) / cell) + 1
    # the groups active in each chunk
    gptr = np.zeros(c1 - c0 + 2, np.int64)
    for g in range(G):
        if lo[g] <= hi[g] and box[g, 0] <= box[g, 2]:
            for c in range(max(lo[g] // chunk, c0), min(hi[g] // chunk, c1) + 1):
                gptr[c - c0 + 1] += 1
    gptr = np.cumsum(gptr)
    glist = np.empty(gptr[-1], np.int64)
    fill = gptr[:-1].copy()
    for g in range(G):
        if lo[g] <= hi[g] and box[g, 0] <= box[g, 2]:
            for c in range(max(lo[g] // chunk, c0), min(hi[g] // chunk, c1) + 1):
                glist[fill[c - c0]] = g
                fill[c - c0] += 1
    head = np.full(nx * ny, -1, np.int64)
    stamp = np.full(nx * ny, -1, np.int64)  # the chunk a cell's list belongs to
    ent = np.empty((4 * M + 16, 2), np.int64)  # (mover, next entry) linked lists per cell
    seen = np.full(M, -1, np.int64)
    n_out = 0
    token = 0
    for c in range(c0, c1 + 1):
        n_ent = 0
        for m in range(M):
            bx = bbox[m, c]
            if not (bx[0] <= bx[2]) or bx[0] > x1 or bx[2] < x0 or bx[1] > y1 or bx[3] < y0:
                continue  # absent, or clear of every group
            ix0, ix1 = max(int((bx[0] - x0) / cell), 0), min(int((bx[2] - x0) / cell), nx - 1)
            iy0, iy1 = max(int((bx[1] - y0) / cell), 0), min(int((bx[3] - y0) / cell), ny - 1)
            ent = _grow(ent, n_ent + (ix1 - ix0 + 1) * (iy1 - iy0 + 1))
            for iy in range(iy0, iy1 + 1):
                for ix in range(ix0, ix1 + 1):
                    k = iy * nx + ix
                    if stamp[k] != c:
                        stamp[k], head[k] = c, -1
                    ent[n_ent, 0], ent[n_ent, 1] = m, head[k]
                    head[k] = n_ent
                    n_ent += 1
        for r in range(gptr[c - c0], gptr[c - c0 + 1]):
            g = glist[r]
            token += 1
            ix0, ix1 = max(int((box[g, 0] - x0) / cell), 0), min(int((box[g, 2] - x0) / cell), nx - 1)
            iy0, iy1 = max(int((box[g, 1] - y0) / cell), 0), min(int((box[g, 3] - y0) / cell), ny - 1)
            for iy in range(iy0, iy1 + 1):
                for ix in range(ix0, ix1 + 1):
                    k = iy * nx + ix
                    e = head[k] if stamp[k] == c else -1
                    while e >= 0:
                        m = ent[e, 0]
                        e = ent[e, 1]
                        if seen[m] == token:
                            continue
                        seen[m] = token
                        if (bbox[m, c, 0] <= box[g, 2] and box[g, 0] <= bbox[m, c, 2]
                                and bbox[m, c, 1] <= box[g, 3] and box[g, 1] <= bbox[m, c, 3]):  # fmt: skip
                            out = _grow(out, n_out + 1)
                            out[n_out, 0], out[n_out, 1], out[n_out, 2] = g, m, c
                            n_out += 1
    out = out[:n_out]
    return out[np.argsort(out[:, 0], kind="mergesort")]


@njit(cache=True)
def mark_unsafe(grid, ptr, lo, hi, xy, cosp, sinp, row_off, buf, present, mxy, margin_tab, bbox, chunk,
                extent, is_disc, mrad, msize, inner, robot_kind, circ, robot_r, hx_r, hy_r, robot_in, pieces,
                counts):  # fmt: skip
    """Mark the unsafe steps of points in groups (phases 1-3 of
    :meth:`gfuzzy.timespace.movers.MoverField.unsafe_pairs`, the same tests in the same operations).

    Parameters
    ----------
    grid : bool
        Find the (group, mover, chunk) whose boxes overlap through a grid
        (:func:`grid_candidates`: many movers), or test them all (few).
    ptr : (G+1,) int ; lo, hi : (G,) int
        Groups of points and the steps examined per group (clipped to the field).
    xy : (k, 2) float ; cosp, sinp : (k,) float
        The points, and their headings' cosine and sine for a box or footprint robot.
    row_off : (k+1,) int ; buf : (row_off[-1],) bool
        Point i's steps lo..hi of its group are ``buf[row_off[i]:row_off[i+1]]``: set
        where unsafe.
    present, mxy, margin_tab, bbox, chunk, extent, is_disc, mrad, msize, inner
        The field's arrays (:class:`gfuzzy.timespace.movers.MoverField`); ``inner``: the movers'
        inscribed radii.
    robot_kind, circ, robot_r, hx_r, hy_r, robot_in : the robot (0 disc, 1 box, 2
        footprint), its circumradius, disc radius, box half sizes, inscribed radius (-inf
        when the reference point is outside a footprint: no disc about it is inside).
    pieces : (P, V, 2) float ; counts : (P,) int
        A footprint's convex pieces (:meth:`gfuzzy.collision.shapes.FootprintShape.padded`); unused
        otherwise.

    Returns
    -------
    int
        Pairs that passed the cheap tests (the reference's ``evaluations``).
    """
    box, p0, seg, inv, seg2, dev, body = _group_geometry(xy, ptr, circ)
    cand = grid_candidates(box, lo, hi, bbox, chunk) if grid else np.empty((0, 3), np.int64)
    if grid and cand.shape[0] == 0:
        return 0
    scratch = np.empty((2, 4, 2))  # a box's corners, for _box_box_gap
    count = 0
    G = len(ptr) - 1
    bounds = np.searchsorted(cand[:, 0], np.arange(G + 1)) if cand.shape[0] else np.zeros(G + 1, np.int64)
    for g in range(G):
        if lo[g] > hi[g] or (cand.shape[0] and bounds[g] == bounds[g + 1]):
            continue
        count += _mark_group(
            g, cand, bounds[g], bounds[g + 1], ptr[g], ptr[g + 1] - ptr[g], lo[g], hi[g], box[g], p0[g, 0], p0[g, 1],
            seg[g, 0], seg[g, 1], inv[g], seg2[g], dev[g], body[g], row_off, buf, present, mxy, margin_tab, bbox,
            chunk, xy, cosp, sinp, circ, extent, inner, is_disc, mrad, msize, robot_kind, robot_r, hx_r, hy_r,
            robot_in, scratch, pieces, counts,
        )  # fmt: skip
    return count


@njit(cache=True)
def safe_runs(buf, row_off, lo_node):
    """The safe intervals of every row: maximal runs of unmarked steps.

    Parameters
    ----------
    buf : (row_off[-1],) bool
    row_off : (k+1,) int
    lo_node : (k,) int
        The step of each row's first cell.

    Returns
    -------
    starts, ends : (q,) int
        Intervals (inclusive steps), row by row, in time order.
    sp : (k+1,) int
        Row i's intervals are ``starts[sp[i]:sp[i+1]]``.
    """
    k = len(row_off) - 1
    n = (len(buf) + k) // 2 + 1  # at most one interval per two cells of a row, plus one
    starts = np.empty(n, np.int64)
    ends = np.empty(n, np.int64)
    sp = np.empty(k + 1, np.int64)
    q = 0
    for r in range(k):
        sp[r] = q
        a, z = row_off[r], row_off[r + 1]
        free = False
        for i in range(a, z):
            if not buf[i]:
                if not free:
                    starts[q] = lo_node[r] + i - a
                    free = True
            elif free:
                ends[q] = lo_node[r] + i - a - 1
                q += 1
                free = False
        if free:
            ends[q] = lo_node[r] + z - a - 1
            q += 1
    sp[k] = q
    return starts[:q], ends[:q], sp


@njit(cache=True)
def merge_runs(ps, pe, off, cnt, used, nodes, gs, ge, sp, first):
    """Append a batch of safe intervals to a pool, after each node's older ones.

    Node ``nodes[r]`` gets its older intervals ``ps/pe[off:off+cnt]`` (``cnt`` -1: none)
    followed by the batch's ``gs/ge[sp[r]:sp[r+1]]``, which start at step ``first[r]``;
    an older interval ending at ``first[r] - 1`` goes on into a new one starting at
    ``first[r]``. ``off`` and ``cnt`` are updated; the pool must have room.

    Returns
    -------
    int
        The pool's new fill.
    """
    q = used
    for r in range(len(nodes)):
        v = nodes[r]
        a, z = sp[r], sp[r + 1]
        o, c = off[v], cnt[v]
        begin = q
        for i in range(max(c, 0)):
            ps[q] = ps[o + i]
            pe[q] = pe[o + i]
            q += 1
        if c > 0 and a < z and pe[q - 1] == first[r] - 1 and gs[a] == first[r]:
            pe[q - 1] = ge[a]
            a += 1
        for i in range(a, z):
            ps[q] = gs[i]
            pe[q] = ge[i]
            q += 1
        off[v] = begin
        cnt[v] = q - begin
    return q
