"""Reading recorded pedestrian tracks (the ETH/UCY text form, or CSV).

Two input formats (``docs/formats.md``, "Pedestrian tracks"):

* **eth**: the plain-text form in which the ETH (Pellegrini et al., ICCV 2009) and UCY
  (Lerner et al., 2007) data sets are redistributed: one annotation per line,
  whitespace-separated ``frame pedestrian_id x y`` and optionally ``vx vy`` (ignored), ``#``
  comments. A time is ``frame / fps``; by default annotated frames are taken to be 0.4 s
  apart (the data sets' convention), i.e. ``fps = step / 0.4`` with ``step`` the smallest
  frame difference between two rows of one pedestrian (6 or 10, depending on the camera).
* **csv**: a header naming the columns ``t``, ``id``, ``x``, ``y`` (any order, other columns
  ignored), then one row per observation; ``t`` in seconds, ``id`` any name of letters,
  digits, ``_ . -``.

Rows of different people may interleave; each person's times must strictly increase in
file order. :func:`read_tracks` returns :class:`Tracks`; :mod:`gfuzzy.scene.tracks` turns them
into a scene.
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
from dataclasses import dataclass, field
from itertools import pairwise
from pathlib import Path

import numpy as np

from ..errors import InputError, SceneError, not_utf8
from ..settings import MAX_MAGNITUDE, MAX_RECORDED_TIME
from ..typed import FloatArray

__all__ = ["ANNOTATION_PERIOD", "FORMATS", "Track", "Tracks", "read_tracks"]

#: Seconds between consecutive annotated frames in the ETH/UCY data sets.
ANNOTATION_PERIOD = 0.4
FORMATS = ("auto", "eth", "csv")
_ID_RE = re.compile(r"^[A-Za-z0-9_.-]+$")


@dataclass(frozen=True)
class Track:
    """One person's recorded track.

    Attributes
    ----------
    id : str
        The person's id in the file (``"17"`` for the ETH/UCY integer 17).
    rows : (n, 3) float
        ``[t, x, y]``: seconds of the recording and metres (before any scaling); t strictly
        increasing.
    """

    id: str
    rows: FloatArray = field(compare=False)

    @property
    def time_range(self) -> tuple[float, float]:
        """First and last time of the track."""
        return float(self.rows[0, 0]), float(self.rows[-1, 0])


@dataclass(frozen=True)
class Tracks:
    """Every track of one file.

    Attributes
    ----------
    source : str
        The file they were read from.
    format : {"eth", "csv"}
    fps : float or None
        Frames per second used to turn frames into seconds (``None`` for csv).
    frame_step : int or None
        Smallest frame difference between two rows of one person (eth only; None when no
        person has two rows).
    tracks : tuple of Track
        In order of first appearance in the file.
    """

    source: str
    format: str
    fps: float | None
    frame_step: int | None
    tracks: tuple[Track, ...]

    @property
    def time_range(self) -> tuple[float, float]:
        """First and last time of any track."""
        return (
            float(min(tr.rows[0, 0] for tr in self.tracks)),
            float(max(tr.rows[-1, 0] for tr in self.tracks)),
        )


# ---------------------------------------------------------------------------------- reading


def _whole(value: float) -> int | None:
    if math.isfinite(value) and value == int(value):
        return int(value)
    return None


def _id_key(pid: str):
    """Natural order of ids: integers by value first, then names."""
    return (0, int(pid), "") if pid.lstrip("-").isdigit() else (1, 0, pid)


def _read_text(path: str) -> str:
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise SceneError(path, "", f"cannot read: {exc.strerror or exc}") from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SceneError(path, "", not_utf8(data, exc)) from None


def _sniff(path: str, text: str) -> str:
    if path.lower().endswith(".csv"):
        return "csv"
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            return "csv" if "," in line else "eth"
    return "eth"


def _add(
    rows: dict,
    lines: dict,
    path: str,
    lineno: int,
    pid: str,
    t: float,
    x: float,
    y: float,
    unit: str,
):
    # else the scene made of it is refused, naming that scene; times are rebased to the
    # window's start (a Unix time is fine), positions are written as they are
    for name, value, bound in ((unit, t, MAX_RECORDED_TIME), ("x", x, MAX_MAGNITUDE), ("y", y, MAX_MAGNITUDE)):
        if abs(value) > bound:
            raise SceneError(path, f"line {lineno}", f"{name} {value:g} is too large (at most {bound:g} in magnitude)")
    prev = rows.setdefault(pid, [])
    if prev and t <= prev[-1][0]:
        raise SceneError(
            path,
            f"line {lineno}",
            f"pedestrian {pid}: {unit} {t:g} does not increase "
            f"(its previous row, line {lines[pid]}, has {prev[-1][0]:g})",
        )
    prev.append((t, x, y))
    lines[pid] = lineno


def _read_eth(path: str, text: str) -> tuple[dict, int | None]:
    """{id: [(frame, x, y), ...]} of an ETH/UCY text file, and the smallest frame step."""
    rows: dict = {}
    lines: dict = {}
    for lineno, line in enumerate(text.splitlines(), start=1):
        body = line.split("#", 1)[0].strip()
        if not body:
            continue
        cols = body.split()
        if len(cols) not in (4, 6):
            raise SceneError(
                path,
                f"line {lineno}",
                f"expected 4 or 6 columns (frame id x y [vx vy]), got {len(cols)}",
            )
        try:
            nums = [float(c) for c in cols]
        except ValueError:
            raise SceneError(path, f"line {lineno}", f"not a number in {body!r}") from None
        if not all(math.isfinite(v) for v in nums):
            raise SceneError(path, f"line {lineno}", f"non-finite number in {body!r}")
        frame, pid = _whole(nums[0]), _whole(nums[1])
        if frame is None or pid is None:
            raise SceneError(
                path, f"line {lineno}", "frame and pedestrian id must be whole numbers"
            )
        _add(rows, lines, path, lineno, str(pid), frame, nums[2], nums[3], "frame")
    steps = [b[0] - a[0] for r in rows.values() for a, b in pairwise(r)]
    return rows, (min(steps) if steps else None)


def _header_hint(cols: list) -> str:
    """Why a CSV header lacks t, id, x, y when the reason is a common one: another separator
    (a spreadsheet's ``t;id;x;y``), ``time`` for ``t``, or no header at all."""
    if len(cols) == 1 and (sep := next((c for c in ";\t|" if c in cols[0]), None)):
        return f"; the header is one column, {cols[0]!r}: columns are separated by commas, not {sep!r}"
    if "time" in (c.lower() for c in cols):
        return "; name the time column t"
    if all(_is_number(c) for c in cols):
        return "; this first line holds numbers: a CSV starts with a header line such as t,id,x,y"
    return ""


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _read_csv(path: str, text: str) -> dict:
    """{id: [(t, x, y), ...]} of a CSV file with a header naming t, id, x, y."""
    reader = csv.reader(io.StringIO(text))
    header = None
    rows: dict = {}
    lines: dict = {}
    for cols in reader:
        lineno = reader.line_num
        if not cols or not "".join(cols).strip() or cols[0].lstrip().startswith("#"):
            continue
        cols = [c.strip() for c in cols]
        if header is None:
            names = [c.lower() for c in cols]
            missing = [k for k in ("t", "id", "x", "y") if k not in names]
            if missing:
                raise SceneError(
                    path,
                    f"line {lineno}",
                    f"the header must name the columns t, id, x, y (missing: {', '.join(missing)}){_header_hint(cols)}",
                )
            twice = [k for k in ("t", "id", "x", "y") if names.count(k) > 1]
            if twice:  # which of the two holds the values is anyone's guess
                raise SceneError(path, f"line {lineno}", f"the header names column {twice[0]} twice")
            header = names
            index = {k: names.index(k) for k in ("t", "id", "x", "y")}
            continue
        if len(cols) != len(header):
            raise SceneError(
                path, f"line {lineno}", f"expected {len(header)} columns, got {len(cols)}"
            )
        pid = cols[index["id"]]
        if not _ID_RE.match(pid):
            raise SceneError(path, f"line {lineno}", f"id {pid!r} must be letters, digits, _ . -")
        try:
            t, x, y = (float(cols[index[k]]) for k in ("t", "x", "y"))
        except ValueError:
            raise SceneError(
                path, f"line {lineno}", f"not a number in {','.join(cols)!r}"
            ) from None
        if not all(math.isfinite(v) for v in (t, x, y)):
            raise SceneError(path, f"line {lineno}", f"non-finite number in {','.join(cols)!r}")
        _add(rows, lines, path, lineno, pid, t, x, y, "time")
    if header is None:
        raise SceneError(path, "", "no header line (t,id,x,y)")
    return rows


def read_tracks(path: str | os.PathLike, format: str = "auto", fps: float | None = None) -> Tracks:
    """Read a file of pedestrian tracks.

    Parameters
    ----------
    path : path-like
        An ETH/UCY text file or a CSV file (see the module docstring).
    format : {"auto", "eth", "csv"}
        ``auto``: csv for a ``.csv`` name or a first data line with a comma, else eth.
    fps : float, optional
        eth only: frames per second of the recording. Default: ``step / 0.4`` (annotated
        frames 0.4 s apart).

    Returns
    -------
    Tracks

    Raises
    ------
    SceneError
        The file cannot be read, a row cannot be parsed (naming its line), a person's time
        does not increase, or there is no row at all.
    ValueError
        ``format`` or ``fps`` is not allowed.
    """
    file = str(path)
    if format not in FORMATS:
        raise InputError(f"format must be one of {', '.join(FORMATS)}, got {format!r}")
    if fps is not None and not (math.isfinite(fps) and fps > 0):
        raise InputError(f"fps must be positive and finite, got {fps!r}")
    text = _read_text(file)
    fmt = _sniff(file, text) if format == "auto" else format
    step = None
    if fmt == "eth":
        raw, step = _read_eth(file, text)
        if raw and fps is None and step is None:
            raise SceneError(
                file, "", "no pedestrian has two rows: cannot derive the frame rate (give fps)"
            )
        if not raw:
            raise SceneError(file, "", "no data rows")
        # seconds per frame, multiplied (not divided) so that times are those of earlier tools
        spf = 1.0 / fps if fps is not None else ANNOTATION_PERIOD / step
        fps_used = fps if fps is not None else step / ANNOTATION_PERIOD
        raw = {pid: [(f * spf, x, y) for f, x, y in rows] for pid, rows in raw.items()}
    else:
        if fps is not None:
            raise InputError("fps applies to the eth format only (csv times are seconds)")
        raw = _read_csv(file, text)
        fps_used = None
    if not raw:
        raise SceneError(file, "", "no data rows")
    tracks = tuple(Track(pid, np.array(rows, dtype=float)) for pid, rows in raw.items())
    return Tracks(file, fmt, fps_used, step, tracks)
