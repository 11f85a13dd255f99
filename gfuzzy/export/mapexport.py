"""A scene's static obstacles as a Nav2 / ROS map_server map (PGM + YAML, trinary).

:func:`rasterise` marks every grid cell that an obstacle overlaps with positive area: the
cell's open square meets the obstacle's interior. That is exact, not sampled: discs by the
distance from their centre to the square (in rational arithmetic where rounding could
decide), map obstacles by their rectangles' coordinates,
boxes, polygons and mesh footprints with shapely's exact predicates: the cells near the
boundary (traced along every ring) by the DE-9IM interior-interior test, every other cell,
which lies wholly inside or outside, by its centre. So the map never loses an obstacle: the
blocked cells cover each obstacle, and a robot that overlaps an obstacle overlaps a blocked
cell. An edge lying on a cell border does not mark the cell beyond it (touching is no
collision, contract section 1), also when the two were computed apart and differ by a
rounding: an obstacle must reach more than :func:`edge_tolerance` into a cell (the
touching ``gfuzzy check`` tolerates) to mark it. A map scene's cells at ``-12.5 + 60 *
0.05`` and the grid's at ``-9.55 + 1 * 0.05`` are the same line a few ulps apart; counted as
overlap, they thickened every wall on one side by a cell (small-house: 771 cells).

The grid covers the scene's bounds from their lower-left corner, rounded up to whole cells;
image row 0 is the top (contract section 6), so the cell in row i, column j of an H-row
image is ``[ox + j res, ox + (j+1) res] x [oy + (H-1-i) res, oy + (H-i) res]``.
"""

from __future__ import annotations

import json
import logging
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..atomic import remove_quietly
from ..errors import InputError, check_interrupt, check_number, interrupts_deferred
from ..scene.scene import Box, Disc, Polygon, Scene
from ..typed import FloatArray

__all__ = ["NavMap", "rasterise", "export_nav2_map", "obstacle_boxes", "edge_tolerance", "MAX_MAP_CELLS", "OCCUPIED", "FREE"]

log = logging.getLogger(__name__)

#: Largest grid written (cells): 50 million, a 354 m square at 5 cm.
MAX_MAP_CELLS = 50_000_000
#: Trinary shades: black is occupied, near-white free (map_saver's values).
OCCUPIED, FREE = 0, 254
OCCUPIED_THRESH, FREE_THRESH = 0.65, 0.25
#: Candidate cells tested per batch (bounds memory on a large obstacle).
_BATCH = 1_000_000


@dataclass(frozen=True)
class NavMap:
    """A rasterised scene.

    Attributes
    ----------
    occupied : (H, W) bool
        Row 0 is the top (largest y), as in the image.
    resolution : float
        Metres per cell.
    origin : (2,) tuple
        World position of the grid's lower-left corner.
    """

    occupied: np.ndarray
    resolution: float
    origin: tuple[float, float]

    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)``."""
        return self.occupied.shape

    def cell_box(self, i: int, j: int) -> tuple[float, float, float, float]:
        """The square of row ``i`` (0 at the top), column ``j``: ``(x0, y0, x1, y1)``."""
        h = self.occupied.shape[0]
        ox, oy = self.origin
        res = self.resolution
        return (ox + j * res, oy + (h - 1 - i) * res, ox + (j + 1) * res, oy + (h - i) * res)

    def pgm(self) -> bytes:
        """The image as binary PGM (P5, 8 bit)."""
        h, w = self.occupied.shape
        pixels = np.where(self.occupied, OCCUPIED, FREE).astype(np.uint8)
        return f"P5\n# gfuzzy export\n{w} {h}\n255\n".encode("ascii") + pixels.tobytes()

    def yaml_text(self, image: str) -> str:
        """The map YAML naming ``image`` (relative to the YAML)."""
        ox, oy = self.origin
        return (
            f"image: {json.dumps(image)}\n"  # a JSON string is a YAML scalar, whatever the name
            f"mode: trinary\n"
            f"resolution: {self.resolution!r}\n"
            f"origin: [{ox!r}, {oy!r}, 0.0]\n"
            f"negate: 0\n"
            f"occupied_thresh: {OCCUPIED_THRESH}\n"
            f"free_thresh: {FREE_THRESH}\n"
        )


def _grid(scene: Scene, resolution: float) -> tuple[int, int, float, float]:
    x0, y0, x1, y1 = scene.bounds
    wf, hf = (x1 - x0) / resolution, (y1 - y0) / resolution
    if not wf * hf <= 1e18:  # a resolution of 1e-300: ceil(inf), or w * h as a float, overflowed
        raise InputError(f"resolution {resolution:g} m gives a grid of {wf * hf:.3g} cells (at most {MAX_MAP_CELLS:,}); use a coarser resolution")
    w = max(1, math.ceil(wf - 1e-9))
    h = max(1, math.ceil(hf - 1e-9))
    if w * h > MAX_MAP_CELLS:
        raise InputError(
            f"resolution {resolution:g} m gives a {w} x {h} grid ({w * h:.3g} cells, at most {MAX_MAP_CELLS:,}); use a coarser resolution"
        )
    return w, h, float(x0), float(y0)


def _span(lo: float, hi: float, origin: float, res: float, n: int) -> tuple[int, int]:
    """Cell indices ``a <= k < b`` whose open interval may meet ``(lo, hi)`` (one cell of slack
    each side against rounding; the exact tests decide)."""
    a = max(0, int(math.floor((lo - origin) / res)) - 1)
    b = min(n, int(math.floor((hi - origin) / res)) + 2)
    return a, max(a, b)


def edge_tolerance(w: int, h: int, ox: float, oy: float, res: float) -> float:
    """How far (m) an obstacle may reach into a cell without marking it: the overlap
    ``gfuzzy check`` tolerates as touching (:data:`gfuzzy.collision.exact.TOUCH_TOL`), or,
    on a grid far from the origin, 8 ulps of its largest coordinate (the rounding of
    ``origin + k * res`` there)."""
    from ..collision.exact import TOUCH_TOL

    far = max(abs(ox), abs(oy), abs(ox + w * res), abs(oy + h * res))
    return max(TOUCH_TOL, 8.0 * float(np.spacing(far)))


def _cell_edges(origin: float, res: float, a: int, b: int) -> FloatArray:
    k = np.arange(a, b + 1)
    return origin + k * res  # the reader's very expression (contract section 6)


def _mark_disc(occ: np.ndarray, d: Disc, w: int, h: int, ox: float, oy: float, res: float, eps: float) -> bool:
    """Whether the disc marked a cell."""
    cx, cy = d.center
    r = d.radius
    ja, jb = _span(cx - r, cx + r, ox, res, w)
    ka, kb = _span(cy - r, cy + r, oy, res, h)
    if ja >= jb or ka >= kb:
        return False
    xe, ye = _cell_edges(ox, res, ja, jb), _cell_edges(oy, res, ka, kb)
    # distance from the centre to each closed square (shrunk by eps), per axis; the open
    # square meets the open disc exactly when that distance is below the radius
    dx = np.maximum(np.maximum(xe[:-1] + eps - cx, cx - (xe[1:] - eps)), 0.0)
    dy = np.maximum(np.maximum(ye[:-1] + eps - cy, cy - (ye[1:] - eps)), 0.0)
    d2 = dy[:, None] ** 2 + dx[None, :] ** 2  # (rows by y, cols)
    hit = d2 < r * r
    # where rounding could decide (a cell within a few ulps of the circle), decide exactly
    for k, j in zip(*np.nonzero(np.abs(d2 - r * r) <= 1e-9 * r * r), strict=True):
        hit[k, j] = _disc_meets_cell(cx, cy, r, xe[j] + eps, ye[k] + eps, xe[j + 1] - eps, ye[k + 1] - eps)
    occ[ka:kb, ja:jb] |= hit
    return bool(hit.any())


def _disc_meets_cell(cx: float, cy: float, r: float, x0: float, y0: float, x1: float, y1: float) -> bool:
    """Whether the open disc meets the open square, in exact rational arithmetic on the
    floats given."""
    from fractions import Fraction as F

    cx, cy, r, x0, y0, x1, y1 = (F(float(v)) for v in (cx, cy, r, x0, y0, x1, y1))
    dx = max(x0 - cx, cx - x1, F(0))
    dy = max(y0 - cy, cy - y1, F(0))
    return dx * dx + dy * dy < r * r


def _boundary_cells(poly, ja: int, ka: int, shape: tuple[int, int], ox: float, oy: float, res: float) -> np.ndarray:
    """A superset of the cells (in the block starting at column ``ja``, row ``ka``) whose
    closed square meets the polygon's boundary: points every res/4 along every ring, and
    the 3 x 3 cells around each.

    Returns
    -------
    (rows, cols) bool
    """
    segs = []
    for ring in (poly.exterior, *poly.interiors):
        c = np.asarray(ring.coords, dtype=float)
        segs.append(np.stack([c[:-1], c[1:]], axis=1))
    seg = np.concatenate(segs)  # (m, 2, 2)
    d = seg[:, 1] - seg[:, 0]
    n = np.ceil(np.hypot(d[:, 0], d[:, 1]) / (0.25 * res)).astype(np.int64) + 1
    which = np.repeat(np.arange(len(seg)), n)
    start = np.repeat(np.cumsum(n) - n, n)
    frac = (np.arange(int(n.sum())) - start) / np.repeat(np.maximum(n - 1, 1), n)
    pts = seg[which, 0] + frac[:, None] * d[which]
    j = np.floor((pts[:, 0] - ox) / res).astype(np.int64) - ja
    k = np.floor((pts[:, 1] - oy) / res).astype(np.int64) - ka
    out = np.zeros(shape, dtype=bool)
    for dk in (-1, 0, 1):
        for dj in (-1, 0, 1):
            kk, jj = k + dk, j + dj
            ok = (kk >= 0) & (kk < shape[0]) & (jj >= 0) & (jj < shape[1])
            out[kk[ok], jj[ok]] = True
    return out


def _mark_polygon(occ: np.ndarray, poly, w: int, h: int, ox: float, oy: float, res: float, eps: float) -> bool:
    """Cells near the boundary by the exact DE-9IM test (their open square, shrunk by
    ``eps``, meets the interior); every other cell lies wholly inside or outside, which its
    centre tells. Whether the polygon marked a cell."""
    import shapely

    bx0, by0, bx1, by1 = poly.bounds
    ja, jb = _span(bx0, bx1, ox, res, w)
    ka, kb = _span(by0, by1, oy, res, h)
    if ja >= jb or ka >= kb:
        return False
    shapely.prepare(poly)
    marked = False
    xe, ye = _cell_edges(ox, res, ja, jb), _cell_edges(oy, res, ka, kb)
    near = _boundary_cells(poly, ja, ka, (kb - ka, jb - ja), ox, oy, res)
    xc = 0.5 * (xe[:-1] + xe[1:])
    rows_per = max(1, _BATCH // (jb - ja))
    for r0 in range(0, kb - ka, rows_per):
        r1 = min(kb - ka, r0 + rows_per)
        yc = 0.5 * (ye[r0:r1] + ye[r0 + 1 : r1 + 1])
        inside = shapely.contains_xy(poly, xc[None, :], yc[:, None])
        inside &= ~near[r0:r1]
        occ[ka + r0 : ka + r1, ja:jb] |= inside
        marked = marked or bool(inside.any())
    k, j = np.nonzero(near)
    if len(k):
        cells = shapely.box(xe[j] + eps, ye[k] + eps, xe[j + 1] - eps, ye[k + 1] - eps)
        hit = shapely.relate_pattern(cells, poly, "T********")
        occ[ka + k[hit], ja + j[hit]] = True
        marked = marked or bool(hit.any())
    return marked


def obstacle_boxes(ob) -> FloatArray | None:
    """The blocked cells of a map obstacle as boxes ``(x0, y0, x1, y1)`` (its ``rects``:
    rectangles whose union is exactly the blocked cells), or None for another obstacle.

    Returns
    -------
    (k, 4) float or None
    """
    rects = getattr(ob, "rects", None)
    if rects is None:
        return None
    return np.asarray(rects, dtype=float).reshape(-1, 4)


def _mark_rects(occ: np.ndarray, rects: FloatArray, w: int, h: int, ox: float, oy: float, res: float, eps: float) -> bool:
    """Axis-aligned rectangles, exactly: the open cell (a, b) shrunk by ``eps`` meets the open
    rectangle (x0, x1) when a + eps < x1 and b - eps > x0 (and the same along y). Whether
    they marked a cell."""
    xe, ye = _cell_edges(ox, res, 0, w), _cell_edges(oy, res, 0, h)
    marked = False
    for x0, y0, x1, y1 in rects:
        ja, jb = int(np.searchsorted(xe[1:] - eps, x0, side="right")), int(np.searchsorted(xe[:-1] + eps, x1, side="left"))
        ka, kb = int(np.searchsorted(ye[1:] - eps, y0, side="right")), int(np.searchsorted(ye[:-1] + eps, y1, side="left"))
        if ja < jb and ka < kb:
            occ[ka:kb, ja:jb] = True
            marked = True
    return marked


def _shapes(ob, index: int):
    """The shapely polygons of a non-disc obstacle."""
    import shapely

    if isinstance(ob, Box):
        return [shapely.Polygon(ob.vertices())]
    if isinstance(ob, Polygon):
        return [shapely.Polygon(ob.points, list(ob.holes))]
    raise InputError(f"obstacles[{index}]: cannot rasterise an obstacle of type {type(ob).__name__}")


def _mark(occ: np.ndarray, ob, index: int, w: int, h: int, ox: float, oy: float, res: float, eps: float) -> bool:
    """Mark the cells obstacle ``ob`` reaches more than ``eps`` into; whether it marked any."""
    boxes = obstacle_boxes(ob)
    if isinstance(ob, Disc):
        return _mark_disc(occ, ob, w, h, ox, oy, res, eps)
    if boxes is not None:
        return _mark_rects(occ, boxes, w, h, ox, oy, res, eps)
    marked = [_mark_polygon(occ, poly, w, h, ox, oy, res, eps) for poly in _shapes(ob, index)]
    return any(marked)


def rasterise(scene: Scene, resolution: float = 0.05) -> NavMap:
    """The scene's static obstacles on a grid over its bounds.

    Parameters
    ----------
    scene : Scene
    resolution : float
        Metres per cell.

    Returns
    -------
    NavMap
        A cell is occupied exactly when an obstacle overlaps it with positive area, reaching
        more than :func:`edge_tolerance` into it (less is touching, as ``gfuzzy check`` sees it);
        an obstacle that reaches that far into no cell marks every cell it overlaps at all.

    Raises
    ------
    InputError
        A resolution that is not a positive number, or a grid above ``MAX_MAP_CELLS``.
    """
    check_number("resolution", resolution)
    res = float(resolution)
    w, h, ox, oy = _grid(scene, res)
    occ = np.zeros((h, w), dtype=bool)  # row k is y-index k (bottom first) until flipped
    eps = edge_tolerance(w, h, ox, oy, res)
    for i, ob in enumerate(scene.obstacles):
        # an obstacle thinner than twice the tolerance (a wall 0.8e-9 m thick on a cell
        # border) would mark no cell: marked again with none, so none is ever lost
        if not _mark(occ, ob, i, w, h, ox, oy, res, eps):
            _mark(occ, ob, i, w, h, ox, oy, res, 0.0)
    return NavMap(occ[::-1].copy(), res, (ox, oy))


def export_nav2_map(scene: Scene, path, resolution: float = 0.05) -> NavMap:
    """Write ``scene``'s static obstacles as a Nav2 map: ``path`` (YAML) and its image.

    The image is the YAML's name with ``.pgm`` beside it. Both files are written to
    temporaries first and renamed into place only once both are complete, so a failure
    leaves neither a half-written file nor a new image without its YAML.

    Parameters
    ----------
    scene : Scene
    path : path-like
        The map YAML (``.yaml`` or ``.yml``).
    resolution : float
        Metres per cell (default 0.05, Nav2's usual).

    Returns
    -------
    NavMap
    """
    import tempfile

    grid = rasterise(scene, resolution)
    path = Path(path)
    image = path.with_suffix(".pgm")
    if image == path:
        raise InputError(f"{path}: the map YAML must not end in .pgm")
    folder = path.parent
    folder.mkdir(parents=True, exist_ok=True)
    temps: list[str] = []
    image_existed = image.exists()
    placed_image = False
    try:
        for suffix, data in ((".pgm", grid.pgm()), (".yaml", grid.yaml_text(image.name).encode())):
            try:
                fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=suffix, dir=folder)
            except OSError as exc:  # name the file asked for, not the temporary one
                raise OSError(exc.errno, exc.strerror, str(image if suffix == ".pgm" else path)) from exc
            temps.append(tmp)
            with os.fdopen(fd, "wb") as fh:
                fh.write(data)
        umask = os.umask(0)
        os.umask(umask)
        for tmp in temps:
            os.chmod(tmp, 0o666 & ~umask)
        check_interrupt()  # an interrupt native code dropped: publish neither file
        with interrupts_deferred():  # Ctrl-C now: both files (a new image beside an old YAML misleads)
            os.replace(temps[0], image)
            placed_image = True
            os.replace(temps[1], path)
            temps.clear()
            placed_image = False  # both published: a Ctrl-C raised as the section ends keeps them
    except BaseException:
        with interrupts_deferred():  # a second Ctrl-C leaves no temporary, no lone image
            remove_quietly(*temps, *([image] if placed_image and not image_existed else []))
        raise
    log.info("wrote %s and %s (%d x %d cells)", path, image, grid.shape[1], grid.shape[0])
    return grid
