"""Figure 14: the 5 m x 5 m simulations with the GA's path.

``scenes/sim-4s1m.yaml`` (4 static + 1 moving obstacle), ``sim-6s1m.yaml`` (6 + 1) and
``sim-5s2m.yaml`` (5 + 2), every query answered twice as Dask batches: the search alone,
and with ``--refine`` (the GA with the paper's parameters, ``gfuzzy.ga.GAOptions``
defaults). Each refined answer of a scene's first query is drawn with ``gfuzzy.render.render``.
"""

from __future__ import annotations

import numpy as np

from gfuzzy.ga import GAOptions
from gfuzzy.planner.planner import PlanOptions
from gfuzzy.render.render import render
from gfuzzy.runs.batch import BatchOptions, run_batch, trajectory_path

from .common import bundled, fmt, load_doc, md_table

SCENES = [("sim-4s1m", "4 static + 1 moving"), ("sim-6s1m", "6 static + 1 moving"), ("sim-5s2m", "5 static + 2 moving")]


#: The paper's GA: population 50, 2000 generations, Pc 0.62, Pm 0.1, smoothing 0.2 (our
#: defaults), run to the end: no early stop (our default stops after 200 idle generations).
GA = GAOptions(patience=None)


def _turning(wp: np.ndarray) -> float:
    d = np.diff(wp[:, 1:3], axis=0)
    d = d[np.hypot(*d.T) > 1e-9]
    if len(d) < 2:
        return 0.0
    h = np.arctan2(d[:, 1], d[:, 0])
    return float(np.abs((np.diff(h) + np.pi) % (2 * np.pi) - np.pi).sum())


def _length(wp: np.ndarray) -> float:
    return float(np.hypot(*np.diff(wp[:, 1:3], axis=0).T).sum())


def run(ctx) -> str:
    pairs = [bundled(name) for name, _ in SCENES]
    plain_dir, ref_dir = ctx.scratch / "fig14-plain", ctx.scratch / "fig14-refined"
    plain = run_batch(ctx.client, pairs, BatchOptions(trajectories=str(plain_dir)))
    refined = run_batch(
        ctx.client, pairs, BatchOptions(plan=PlanOptions(refine=True, seed=ctx.seed, ga=GA), trajectories=str(ref_dir))
    )
    rows = []
    pictures = []
    for (scene, _rm), (name, label) in zip(pairs, SCENES, strict=True):
        for qi, q in enumerate(scene.queries):
            a = load_doc(trajectory_path(plain_dir, scene.name, q.name))
            b = load_doc(trajectory_path(ref_dir, scene.name, q.name))
            ra = next(r for r in plain.rows if r.scene == scene.name and r.query == q.name)
            rb = next(r for r in refined.rows if r.scene == scene.name and r.query == q.name)
            if a["status"] != "solved" or b["status"] != "solved":
                rows.append([name, label, q.name, a["status"], b["status"], "", "", "", "", ""])
                continue
            wa, wb = np.asarray(a["waypoints"]), np.asarray(b["waypoints"])
            info = b.get("stats", {}).get("refine", {})
            applied = "yes" if info.get("applied") else f"no ({info.get('reason', '')})"
            rows.append([
                name, label, q.name,
                f"{_length(wa):.2f} -> {_length(wb):.2f}",
                f"{_turning(wa):.2f} -> {_turning(wb):.2f}",
                f"{ra.duration:.2f} -> {rb.duration:.2f}",
                f"{ra.delay_factor:.3f} -> {rb.delay_factor:.3f}",
                applied,
                f"{info.get('generations', '-')}",
                f"{fmt(ra.planning_seconds * 1000, '.0f')} / {fmt(rb.planning_seconds * 1000, '.0f')}",
                rb.check,
            ])  # fmt: skip
            if qi == 0:
                out = ctx.img / f"fig14-{name}.png"
                render(scene, out, trajectory=wb, title=f"{name} ({label}), {q.name}: GA-refined path")
                pictures.append((name, label, out.name))
    params = (
        f"population {GA.population}, {GA.generations} generations, Pc {GA.pc}, Pm {GA.pm}, "
        f"smoothing {GA.p_smooth}, no early stop"
    )
    table = md_table(
        ["scene", "obstacles", "query", "path length m", "turning rad", "duration s", "delay factor",
         "GA applied", "generations", "ms search / with GA", "check"],  # fmt: skip
        rows,
    )
    pics = "\n\n".join(f"![{n}: {lab}, the GA's path](img/{f})" for n, lab, f in pictures)
    return f"""## Figure 14: the 5 m x 5 m simulations with the GA's path

`python -m tools.experiments fig14`. The three simulations of the paper's Figure 14 as we
read them (a disc robot among disc obstacles in a 5 m x 5 m field; positions, sizes and the
movers' paths are ours: `docs/scenes.md`), every query answered by the search alone and with
`--refine`: the GA with the paper's parameters ({params}; `gfuzzy.ga.GAOptions`), seed
{ctx.seed}. Each pair "a -> b" is search alone -> refined; "turning" sums the heading
changes along the path; every refined answer passed `gfuzzy check` where the table says
`valid`.

{table}

{pics}

The GA shortens and straightens every corridor the search found (the search's path follows
roadmap edges, so it zig-zags), and the refined path is then re-timed among the movers; it is
kept only if it arrives at most 10 % later (`PlanOptions.refine_max_slowdown`), so its duration
can be a little longer than the search's when the straighter path meets a mover and has to
wait. The paper's pictures show the same kind of smooth path bending around the discs; we
have no numbers of the paper's to put beside ours for these scenes.
"""
