"""Occupancy-grid maps (ROS map_server / Nav2 format) as static obstacles.

A ``map`` obstacle names a map YAML file (``image``, ``resolution``, ``origin``,
``negate``, ``occupied_thresh``, ``free_thresh``, optional ``mode``) and the image it
names (PGM or PNG, read with Pillow; a relative ``image`` is taken from the YAML's folder,
an absolute one as written, as Nav2 takes them; either must lie inside the scene file's
folder). Each pixel becomes the value Nav2's ``map_io``
(``nav2_map_server/src/map_io.cpp``, ``loadMapFromFile``) gives it, computed the way it
computes it:

* the channels are red, green and blue (a gray image has three equal ones), plus the
  alpha channel in *trinary* mode when the image has one; each 8-bit value v is the
  quantum 257 v (GraphicsMagick's 16-bit quantum), and
  ``shade = (sum / channels) / 65535``;
* ``occ = shade`` when ``negate``, else ``1 - shade``;
* *trinary*: 100 (occupied) when ``occupied_thresh < occ``, else 0 (free) when
  ``occ < free_thresh``, else -1 (unknown): both comparisons strict, as Nav2's;
* *scale*: -1 when alpha is not 255; else 100 / 0 as in trinary, else the cost
  ``rint((occ - free_thresh) / (occupied_thresh - free_thresh) * 100)``;
* *raw*: ``round(shade * 255)`` (half away from zero) when it lies in 0..100, else -1;
  ``negate`` and alpha play no part.

A cell whose value is 100 blocks (Nav2's costmap treats it as lethal), and so does an
unknown one (-1) unless the obstacle says ``unknown: free``. Image row 0 is the top: the
cell in row i, column j of an H-row image is the square
``[ox + j res, ox + (j+1) res] x [oy + (H-1-i) res, oy + (H-i) res]``.

The blocked cells are covered exactly by axis-aligned rectangles (:func:`blocked_rectangles`:
runs of a row merged with the same runs of the rows below), never simplified.
"""

from __future__ import annotations

import hashlib
import io
import math
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import SceneError, not_utf8
from ..typed import FloatArray
from .yamldoc import _V, MAX_MAGNITUDE, _inside, _join, _kind, _load_yaml

__all__ = [
    "MAP_MODES",
    "OCCUPIED",
    "FREE",
    "UNKNOWN",
    "MapInfo",
    "MapObstacle",
    "read_map_yaml",
    "read_image",
    "nav2_values",
    "blocked_rectangles",
    "load_map",
    "free_cell_draw",
]

MAP_MODES = ("trinary", "scale", "raw")
OCCUPIED, FREE, UNKNOWN = 100, 0, -1
MAX_MAP_CELLS = 64_000_000  # a 8000 x 8000 map; beyond that the grid alone is gigabytes
_QUANTUM = 65535.0  # GraphicsMagick's MaxRGB (16-bit quantum, as Ubuntu's ROS packages build it)
_BLOCK_CELLS = 1 << 18  # cells per block of rows when values are computed


@dataclass(frozen=True)
class MapInfo:
    """A map YAML file's contents.

    Attributes
    ----------
    image : Path
        The image file, resolved (as written when absolute, else from the YAML file's folder,
        as Nav2 reads it).
    resolution : float
        Cell size, metres.
    origin : (2,) tuple
        World position of the image's lower-left corner.
    negate : bool
    occupied_thresh, free_thresh : float
    mode : str
        One of :data:`MAP_MODES`.
    """

    image: Path
    resolution: float
    origin: tuple[float, float]
    negate: bool
    occupied_thresh: float
    free_thresh: float
    mode: str = "trinary"


@dataclass(frozen=True)
class MapObstacle:
    """A static obstacle made of an occupancy grid's blocked cells.

    Attributes
    ----------
    file : str
        The map YAML path as the scene wrote it.
    path : Path
        The map YAML file, resolved.
    info : MapInfo
    unknown_free : bool
        True when unknown cells do not block (``unknown: free``).
    values : (H, W) int8
        Nav2's cell values (100 occupied, 0 free, -1 unknown, 1..99 a cost in scale mode,
        0..100 in raw mode), row 0 the image's top row.
    blocked : (H, W) bool
        Cells that are obstacles.
    rects : (k, 4) float
        ``[xmin, ymin, xmax, ymax]`` rectangles whose union is exactly the blocked cells;
        they do not overlap.
    digest : str
        SHA-256 of the YAML and image bytes (enters the scene's static hash).
    """

    file: str
    path: Path
    info: MapInfo
    unknown_free: bool
    values: np.ndarray = field(compare=False, repr=False)
    blocked: np.ndarray = field(compare=False, repr=False)
    rects: FloatArray = field(compare=False, repr=False)
    digest: str = ""

    @property
    def resolution(self) -> float:
        return self.info.resolution

    @property
    def origin(self) -> tuple[float, float]:
        return self.info.origin

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, columns) of the grid."""
        return tuple(self.values.shape)  # type: ignore[return-value]

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` of the whole grid."""
        h, w = self.values.shape
        ox, oy = self.info.origin
        res = self.info.resolution
        return (ox, oy, ox + w * res, oy + h * res)

    def cells_of(self, xy: FloatArray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Row and column of the cell holding each point, and whether it lies on the grid.

        Parameters
        ----------
        xy : (n, 2) float

        Returns
        -------
        rows, cols : (n,) int (clipped to the grid)
        inside : (n,) bool
        """
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        h, w = self.values.shape
        ox, oy = self.info.origin
        res = self.info.resolution
        j = np.floor((xy[:, 0] - ox) / res).astype(np.int64)
        k = np.floor((xy[:, 1] - oy) / res).astype(np.int64)  # from the bottom
        inside = (j >= 0) & (j < w) & (k >= 0) & (k < h)
        return np.clip(h - 1 - k, 0, h - 1), np.clip(j, 0, w - 1), inside

    def centre_axes(self) -> tuple[FloatArray, FloatArray]:
        """The cells' centres: x by column (W,) and y by row (H,), row 0 the top."""
        h, w = self.values.shape
        ox, oy = self.info.origin
        res = self.info.resolution
        return ox + (np.arange(w) + 0.5) * res, oy + (h - 1 - np.arange(h) + 0.5) * res

    def free_centres(self) -> FloatArray:
        """(m, 2) float: centres of the cells that do not block."""
        cx, cy = self.centre_axes()
        i, j = np.nonzero(~self.blocked)
        return np.stack([cx[j], cy[i]], axis=1)


# --------------------------------------------------------------------------- the YAML


def _read_bytes(v: _V, path: Path, place: str, what: str) -> bytes:
    try:
        return path.read_bytes()
    except OSError as exc:
        v.fail(place, f"cannot read {what} {path.name!r}: {exc.strerror or exc}")
    raise AssertionError  # unreachable: fail raises


def _image_hint(data: bytes) -> str:
    """A hint when ``data`` starts as a PGM/PPM, PNG, BMP, JPEG or TIFF file does, else ''."""
    image = data[:2] in (b"P2", b"P3", b"P5", b"P6", b"BM", b"\xff\xd8", b"II", b"MM")
    if image or data[:8] == b"\x89PNG\r\n\x1a\n":
        return " (an image? name the map's YAML file, which names its image)"
    return ""


def _scalar(value):
    """A number written as YAML 1.1 reads it as a string (``1e-07``) is a number to
    yaml-cpp, which Nav2 reads these files with."""
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            return value
    return value


def read_map_yaml(
    path: str | os.PathLike, root: str | os.PathLike | None = None
) -> tuple[MapInfo, bytes]:
    """Read and validate a map YAML file.

    Parameters
    ----------
    path : path-like
        The map YAML file.
    root : path-like, optional
        The folder the image must stay inside (the scene's folder; default: the YAML's).

    Returns
    -------
    MapInfo, bytes
        The contents and the file's bytes.

    Raises
    ------
    SceneError
        Naming the map YAML file and the key: unreadable file, missing key, wrong type,
        resolution not positive, origin not 3 numbers or a non-zero yaw, thresholds not
        ``0 <= free_thresh < occupied_thresh <= 1``, unknown ``mode``, bad ``negate``,
        an image path that leaves ``root``.
    """
    path = Path(path)
    file = str(path)
    v = _V(file)
    data = _read_bytes(v, path, "", "map file")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        v.fail("", f"{not_utf8(data, exc)}{_image_hint(data)}")
    try:
        doc = _load_yaml(text, file)
    except SceneError:
        if _image_hint(data):
            v.fail("", f"not a map YAML file{_image_hint(data)}")
        raise
    if not isinstance(doc, dict):
        v.fail("top level", f"expected a mapping, got {_kind(doc)}{_image_hint(data)}")
    for key in ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh"):
        if key not in doc:
            # a gfuzzy scene handed where a map belongs said only "image: missing required key"
            scene = {"robot", "bounds", "queries"} & set(doc) and "image" not in doc
            v.fail(key, "missing required key" + (": this is a gfuzzy scene file, not a ROS/Nav2 map YAML "
                                                 "(image, resolution, origin, ...)" if scene else ""))  # fmt: skip
    folder = path.resolve().parent
    root = Path(root).resolve() if root is not None else folder
    image = _inside(v, folder, doc["image"], "image", "image", absolute=True)
    try:
        image.relative_to(root)
    except ValueError:
        v.fail(
            "image",
            f"image path {doc['image']!r} leaves the scene file's folder {str(root)!r} "
            "(copy the image beside the map YAML and name it relative)",
        )
    for key in ("resolution", "occupied_thresh", "free_thresh"):
        doc[key] = _scalar(doc[key])
    if isinstance(doc["origin"], list):
        doc["origin"] = [_scalar(x) for x in doc["origin"]]
    resolution = v.number(doc["resolution"], "resolution", positive=True)
    origin = v.vector(doc["origin"], "origin", 3)
    if origin[2] != 0.0:
        v.fail(
            "origin[2]", f"a rotated map (yaw {origin[2]:g}) is not supported: the yaw must be 0"
        )
    negate = doc["negate"]
    if isinstance(negate, bool):
        negate = bool(negate)
    elif isinstance(negate, int) and negate in (0, 1):
        negate = bool(negate)
    else:
        v.fail("negate", f"expected 0 or 1, got {negate!r}")
    occ = v.number(doc["occupied_thresh"], "occupied_thresh")
    free = v.number(doc["free_thresh"], "free_thresh")
    if not 0.0 <= free < occ <= 1.0:
        v.fail(
            "free_thresh",
            f"need 0 <= free_thresh < occupied_thresh <= 1, got free_thresh {free:g}, "
            f"occupied_thresh {occ:g}",
        )
    mode = doc.get("mode", "trinary")
    if mode not in MAP_MODES:
        v.fail("mode", f"unknown mode {mode!r} (allowed: {', '.join(MAP_MODES)})")
    info = MapInfo(image, resolution, (origin[0], origin[1]), negate, occ, free, mode)
    return info, data


# --------------------------------------------------------------------------- the image


def read_image(
    path: str | os.PathLike, data: bytes | None = None, file: str | None = None
) -> tuple[np.ndarray, bool]:
    """Read an image as GraphicsMagick quanta, as Nav2 sees it.

    Parameters
    ----------
    path : path-like
        The image (PGM/PPM, PNG or anything else Pillow reads).
    data : bytes, optional
        Its bytes, when already read.
    file : str, optional
        Name used in error messages (default ``path``).

    Returns
    -------
    quanta : (H, W, 4) uint16
        Red, green, blue and alpha, each 0..65535 (an 8-bit value v is 257 v); integers,
        so that a big map costs 8 bytes a cell here, not 32.
    has_alpha : bool
        Whether the image has an alpha channel (GraphicsMagick's ``matte``).

    Raises
    ------
    SceneError
        Missing, unreadable, truncated or not an image, empty, or more than
        ``MAX_MAP_CELLS`` pixels.
    """
    from PIL import Image, UnidentifiedImageError

    file = str(file or path)
    v = _V(file)
    if data is None:
        check_image_size(v, Path(path))
        data = _read_bytes(v, Path(path), "", "image")
    try:
        with warnings.catch_warnings():  # its size is checked below, against our own bound
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            img = Image.open(io.BytesIO(data))
        with img:
            _refuse_size(v, *img.size)
            img.load()
            arr = _quanta(img)
    except SceneError:
        raise
    except UnidentifiedImageError:
        v.fail("", "not an image Pillow can read (PGM or PNG expected)")
    except (OSError, ValueError, SyntaxError, Image.DecompressionBombError) as exc:
        v.fail("", f"cannot read the image: {' '.join(str(exc).split()) or type(exc).__name__}")
    if arr is None:
        v.fail("", "unsupported image mode (expected gray, RGB, with or without alpha)")
    quanta, has_alpha = arr
    if quanta.shape[0] == 0 or quanta.shape[1] == 0:
        v.fail("", "the image is empty")
    return quanta, has_alpha


def check_image_size(v: _V, path: Path) -> None:
    """Refuse (``v.fail``) an image of more than ``MAX_MAP_CELLS`` pixels from its header,
    before its bytes are read: a 60000 x 60000 PGM took 19 s and 3.6 GB to be refused.
    A PGM/PPM's own header, else Pillow's lazy open (it reads the header only); nothing is
    said when neither tells (:func:`read_image` reads the file and says why)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(4096)
    except OSError:
        return
    if head[:2] in (b"P1", b"P2", b"P3", b"P4", b"P5", b"P6"):
        size = _pnm_size(head)
        if size is not None:
            _refuse_size(v, *size)
        return
    from PIL import Image

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            with Image.open(path) as img:
                size = img.size
    except Image.DecompressionBombError:  # beyond Pillow's own bound, which is above ours
        v.fail("", f"image of more than {2 * Image.MAX_IMAGE_PIXELS:,} pixels, more than gfuzzy's limit "
                   f"MAX_MAP_CELLS ({MAX_MAP_CELLS:,} cells)")  # fmt: skip
    except Exception:  # noqa: BLE001 - not an image Pillow knows: read_image says so
        return
    _refuse_size(v, *size)


def _pnm_size(head: bytes) -> tuple[int, int] | None:
    """(width, height) of a PGM/PPM/PBM header (comments skipped), or None."""
    tokens: list = []
    for line in head[2:].splitlines():
        tokens += line.split(b"#", 1)[0].split()
        if len(tokens) >= 2:
            break
    if len(tokens) >= 2 and tokens[0].isdigit() and tokens[1].isdigit():
        return int(tokens[0]), int(tokens[1])
    return None


def _refuse_size(v: _V, w: int, h: int) -> None:
    if w * h > MAX_MAP_CELLS:
        v.fail("", f"image of {w} x {h} pixels, more than gfuzzy's limit MAX_MAP_CELLS ({MAX_MAP_CELLS:,} cells)")


def _quanta(img) -> tuple[np.ndarray, bool] | None:
    """(H, W, 4) uint16 quanta and whether there is alpha, or None for an odd mode."""
    mode = img.mode
    if mode in ("I;16", "I;16B", "I;16L", "I"):  # 16-bit gray: values are quanta already
        g = np.clip(np.asarray(img), 0, int(_QUANTUM)).astype(np.uint16)
        out = np.empty(g.shape + (4,), dtype=np.uint16)
        out[..., :3] = g[..., None]
        out[..., 3] = int(_QUANTUM)
        return out, False
    has_alpha = mode in ("LA", "La", "RGBA", "RGBa", "PA") or (
        mode == "P" and "transparency" in img.info
    )
    if mode == "L" and "transparency" in img.info:
        has_alpha = True
    if mode not in ("1", "L", "LA", "P", "PA", "RGB", "RGBA", "CMYK", "YCbCr"):
        return None
    rgba = np.asarray(img.convert("RGBA"), dtype=np.uint16)
    rgba *= 257  # 255 * 257 = 65535: no overflow
    return rgba, has_alpha


def nav2_values(quanta: np.ndarray, has_alpha: bool, info: MapInfo) -> np.ndarray:
    """Nav2 ``map_io``'s cell values for an image (module docstring).

    Parameters
    ----------
    quanta : (H, W, 4) uint16 or float
        From :func:`read_image`.
    has_alpha : bool
    info : MapInfo

    Returns
    -------
    (H, W) int8
        100 occupied, 0 free, -1 unknown, other values costs (scale, raw); row 0 the top.
        Computed a block of rows at a time (about 260,000 cells), in double precision as
        Nav2 computes it, so that a big map needs no full-size float arrays.
    """
    h, w = quanta.shape[:2]
    out = np.empty((h, w), dtype=np.int8)
    step = max(1, _BLOCK_CELLS // max(w, 1))
    for r in range(0, h, step):
        out[r : r + step] = _block_values(quanta[r : r + step].astype(np.float64), has_alpha, info)
    return out


def _block_values(quanta: np.ndarray, has_alpha: bool, info: MapInfo) -> np.ndarray:
    """:func:`nav2_values` of some rows, their quanta as float."""
    rgb_sum = quanta[..., 0] + quanta[..., 1] + quanta[..., 2]
    alpha = quanta[..., 3]
    if info.mode == "trinary" and has_alpha:
        shade = (rgb_sum + alpha) / 4.0 / _QUANTUM
    else:
        shade = rgb_sum / 3.0 / _QUANTUM
    out = np.full(shade.shape, UNKNOWN, dtype=np.int8)
    if info.mode == "raw":
        pct = np.floor(shade * 255.0 + 0.5)  # std::round: half away from zero (shade >= 0)
        ok = (pct >= FREE) & (pct <= OCCUPIED)
        out[ok] = pct[ok].astype(np.int8)
        return out
    occ = shade if info.negate else 1.0 - shade
    occupied = info.occupied_thresh < occ
    free = ~occupied & (occ < info.free_thresh)
    out[occupied] = OCCUPIED
    out[free] = FREE
    if info.mode == "scale":
        between = ~occupied & ~free
        cost = np.rint((occ - info.free_thresh) / (info.occupied_thresh - info.free_thresh) * 100.0)
        out[between] = cost[between].astype(np.int8)
        out[alpha != _QUANTUM] = UNKNOWN
    return out


def blocked_cells(values: np.ndarray, unknown_free: bool) -> np.ndarray:
    """(H, W) bool: cells with value 100, and unknown ones (-1) unless ``unknown_free``."""
    blocked = values == OCCUPIED
    if not unknown_free:
        blocked |= values == UNKNOWN
    return blocked


# --------------------------------------------------------------------------- rectangles


def blocked_rectangles(
    blocked: np.ndarray, resolution: float, origin: tuple[float, float]
) -> FloatArray:
    """Exact cover of the blocked cells by non-overlapping axis-aligned rectangles.

    Each row's runs of blocked cells are found; a run continues a rectangle of the row
    above that has exactly the same columns, and otherwise starts one. Rectangular
    blocks (racks, walls, unknown regions) become one rectangle each.

    Parameters
    ----------
    blocked : (H, W) bool
        Row 0 is the top.
    resolution : float
    origin : (2,) float
        World position of the grid's lower-left corner.

    Returns
    -------
    (k, 4) float
        ``[xmin, ymin, xmax, ymax]`` rows.
    """
    h, w = blocked.shape
    pad = np.zeros((h, w + 2), dtype=np.int8)
    pad[:, 1:-1] = blocked
    d = np.diff(pad, axis=1)
    rs, cs = np.nonzero(d == 1)  # run starts (row-major order)
    _, ce = np.nonzero(d == -1)  # run ends (exclusive), same order
    open_: dict[tuple[int, int], int] = {}  # (start, end) -> first row of the open rectangle
    out: list[tuple[int, int, int, int]] = []  # (first row, last row + 1, start, end)
    k, n = 0, len(rs)
    for row in range(h):
        now: dict[tuple[int, int], int] = {}
        while k < n and rs[k] == row:
            key = (int(cs[k]), int(ce[k]))
            now[key] = open_.pop(key, row)
            k += 1
        for (c0, c1), r0 in open_.items():
            out.append((r0, row, c0, c1))
        open_ = now
    for (c0, c1), r0 in open_.items():
        out.append((r0, h, c0, c1))
    if not out:
        return np.zeros((0, 4))
    a = np.asarray(out, dtype=np.float64)
    ox, oy = origin
    xmin = ox + a[:, 2] * resolution
    xmax = ox + a[:, 3] * resolution
    ymax = oy + (h - a[:, 0]) * resolution
    ymin = oy + (h - a[:, 1]) * resolution
    return np.stack([xmin, ymin, xmax, ymax], axis=1)


# --------------------------------------------------------------------------- the obstacle


def load_map(spec, place: str, scene_file: str, folder: str | os.PathLike) -> MapObstacle:
    """Parse a scene's ``map:`` item and read its files.

    Parameters
    ----------
    spec : dict
        ``{file: ..., unknown: blocked | free}``.
    place : str
        Where it is in the scene file (``obstacles[3].map``).
    scene_file : str
        The scene file's name, for errors in ``spec``.
    folder : path-like
        The scene file's folder: both files must stay inside it.

    Raises
    ------
    SceneError
        Naming the scene file (bad ``spec``, a path that leaves the folder), the map YAML
        file and its key, or the image file.
    """
    v = _V(scene_file)
    spec = v.mapping(spec, place, required=("file",), optional=("unknown",))
    folder = Path(folder).resolve()
    fplace = _join(place, "file")
    path = _inside(v, folder, spec["file"], fplace, "map")
    try:
        path.relative_to(folder)
    except ValueError:
        v.fail(fplace, f"map path {spec['file']!r} leaves the scene file's folder")
    if not path.is_file():  # a folder was 'no such file'
        v.fail(fplace, f"cannot read map {spec['file']!r}: {'a folder, not a file' if path.is_dir() else 'no such file'}")
    unknown = spec.get("unknown", "blocked")
    if unknown not in ("blocked", "free"):
        v.fail(_join(place, "unknown"), f"expected blocked or free, got {unknown!r}")
    info, ydata = read_map_yaml(path, root=folder)
    check_image_size(_V(str(info.image)), info.image)  # before its bytes are read
    idata = _read_bytes(_V(str(info.image)), info.image, "", "image")
    quanta, has_alpha = read_image(info.image, idata, file=str(info.image))
    values = nav2_values(quanta, has_alpha, info)
    blocked = blocked_cells(values, unknown == "free")
    rects = blocked_rectangles(blocked, info.resolution, info.origin)
    h, w = values.shape
    far = (info.origin[0] + w * info.resolution, info.origin[1] + h * info.resolution)
    if not all(math.isfinite(c) and abs(c) <= MAX_MAGNITUDE for c in far):  # a scene's bounds: else the
        # error named the bounds of a scene `gfuzzy map` had not written (its output file)
        raise SceneError(
            str(path), "resolution", f"the map's far corner ({far[0]:g}, {far[1]:g}) = origin + {w} x {h} cells x "
            f"{info.resolution:g} m lies beyond {MAX_MAGNITUDE:g} in magnitude (a scene's bound)"
        )
    # cells narrower than a float's spacing at the map's coordinates have no size: their edges
    # coincide (resolution 1e-300 at origin -10 made bounds of zero width, and a traceback)
    spacing = float(np.spacing(max(abs(c) for c in (*info.origin, *far))))
    if not info.resolution > spacing:
        raise SceneError(
            str(path), "resolution", f"{info.resolution:g} m is too small: floats are {spacing:g} m apart at the "
            f"map's coordinates (origin ({info.origin[0]:g}, {info.origin[1]:g})), so its cells would have no size"
        )
    digest = hashlib.sha256(ydata + b"\0" + idata).hexdigest()
    return MapObstacle(spec["file"], path, info, unknown == "free", values, blocked, rects, digest)


# --------------------------------------------------------------------------- sampling


def free_cell_draw(obstacles, bounds, rng: np.random.Generator, share: float):
    """A draw of points uniform over the free cells of the maps among ``obstacles``.

    Parameters
    ----------
    obstacles : sequence
        A scene's static obstacles; only its :class:`MapObstacle` items count.
    bounds : (4,) float
        Cells whose centre lies outside are left out.
    rng : numpy.random.Generator
        The roadmap's generator (seeded by its seed).
    share : float
        Returns None when the free cells cover more than this share of the bounds (uniform
        sampling in the bounds then wastes little).

    Returns
    -------
    callable () -> (2,) float, or None
        None without a map.
    """
    xmin, ymin, xmax, ymax = bounds
    grids, axes, cells = [], [], []  # the maps, their centres' axes, their free cells' flat indices
    for grid in obstacles:
        if isinstance(grid, MapObstacle):
            cx, cy = grid.centre_axes()
            keep = ~np.asarray(grid.blocked)
            keep &= ((cy > ymin) & (cy < ymax))[:, None]
            keep &= ((cx > xmin) & (cx < xmax))[None, :]
            grids.append(grid)
            axes.append((cx, cy))
            cells.append(np.flatnonzero(keep))
    if not grids:
        return None
    counts = np.array([len(c) for c in cells])
    area = sum(int(n) * g.resolution**2 for n, g in zip(counts, grids, strict=True))
    if counts.sum() == 0 or area > share * (xmax - xmin) * (ymax - ymin):
        return None
    ends = np.cumsum(counts)

    def draw() -> FloatArray:
        k = int(rng.integers(int(ends[-1])))
        g = int(np.searchsorted(ends, k, side="right"))
        (cx, cy), res = axes[g], grids[g].resolution
        i, j = divmod(int(cells[g][k - (int(ends[g - 1]) if g else 0)]), len(cx))
        return np.array([cx[j], cy[i]]) + (rng.random(2) - 0.5) * res

    return draw
