"""The precompiled kernels (gfuzzy.timespace.jit, gfuzzy.timespace.precompile): what a cold process imports,
that they answer as numba's kernels do, that a stale or mismatched build is not used, and
that `planning_seconds` counts the kernels' load. Each check runs in a fresh process."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from gfuzzy.timespace import jit

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def kernel_dir(tmp_path_factory):
    """A folder holding the fresh extension: where `make warm` put it, else built here."""
    name = jit.module_name()
    for folder in jit.kernel_dirs():
        if (folder / f"{name}.json").exists():
            return folder
    try:
        from gfuzzy.timespace.precompile import build

        return build(tmp_path_factory.mktemp("kernels")).parent
    except RuntimeError as exc:  # no C compiler: nothing to test here
        pytest.skip(f"precompiled kernels cannot be built here: {exc}")


def _run(code: str, kernel_dir, precompiled: bool = True) -> list:
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg", GFUZZY_KERNEL_DIR=str(kernel_dir))
    env["GFUZZY_PRECOMPILED"] = "1" if precompiled else "0"
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


HEAVY = ("numba", "scipy.sparse.csgraph", "matplotlib", "dask", "networkx", "trimesh")

PLAN = """
import json, sys
import gfuzzy
from gfuzzy.timespace import jit
from gfuzzy.roadmap.roadmap import load_roadmap
from gfuzzy.scene.scene import load_scene
rows = []
for name in sys.argv[1:] or {scenes!r}:
    s = load_scene(f"scenes/{{name}}.yaml")
    r = gfuzzy.plan(s, load_roadmap(f"roadmaps/{{name}}.json", s), s.queries[0].start, s.queries[0].goal, s.queries[0].t0)
    rows.append([name, r.status.value, r.trajectory.duration if r.trajectory else None,
                 r.trajectory.waypoints.tolist() if r.trajectory else None])
print(json.dumps([rows, jit.loaded() is not None, [m for m in {heavy!r} if m in sys.modules]]))
"""


def test_a_cold_query_loads_no_numba_scipy_graph_or_pictures(kernel_dir):
    """`import gfuzzy` and compiled queries (a box robot among two movers, a disc robot)
    run on the precompiled kernels: numba, scipy's graph module, matplotlib, dask,
    networkx and trimesh are never imported."""
    code = PLAN.format(scenes=["building-floor", "sim-5s2m"], heavy=HEAVY)
    rows, precompiled, heavy = _run(code, kernel_dir)
    assert precompiled is True
    assert heavy == []
    assert [r[1] for r in rows] == ["solved", "solved"]


def test_cli_plan_loads_no_numba(kernel_dir, tmp_path):
    """The `gfuzzy plan` command itself (parser, scene, roadmap, plan, file) imports none
    of them either."""
    code = (
        "import json, sys, runpy\n"
        f"sys.argv = ['gfuzzy', 'plan', 'scenes/building-floor.yaml', '-o', {str(tmp_path / 'x.json')!r}]\n"
        "try:\n    runpy.run_module('gfuzzy', run_name='__main__')\n"
        "except SystemExit as e:\n    assert not e.code, e.code\n"
        f"print(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))\n"
    )
    assert _run(code, kernel_dir) == []
    assert json.loads((tmp_path / "x.json").read_text())["status"] == "solved"


def test_precompiled_answers_are_numbas(kernel_dir):
    """The same queries on the precompiled kernels and on numba's (GFUZZY_PRECOMPILED=0):
    the same status, duration and waypoints; numba is loaded only in the second."""
    scenes = ["building-floor", "sim-5s2m", "wait-corridor", "sealed-room"]
    code = PLAN.format(scenes=scenes, heavy=("numba",))
    fast = _run(code, kernel_dir)
    slow = _run(code, kernel_dir, precompiled=False)
    assert fast[1:] == [True, []] and slow[1:] == [False, ["numba"]]
    assert fast[0] == slow[0]
    assert {r[1] for r in fast[0]} >= {"solved"}


def test_a_stale_extension_is_not_loaded(kernel_dir, tmp_path):
    """An extension built from other kernel source (another key in its name) is ignored:
    the kernels are numba's; a folder with the fresh one loads it."""
    name = jit.module_name()
    for f in kernel_dir.glob(f"{name}*"):
        shutil.copy(f, tmp_path / f.name.replace(name, jit.module_name("0" * 16)))
    code = "import json\nfrom gfuzzy.timespace import jit, search_kernel\nprint(json.dumps(jit.loaded() is not None))\n"
    assert _run(code, tmp_path) is False
    assert _run(code, kernel_dir) is True


def test_other_argument_types_fall_back_to_numba(kernel_dir):
    """A precompiled kernel called with types it was not built for (int32 arrays, a strided
    view) runs numba's dispatcher, with the right answer, instead of reading the memory
    wrongly; the types it was built for never load numba."""
    code = """
import json, sys
import numpy as np
from gfuzzy.timespace import search_kernel as k
tk = np.full(8, -1, np.int64); tb = np.zeros(8, np.int64); tp = np.zeros(8, np.int64); ctr = np.zeros(7, np.int64)
k._set(tk, tb, tp, ctr, 5, 42, -1)
out = [k._get(tk, tb, 5, -9), k._get(tk, tb, 6, -9), "numba" in sys.modules, k._get.precompiled]
wide = np.full(16, -1, np.int64); wide[::2] = tk; wtb = np.zeros(16, np.int64); wtb[::2] = tb
out += [k._get(tk.astype(np.int32), tb.astype(np.int32), 5, -9), k._get(wide[::2], wtb[::2], 5, -9), "numba" in sys.modules]
print(json.dumps(out))
"""
    assert _run(code, kernel_dir) == [42, -9, False, True, 42, 42, True]


def test_planning_seconds_counts_the_kernels_load(kernel_dir):
    """`planning_seconds` of a process's first compiled query includes loading the
    kernels (`search_function`: the extension, or numba and its cache), whichever way
    they load: the reported figure is at least the time measured around that load."""
    code = """
import json, time
import gfuzzy, gfuzzy.planner.planner as P
from gfuzzy.roadmap.roadmap import load_roadmap
from gfuzzy.scene.scene import load_scene
spans = []
inner = P.search_function
def timed(backend):
    t = time.perf_counter(); f = inner(backend); spans.append(time.perf_counter() - t); return f
P.search_function = timed
s = load_scene("scenes/sim-5s2m.yaml")
r = gfuzzy.Planner(s, load_roadmap("roadmaps/sim-5s2m.json", s)).plan(s.queries[0].start, s.queries[0].goal)
print(json.dumps([r.status.value, len(spans), r.planning_seconds >= sum(spans) > 0]))
"""
    for precompiled in (True, False):
        assert _run(code, kernel_dir, precompiled) == ["solved", 1, True]
    # the first look at the kernels (jit.loaded: the extension loaded, its source hashed) is
    # the query's time too, also when plan() asks before its search (compile_if_cold);
    # here that load takes 1000 s on the planner's clock
    slow = """
import json, time, types
import gfuzzy, gfuzzy.planner.planner as P
from gfuzzy.timespace import jit
from gfuzzy.roadmap.roadmap import load_roadmap
from gfuzzy.scene.scene import load_scene
real, late, loads = time.perf_counter, [0.0], []
P.time = types.SimpleNamespace(perf_counter=lambda: real() + late[0])
inner = jit.loaded
def loading():
    if "ext" not in jit._state:
        loads.append(late[0]); late[0] += 1000.0
    return inner()
jit.loaded = loading
s = load_scene("scenes/sim-5s2m.yaml")
r = gfuzzy.Planner(s, load_roadmap("roadmaps/sim-5s2m.json", s)).plan(s.queries[0].start, s.queries[0].goal)
print(json.dumps([jit.cold(), loads, r.planning_seconds >= 1000.0]))
"""
    assert _run(slow, kernel_dir) == [False, [0.0], True]


def test_a_cold_install_says_it_compiles_before_the_first_search(monkeypatch, tmp_path):
    """A fresh install's first query waited about 30 s in silence while numba compiled the
    kernels (a newcomer measured it): the first search of a process now says so on a
    terminal, when there is neither a precompiled extension nor numba's cache of the
    search kernels; once, into a pipe too (a CI log waited minutes with no word)."""
    import io

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    from numba.core import caching  # noqa: F401  (before NUMBA_CACHE_DIR: see _cache_of)

    cache = tmp_path / "numba"
    cache.mkdir()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache))
    monkeypatch.setattr(jit, "loaded", lambda: None)
    monkeypatch.setattr(jit, "_noted", [])
    assert jit.cold()
    pipe, term = io.StringIO(), Terminal()
    jit.note_cold(pipe)
    assert pipe.getvalue().count("note: compiling the search kernels") == 1 and "precompile" in pipe.getvalue()
    jit.note_cold(pipe)
    jit.note_cold(term)
    assert pipe.getvalue().count("note:") == 1 and term.getvalue() == ""  # once per process
    monkeypatch.setattr(jit, "_noted", [])
    jit.note_cold(term)
    assert term.getvalue().count("note: compiling the search kernels") == 1
    _cache_of(cache, jit.__file__, "search_kernel.astar-100.py311.nbi")
    assert not jit.cold()  # numba's cache holds them
    monkeypatch.setattr(jit, "loaded", lambda: object())
    for f in cache.rglob("*.nbi"):
        f.unlink()
    assert not jit.cold()  # the precompiled extension serves
    monkeypatch.setattr(jit, "_noted", [])
    term = Terminal()
    jit.note_cold(term)
    assert term.getvalue() == ""


def _cache_of(cache: Path, source: str, name: str) -> Path:
    """An empty numba index file ``name`` where numba keeps the cache of kernels whose source
    is beside ``source`` under ``NUMBA_CACHE_DIR=cache`` (its own rule, asked of numba: import
    numba before setting NUMBA_CACHE_DIR, which numba reads at its import, or this process's
    later compiles go to the test's empty folder)."""
    from numba.core.caching import UserProvidedCacheLocator

    folder = cache / UserProvidedCacheLocator.get_suitable_cache_subpath(source)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_bytes(b"")
    return folder / name


def test_numba_cached_looks_where_numba_keeps_gfuzzys_kernels(monkeypatch, tmp_path):
    """`jit.numba_cached` (behind `jit.cold` and `ga.refine.warm_if_cold`) finds numba's index
    of a gfuzzy kernel module in a shared NUMBA_CACHE_DIR, and not another package's module of
    the same name there (a `kernels.*.nbi` of any package counted as the GA's)."""
    from numba.core import caching  # noqa: F401  (before NUMBA_CACHE_DIR: see _cache_of)

    from gfuzzy.ga import kernels

    cache = tmp_path / "numba"
    cache.mkdir()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache))
    ga = os.path.dirname(os.path.abspath(kernels.__file__))
    other = tmp_path / "other_pkg" / "kernels.py"
    _cache_of(cache, str(other), "kernels.mutate-12.py311.nbi")
    _cache_of(cache, jit.__file__, "search_kernel.sipp-40.py311.nbi")
    assert not jit.numba_cached("kernels", ga)  # another package's, and the search's
    assert jit.numba_cached("search_kernel", os.path.dirname(jit.__file__))
    _cache_of(cache, kernels.__file__, "kernels.mutation_apply-39.py311.nbi")
    assert jit.numba_cached("kernels", ga)
    monkeypatch.delenv("NUMBA_CACHE_DIR")  # then the folder's own __pycache__
    assert not jit.numba_cached("kernels", tmp_path / "other_pkg")
    (tmp_path / "other_pkg" / "__pycache__").mkdir(parents=True)
    (tmp_path / "other_pkg" / "__pycache__" / "kernels.mutate-12.py311.nbi").write_bytes(b"")
    assert jit.numba_cached("kernels", tmp_path / "other_pkg")


def test_plan_compiles_a_cold_install_before_its_clock(monkeypatch):
    """A fresh `pip install`'s first `gfuzzy plan` of the building floor answered `timeout`
    after 2 minutes on a busy 2-core machine: numba compiled the kernels inside the query's
    60 s budget (a newcomer met it). On a cold install `Planner.plan` now compiles them
    first, once per process, and its clock starts after: here a compile that takes 1000 s
    on the planner's clock leaves the answer solved and its planning_seconds small."""
    import types

    import gfuzzy.planner.planner as P
    from gfuzzy.roadmap.roadmap import load_roadmap
    from gfuzzy.scene.scene import load_scene
    from gfuzzy.timespace import backends, graph_kernel, search_kernel

    real = P.time.perf_counter
    late = [0.0]
    compiles = []

    def compiling():  # slower than any budget, on the planner's clock
        compiles.append(late[0])
        late[0] += 1000.0

    def graph_compiling():
        graphs.append(late[0])

    graphs: list = []
    monkeypatch.setattr(P, "time", types.SimpleNamespace(perf_counter=lambda: real() + late[0]))
    monkeypatch.setattr(backends, "_compiled", [], raising=False)
    monkeypatch.setattr(jit, "cold", lambda: True)
    monkeypatch.setattr(search_kernel, "warm", compiling)
    monkeypatch.setattr(graph_kernel, "warm", graph_compiling)
    s = load_scene(ROOT / "scenes" / "sim-5s2m.yaml")
    planner = P.Planner(s, load_roadmap(ROOT / "roadmaps" / "sim-5s2m.json", s))
    q = s.queries[0]
    first = planner.plan(q.start, q.goal, q.t0, options=P.PlanOptions(time_limit=60.0))
    assert compiles == [0.0] and graphs == [1000.0]  # both kernels' warms, once each
    assert first.status == "solved" and first.planning_seconds < 1000.0
    again = planner.plan(q.start, q.goal, q.t0)
    assert compiles == [0.0] and graphs == [1000.0] and again.status == "solved"  # once per process
    monkeypatch.setattr(backends, "_compiled", [], raising=False)
    monkeypatch.setattr(jit, "cold", lambda: False)  # a cache or the extension: nothing to compile
    planner.plan(q.start, q.goal, q.t0)
    assert compiles == [0.0] and graphs == [1000.0]
    monkeypatch.setattr(backends, "_compiled", [], raising=False)
    monkeypatch.setattr(jit, "cold", lambda: True)
    planner.plan(q.start, q.goal, q.t0, options=P.PlanOptions(backend="reference"))
    assert compiles == [0.0] and graphs == [1000.0]  # the reference search compiles nothing


def test_plan_compiles_the_ga_of_a_cold_install_before_its_clock(monkeypatch, tmp_path):
    """`--refine --time-limit 10` with numba's cache empty answered `solved` after 137 s, 136
    of them compiling the GA's kernels inside the GA, which no deadline stops. With `refine`
    `Planner.plan` now compiles them first when numba's cache holds none (once per process),
    and never when it does or without `refine`."""
    import types

    import gfuzzy.planner.planner as P
    from gfuzzy.ga import refine
    from gfuzzy.roadmap.roadmap import load_roadmap
    from gfuzzy.scene.scene import load_scene

    real = P.time.perf_counter
    late = [0.0]
    compiles = []

    def compiling():
        compiles.append(late[0])
        late[0] += 1000.0

    from numba.core import caching  # noqa: F401  (before NUMBA_CACHE_DIR: see _cache_of)

    cache = tmp_path / "numba"
    cache.mkdir()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache))
    monkeypatch.setattr(P, "time", types.SimpleNamespace(perf_counter=lambda: real() + late[0]))
    monkeypatch.setattr(refine, "_warmed", [], raising=False)
    monkeypatch.setattr(refine, "warm", compiling)
    s = load_scene(ROOT / "scenes" / "sim-5s2m.yaml")
    planner = P.Planner(s, load_roadmap(ROOT / "roadmaps" / "sim-5s2m.json", s))
    q = s.queries[0]
    planner.plan(q.start, q.goal, q.t0)
    assert compiles == []  # no refine: no GA
    r = planner.plan(q.start, q.goal, q.t0, options=P.PlanOptions(refine=True, time_limit=60.0))
    assert compiles == [0.0]
    assert r.status == "solved" and r.planning_seconds < 1000.0
    planner.plan(q.start, q.goal, q.t0, options=P.PlanOptions(refine=True))
    assert compiles == [0.0]  # once per process
    monkeypatch.setattr(refine, "_warmed", [], raising=False)
    _cache_of(cache, str(tmp_path / "other" / "kernels.py"), "kernels.mutation_apply-39.py311.nbi")
    planner.plan(q.start, q.goal, q.t0, options=P.PlanOptions(refine=True))
    assert compiles == [0.0, 1000.0]  # another package's kernels in the shared cache are not the GA's
    monkeypatch.setattr(refine, "_warmed", [], raising=False)
    _cache_of(cache, refine.__file__, "kernels.mutation_apply-39.py311.nbi")
    planner.plan(q.start, q.goal, q.t0, options=P.PlanOptions(refine=True))
    assert compiles == [0.0, 1000.0]  # numba's cache holds them


@pytest.mark.filterwarnings("ignore:The 'pycc' module is pending deprecation")
def test_precompile_warms_modules_beside_its_ahead_of_time_compile(monkeypatch, tmp_path):
    """`make warm` runs soft_kernel's warm beside the ahead-of-time compile (``precompile
    --beside``): its process starts once numba has compiled the search kernels (whose cache
    it loads), on numba's kernels, before the extension's compile, and the build waits
    for it. numba's warm-ups, the compiler and the process are stood in for here."""
    import numba.pycc

    from gfuzzy.timespace import graph_kernel, precompile, search_kernel

    events = []

    class CC:  # numba.pycc.CC: writes an empty "extension"
        def __init__(self, name):
            self.name = name

        def export(self, *args):
            return lambda func: func

        def compile(self):
            events.append("compile")
            Path(self.output_dir, f"{self.name}.so").write_bytes(b"")

    class Popen:
        def __init__(self, args, env):
            events.append(("start", args[3:], env["GFUZZY_PRECOMPILED"]))
            self.args, self.returncode = args, 0

        def wait(self):
            events.append("wait")
            return 0

    monkeypatch.setattr(jit, "BUILDING", False)
    monkeypatch.setattr(jit, "_state", {})
    monkeypatch.setattr(jit, "loaded", lambda: None)
    monkeypatch.setattr(numba.pycc, "CC", CC)
    monkeypatch.setattr(precompile.subprocess, "Popen", Popen)
    monkeypatch.setattr(search_kernel, "warm", lambda: events.append("numba"))
    monkeypatch.setattr(graph_kernel, "warm", lambda: events.append("numba"))
    built = precompile._build_here(tmp_path, "", ["gfuzzy.timespace.soft_kernel"])
    assert built.parent == tmp_path and (tmp_path / f"{jit.module_name()}.json").exists()
    assert events == ["numba", "numba", ("start", ["gfuzzy.timespace.soft_kernel"], "0"), "compile", "wait"]
    events.clear()
    precompile._build_here(tmp_path, "")  # without --beside: no second process
    assert events == ["numba", "numba", "compile"]


def test_a_module_warmed_beside_the_build_runs_in_its_own_process(tmp_path, caplog, monkeypatch):
    """The second process imports each module and calls its ``warm()``, on numba's kernels;
    one that fails is a warning, not a failed build (`make warm` warms it again after)."""
    from gfuzzy.timespace import precompile

    (tmp_path / "warm_ok.py").write_text(
        "import os, pathlib\ndef warm():\n"
        f"    pathlib.Path({str(tmp_path)!r}, 'ok').write_text(os.environ['GFUZZY_PRECOMPILED'])\n"
    )
    (tmp_path / "warm_bad.py").write_text("def warm():\n    raise SystemExit(3)\n")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(tmp_path), os.environ.get("PYTHONPATH")])))
    monkeypatch.setenv("GFUZZY_PRECOMPILED", "1")
    precompile._finish_beside(precompile._start_beside(["warm_ok"]))
    assert (tmp_path / "ok").read_text() == "0" and caplog.records == []
    caplog.set_level("WARNING", logger=precompile.__name__)
    precompile._finish_beside(precompile._start_beside(["warm_bad"]))
    assert [r.getMessage() for r in caplog.records] == ["warming warm_bad beside the build failed (exit status 3)"]
