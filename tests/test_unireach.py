"""A box drive's query whose lanes cannot join its ends answers ``no_path`` before the
turning rings are built (:mod:`gfuzzy.timespace.unireach`): a room cut by a wall whose door
is narrower than the body."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

import gfuzzy.timespace.unicycle as unicycle
from gfuzzy.planner.planner import Planner
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap
from gfuzzy.scene.scene import parse_scene
from gfuzzy.timespace.unilanes import lanes
from gfuzzy.timespace.unireach import ends_apart

# a wall across x = 3 with a door 0.3 m wide: the 0.6 x 0.4 body passes it at no heading;
# a pillar on the left between the two ends of SAME_SIDE (no straight drive joins them)
WALL = [
    {"box": {"center": [3.0, 0.925], "size": [0.1, 1.85]}},
    {"box": {"center": [3.0, 3.075], "size": [0.1, 1.85]}},
    {"box": {"center": [1.5, 2.0], "size": [0.4, 0.4]}},
]
ACROSS = ([1.0, 3.0, 0.0], [5.0, 2.0, 0.0])
SAME_SIDE = ([0.7, 2.0, 0.0], [2.3, 2.0, 0.0])


def scene(reverse: bool = False):
    return parse_scene({
        "version": 1, "name": "narrow-door", "bounds": [0, 0, 6, 4],
        "robot": {"box": [0.6, 0.4], "vmax": 1.0, "kinematics": "unicycle", "reverse": reverse},
        "obstacles": WALL,
        "queries": [{"name": "across", "start": ACROSS[0], "goal": ACROSS[1]}],
    })  # fmt: skip


@pytest.fixture(scope="module")
def roadmap():
    return build_roadmap(scene(), RoadmapOptions(vertices=50, seed=1))


@pytest.fixture
def rings(monkeypatch):
    """Records every call of the turning rings' builder (the graph's costly part)."""
    calls = []
    real = unicycle._rings

    def spy(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(unicycle, "_rings", spy)
    return calls


@pytest.mark.parametrize("reverse", [False, True])
def test_an_unsolvable_drive_query_never_builds_the_rings(roadmap, rings, reverse):
    sc = scene(reverse)
    res = Planner(sc, roadmap).plan(*ACROSS)
    assert res.status == "no_path"
    # proved before any graph: the disc inside the body finds the ends in separate parts
    assert "no way exists for this robot" in res.message, res.message
    assert rings == []  # main built them (both graphs: without and with tilts) before it said so


def test_ends_on_one_side_of_lanes_in_pieces_are_planned(roadmap, rings):
    sc = scene()
    planner = Planner(sc, roadmap)
    ln = lanes(roadmap, planner.geometry)
    n = len(ln.xy)
    e = ln.edges
    _, label = connected_components(coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)), directed=False)
    assert len(set(label[np.unique(e)].tolist())) > 1  # the lanes are in pieces: the ends decided
    assert not ends_apart(planner, *SAME_SIDE, 10, 1.0)
    res = planner.plan(*SAME_SIDE)
    assert res.status == "solved"  # the graph was built and searched
    assert ends_apart(planner, *ACROSS, 10, 1.0)
