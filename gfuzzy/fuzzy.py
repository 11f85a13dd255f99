"""The fuzzy speed layer: a Mamdani controller that bounds the speed along a path.

After Antonelli, Chiaverini and Fusco, "A fuzzy-logic-based approach for mobile
robot path tracking", IEEE Transactions on Fuzzy Systems 15(2), 2007: the robot
looks ahead along its path, measures how much the path turns there (*curve*) and
how far away that bend is (*distance*), and a fuzzy rule base turns the pair into
a cruise speed. Sharp, near bends give a low speed, straights and far bends a high
one. The rule base is a chromosome (one allele per pair of input sets) and can be
learned by a genetic algorithm in three self-organising stages (:func:`learn_rules`).

Pipeline of :func:`speed_limit`::

    path (n, 2) --curve_ahead--> curve, distance in [0, 1] at arc lengths s
                --Mamdani (min AND, max aggregation, centroid)--> speed fraction
                --x vmax, forward-backward pass with amax--> v(s)

Conventions
-----------
* Inputs and output live on ``[0, 1]``. Every partition is a Ruspini partition of
  triangles: the feet of set ``i`` are the peaks of its neighbours (the end sets
  mirror theirs outside ``[0, 1]``), so memberships sum to one everywhere.
* The chromosome is ``genes[i * n_distance + j]`` for curve set ``i`` and distance
  set ``j``; ``0`` means *no rule*, ``k >= 1`` means *speed is output set k - 1*.
* When no rule fires the raw controller output is ``FuzzyOptions.min_speed``.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gfuzzy.errors import SceneError
from gfuzzy.rng import create_rng
from gfuzzy.typing import ArrayLike, FloatArray, PathType

logger = logging.getLogger(__name__)
logger.addHandler(logging.NullHandler())

__all__ = [
    "LABELS",
    "UNEQUAL_PEAKS",
    "Partition",
    "RuleBase",
    "FuzzyOptions",
    "SpeedController",
    "LearnOptions",
    "LearnResult",
    "curve_ahead",
    "infer_exact",
    "limit_acceleration",
    "speed_limit",
    "profile_times",
    "expert_rules",
    "learned_rules",
    "parse_rules",
    "format_rules",
    "load_rules",
    "save_rules",
    "learn_rules",
]

#: Set labels by partition size, from the lowest value to the highest.
LABELS: dict[int, tuple[str, ...]] = {
    3: ("L", "Z", "H"),
    5: ("VL", "L", "Z", "H", "VH"),
    7: ("VVL", "VL", "L", "Z", "H", "VH", "VVH"),
}

#: Peaks of the unequal partitions: narrow sets near 0 (near-straight paths,
#: near bends), where small differences matter most, wide ones near 1. All are
#: multiples of 0.05 so they fall on the default grids exactly.
UNEQUAL_PEAKS: dict[int, tuple[float, ...]] = {
    3: (0.0, 0.3, 1.0),
    5: (0.0, 0.1, 0.3, 0.6, 1.0),
    7: (0.0, 0.05, 0.15, 0.3, 0.5, 0.75, 1.0),
}

_DATA = "data"
_EXPERT_FILE = "rules_expert.txt"
_LEARNED_FILE = "rules_learned.txt"


# --------------------------------------------------------------------------
# Membership functions and rule bases
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class Partition:
    """A Ruspini partition of ``[0, 1]`` into triangular fuzzy sets.

    Parameters
    ----------
    peaks : tuple of float, length 3, 5 or 7
        Strictly increasing peaks, the first 0 and the last 1. Set ``i`` is the
        triangle ``(peaks[i-1], peaks[i], peaks[i+1])``; the end sets mirror
        their inner foot outside ``[0, 1]`` (so each is a full triangle whose
        centre sits on the universe's edge).

    Raises
    ------
    ValueError
        If the peaks are not as above.
    """

    peaks: tuple[float, ...]

    def __post_init__(self) -> None:
        peaks = tuple(float(p) for p in self.peaks)
        object.__setattr__(self, "peaks", peaks)
        if len(peaks) not in LABELS:
            raise ValueError(f"a partition has 3, 5 or 7 sets, not {len(peaks)}")
        if not all(math.isfinite(p) for p in peaks):
            raise ValueError("partition peaks must be finite")
        if peaks[0] != 0.0 or peaks[-1] != 1.0:
            raise ValueError("partition peaks must start at 0 and end at 1")
        if any(b <= a for a, b in zip(peaks, peaks[1:], strict=False)):
            raise ValueError("partition peaks must be strictly increasing")

    @classmethod
    def uniform(cls, n: int) -> Partition:
        """``n`` sets with equal base lengths (peaks ``linspace(0, 1, n)``)."""
        if n not in LABELS:
            raise ValueError(f"a partition has 3, 5 or 7 sets, not {n}")
        return cls(tuple(i / (n - 1) for i in range(n)))

    @classmethod
    def unequal(cls, n: int) -> Partition:
        """``n`` sets with unequal base lengths (:data:`UNEQUAL_PEAKS`)."""
        if n not in UNEQUAL_PEAKS:
            raise ValueError(f"a partition has 3, 5 or 7 sets, not {n}")
        return cls(UNEQUAL_PEAKS[n])

    @property
    def size(self) -> int:
        """Number of sets."""
        return len(self.peaks)

    @property
    def labels(self) -> tuple[str, ...]:
        """Set labels, lowest first (:data:`LABELS`)."""
        return LABELS[self.size]

    @property
    def triangles(self) -> FloatArray:
        """Feet and peaks, ``(n, 3) float``: rows ``(a, b, c)`` with ``a < b < c``."""
        p = np.asarray(self.peaks)
        left = np.concatenate(([2 * p[0] - p[1]], p[:-1]))
        right = np.concatenate((p[1:], [2 * p[-1] - p[-2]]))
        return np.stack([left, p, right], axis=1)

    def membership(self, x: ArrayLike) -> FloatArray:
        """Membership degrees of ``x`` in every set.

        Parameters
        ----------
        x : (m,) float
            Values; clipped to ``[0, 1]``.

        Returns
        -------
        (m, n) float
            Degrees in ``[0, 1]``; each row sums to 1.
        """
        x = np.clip(np.asarray(x, dtype=float).reshape(-1), 0.0, 1.0)
        return _triangles(x[:, None], self.triangles)

    def spec(self) -> str:
        """The partition as written in a rule file: ``uniform 7``, ``unequal 5``
        or ``peaks 0 0.2 ... 1``."""
        n = self.size
        if self == Partition.uniform(n):
            return f"uniform {n}"
        if self == Partition.unequal(n):
            return f"unequal {n}"
        return "peaks " + " ".join(repr(p) for p in self.peaks)


def _triangles(x: FloatArray, tri: FloatArray) -> FloatArray:
    """Triangle memberships, ``x`` broadcast against rows of ``tri`` ``(n, 3)``."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    up = (x - a) / (b - a)
    down = (c - x) / (c - b)
    return np.clip(np.minimum(up, down), 0.0, 1.0)


_UNIFORM7 = Partition.uniform(7)
_UNIFORM5 = Partition.uniform(5)


@dataclass(frozen=True)
class RuleBase:
    """A Mamdani rule base over *curve* x *distance* -> *speed*: the chromosome.

    Parameters
    ----------
    genes : tuple of int, length ``curve.size * distance.size``
        Row-major: ``genes[i * distance.size + j]`` is the rule for curve set
        ``i`` and distance set ``j``; 0 = no rule, ``k`` in ``1..speed.size`` =
        *speed is* ``speed.labels[k - 1]``.
    curve, distance, speed : Partition
        The partitions of the two inputs and of the output (defaults 7, 5, 7
        uniform sets). They travel with the genes: an allele means nothing
        without them.

    Raises
    ------
    ValueError
        If the genes do not fit the partitions.
    """

    genes: tuple[int, ...]
    curve: Partition = _UNIFORM7
    distance: Partition = _UNIFORM5
    speed: Partition = _UNIFORM7

    def __post_init__(self) -> None:
        genes = tuple(int(g) for g in np.asarray(self.genes).reshape(-1))
        object.__setattr__(self, "genes", genes)
        n = self.curve.size * self.distance.size
        if len(genes) != n:
            raise ValueError(
                f"expected {n} genes ({self.curve.size} x {self.distance.size}), got {len(genes)}"
            )
        bad = [g for g in genes if not 0 <= g <= self.speed.size]
        if bad:
            raise ValueError(f"genes must be in 0..{self.speed.size}, got {bad[0]}")

    @classmethod
    def from_matrix(
        cls,
        matrix: ArrayLike,
        curve: Partition = _UNIFORM7,
        distance: Partition = _UNIFORM5,
        speed: Partition = _UNIFORM7,
    ) -> RuleBase:
        """Build from a ``(curve.size, distance.size) int`` matrix of alleles."""
        m = np.asarray(matrix)
        if m.shape != (curve.size, distance.size):
            raise ValueError(f"matrix shape {m.shape} != {(curve.size, distance.size)}")
        return cls(tuple(int(g) for g in m.reshape(-1)), curve, distance, speed)

    @property
    def matrix(self) -> np.ndarray:
        """Alleles as a ``(curve.size, distance.size) int`` array (a copy)."""
        return np.array(self.genes, dtype=np.int64).reshape(self.curve.size, self.distance.size)

    @property
    def n_rules(self) -> int:
        """Number of rules (non-zero alleles)."""
        return sum(1 for g in self.genes if g)

    def table(self) -> str:
        """The rule base as a table: rows curve labels, columns distance labels,
        entries speed labels or ``-`` for no rule."""
        corner = "curve\\dist"
        cols = self.distance.labels
        width = max(4, max(len(s) for s in self.speed.labels) + 1)
        head = f"{corner:<11}" + "".join(f"{c:<{width}}" for c in cols).rstrip()
        rows = [head]
        m = self.matrix
        for i, lab in enumerate(self.curve.labels):
            cells = [self.speed.labels[g - 1] if g else "-" for g in m[i]]
            rows.append(f"{lab:<11}" + "".join(f"{c:<{width}}" for c in cells).rstrip())
        return "\n".join(rows)

    def __str__(self) -> str:
        return self.table()


# --------------------------------------------------------------------------
# Rule files
# --------------------------------------------------------------------------

_HEADER = """\
# gfuzzy fuzzy speed rule base (Mamdani: min AND, max aggregation, centroid).
# Inputs in [0, 1]: curve = turning ahead / max_turn, dist = distance to the bend / look-ahead.
# Output: speed as a fraction of vmax. Rows: curve sets; columns: distance sets;
# entries: speed set, '-' = no rule. Partitions: 'uniform N', 'unequal N' or 'peaks ...'.
"""


def format_rules(rulebase: RuleBase, comment: str = "") -> str:
    """The text of a rule file for ``rulebase`` (see :func:`parse_rules`).

    Parameters
    ----------
    rulebase : RuleBase
    comment : str
        Extra lines written as ``#`` comments after the standard header.
    """
    lines = [_HEADER.rstrip("\n")]
    lines += [f"# {c}".rstrip() for c in comment.splitlines()]
    lines += [
        f"curve: {rulebase.curve.spec()}",
        f"distance: {rulebase.distance.spec()}",
        f"speed: {rulebase.speed.spec()}",
        "",
        "rules:",
        rulebase.table(),
    ]
    return "\n".join(lines) + "\n"


def _parse_partition(spec: str, file: str, place: str) -> Partition:
    words = spec.split()
    try:
        if len(words) == 2 and words[0] in ("uniform", "unequal"):
            n = int(words[1])
            return Partition.uniform(n) if words[0] == "uniform" else Partition.unequal(n)
        if len(words) >= 2 and words[0] == "peaks":
            return Partition(tuple(float(w) for w in words[1:]))
    except ValueError as exc:
        raise SceneError(file, place, str(exc)) from None
    raise SceneError(file, place, f"expected 'uniform N', 'unequal N' or 'peaks ...', got {spec!r}")


def parse_rules(text: str, file: str = "<string>") -> RuleBase:
    """Parse the text of a rule file.

    The format (``#`` starts a comment, blank lines are ignored)::

        curve: uniform 7
        distance: unequal 5
        speed: uniform 7
        rules:
        curve\\dist  VL   L    Z    H    VH
        VVL         VVH  VVH  VVH  VVH  VVH
        ...

    The first row after ``rules:`` names the distance sets (its first word is
    free); then one row per curve set, in order, each naming its set and giving
    one speed label or ``-`` per distance set.

    Parameters
    ----------
    text : str
    file : str
        Name used in error messages.

    Returns
    -------
    RuleBase

    Raises
    ------
    SceneError
        On any malformed line, naming the file and ``line N``.
    """
    parts: dict[str, Partition] = {}
    rows: list[tuple[int, list[str]]] = []
    in_rules = False
    last_line = 0
    for number, raw in enumerate(text.splitlines(), start=1):
        last_line = number
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        place = f"line {number}"
        if in_rules:
            rows.append((number, line.split()))
            continue
        key, sep, value = line.partition(":")
        key = key.strip()
        if not sep:
            raise SceneError(file, place, f"expected 'key: value' or 'rules:', got {line!r}")
        if key == "rules":
            if value.strip():
                raise SceneError(file, place, "nothing may follow 'rules:' on its line")
            in_rules = True
            continue
        if key not in ("curve", "distance", "speed"):
            raise SceneError(
                file, place, f"unknown key {key!r} (expected curve, distance, speed or rules)"
            )
        if key in parts:
            raise SceneError(file, place, f"duplicate key {key!r}")
        parts[key] = _parse_partition(value, file, place)
    for key in ("curve", "distance", "speed"):
        if key not in parts:
            raise SceneError(file, "", f"missing '{key}:' partition")
    if not in_rules:
        raise SceneError(file, "", "missing 'rules:' section")
    curve, distance, speed = parts["curve"], parts["distance"], parts["speed"]
    if not rows:
        raise SceneError(file, f"line {last_line}", "empty rule table")
    number, header = rows[0]
    if tuple(header[1:]) != distance.labels:
        raise SceneError(
            file,
            f"line {number}",
            f"table header must name the distance sets {' '.join(distance.labels)}, got {' '.join(header[1:])!r}",
        )
    body = rows[1:]
    if len(body) != curve.size:
        where = f"line {body[-1][0]}" if body else f"line {number}"
        raise SceneError(
            file, where, f"expected {curve.size} rows (one per curve set), got {len(body)}"
        )
    code = {lab: k + 1 for k, lab in enumerate(speed.labels)}
    code["-"] = 0
    genes: list[int] = []
    for (number, words), label in zip(body, curve.labels, strict=True):
        place = f"line {number}"
        if words[0] != label:
            raise SceneError(
                file, place, f"expected the row of curve set {label!r}, got {words[0]!r}"
            )
        if len(words) - 1 != distance.size:
            raise SceneError(file, place, f"expected {distance.size} entries, got {len(words) - 1}")
        for col, word in enumerate(words[1:], start=1):
            if word not in code:
                raise SceneError(
                    file,
                    f"{place}, column {col}",
                    f"unknown speed label {word!r} (expected one of {' '.join(speed.labels)} or -)",
                )
            genes.append(code[word])
    return RuleBase(tuple(genes), curve, distance, speed)


def load_rules(path: PathType) -> RuleBase:
    """Read a rule file (format in :func:`parse_rules`).

    Raises
    ------
    SceneError
        If the file cannot be read or is malformed.
    """
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(str(path), "", f"cannot read rule file: {exc}") from None
    return parse_rules(text, str(path))


def save_rules(rulebase: RuleBase, path: PathType, comment: str = "") -> None:
    """Write ``rulebase`` as a rule file (read back by :func:`load_rules`)."""
    Path(path).write_text(format_rules(rulebase, comment), encoding="utf-8")


@functools.cache
def _packaged(name: str) -> RuleBase:
    # Beside this module: works for source trees, wheels and editable installs alike.
    return load_rules(Path(__file__).resolve().parent / _DATA / name)


def expert_rules() -> RuleBase:
    """The default, hand-written rule base shipped in ``gfuzzy/data/rules_expert.txt``:
    slow for sharp, near bends; fast on straights and far bends."""
    return _packaged(_EXPERT_FILE)


def learned_rules() -> RuleBase:
    """The rule base learned by :func:`learn_rules` (``tools/learn_rules.py``),
    shipped in ``gfuzzy/data/rules_learned.txt``."""
    return _packaged(_LEARNED_FILE)


# --------------------------------------------------------------------------
# Inference
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class FuzzyOptions:
    """Settings of the fuzzy speed layer.

    The partitions are not here: they belong to the :class:`RuleBase` (a rule
    file names them), since the chromosome means nothing without them.

    Attributes
    ----------
    lookahead : float
        Look-ahead distance along the path, metres; the distance input is the
        distance to the bend divided by it.
    max_turn : float
        Turning (radians) that maps to curve = 1; more is clipped.
    min_speed : float
        Lowest speed fraction of vmax away from the path's ends, and the raw
        controller output when no rule fires.
    ds : float
        Arc-length step of the speed profile, metres (path vertices are added).
    surface_resolution : int
        Grid points per input axis of the precomputed control surface (61 puts
        grid nodes on every peak of the standard partitions).
    output_resolution : int
        Points of the output universe used by the centroid.
    exact : bool
        Evaluate the controller exactly at every sample instead of
        interpolating the surface bilinearly.
    """

    lookahead: float = 1.5
    max_turn: float = math.pi
    min_speed: float = 0.1
    ds: float = 0.05
    surface_resolution: int = 61
    output_resolution: int = 601
    exact: bool = False

    def __post_init__(self) -> None:
        for name in ("lookahead", "max_turn", "ds"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be positive and finite, got {value}")
        if not 0.0 < self.min_speed <= 1.0:
            raise ValueError(f"min_speed must be in (0, 1], got {self.min_speed}")
        if self.surface_resolution < 2 or self.output_resolution < 2:
            raise ValueError("resolutions must be at least 2")


_CHUNK = 1024


def infer_exact(
    curve: ArrayLike,
    dist: ArrayLike,
    rulebase: RuleBase | None = None,
    options: FuzzyOptions | None = None,
) -> FloatArray:
    """Mamdani inference evaluated exactly at every input pair.

    Fuzzification by the triangles of the rule base's partitions, ``min`` for
    AND (and for implication), ``max`` aggregation, and the centroid of the
    aggregated output. The aggregated membership is sampled on
    ``options.output_resolution`` points of ``[0, 1]`` plus the points where
    each output set meets its firing level, and its centroid is that of the
    piecewise-linear interpolant (the same construction as scikit-fuzzy's
    ``ControlSystemSimulation``, so the two agree to rounding).

    Parameters
    ----------
    curve, dist : (m,) float
        Normalised inputs, broadcast together; clipped to ``[0, 1]``.
    rulebase : RuleBase, optional
        Default :func:`expert_rules`.
    options : FuzzyOptions, optional

    Returns
    -------
    (m,) float
        Raw centroid in ``[0, 1]``; ``options.min_speed`` where no rule fires.
    """
    rb = expert_rules() if rulebase is None else rulebase
    opt = FuzzyOptions() if options is None else options
    c, d = np.broadcast_arrays(np.asarray(curve, dtype=float), np.asarray(dist, dtype=float))
    shape = c.shape
    c, d = c.reshape(-1), d.reshape(-1)
    out = np.empty(c.size)
    for lo in range(0, c.size, _CHUNK):
        sl = slice(lo, lo + _CHUNK)
        act = _activations(rb, c[sl], d[sl])
        out[sl] = _centroid(act, rb.speed.triangles, opt.output_resolution, opt.min_speed)
    return out.reshape(shape)


def _activations(rb: RuleBase, c: FloatArray, d: FloatArray) -> FloatArray:
    """Firing level of every output set, ``(m, speed.size)``."""
    fire = np.minimum(rb.curve.membership(c)[:, :, None], rb.distance.membership(d)[:, None, :])
    fire = fire.reshape(c.size, -1)
    genes = np.asarray(rb.genes)
    act = np.zeros((c.size, rb.speed.size))
    for k in range(1, rb.speed.size + 1):
        cols = genes == k
        if cols.any():
            act[:, k - 1] = fire[:, cols].max(axis=1)
    return act


def _centroid(act: FloatArray, tri: FloatArray, resolution: int, fallback: float) -> FloatArray:
    """Centroid of ``max_k min(act_k, tri_k)`` over ``[0, 1]`` for each row of ``act``."""
    m, k = act.shape
    grid = np.linspace(0.0, 1.0, resolution)
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    # The cut points make the clipped sets exactly piecewise linear on the samples.
    rise = a + act * (b - a)
    fall = c - act * (c - b)
    extra = np.clip(np.concatenate([rise, fall], axis=1), 0.0, 1.0)
    x = np.sort(np.concatenate([np.broadcast_to(grid, (m, resolution)), extra], axis=1), axis=1)
    y = np.zeros_like(x)
    for j in range(k):
        if np.any(act[:, j] > 0):
            mu = np.clip(
                np.minimum((x - a[j]) / (b[j] - a[j]), (c[j] - x) / (c[j] - b[j])), 0.0, 1.0
            )
            np.maximum(y, np.minimum(mu, act[:, j : j + 1]), out=y)
    x1, x2, y1, y2 = x[:, :-1], x[:, 1:], y[:, :-1], y[:, 1:]
    dx = x2 - x1
    area = np.sum(dx * (y1 + y2), axis=1) / 2.0
    moment = np.sum(dx * (x1 * (2 * y1 + y2) + x2 * (y1 + 2 * y2)), axis=1) / 6.0
    fired = area > 0
    return np.where(fired, moment / np.where(fired, area, 1.0), fallback)


@functools.lru_cache(maxsize=32)
def _surface(rb: RuleBase, n: int, resolution: int, min_speed: float) -> FloatArray:
    axis = np.linspace(0.0, 1.0, n)
    cc, dd = np.meshgrid(axis, axis, indexing="ij")
    opt = FuzzyOptions(surface_resolution=n, output_resolution=resolution, min_speed=min_speed)
    surf = infer_exact(cc, dd, rb, opt)
    surf.setflags(write=False)
    return surf


class SpeedController:
    """A rule base made ready for fast evaluation on arrays.

    The control surface is computed once on an ``n x n`` grid of
    (curve, distance) and cached per (rule base, resolutions); :meth:`infer`
    interpolates it bilinearly.

    Parameters
    ----------
    rulebase : RuleBase, optional
        Default :func:`expert_rules`.
    options : FuzzyOptions, optional
    """

    def __init__(self, rulebase: RuleBase | None = None, options: FuzzyOptions | None = None):
        self.rulebase = expert_rules() if rulebase is None else rulebase
        self.options = FuzzyOptions() if options is None else options
        lone = np.eye(self.rulebase.speed.size)[[0, -1]]
        lo, hi = _centroid(lone, self.rulebase.speed.triangles, self.options.output_resolution, 0.0)
        #: Centroids of the lowest and highest output set fired alone: a Mamdani
        #: centroid never reaches 0 or 1, so :meth:`speed_fraction` maps these to 0 and 1.
        self.output_range = (float(lo), float(hi))

    @property
    def surface(self) -> FloatArray:
        """Raw controller output on the grid, ``(n, n) float``, indexed ``[curve, distance]``."""
        o = self.options
        return _surface(self.rulebase, o.surface_resolution, o.output_resolution, o.min_speed)

    def infer_exact(self, curve: ArrayLike, dist: ArrayLike) -> FloatArray:
        """Raw output evaluated exactly (:func:`infer_exact`), ``(m,) float``."""
        return infer_exact(curve, dist, self.rulebase, self.options)

    def infer(self, curve: ArrayLike, dist: ArrayLike) -> FloatArray:
        """Raw output by bilinear interpolation of :attr:`surface`.

        Parameters
        ----------
        curve, dist : (m,) float
            Broadcast together; clipped to ``[0, 1]``.

        Returns
        -------
        (m,) float
        """
        if self.options.exact:
            return self.infer_exact(curve, dist)
        surf = self.surface
        n = surf.shape[0]
        c, d = np.broadcast_arrays(np.asarray(curve, dtype=float), np.asarray(dist, dtype=float))
        u = np.clip(c, 0.0, 1.0) * (n - 1)
        w = np.clip(d, 0.0, 1.0) * (n - 1)
        i = np.minimum(u.astype(np.int64), n - 2)
        j = np.minimum(w.astype(np.int64), n - 2)
        fu, fw = u - i, w - j
        top = surf[i, j] * (1 - fw) + surf[i, j + 1] * fw
        bottom = surf[i + 1, j] * (1 - fw) + surf[i + 1, j + 1] * fw
        return top * (1 - fu) + bottom * fu

    def speed_fraction(self, curve: ArrayLike, dist: ArrayLike) -> FloatArray:
        """Speed as a fraction of vmax: the raw output rescaled so that the lowest
        output set alone gives 0 and the highest alone gives 1, then clipped to
        ``[options.min_speed, 1]``. ``(m,) float``."""
        lo, hi = self.output_range
        raw = self.infer(curve, dist)
        return np.clip((raw - lo) / (hi - lo), self.options.min_speed, 1.0)


# --------------------------------------------------------------------------
# Path features and the speed profile
# --------------------------------------------------------------------------


def _clean_path(path_xy: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Path without repeated points, and its cumulative arc length."""
    p = np.asarray(path_xy, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 1:
        raise ValueError(f"path_xy must have shape (n, 2) with n >= 1, got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError("path_xy must be finite")
    seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
    keep = np.concatenate(([True], seg > 1e-12))
    p = p[keep]
    s = np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))))
    return p, s


def curve_ahead(
    path_xy: ArrayLike,
    s: ArrayLike,
    lookahead: float,
    max_turn: float = math.pi,
    spread: float | None = None,
) -> tuple[FloatArray, FloatArray]:
    """The bend ahead of each arc-length position: how sharp and how far.

    For position ``s`` the window is ``[s, s + lookahead]``. *curve* is the
    absolute turning of the path within the window, divided by ``max_turn`` and
    clipped to 1; turning accumulates, so a finely sampled arc counts as much as
    one sharp corner. Each vertex's turning is spread evenly over
    ``+-min(spread, half of each adjacent segment)`` around it, which makes the
    turning a continuous function of arc length: a sampled arc then reads as
    its curvature integral, without the jitter of vertices entering and leaving
    the window. The bend is the point where the window's turning reaches half
    its total; *distance* is its arc-length distance from ``s`` divided by
    ``lookahead`` (1 when the window does not turn).

    Parameters
    ----------
    path_xy : (n, 2) float
        Polyline; repeated points are ignored.
    s : (m,) float
        Arc-length positions, metres.
    lookahead : float
        Window length, metres.
    max_turn : float
        Turning (radians) that maps to curve = 1.
    spread : float, optional
        Largest half-width over which a vertex's turning is spread, metres
        (default ``0.1 * lookahead``).

    Returns
    -------
    curve : (m,) float
        In ``[0, 1]``.
    dist : (m,) float
        In ``[0, 1]``.

    Raises
    ------
    ValueError
        If the path is not ``(n, 2)`` finite or ``lookahead``, ``max_turn`` or
        ``spread`` is not positive.
    """
    spread = 0.1 * lookahead if spread is None else spread
    if not (lookahead > 0 and max_turn > 0 and spread > 0):
        raise ValueError("lookahead, max_turn and spread must be positive")
    p, sp = _clean_path(path_xy)
    s = np.asarray(s, dtype=float)
    if p.shape[0] < 3:
        return np.zeros_like(s), np.ones_like(s)
    seg = np.diff(sp)
    heading = np.arctan2(*np.diff(p, axis=0).T[::-1])
    turn = np.abs(np.angle(np.exp(1j * np.diff(heading))))
    half = np.minimum(np.minimum(seg[:-1], seg[1:]) / 2, spread)
    # Cumulative turning A(s): piecewise linear, rising by turn[i] across
    # [sv[i] - half[i], sv[i] + half[i]]; the ramps never overlap.
    sv = sp[1:-1]
    before = np.concatenate(([0.0], np.cumsum(turn)[:-1]))
    knots_x = np.stack([sv - half, sv + half], axis=1).reshape(-1)
    knots_y = np.stack([before, before + turn], axis=1).reshape(-1)
    a0 = np.interp(s, knots_x, knots_y)
    total = np.interp(s + lookahead, knots_x, knots_y) - a0
    # First point where A reaches a0 + total / 2, by inverting A on its knots.
    target = a0 + 0.5 * total
    k = np.clip(np.searchsorted(knots_y, target, side="left"), 1, knots_y.size - 1)
    rise = knots_y[k] - knots_y[k - 1]
    frac = np.divide(target - knots_y[k - 1], rise, out=np.zeros_like(target), where=rise > 0)
    bend = knots_x[k - 1] + frac * (knots_x[k] - knots_x[k - 1])
    turning = total > 1e-12
    curve = np.where(turning, np.minimum(total / max_turn, 1.0), 0.0)
    dist = np.where(turning, np.clip((bend - s) / lookahead, 0.0, 1.0), 1.0)
    return curve, dist


def limit_acceleration(
    s: ArrayLike, v: ArrayLike, amax: float, v_start: float = 0.0, v_end: float = 0.0
) -> FloatArray:
    """Largest profile below ``v`` whose speed changes respect ``amax`` along ``s``.

    The forward-backward pass ``v[i+1]**2 <= v[i]**2 + 2 amax ds`` (forward, from
    ``v_start``) and the same backwards (from ``v_end``). Each pass is a running
    minimum: forward, ``v[i]**2 = 2 amax s[i] + min_{j<=i}(v[j]**2 - 2 amax s[j])``.

    Parameters
    ----------
    s : (k,) float
        Non-decreasing arc lengths.
    v : (k,) float
        Speed bound, non-negative.
    amax : float
        Acceleration bound, positive.
    v_start, v_end : float
        Speeds at the ends (0 = start and end at rest).

    Returns
    -------
    (k,) float
        The feasible profile, ``<= v`` everywhere.

    Raises
    ------
    ValueError
        If the shapes differ or ``amax`` is not positive.
    """
    s = np.asarray(s, dtype=float)
    u = np.array(v, dtype=float)
    if s.shape != u.shape or s.ndim != 1:
        raise ValueError("s and v must be 1-D arrays of the same length")
    if not amax > 0:
        raise ValueError(f"amax must be positive, got {amax}")
    if s.size == 0:
        return u
    u[0] = min(u[0], v_start)
    u[-1] = min(u[-1], v_end)
    sq = u**2
    idx = np.arange(s.size)
    # Running argmin j(i) of the key, then v[i]**2 = v[j]**2 + 2 amax |s[i] - s[j]|
    # computed directly (adding the key back would cancel digits near rest).
    key = sq - 2 * amax * s
    j = np.maximum.accumulate(np.where(key <= np.minimum.accumulate(key), idx, 0))
    fwd = sq[j] + 2 * amax * (s - s[j])
    key = (sq + 2 * amax * s)[::-1]
    j = np.maximum.accumulate(np.where(key <= np.minimum.accumulate(key), idx, 0))
    j = s.size - 1 - j[::-1]
    bwd = sq[j] + 2 * amax * (s[j] - s)
    return np.minimum(np.sqrt(np.minimum(fwd, bwd)), u)


def _samples(sp: FloatArray, ds: float) -> FloatArray:
    """Arc lengths every ``ds`` plus the path's vertices."""
    length = sp[-1]
    n = max(2, int(math.ceil(length / ds)) + 1)
    s = np.union1d(np.linspace(0.0, length, n), sp)
    return s[np.concatenate(([True], np.diff(s) > 1e-9 * max(1.0, length)))]


def speed_limit(
    path_xy: ArrayLike,
    vmax: float,
    amax: float,
    rulebase: RuleBase | None = None,
    options: FuzzyOptions | None = None,
) -> tuple[FloatArray, FloatArray]:
    """The fuzzy speed bound along a path, made feasible for ``amax``.

    Stable interface for re-timing: ``v[i]`` is the largest allowed speed at
    arc length ``s[i]``. Between samples interpolate ``v**2`` linearly (constant
    acceleration on each interval): that interpolant respects ``amax`` exactly,
    whereas interpolating ``v`` linearly can exceed it up to twice near rest.
    :func:`profile_times` gives the time at each sample when the profile is
    driven at its limit.

    Steps: sample the path every ``options.ds`` (plus its vertices), measure the
    bend ahead (:func:`curve_ahead`), evaluate the controller
    (:meth:`SpeedController.speed_fraction`, clipped to ``[min_speed, 1]``),
    scale by ``vmax``, then the forward-backward pass (:func:`limit_acceleration`)
    starting and ending at rest.

    Parameters
    ----------
    path_xy : (n, 2) float
        Polyline, metres.
    vmax : float
        Speed bound, m/s.
    amax : float
        Acceleration bound, m/s^2.
    rulebase : RuleBase, optional
        Default :func:`expert_rules`.
    options : FuzzyOptions, optional

    Returns
    -------
    s : (k,) float
        Increasing arc lengths from 0 to the path length (``k = 1`` for a path
        of zero length).
    v : (k,) float
        Speed bound: ``0`` at both ends, in ``(0, vmax]`` in between, and
        ``|v[i+1]**2 - v[i]**2| <= 2 amax (s[i+1] - s[i])``.

    Raises
    ------
    ValueError
        If the path is malformed or ``vmax``/``amax`` is not positive.

    References
    ----------
    G. Antonelli, S. Chiaverini, G. Fusco, "A fuzzy-logic-based approach for
    mobile robot path tracking", IEEE Trans. Fuzzy Systems 15(2):211-221, 2007.
    """
    if not (math.isfinite(vmax) and vmax > 0 and math.isfinite(amax) and amax > 0):
        raise ValueError(f"vmax and amax must be positive and finite, got {vmax}, {amax}")
    ctl = SpeedController(rulebase, options)
    p, sp = _clean_path(path_xy)
    if sp[-1] <= 0:
        return np.zeros(1), np.zeros(1)
    s = _samples(sp, ctl.options.ds)
    curve, dist = curve_ahead(p, s, ctl.options.lookahead, ctl.options.max_turn)
    return s, _profile(s, curve, dist, vmax, amax, ctl)


def profile_times(s: ArrayLike, v: ArrayLike) -> FloatArray:
    """Times at the samples of a speed profile driven at its limit.

    Each interval is crossed at constant acceleration (``v**2`` linear in
    ``s``), taking ``2 ds / (v[i] + v[i+1])``.

    Parameters
    ----------
    s : (k,) float
        Increasing arc lengths.
    v : (k,) float
        Speeds; no two consecutive zeros.

    Returns
    -------
    (k,) float
        Times from 0.

    Raises
    ------
    ValueError
        If the shapes differ, or an interval of positive length has zero speed at
        both ends (it would never be crossed).
    """
    s = np.asarray(s, dtype=float)
    v = np.asarray(v, dtype=float)
    if s.shape != v.shape or s.ndim != 1:
        raise ValueError("s and v must be 1-D arrays of the same length")
    ds = np.diff(s)
    vsum = v[:-1] + v[1:]
    if np.any((vsum <= 0) & (ds > 0)):
        raise ValueError("an interval has zero speed at both ends")
    dt = np.divide(2.0 * ds, vsum, out=np.zeros_like(ds), where=vsum > 0)
    return np.concatenate(([0.0], np.cumsum(dt)))


def _profile(
    s: FloatArray,
    curve: FloatArray,
    dist: FloatArray,
    vmax: float,
    amax: float,
    ctl: SpeedController,
) -> FloatArray:
    return limit_acceleration(s, vmax * ctl.speed_fraction(curve, dist), amax)


# --------------------------------------------------------------------------
# Learning the rule base: self-organising GA rule generation in three stages
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class LearnOptions:
    """Settings of :func:`learn_rules`.

    Attributes
    ----------
    population : int
        Individuals per generation.
    generations : (int, int, int)
        Generations of stages 1, 2 and 3.
    crossover_rate : float
        Probability that two parents are crossed (two-point, on the flat
        chromosome); the paper's Pc.
    mutation_rate : float
        Per-allele mutation probability in stages 1 and 2 (stage 3 uses half).
    tournament : int
        Tournament size for selection.
    elite : int
        Best individuals copied unchanged to the next generation.
    set_point_curve : float
        Stage 1 learns the curve sets whose peak is at most this (near-straight).
    time_weight, error_weight, max_error_weight, violation_weight : float
        Objective weights: traversal time over the time at vmax; mean and max
        lateral error over ``error_scale``; fraction of time steps with a bound
        violation.
    error_scale : float
        Lateral error (metres) that costs as much as doubling the traversal time.
    rule_penalty : float
        Stage 3 cost per rule, so redundant rules are deleted.
    consistency_weight : float
        Stages 2 and 3 cost per pair of neighbouring rules that contradict the
        domain's monotonicity (a sharper bend never allows more speed, a farther
        one never less). Cells that seldom fire on the training paths get little
        say from the simulations; this keeps them in line with their neighbours.
    curve, distance, speed : Partition
        Partitions of the learned rule base.
    fuzzy : FuzzyOptions
        Speed-layer settings used in the objective. While learning, inference
        is always ``exact`` on the training samples; the default coarse output
        grid (61 points, still through every peak) makes it cheap.
    """

    population: int = 20
    generations: tuple[int, int, int] = (8, 32, 16)
    crossover_rate: float = 0.62
    mutation_rate: float = 0.1
    tournament: int = 2
    elite: int = 2
    set_point_curve: float = 0.2
    time_weight: float = 1.0
    error_weight: float = 1.0
    max_error_weight: float = 0.25
    violation_weight: float = 10.0
    error_scale: float = 0.1
    rule_penalty: float = 0.002
    consistency_weight: float = 0.01
    curve: Partition = _UNIFORM7
    distance: Partition = _UNIFORM5
    speed: Partition = _UNIFORM7
    fuzzy: FuzzyOptions = field(default_factory=lambda: FuzzyOptions(output_resolution=61))

    def __post_init__(self) -> None:
        if self.population < 2 or self.elite < 0 or self.elite >= self.population:
            raise ValueError("need population >= 2 and 0 <= elite < population")
        if len(self.generations) != 3 or min(self.generations) < 0:
            raise ValueError("generations must be three non-negative ints")
        if self.tournament < 1:
            raise ValueError("tournament must be >= 1")


@dataclass(frozen=True)
class LearnResult:
    """Outcome of :func:`learn_rules`.

    Attributes
    ----------
    rulebase : RuleBase
        Best rule base of stage 3.
    cost : float
        Its stage-3 cost.
    history : tuple of tuple of float
        Best cost per generation, one tuple per stage.
    evaluations : int
        Distinct (stage, chromosome) simulations run.
    """

    rulebase: RuleBase
    cost: float
    history: tuple[tuple[float, ...], ...]
    evaluations: int


class _Objective:
    """Cost of a chromosome from tracking simulations on fixed training paths."""

    def __init__(self, paths, lopt: LearnOptions, limits, tracking_options):
        from gfuzzy import tracking  # the objective simulates; tracking is downstream

        self.lopt = lopt
        self.limits = tracking.UnicycleLimits() if limits is None else limits
        self.topt = tracking.TrackingOptions() if tracking_options is None else tracking_options
        self.fopt = dataclasses.replace(lopt.fuzzy, exact=True)
        self.cases = []
        for path in paths:
            p, sp = _clean_path(path)
            if sp[-1] <= 0:
                continue
            s = _samples(sp, self.fopt.ds)
            curve, dist = curve_ahead(p, s, self.fopt.lookahead, self.fopt.max_turn)
            self.cases.append((p, s, curve, dist, sp[-1] / self.limits.vmax))
        if not self.cases:
            raise ValueError("no training path of positive length")
        # One inference call for all paths' distinct samples (straights repeat).
        pairs = np.stack(
            [
                np.concatenate([case[2] for case in self.cases]),
                np.concatenate([case[3] for case in self.cases]),
            ],
            axis=1,
        )
        pairs, self.inverse = np.unique(pairs, axis=0, return_inverse=True)
        self.inverse = self.inverse.reshape(-1)
        self.curve, self.dist = pairs[:, 0], pairs[:, 1]
        self.splits = np.cumsum([case[1].size for case in self.cases])[:-1]

    def __call__(self, genes: tuple[int, ...], with_violations: bool) -> float:
        from gfuzzy import tracking

        lopt = self.lopt
        rb = RuleBase(genes, lopt.curve, lopt.distance, lopt.speed)
        frac = SpeedController(rb, self.fopt).speed_fraction(self.curve, self.dist)
        frac = np.split(frac[self.inverse], self.splits)
        total = 0.0
        for (p, s, _, _, t_min), f in zip(self.cases, frac, strict=True):
            v = limit_acceleration(s, self.limits.vmax * f, self.limits.amax)
            res = tracking.track(p, (s, v), self.limits, self.topt)
            t = res.traversal_time if res.status is tracking.TrackStatus.REACHED else 10 * t_min
            cost = lopt.time_weight * t / t_min
            cost += lopt.error_weight * res.mean_lateral_error / lopt.error_scale
            cost += lopt.max_error_weight * res.max_lateral_error / lopt.error_scale
            if with_violations:
                cost += lopt.violation_weight * res.violations.steps / max(1, res.t.size)
            total += cost
        return total / len(self.cases)


def _default_set_point_paths() -> list[FloatArray]:
    x = np.linspace(0.0, 8.0, 33)
    gentle = np.stack([x, 0.25 * np.sin(x * 2 * math.pi / 8.0)], axis=1)
    kinks = np.array([[0, 0], [2, 0], [4, 0.35], [6, 0.35], [8, 0.0]], dtype=float)
    return [np.array([[0.0, 0.0], [6.0, 0.0]]), gentle, kinks]


def learn_rules(
    paths: Sequence[ArrayLike],
    *,
    set_point_paths: Sequence[ArrayLike] | None = None,
    options: LearnOptions | None = None,
    limits=None,
    tracking_options=None,
    seed: int | np.random.Generator | None = None,
    map_fn: Callable | None = None,
) -> LearnResult:
    """Learn a rule base with a self-organising GA in three stages (SOGARG).

    Every chromosome is scored by simulating a unicycle tracking the training
    paths under the speed bound it produces (:func:`gfuzzy.tracking.track`).

    1. **Set point.** Only the alleles of the near-straight curve sets (peak <=
       ``set_point_curve``) are learned, on near-straight paths; every allele
       must be a rule (mutation: reset to a random label or step +-1). Cost:
       traversal time and lateral error.
    2. **Whole input space.** All alleles, on the training paths plus the
       set-point paths. Stage-1 alleles start from stage 1's best; the others
       grow out of them row by row (a neighbour's label plus a random step), and
       mutation (reset or step +-1) may also remove a rule. Cost: stage 1's plus the fraction of steps that violate a
       bound of the robot and ``consistency_weight`` per inconsistent pair of
       neighbouring rules.
    3. **Fine tuning.** From stage 2's population, with mutations that *modify*
       (step +-1), *delete* or *add* (copy a neighbour's label) one rule. Cost:
       stage 2's plus ``rule_penalty`` per rule, so redundant rules go.

    Each generation: keep the ``elite`` best, fill with children of tournament
    parents by two-point crossover (probability ``crossover_rate``) and the
    stage's mutation.

    Parameters
    ----------
    paths : sequence of (n, 2) float
        Training paths.
    set_point_paths : sequence of (n, 2) float, optional
        Near-straight paths for stage 1 (default: a straight line, a gentle wave
        and a gentle double kink).
    options : LearnOptions, optional
    limits : gfuzzy.tracking.UnicycleLimits, optional
    tracking_options : gfuzzy.tracking.TrackingOptions, optional
    seed : int or numpy.random.Generator, optional
        Same seed, same rule base.
    map_fn : callable, optional
        ``map``-like ``map_fn(f, iterable)`` used to score new chromosomes (for
        instance a process pool's ``map``); it must keep the order. Default: the
        built-in ``map``.

    Returns
    -------
    LearnResult

    Notes
    -----
    The stages follow the self-organising GA rule generation (SOGARG) scheme
    the project's source paper uses to learn its fuzzy layer; the chromosome
    (one allele per pair of input sets, 0 = no rule) is the paper's. The
    consistency term is this implementation's addition.
    """
    lopt = LearnOptions() if options is None else options
    rng = create_rng(seed)
    mapper = map if map_fn is None else map_fn
    near = _default_set_point_paths() if set_point_paths is None else list(set_point_paths)
    obj_near = _Objective(near, lopt, limits, tracking_options)
    # Stages 2 and 3 keep the set-point paths, so the set-point rules stay earned.
    obj_all = _Objective(list(paths) + near, lopt, limits, tracking_options)
    nc, nd, k = lopt.curve.size, lopt.distance.size, lopt.speed.size
    region = np.zeros((nc, nd), dtype=bool)
    region[np.asarray(lopt.curve.peaks) <= lopt.set_point_curve + 1e-12, :] = True
    region = region.reshape(-1)
    if not region.any():
        region[:nd] = True
    cache: dict[tuple[int, tuple[int, ...]], float] = {}
    history: list[tuple[float, ...]] = []

    def score(stage: int, pop: list[np.ndarray]) -> np.ndarray:
        keys = [tuple(int(g) for g in ind) for ind in pop]
        new = list(dict.fromkeys(key for key in keys if (stage, key) not in cache))
        if new:
            fn = _StageCost(stage, obj_near if stage == 1 else obj_all, lopt)
            for key, cost in zip(new, mapper(fn, new), strict=True):
                cache[(stage, key)] = float(cost)
        return np.array([cache[(stage, key)] for key in keys])

    def evolve(stage: int, pop: list[np.ndarray], gens: int, mutate) -> list[np.ndarray]:
        costs = score(stage, pop)
        best = [float(costs.min())]
        for _ in range(gens):
            order = np.argsort(costs, kind="stable")
            nxt = [pop[i].copy() for i in order[: lopt.elite]]
            while len(nxt) < lopt.population:
                a = pop[_tournament(rng, costs, lopt.tournament)]
                b = pop[_tournament(rng, costs, lopt.tournament)]
                if rng.random() < lopt.crossover_rate:
                    i, j = np.sort(rng.choice(a.size + 1, size=2, replace=False))
                    c1, c2 = a.copy(), b.copy()
                    c1[i:j], c2[i:j] = b[i:j], a[i:j]
                else:
                    c1, c2 = a.copy(), b.copy()
                for child in (c1, c2):
                    if len(nxt) < lopt.population:
                        nxt.append(mutate(child))
            pop = nxt
            costs = score(stage, pop)
            best.append(float(costs.min()))
        history.append(tuple(best))
        order = np.argsort(costs, kind="stable")
        logger.info("SOGARG stage %d: best cost %.4f", stage, costs[order[0]])
        return [pop[i] for i in order]

    pm = lopt.mutation_rate

    def mutate1(g: np.ndarray) -> np.ndarray:
        hit = region & (rng.random(g.size) < pm)
        step = rng.random(g.size) < 0.5
        delta = rng.choice([-1, 1], size=g.size)
        reset = rng.integers(1, k + 1, size=g.size)
        g[hit] = np.where(step[hit], np.clip(g[hit] + delta[hit], 1, k), reset[hit])
        return g

    def mutate2(g: np.ndarray) -> np.ndarray:
        rate = np.where(region, pm / 2, pm)
        hit = rng.random(g.size) < rate
        step = rng.random(g.size) < 0.5
        delta = rng.choice([-1, 1], size=g.size)
        reset = np.where(rng.random(g.size) < 0.05, 0, rng.integers(1, k + 1, size=g.size))
        g[hit] = np.where(step[hit] & (g[hit] > 0), np.clip(g[hit] + delta[hit], 1, k), reset[hit])
        return g

    grid = np.arange(nc * nd).reshape(nc, nd)

    def mutate3(g: np.ndarray) -> np.ndarray:
        for i in np.flatnonzero(rng.random(g.size) < pm / 2):
            r, c = divmod(int(i), nd)
            if g[i] == 0:  # add: copy a neighbouring rule's label
                nb = [
                    grid[rr, cc]
                    for rr, cc in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1))
                    if 0 <= rr < nc and 0 <= cc < nd and g[grid[rr, cc]] > 0
                ]
                g[i] = g[nb[int(rng.integers(len(nb)))]] if nb else int(rng.integers(1, k + 1))
            elif rng.random() < 0.25:  # delete
                g[i] = 0
            else:  # modify
                g[i] = int(np.clip(g[i] + rng.choice([-1, 1]), 1, k))
        return g

    g1, g2, g3 = lopt.generations
    # Stage 1: set-point region only; the rest stays "no rule" (min speed).
    pop = []
    for _ in range(lopt.population):
        g = np.zeros(nc * nd, dtype=np.int64)
        g[region] = rng.integers(1, k + 1, size=int(region.sum()))
        pop.append(g)
    pop = evolve(1, pop, g1, mutate1)
    # Stage 2: keep the set-point rules and grow the rest out of them: each new
    # rule takes its lower-curve neighbour's label plus a random step in
    # {-2, -1, 0, +1} (a random walk, not a fixed table).
    seeds = pop[: max(1, lopt.population // 4)]
    pop = []
    rows = region.reshape(nc, nd).any(axis=1)
    for idx in range(lopt.population):
        g = seeds[idx % len(seeds)].reshape(nc, nd).copy()
        for r in range(nc):
            if not rows[r]:
                above = g[r - 1] if r > 0 else rng.integers(1, k + 1, size=nd)
                g[r] = np.clip(np.maximum(above, 1) + rng.integers(-2, 2, size=nd), 1, k)
        pop.append(g.reshape(-1))
    pop = evolve(2, pop, g2, mutate2)
    # Stage 3: fine tuning of stage 2's population.
    pop = evolve(3, [p.copy() for p in pop], g3, mutate3)
    best = pop[0]
    rb = RuleBase(tuple(int(x) for x in best), lopt.curve, lopt.distance, lopt.speed)
    cost = cache[(3, tuple(int(x) for x in best))]
    return LearnResult(rb, cost, tuple(history), len(cache))


def _tournament(rng: np.random.Generator, costs: np.ndarray, size: int) -> int:
    idx = rng.integers(0, costs.size, size=size)
    return int(idx[np.argmin(costs[idx])])


def _inconsistencies(m: np.ndarray) -> int:
    """Neighbouring rule pairs whose speed rises with curve or falls with distance."""
    down = (m[1:, :] > m[:-1, :]) & (m[1:, :] > 0) & (m[:-1, :] > 0)
    right = (m[:, 1:] < m[:, :-1]) & (m[:, 1:] > 0) & (m[:, :-1] > 0)
    return int(down.sum() + right.sum())


class _StageCost:
    """Picklable cost of one stage (so a process pool can run it)."""

    def __init__(self, stage: int, objective: _Objective, lopt: LearnOptions):
        self.stage = stage
        self.objective = objective
        self.rule_penalty = lopt.rule_penalty
        self.consistency_weight = lopt.consistency_weight
        self.shape = (lopt.curve.size, lopt.distance.size)

    def __call__(self, genes: tuple[int, ...]) -> float:
        cost = self.objective(genes, with_violations=self.stage >= 2)
        if self.stage == 3:
            cost += self.rule_penalty * sum(1 for g in genes if g)
        if self.stage >= 2 and self.consistency_weight:
            cost += self.consistency_weight * _inconsistencies(np.reshape(genes, self.shape))
        return cost
