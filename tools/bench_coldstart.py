"""Cold start: what the first query of a process costs, per way of loading the kernels.

    python tools/bench_coldstart.py               # every option, 5 cold CLI runs each
    python tools/bench_coldstart.py --runs 9 --options precompiled numba

Options (each measured in fresh processes, one after the other in the same run):

* ``precompiled``: the default when ``make warm`` built the extension
  (:mod:`gfuzzy.timespace.jit`, ``python -m gfuzzy.timespace.precompile``): numba never imported.
* ``numba``: ``GFUZZY_PRECOMPILED=0``, numba's just-in-time dispatchers loaded from its
  on-disk cache (what every process paid before).
* ``reference``: ``--backend reference`` (and ``GFUZZY_PRECOMPILED=0``): the pure-Python
  search, no compiled code at all.
* ``host``: the extension built for this machine's CPU (``--cpu host``) into a temporary
  folder, against the generic build of ``precompiled`` (warm speed).

Figures per option:

* cold CLI: wall time of ``python -m gfuzzy plan scenes/building-floor.yaml -o X.json``
  (median of ``--runs``) and the ``planning_seconds`` it reports (its "planned in");
* first / warm: in one fresh process, ``import gfuzzy``, the scene, its roadmap and a
  ``Planner``, then its first query and 10 more (warm: their median), per scene;
* kernel load: the precompiled extension's load, or numba's import and the load of the
  kernels a query calls from numba's cache (the warm-up search of
  :func:`gfuzzy.timespace.search_kernel.warm`, which also runs a tiny search), in a fresh process,
  with the kernels numba found in its cache.

Targets (issue 20): cold CLI <= 0.6 s; first query <= 3 x a warm one; the warm figures
of ``tools/bench_plan.py`` kept. The machine is shared: the load (``uptime``) is printed.
The children run without ``PYTHONDONTWRITEBYTECODE``, as an installed package does (its
modules byte-compiled once, not at every import).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENES = ("building-floor", "sim-5s2m", "wait-corridor")
OPTIONS = ("precompiled", "numba", "reference", "host")

FIRST_WARM = r"""
import json, statistics, sys, time
t0 = time.perf_counter()
import gfuzzy
from gfuzzy.roadmap.roadmap import load_roadmap
from gfuzzy.scene.scene import load_scene
t1 = time.perf_counter()
scene = load_scene(f"scenes/{sys.argv[1]}.yaml")
planner = gfuzzy.Planner(scene, load_roadmap(f"roadmaps/{sys.argv[1]}.json", scene))
q = scene.queries[0]
opts = gfuzzy.PlanOptions(backend=sys.argv[2])
times, secs = [], []
for _ in range(11):
    t = time.perf_counter()
    r = planner.plan(q.start, q.goal, q.t0, opts)
    times.append(time.perf_counter() - t)
    secs.append(r.planning_seconds)
from gfuzzy.timespace import jit
print(json.dumps({"import": t1 - t0, "first": times[0], "warm": statistics.median(times[1:]),
                  "first_reported": secs[0], "duration": r.trajectory.duration if r.trajectory else None,
                  "numba": "numba" in sys.modules, "scipy_csgraph": "scipy.sparse.csgraph" in sys.modules,
                  "precompiled": jit.loaded() is not None}))
"""

KERNEL_LOAD = r"""
import json, sys, time
from gfuzzy.timespace import jit
out = {}
t = time.perf_counter()
ext = jit.loaded()
out["extension"] = time.perf_counter() - t if ext is not None else None
if ext is None:
    t = time.perf_counter()
    import numba
    out["import numba"] = time.perf_counter() - t
    from gfuzzy.timespace import search_kernel
    from numba.core.registry import CPUDispatcher
    t = time.perf_counter()
    search_kernel.warm()  # the kernels a query calls, loaded from numba's cache
    out["cache load (warm-up search)"] = time.perf_counter() - t
    for mod in (search_kernel, sys.modules["gfuzzy.timespace.movers_kernel"]):
        for name, d in sorted(vars(mod).items()):
            if isinstance(d, CPUDispatcher) and d.py_func.__module__ == mod.__name__ and d.stats.cache_hits:
                out[f"  {mod.__name__.split('.')[-1]}.{name} (hit)"] = 0.0
print(json.dumps(out))
"""


def _env(option: str, kernel_dir: str | None = None) -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    env.pop("GFUZZY_KERNEL_DIR", None)
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # as an installed package: imports read .pyc files
    if option in ("numba", "reference"):
        env["GFUZZY_PRECOMPILED"] = "0"
    if kernel_dir:
        env["GFUZZY_KERNEL_DIR"] = kernel_dir
    return env


def cold_cli(option: str, runs: int, env: dict) -> tuple[float, float]:
    """Median wall seconds of a cold ``gfuzzy plan`` and median reported planning seconds."""
    walls, planned = [], []
    backend = ["--backend", "reference"] if option == "reference" else []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(runs):
            out = Path(tmp) / "x.json"
            t = time.perf_counter()
            subprocess.run(
                [sys.executable, "-m", "gfuzzy", "plan", "scenes/building-floor.yaml", "-o", str(out), *backend],
                cwd=ROOT, env=env, check=True, capture_output=True,
            )  # fmt: skip
            walls.append(time.perf_counter() - t)
            planned.append(json.loads(out.read_text())["planning_seconds"])
    return statistics.median(walls), statistics.median(planned)


def first_warm(option: str, scene: str, env: dict) -> dict:
    backend = "reference" if option == "reference" else "compiled"
    out = subprocess.run(
        [sys.executable, "-c", FIRST_WARM, scene, backend], cwd=ROOT, env=env, check=True, capture_output=True, text=True
    )
    return json.loads(out.stdout)


def kernel_load(env: dict) -> dict:
    out = subprocess.run([sys.executable, "-c", KERNEL_LOAD], cwd=ROOT, env=env, check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5, help="cold CLI runs per option (median)")
    parser.add_argument("--options", nargs="+", choices=OPTIONS, default=list(OPTIONS))
    args = parser.parse_args()
    print(f"load: {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} {os.getloadavg()[2]:.2f} (1, 5, 15 min)")
    tmp = tempfile.TemporaryDirectory()
    for option in args.options:
        kernel_dir = None
        if option == "host":
            sys.path.insert(0, str(ROOT))
            from gfuzzy.timespace.precompile import build

            kernel_dir = str(build(tmp.name, target_cpu="host").parent)
        env = _env(option, kernel_dir)
        wall, planned = cold_cli(option, args.runs, env)
        print(f"\n[{option}] cold CLI plan building-floor: {wall:.3f} s wall, planned in {1e3 * planned:.0f} ms")
        for scene in SCENES:
            r = first_warm(option, scene, env)
            print(
                f"  {scene:15s} import {1e3 * r['import']:5.0f} ms  first {1e3 * r['first']:7.1f} ms"
                f" (reported {1e3 * r['first_reported']:7.1f})  warm {1e3 * r['warm']:6.1f} ms"
                f"  first/warm {r['first'] / r['warm']:5.1f}  numba {r['numba']!s:5} csgraph"
                f" {r['scipy_csgraph']!s:5} precompiled {r['precompiled']!s:5} duration {r['duration']}"
            )
        if option in ("precompiled", "numba"):
            loads = kernel_load(env)
            hits = [k.strip().removesuffix(" (hit)") for k in loads if k.endswith("(hit)")]
            times = {k: v for k, v in loads.items() if v is not None and not k.endswith("(hit)")}
            print("  kernel load: " + ", ".join(f"{k} {1e3 * v:.1f} ms" for k, v in times.items()))
            if hits:
                print(f"  loaded from numba's cache ({len(hits)}): " + ", ".join(hits))
    tmp.cleanup()


if __name__ == "__main__":
    main()
