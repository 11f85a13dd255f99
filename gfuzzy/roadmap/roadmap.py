"""Static roadmaps: OMPL's PRM over R^2 (disc robot) or SE(2) (box robot), FCL validity.

The roadmap is grown to a vertex count, never to a time budget, so that a seed gives the
same roadmap in every process (OMPL's RNG is process-wide and takes one seed; see
``docs/planner.md``, section 1). Every edge OMPL proposes is then *certified* with
:meth:`gfuzzy.collision.geometry.StaticGeometry.motion_free`, which proves the whole straight
motion free rather than sampling it; uncertifiable edges are dropped.
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import numbers
import os
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import numpy as np

from ..atomic import write_atomic
from ..collision.geometry import StaticGeometry, metric_distance
from ..errors import InputError, LimitError, SceneError, not_utf8
from ..scene.scene import Scene
from ..scene.yamldoc import _kind
from ..settings import MAX_POINTS
from ..typed import FloatArray, IntArray
from .join import count_components, join_roadmap, repair_roadmap
from .passage import PassageDraws, passage_sampler_type

__all__ = [
    "RoadmapOptions",
    "Roadmap",
    "build_roadmap",
    "grow_roadmaps",
    "load_roadmap",
    "default_roadmap_path",
]

log = logging.getLogger(__name__)

FORMAT = "gfuzzy-roadmap"
#: Validity checks without a new milestone after which the free space counts as empty.
STALL_CHECKS = 200_000
#: Validity checks without a new milestone after which the robot's inscribed disc is asked
#: whether it has room anywhere (no room: the robot fits nowhere, said at once).
PROOF_CHECKS = 1_000
FORMAT_VERSION = 1
FREE_CELL_SHARE = 0.5  # maps' free cells below this share of the bounds: half the samples drawn in them


@dataclass(frozen=True)
class RoadmapOptions:
    """Settings of the PRM build.

    Attributes
    ----------
    vertices : int
        Number of milestones to grow the roadmap to.
    seed : int
        OMPL seed (OMPL refuses 0, so ``seed + 1`` is handed to it).
    neighbors : int
        PRM's ``maxNearestNeighbors`` (k of the k-nearest connection strategy).
    resolution : float
        OMPL's validity-checking resolution (a fraction of the space's extent) used while
        PRM decides which neighbours to connect; edges are certified exactly afterwards.
    sampler : {"passage", "uniform"}
        ``"uniform"``: OMPL's uniform valid-state sampler. ``"passage"`` (default): a mix
        of uniform samples and bridge-test samples (Hsu et al., ICRA 2003) that find
        narrow passages; for a box robot the bridge sample is turned across the bridge
        (along the passage) and followed by samples shifted along its heading, so that
        a chain of aligned milestones crosses a door the robot fits through only turned.
    bridge_ratio : float
        Share of bridge-test samples in the ``"passage"`` sampler.
    repair : bool
        Disc robots: join the components sharing a free-space region (:func:`gfuzzy.roadmap.freespace.repair`),
        adding vertices beyond ``vertices`` (``info.repair``); older files load with False.
    join : bool
        Box and footprint robots: join the components within a budget of collision checks
        (:func:`gfuzzy.roadmap.join.join_components`), adding vertices beyond ``vertices``
        (``info.join``); older files load with False.
    """

    vertices: int = 200
    seed: int = 1
    neighbors: int = 10
    resolution: float = 0.05
    sampler: str = "passage"
    bridge_ratio: float = 0.5
    repair: bool = True
    join: bool = True

    def __post_init__(self):
        for name in ("vertices", "neighbors"):  # a file's "x" met `<` (Python's wording), 2.5 a range()
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise InputError(f"{name} must be a whole number, got {value!r}")
        for name in ("resolution", "bridge_ratio"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, numbers.Real):  # its range is checked below
                raise InputError(f"{name} must be a number, got {value!r}")
        for name in ("repair", "join"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise InputError(f"{name} must be true or false, got {getattr(self, name)!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) or not 0 <= self.seed < 2**31:
            raise InputError(f"seed must be a whole number from 0 to {2**31 - 1}, got {self.seed!r}")
        if self.vertices < 1:
            raise InputError(f"a roadmap needs at least 1 vertex, got {self.vertices}")
        if self.vertices > MAX_POINTS:  # every vertex is a point of the query graph: never searchable
            raise LimitError(
                f"a roadmap of {self.vertices:,} vertices could never be searched (a query's graph "
                f"holds at most {MAX_POINTS:,} points); use fewer vertices"
            )
        if self.neighbors < 1:
            raise InputError(f"neighbors must be >= 1, got {self.neighbors}")
        if not 0 < self.resolution <= 0.5:
            raise InputError(f"resolution must be in (0, 0.5], got {self.resolution}")
        if not 0 <= self.bridge_ratio <= 1:  # a share of the samples
            raise InputError(f"bridge_ratio must be in [0, 1], got {self.bridge_ratio}")
        if self.sampler not in ("uniform", "passage"):
            raise InputError(f"sampler must be 'uniform' or 'passage', got {self.sampler!r}")


class _Derived(dict):
    """A cache dict that pickles and copies as empty (a worker rebuilds what it needs)."""

    def __reduce__(self):
        return (_Derived, ())

    def __copy__(self):
        return _Derived()

    def __deepcopy__(self, memo):
        return _Derived()


@dataclass(frozen=True)
class RoadmapInfo:
    """How a roadmap was built (its file's ``info``).

    ``seconds`` is the whole build, ``grow_seconds`` OMPL's PRM growing; ``validity_calls`` and
    ``certify_calls`` count collision-model calls while growing and while certifying edges;
    ``edges_dropped`` PRM edges that could not be certified free; ``components`` the
    roadmap's connected components; ``repair`` what the free-space repair of a disc robot's
    roadmap added (:meth:`gfuzzy.roadmap.freespace.Repair.to_dict` and ``seconds``; empty, and not
    written, without it); ``join`` what the component join of a box or footprint robot's
    roadmap did (:meth:`gfuzzy.roadmap.join.Join.to_dict` and ``seconds``; the same);
    ``extra`` keys of another version's file, kept as they were.
    """

    ompl_version: str = ""
    seconds: float = 0.0
    grow_seconds: float = 0.0
    validity_calls: int = 0
    certify_calls: int = 0
    edges_dropped: int = 0
    components: int = 0
    repair: dict = field(default_factory=dict)
    join: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """Plain JSON: the fields, then the extra keys."""
        doc = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "extra"}
        for key in ("repair", "join"):  # as files written before them
            if not doc[key]:
                del doc[key]
        return {**doc, **self.extra}

    @classmethod
    def from_dict(cls, doc) -> RoadmapInfo:
        """From a roadmap file's ``info`` (anything but a mapping gives the defaults)."""
        if not isinstance(doc, dict):
            return cls()
        casts = {"str": str, "float": float, "int": int, "dict": dict}
        types = {f.name: casts[f.type] for f in fields(cls) if f.name != "extra"}
        kwargs, extra = {}, {}
        for key, value in doc.items():
            cast = types.get(key)
            if cast is not None and _of_type(value, cast):
                kwargs[key] = cast(value)
            else:  # another version's key, or odd (a list where a string belongs): kept as it is
                extra[key] = value
        return cls(**kwargs, extra=extra)


def _of_type(value, cast) -> bool:
    """Whether a roadmap file's ``info`` value is of its field's type as JSON gives it (an
    integer is a float too; a boolean is no number): ``str([1])`` read a list as ``"[1]"``."""
    if cast is float:
        return isinstance(value, numbers.Real) and not isinstance(value, bool)
    if cast is int:
        return isinstance(value, numbers.Integral) and not isinstance(value, bool)
    return isinstance(value, cast)


@dataclass
class Roadmap:
    """A roadmap of the static scene.

    Attributes
    ----------
    vertices : (V, d) float
        Poses ``[x, y]`` or ``[x, y, heading]``.
    edges : (E, 2) int
        Undirected, ``edges[:, 0] < edges[:, 1]``.
    lengths : (E,) float
        Contract metric: xy distance + |heading change| * circumradius.
    scene_name, scene_hash : str
        The scene it was built for (``Scene.static_hash``).
    options : RoadmapOptions
    info : RoadmapInfo
        Build statistics: seconds, validity calls, edges dropped, OMPL version.
    """

    vertices: FloatArray
    edges: IntArray
    lengths: FloatArray
    scene_name: str
    scene_hash: str
    circumradius: float
    options: RoadmapOptions = field(default_factory=RoadmapOptions)
    info: RoadmapInfo = field(default_factory=RoadmapInfo)
    #: Cache of :meth:`spanner` results by stretch (derived data: not saved, not compared).
    #: A Roadmap is otherwise immutable after building, so the cache never goes stale.
    _spanners: dict = field(default_factory=dict, repr=False, compare=False)
    #: Other derived data of the queries (:mod:`gfuzzy.timespace.roadgraph`: vertex clearances, split
    #: spanners); never saved, pickled, compared or copied by ``dataclasses.replace``.
    _derived: dict = field(default_factory=_Derived, init=False, repr=False, compare=False)

    @property
    def dof(self) -> int:
        return int(self.vertices.shape[1])

    def __len__(self) -> int:
        return len(self.vertices)

    def graph(self):
        """A ``networkx.Graph`` with vertex attribute ``pose`` and edge attribute ``weight``."""
        import networkx as nx

        g = nx.Graph()
        for i, v in enumerate(self.vertices):
            g.add_node(i, pose=v)
        g.add_weighted_edges_from(
            (int(a), int(b), float(w)) for (a, b), w in zip(self.edges, self.lengths, strict=True)
        )
        return g

    def spanner(self, stretch: float) -> np.ndarray:
        """Edges to keep so that every shortest path is at most ``stretch`` times longer.

        The greedy spanner (Althofer et al., 1993) with a two-edge test: edges in order of
        length, an edge is dropped when two kept edges through a common vertex already join
        its ends within ``stretch`` times its length. Kept edges only shorten later detours,
        so every dropped edge, and hence every path, stays within the stretch. A PRM's
        k-nearest edges are largely redundant: at 1.05 about 55-60 % of the total edge
        length remains on building-floor.

        Returns
        -------
        (E,) bool
        """
        if not stretch >= 1.0:
            raise InputError(f"stretch must be >= 1, got {stretch}")
        cached = self._spanners.get(stretch)
        if cached is not None:  # computed once per roadmap and stretch
            return cached
        keep = np.ones(len(self.edges), dtype=bool)
        if stretch > 1.0:
            self._prune_to_spanner(keep, stretch)
        # published only once complete (an interrupted build leaves nothing behind), read-only
        keep.flags.writeable = False
        self._spanners[stretch] = keep
        return keep

    def _prune_to_spanner(self, keep: np.ndarray, stretch: float) -> None:
        """Clear in ``keep`` the edges the greedy two-edge test drops (see `spanner`)."""
        adj: list[dict] = [{} for _ in range(len(self.vertices))]
        ends, lens = self.edges.tolist(), self.lengths.tolist()
        for e in np.argsort(self.lengths, kind="stable").tolist():
            a, b = ends[e]
            length = lens[e]
            limit = stretch * length
            na, nb = adj[a], adj[b]
            if len(na) > len(nb):
                na, nb = nb, na
            if any(la + nb[w] <= limit for w, la in na.items() if w in nb):
                keep[e] = False
                continue
            adj[a][b] = length
            adj[b][a] = length

    def check_scene(self, scene: Scene, file: str = "<roadmap>") -> None:
        """Raise SceneError if this roadmap was not built for ``scene``'s static part."""
        if self.scene_hash != scene.static_hash:
            raise SceneError(
                file,
                "scene_hash",
                f"roadmap was built for scene {self.scene_name!r} with other static content "
                f"(hash {self.scene_hash[:12]}), not for {scene.source} (hash {scene.static_hash[:12]}); "
                "rebuild it with `gfuzzy roadmap`",
            )

    def to_dict(self) -> dict:
        return {
            "format": FORMAT,
            "version": FORMAT_VERSION,
            "scene": self.scene_name,
            "scene_hash": self.scene_hash,
            "circumradius": self.circumradius,
            "options": asdict(self.options),
            "info": self.info.to_dict(),
            "digest": roadmap_digest(self),
            "vertices": self.vertices.tolist(),
            "edges": self.edges.tolist(),
            "lengths": self.lengths.tolist(),
        }

    def save(self, path: str | os.PathLike) -> None:
        """Write the roadmap as JSON, atomically (a temporary file, then a rename)."""
        write_atomic(path, json.dumps(self.to_dict(), separators=(",", ":")))


def load_roadmap(path: str | os.PathLike, scene: Scene | None = None) -> Roadmap:
    """Read a roadmap file; with ``scene``, also check it was built for that scene.

    Raises
    ------
    SceneError
        Unreadable or malformed file, or a roadmap of another scene.
    """
    file = str(path)
    try:
        data = Path(path).read_bytes()
        doc = json.loads(data.decode("utf-8-sig"))  # a BOM (a Windows editor's) is read past
    except OSError as exc:
        raise SceneError(file, "", f"cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise SceneError(file, "", f"not a roadmap file ({not_utf8(data, exc)})") from None
    except (json.JSONDecodeError, RecursionError) as exc:
        raise SceneError(file, "", f"not a roadmap file (invalid JSON: {' '.join(str(exc).split())[:80]})") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise SceneError(file, "format", "not a gfuzzy roadmap file")
    if doc.get("version") != FORMAT_VERSION:
        raise SceneError(file, "version", f"unsupported roadmap version {doc.get('version')!r}")
    for key in ("vertices", "edges", "lengths", "options", "scene", "scene_hash", "circumradius"):
        if key not in doc:
            raise SceneError(file, key, "missing required key")
    arrays = {}
    for key, dtype, want in (("vertices", float, "expected rows of 2 or 3 finite numbers"),
                             ("edges", None, "expected pairs of whole vertex indices"),
                             ("lengths", float, "expected one finite, non-negative length per edge")):  # fmt: skip
        try:  # numpy's wording ("setting an array element with a sequence ...") named no key
            arrays[key] = np.asarray(doc[key], dtype=dtype)
        except (TypeError, ValueError, OverflowError):
            raise SceneError(file, key, want) from None
    vertices, raw_edges, lengths = arrays["vertices"], arrays["edges"], arrays["lengths"]
    opts = _options_from(file, doc["options"])
    circumradius = doc["circumradius"]  # float() of a string "2" read it; of "x", Python's wording
    if isinstance(circumradius, bool) or not isinstance(circumradius, numbers.Real) or not (
        0 < circumradius <= sys.float_info.max  # NaN and inf fail it, a 400-digit integer too
    ):
        raise SceneError(file, "circumradius", f"expected a positive finite number, got {circumradius!r}")
    circumradius = float(circumradius)
    if vertices.ndim != 2 or vertices.shape[1] not in (2, 3) or not np.all(np.isfinite(vertices)):
        raise SceneError(file, "vertices", "expected rows of 2 or 3 finite numbers")
    if raw_edges.size == 0:
        raw_edges = np.zeros((0, 2), dtype=np.int64)
    if raw_edges.ndim != 2 or raw_edges.shape[1] != 2 or raw_edges.dtype.kind not in "iu":
        raise SceneError(file, "edges", "expected pairs of whole vertex indices")
    edges = raw_edges.astype(np.int64)
    if edges.size and (edges.min() < 0 or edges.max() >= len(vertices)):
        raise SceneError(file, "edges", "a vertex index is out of range")
    if np.any(edges[:, 0] >= edges[:, 1]):
        k = int(np.nonzero(edges[:, 0] >= edges[:, 1])[0][0])
        raise SceneError(file, f"edges[{k}]", "edges must list the smaller vertex index first (no self-loops)")
    if lengths.shape != (len(edges),) or not np.all(np.isfinite(lengths)) or np.any(lengths < 0):
        raise SceneError(file, "lengths", "expected one finite, non-negative length per edge")
    rm = Roadmap(
        vertices,
        edges,
        lengths,
        _text(file, doc, "scene"),
        _text(file, doc, "scene_hash"),
        circumradius,
        opts,
        RoadmapInfo.from_dict(doc.get("info", {})),
    )
    if scene is not None:
        rm.check_scene(scene, file)
        if rm.dof != scene.robot.space_dof:
            raise SceneError(file, "vertices", "roadmap poses do not match the robot kind")
        if abs(circumradius - scene.robot.circumradius) > 1e-12:
            raise SceneError(file, "circumradius", "does not match the scene's robot")
    _check_digest(file, doc.get("digest"), vertices, edges)  # after the scene's checks, as the lengths'
    if edges.size:  # after the scene's checks: a roadmap of another robot is named as such
        want = metric_distance(vertices[edges[:, 0]], vertices[edges[:, 1]], circumradius)
        bad = np.nonzero(np.abs(want - lengths) > 1e-9 * (1 + want))[0]
        if bad.size:
            raise SceneError(file, f"lengths[{int(bad[0])}]", "does not match the distance between its vertices")
    return rm


def _text(file: str, doc: dict, key: str) -> str:
    """A roadmap file's string ``doc[key]``; anything else is bad input naming the key (``str``
    read a list ``[1]`` as the name ``"[1]"``)."""
    value = doc[key]
    if not isinstance(value, str):
        raise SceneError(file, key, f"expected a string, got {_kind(value)}")
    return value


def _options_from(file: str, raw) -> RoadmapOptions:
    """A roadmap file's ``options``; a file from before the repair (the join) loads as
    ``repair: false`` (``join: false``)."""
    if not isinstance(raw, dict):
        raise SceneError(file, "options", f"expected a mapping, got {type(raw).__name__}")
    known = {f.name for f in fields(RoadmapOptions)}
    for key in raw:
        if key not in known:
            raise SceneError(file, f"options.{key}", f"unknown key (allowed: {', '.join(sorted(known))})")
    try:
        return RoadmapOptions(**{"repair": False, "join": False, **raw})
    except (TypeError, ValueError) as exc:
        text = " ".join(str(exc).split())[:120]
        field_name, _, rest = text.partition(" ")  # "vertices must be ...": options.vertices: must be ...
        if field_name in known:
            raise SceneError(file, f"options.{field_name}", rest) from None
        raise SceneError(file, "options", text) from None


def default_roadmap_path(scene: Scene, folder: str | os.PathLike = "roadmaps") -> Path:
    """Where ``gfuzzy roadmap`` writes by default: ``roadmaps/<scene name>.json``."""
    return Path(folder) / f"{scene.name}.json"


# --------------------------------------------------------------------------- building


def _ompl_version() -> str:
    from importlib import metadata  # ~20 ms to import: only when a roadmap is built

    try:
        return metadata.version("ompl")
    except metadata.PackageNotFoundError:  # pragma: no cover
        return "unknown"


def _seed_ompl(seed: int) -> None:
    from ompl import util as ou

    level = ou.getLogLevel()
    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    try:
        ou.RNG.setSeed(int(seed) % 2_147_483_646 + 1)
    finally:
        ou.setLogLevel(level)


def _check_extent(scene: Scene, options: RoadmapOptions) -> None:
    """Raise SceneError for bounds too small for OMPL: its edge-checking step, the bounds'
    diagonal times ``options.resolution``, must exceed the float epsilon (else its set-up
    throws a RuntimeError; bounds of 1e-20 m, or a map of resolution 1e-300)."""
    xmin, ymin, xmax, ymax = scene.bounds
    diagonal = math.hypot(xmax - xmin, ymax - ymin)
    if not diagonal * options.resolution > np.finfo(float).eps:
        raise SceneError(
            scene.source,
            "bounds",
            f"bounds {xmax - xmin:g} x {ymax - ymin:g} are too small for a roadmap (OMPL checks edges in steps "
            f"of {options.resolution:g} of the diagonal, which must exceed {np.finfo(float).eps:.3g})",
        )


class _Builder:
    """Holds the OMPL objects of one build; they die with it (no nanobind leak warnings)."""

    def __init__(self, scene: Scene, options: RoadmapOptions, geometry: StaticGeometry):
        from ompl import base as ob
        from ompl import geometric as og
        from ompl import util as ou

        _check_extent(scene, options)

        # OMPL's log level is process-wide: quieter while we build, restored by close()
        self._log_level = ou.getLogLevel()
        ou.setLogLevel(ou.LogLevel.LOG_WARN)
        self.geometry = geometry
        xmin, ymin, xmax, ymax = scene.bounds
        bounds = ob.RealVectorBounds(2)
        bounds.setLow(0, xmin)
        bounds.setHigh(0, xmax)
        bounds.setLow(1, ymin)
        bounds.setHigh(1, ymax)
        self.box = scene.robot.space_dof == 3
        if self.box:
            space = ob.SE2StateSpace()
            space.setBounds(bounds)
            space.setSubspaceWeight(1, scene.robot.circumradius)  # the contract's metric
        else:
            space = ob.RealVectorStateSpace(2)
            space.setBounds(bounds)
        self.space = space
        si = ob.SpaceInformation(space)
        valid = geometry.is_valid
        if self.box:
            si.setStateValidityChecker(lambda s: valid((s.getX(), s.getY(), s.getYaw())))
        else:
            si.setStateValidityChecker(lambda s: valid((s[0], s[1])))
        si.setStateValidityCheckingResolution(options.resolution)
        self._samplers: list = []  # keep Python samplers alive as long as OMPL uses them
        self.sampled: list = []  # milestones in the order PRM added them (passage sampler)
        if options.sampler == "passage":
            rng = np.random.default_rng(options.seed)

            def alloc(si_):
                draws = PassageDraws(geometry, rng, options.bridge_ratio, FREE_CELL_SHARE)
                smp = passage_sampler_type()(si_, draws, self.sampled)
                self._samplers.append(smp)
                return smp

            si.setValidStateSamplerAllocator(alloc)
        si.setup()
        self.si = si
        prm = og.PRM(si)
        prm.setMaxNearestNeighbors(options.neighbors)
        prm.setProblemDefinition(ob.ProblemDefinition(si))
        prm.setup()
        self.prm = prm
        self.no_room: str | None = None  # why the robot fits nowhere ("": not proved), once asked

    def close(self) -> None:
        """Break the Python <-> OMPL reference cycle of the sampler allocator; give OMPL
        back the log level it had. The build's OMPL objects die here, by reference counting."""
        from ompl import util as ou

        ou.setLogLevel(self._log_level)
        if self._samplers:
            self.si.clearValidStateSamplerAllocator()
            self._samplers.clear()
        self.prm.clear()
        self.prm = self.si = self.space = None

    def grow(self, n: int, progress: Callable[[int, int], None] | None) -> None:
        """Grow to ``n`` milestones; raise SceneError if the free space is (nearly) empty.

        PRM samples until it finds a valid state, for ever if there is none, so growth also
        stops after ``STALL_CHECKS`` validity checks without a new milestone, and after
        ``PROOF_CHECKS`` when the robot's inscribed disc has no room anywhere
        (:func:`_no_room`: a robot that fits nowhere took 200,000 checks to say so).
        """
        from ompl import base as ob

        prm, geometry = self.prm, self.geometry
        last = [-1]
        seen = [prm.milestoneCount(), geometry.checks]

        def done() -> bool:
            count = prm.milestoneCount()
            if progress is not None and count != last[0] and count % 50 == 0:
                last[0] = count
                progress(count, n)
            if count > seen[0]:
                seen[0], seen[1] = count, geometry.checks
            elif geometry.checks - seen[1] > STALL_CHECKS:
                return True
            elif geometry.checks - seen[1] > PROOF_CHECKS and self.no_room is None:
                self.no_room = _no_room(geometry.scene) if count == 0 else ""
            return count >= n or bool(self.no_room)  # asked again (OMPL's two loops): the same answer

        prm.growRoadmapPtc(ob.PlannerTerminationCondition(done))
        count = prm.milestoneCount()
        if count == 0 and self.no_room:
            raise SceneError(geometry.scene.source, "robot", f"the robot fits nowhere: {self.no_room}")
        if count < n:
            raise SceneError(
                geometry.scene.source,
                "robot",
                f"the robot fits (almost) nowhere: {count} of {n} roadmap vertices found free "
                f"after {geometry.checks} collision checks",
            )

    def export(self) -> tuple[FloatArray, IntArray]:
        from ompl import base as ob

        pd = ob.PlannerData(self.si)
        self.prm.getPlannerData(pd)
        nv = pd.numVertices()
        verts = []
        for i in range(nv):
            s = pd.getVertex(i).getState()
            verts.append((s.getX(), s.getY(), s.getYaw()) if self.box else (s[0], s[1]))
        edges = set()
        for i in range(nv):
            for j in pd.getEdges(i):
                a, b = (i, int(j)) if i < j else (int(j), i)
                if a != b:
                    edges.add((a, b))
        e = np.array(sorted(edges), dtype=np.int64).reshape(-1, 2)
        if self.sampled:
            # PRM's planner data leaves out milestones without an edge: add them back
            dim = 3 if self.box else 2
            have = {np.asarray(v, dtype=float).tobytes() for v in verts}
            for q in self.sampled:
                arr = np.asarray(q, dtype=float)
                if dim == 3:  # OMPL stores the yaw it was given; match its float exactly
                    arr[2] = float(arr[2])
                if arr.tobytes() not in have:
                    have.add(arr.tobytes())
                    verts.append(tuple(arr.tolist()))
        return np.array(verts, dtype=float).reshape(len(verts), 3 if self.box else 2), e


def _no_room(scene: Scene) -> str:
    """Why the robot fits nowhere, when its inscribed disc has no room anywhere in the bounds
    among the obstacles (grown by the clearance), else ``""``
    (:func:`~gfuzzy.roadmap.freespace.inscribed_free_space`: a proof, not a guess)."""
    from .freespace import inscribed_disc, inscribed_free_space

    got = inscribed_free_space(scene)
    if got is None or got[1].regions:
        return ""
    radius = inscribed_disc(scene.robot)[1]
    keep = f" {scene.robot.clearance:g} m from the obstacles" if scene.robot.clearance > 0 else ""
    bounds = ", ".join(f"{v:g}" for v in scene.bounds)
    return f"the disc inside its body (radius {radius:.3f} m) has room nowhere{keep} within the bounds [{bounds}]"


def build_roadmap(
    scene: Scene,
    options: RoadmapOptions | None = None,
    progress: Callable[[int, int], None] | None = None,
    geometry: StaticGeometry | None = None,
) -> Roadmap:
    """Build a roadmap of the static scene with OMPL's PRM.

    Parameters
    ----------
    scene : Scene
    options : RoadmapOptions, optional
    progress : callable(count, total), optional
        Called as milestones are added (every 50) and as edges are certified.
    geometry : StaticGeometry, optional
        Reuse an existing collision model of ``scene``.

    Returns
    -------
    Roadmap
        Seeded and reproducible: the same scene, options and seed give the same roadmap
        in any process.
    """
    options = options or RoadmapOptions()
    return grow_roadmaps(scene, [options.vertices], options, progress, geometry)[0]


def grow_roadmaps(
    scene: Scene,
    sizes: list[int],
    options: RoadmapOptions | None = None,
    progress: Callable[[int, int], None] | None = None,
    geometry: StaticGeometry | None = None,
) -> list[Roadmap]:
    """Grow one PRM through increasing vertex counts, exporting a roadmap at each.

    Each roadmap extends the previous one (the paper's Table 1: 100, 200, ... 1000).
    ``options.vertices`` is ignored; each result records its own count.
    """
    options = options or RoadmapOptions()
    sizes = sorted(int(n) for n in sizes)
    if not sizes or sizes[0] < 1:
        raise InputError("sizes must be positive vertex counts")
    geometry = geometry or StaticGeometry(scene)
    calls0 = geometry.calls
    t_start = time.perf_counter()
    _seed_ompl(options.seed)
    builder = _Builder(scene, options, geometry)
    from .freespace import free_space

    fs = free_space(scene) if options.repair and scene.robot.shape == "disc" else None
    certified: dict = {}  # (pose a, pose b) bytes -> free: later sizes reuse the answers
    vertex_clear: dict = {}  # pose bytes -> clearance
    out = []
    try:
        for n in sizes:
            builder.grow(n, progress)
            vertices, edges = builder.export()
            t_grow = time.perf_counter() - t_start
            calls_grow = geometry.calls - calls0
            keep = np.ones(len(edges), dtype=bool)
            vlist = vertices.tolist()
            vkeys = [v.tobytes() for v in vertices]
            clear = []
            for key, pose in zip(vkeys, vlist, strict=True):  # once per vertex, not per edge
                c = vertex_clear.get(key)
                if c is None:
                    c = vertex_clear[key] = geometry.clearance1(pose)
                clear.append(c)
            for k, (a, b) in enumerate(edges.tolist()):
                key = (vkeys[a], vkeys[b])
                free = certified.get(key)
                if free is None:
                    free = certified[key] = geometry.motion_free(vlist[a], vlist[b], ca=clear[a], cb=clear[b])
                keep[k] = free
                if progress is not None and k % 2000 == 1999:
                    progress(k + 1, len(edges))
            dropped = int((~keep).sum())
            edges = edges[keep]
            vertices, edges, repaired = repair_roadmap(geometry, fs, vertices, edges, options.neighbors)
            vertices, edges, joined = join_roadmap(geometry, vertices, edges, options)
            lengths = metric_distance(
                vertices[edges[:, 0]], vertices[edges[:, 1]], scene.robot.circumradius
            )
            if dropped:
                log.info("dropped %d of %d PRM edges that could not be certified free", dropped, len(keep))
            info = RoadmapInfo(
                ompl_version=_ompl_version(),
                seconds=round(time.perf_counter() - t_start, 4),
                grow_seconds=round(t_grow, 4),
                validity_calls=int(calls_grow),
                certify_calls=int(geometry.calls - calls0 - calls_grow),
                edges_dropped=dropped,
                components=count_components(len(vertices), edges),
                repair=repaired,
                join=joined,
            )
            opts = RoadmapOptions(**{**asdict(options), "vertices": n})
            out.append(
                Roadmap(
                    vertices,
                    edges,
                    np.asarray(lengths, dtype=float),
                    scene.name,
                    scene.static_hash,
                    scene.robot.circumradius,
                    opts,
                    info,
                )
            )
    finally:
        builder.close()
    return out


def roadmap_digest(rm: Roadmap) -> str:
    """SHA-256 over vertices and edges: equal digests mean identical roadmaps."""
    return _digest(rm.vertices, rm.edges)


def _digest(vertices: FloatArray, edges: IntArray) -> str:
    h = hashlib.sha256(np.ascontiguousarray(vertices, dtype="<f8").tobytes())
    h.update(np.ascontiguousarray(edges, dtype="<i8").tobytes())
    return h.hexdigest()


def _check_digest(file: str, digest, vertices: FloatArray, edges: IntArray) -> None:
    """Refuse a file whose vertices or edges were edited: its edges are certified free only
    as built (a file without ``digest``, written before it was kept, is taken as it is)."""
    if digest is not None and not isinstance(digest, str):
        raise SceneError(file, "digest", f"expected the SHA-256 string written with the roadmap, got {digest!r:.40}")
    if digest is not None and digest != _digest(vertices, edges):
        why = "edited after the roadmap was built (its edges are certified free only as built)"
        raise SceneError(file, "digest", f"the vertices or edges were {why}; rebuild it with `gfuzzy roadmap`")
