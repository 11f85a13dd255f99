"""The interval store's set-up kept between searches (``gfuzzy.timespace.spacetime.store_layout``,
``IntervalStore.set_horizon``): the same numbers as computed afresh."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gfuzzy.planner.planner import Planner
from gfuzzy.roadmap.roadmap import Roadmap
from gfuzzy.scene.scene import parse_scene
from gfuzzy.timespace.movers import MoverField
from gfuzzy.timespace.spacetime import IntervalStore, store_layout
from gfuzzy.timespace.unicycle import prepare_goal

DOC = {
    "version": 1, "name": "store", "bounds": [0, 0, 6, 4],
    "robot": {"disc": 0.2, "vmax": 1.0, "kinematics": "unicycle", "wmax": 2.0},
    "movers": [{"name": "m", "disc": 0.3, "speed": 0.7, "path": [[3.0, 0.4], [3.0, 3.6]], "mode": "bounce"}],
}  # fmt: skip


@pytest.fixture(scope="module")
def spliced():
    """A goal's kept graph and two starts spliced into it (the navigator's calls)."""
    sc = parse_scene(DOC)
    verts = np.array([[1.5, 2.0], [3.0, 2.0], [4.5, 2.0], [3.0, 1.0]])
    edges = np.array([[0, 1], [1, 2], [1, 3]])
    lengths = np.hypot(*(verts[edges[:, 1]] - verts[edges[:, 0]]).T)
    pl = Planner(sc, Roadmap(verts, edges, lengths, sc.name, sc.static_hash, sc.robot.circumradius))
    kept = prepare_goal(pl, np.array([4.8, 2.0, 0.0]), 0.1, 1.0)
    starts = ([1.0, 2.0, 0.3], [1.2, 1.8, -2.0])
    return sc, kept, [kept.splice(pl, np.array(s)).graph for s in starts]


def _same(a, b):
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        assert x.dtype == y.dtype and np.array_equal(x, y), f.name


def test_a_spliced_graphs_layout_is_the_one_computed_afresh(spliced):
    """A graph spliced from a kept one computes only its own groups and takes the kept
    graph's from it (kept with it for the next call): the layout computed from the whole
    graph, for two calls."""
    _, kept, graphs = spliced
    for g in graphs:
        assert g.kept is kept and len(g.poses) > len(kept.poses)
        _same(store_layout(g), store_layout(dataclasses.replace(g, kept=None)))
        assert store_layout(g) is store_layout(g)  # kept with the graph for its second search
    assert getattr(kept, "_store_layout", None) is not None
    assert store_layout(graphs[0]).same.any()  # turns in place: groups at one position


def _field(sc, steps):
    f = MoverField(sc, 0.0, 0.1, steps, 1.0)
    f.compiled = True
    return f


@pytest.mark.parametrize("steps", [8, 60])
def test_the_ready_counts_are_the_ones_computed_afresh(spliced, steps):
    """A fresh pool's ready counts (only windows that are empty: none computed), and the same
    field set again (the navigator's goal test, then its search: nothing recomputed): the
    counts ``set_horizon`` computes from the pool. A short horizon empties many windows."""
    sc, _, graphs = spliced
    g = graphs[0]
    store = IntervalStore(g)
    f = _field(sc, steps)
    store.set_horizon(f, pool=True)
    grp = store._node_group

    def afresh():
        return np.where(store.done_hi[grp] >= store.cap, np.maximum(store.cnt, 0), -1)

    assert np.array_equal(store.ready, afresh())
    assert (store.ready == 0).any() == (steps == 8)
    for node in range(0, len(g.poses), 7):
        store.get(node)
    store.set_horizon(f, pool=True)
    assert (store.done_hi >= 0).any() and np.array_equal(store.ready, afresh())
    other = IntervalStore(dataclasses.replace(g, kept=None))
    other.set_horizon(_field(sc, steps), pool=True)
    for node in range(len(g.poses)):
        a, b = store.get(node), other.get(node)
        assert (list(a[0]), list(a[1]), a[2]) == (list(b[0]), list(b[1]), b[2])


def test_a_store_after_a_more_cautious_one_skips_its_safe_groups(spliced):
    """A store given a ``prior`` (a store of the same graph for a field at least as cautious:
    here 0.3 m more kept from the walker) computes only the groups it did not find safe all
    through the window; every point's intervals are the ones a store computes afresh."""
    sc, _, graphs = spliced
    g = graphs[0]
    cautious = MoverField(sc, 0.0, 0.1, 60, 1.0, clearance=sc.robot.mover_clearance + 0.3)
    cautious.compiled = True
    prior = IntervalStore(g)
    prior.set_horizon(cautious, pool=True)
    for node in range(len(g.poses)):
        prior.get(node)
    asked = {}

    def counted(name, store):
        f = _field(sc, 60)
        plain = f.safe_intervals

        def safe_intervals(poses, ptr, lo, hi):
            asked[name] = asked.get(name, 0) + len(poses)
            return plain(poses, ptr, lo, hi)

        f.safe_intervals = safe_intervals
        store.set_horizon(f, pool=True)
        return store

    after, afresh = IntervalStore(g), IntervalStore(g)
    after.prior = prior
    counted("after", after), counted("afresh", afresh)
    for node in range(len(g.poses) - 1, -1, -1):  # from the goal's side: several batches
        a, b = after.get(node), afresh.get(node)
        assert (list(a[0]), list(a[1]), a[2]) == (list(b[0]), list(b[1]), b[2]), node
    assert 0 < asked["after"] < 0.8 * asked["afresh"], asked  # the groups safe all through: not again
