"""The experiments' scene variants (tools/experiments/fig12.py) are valid scenes."""

from __future__ import annotations

import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from gfuzzy.roadmap.roadmap import load_roadmap  # noqa: E402
from gfuzzy.scene.scene import load_scene  # noqa: E402
from tools.experiments.fig12 import BEHAVIOURS, SPEEDS, variant  # noqa: E402


def test_fig12_variants_are_55_valid_scenes_on_one_roadmap(tmp_path):
    doc = yaml.safe_load((ROOT / "scenes" / "building-floor.yaml").read_text())
    base = load_scene(ROOT / "scenes" / "building-floor.yaml")
    names = set()
    for beh in BEHAVIOURS:
        for v in SPEEDS:
            d = variant(doc, beh, v)
            path = tmp_path / f"{d['name']}.yaml"
            path.write_text(yaml.safe_dump(d, sort_keys=False))
            scene = load_scene(path)
            names.add(scene.name)
            assert scene.static_hash == base.static_hash  # the saved roadmap fits every variant
            assert all(m.speed == v for m in scene.movers)
            assert [q.start for q in scene.queries] == [q.start for q in base.queries]
            if beh == "once":
                assert all(m.mode == "once" and m.path[0].tolist() == m.path[-1].tolist() for m in scene.movers)
            elif beh == "bounce":
                assert all(m.mode == "bounce" for m in scene.movers)
            elif beh == "reverse":
                assert [m.path[1].tolist() for m in scene.movers] == [m.path[-1].tolist() for m in base.movers]
            elif beh == "offset":
                assert all(m.offset > 0 for m in scene.movers)
    assert len(names) == 55
    load_roadmap(ROOT / "roadmaps" / "building-floor.json", scene)
