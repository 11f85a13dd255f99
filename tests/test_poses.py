"""gfuzzy.poses: the one implementation of pose arithmetic, against hand-computed values."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from gfuzzy.poses import (
    arc_length,
    discretise,
    interpolate_segment,
    metric_distance,
    pose_at,
    row_words,
    split_counts,
    wrap_angle,
)


def test_wrap_angle_range_and_values():
    a = np.array([0.0, math.pi, -math.pi, 3 * math.pi / 2, -7.0])
    w = wrap_angle(a)
    assert np.all(w >= -math.pi) and np.all(w < math.pi)
    assert w[1] == pytest.approx(-math.pi) and w[3] == pytest.approx(-math.pi / 2)
    assert w[4] == pytest.approx(-7.0 + 2 * math.pi)


def test_metric_counts_the_shorter_turn():
    a, b = np.array([0.0, 0.0, 3.0]), np.array([3.0, 4.0, -3.0])
    # xy 5, turn 2*pi - 6 the short way, weighted by the circumradius 2
    assert metric_distance(a, b, 2.0) == pytest.approx(5.0 + 2.0 * (2 * math.pi - 6.0))


def test_interpolate_segment_rows_and_single_motion_agree():
    a, b = np.array([0.0, 0.0, 3.0]), np.array([2.0, 0.0, -3.0])
    f = np.array([0.0, 0.5, 1.0])
    one = interpolate_segment(a, b, f)
    many = interpolate_segment(np.tile(a, (3, 1)), np.tile(b, (3, 1)), f)
    np.testing.assert_array_equal(one, many)
    assert one[1, 0] == 1.0 and abs(abs(one[1, 2]) - math.pi) < 1e-12  # through pi, not through 0


def test_pose_at_by_time_and_by_arc_length():
    path = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]])
    s = arc_length(path)
    np.testing.assert_allclose(s, [0.0, 3.0, 7.0])
    np.testing.assert_allclose(pose_at(s, path, np.array([1.5, 5.0])), [[1.5, 0.0], [3.0, 2.0]])
    # a repeated pose (zero-length piece) gives its first pose, never a division by zero
    rep = np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 0.0]])
    np.testing.assert_allclose(pose_at(arc_length(rep), rep, np.array([0.0, 0.5])), [[0.0, 0.0], [0.5, 0.0]])


@pytest.mark.parametrize("length, step, k", [(1.0, 0.25, 4), (1.0, 0.3, 4), (0.1, 1.0, 1), (0.0, 1.0, 1)])
def test_split_counts_hand_values(length, step, k):
    assert split_counts(np.array([length]), step)[0] == k


def test_split_counts_adds_one_when_rounding_leaves_a_long_piece():
    # 0.9000000000000001 / 0.1 rounds to exactly 9.0, yet a ninth of it exceeds 0.1
    length, step = 0.9000000000000001, 0.1
    assert math.ceil(length / step) == 9 and length / 9 > step
    k = split_counts(np.array([length]), step)[0]
    assert k == 10 and length / k <= step


def test_discretise_keeps_corners_and_bounds_the_step():
    path = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, math.pi / 2], [1.0, 1.0, math.pi / 2]])
    poses, s = discretise(path, 0.5, 0.3)
    steps = metric_distance(poses[:-1], poses[1:], 0.5)
    assert np.all(steps <= 0.3 + 1e-12) and np.all(np.diff(s) > 0)
    for corner in path[:3]:  # every corner is a point of the chain
        assert np.min(np.abs(poses - corner).sum(axis=1)) < 1e-12
    np.testing.assert_allclose(poses[-1], path[-1])


def test_the_space_time_graph_cuts_edges_by_the_same_rule():
    """spacetime.split_edges (the planner's and prepared's graph) uses split_counts and
    interpolate_segment: every one-step move is at most one step long, headings wrapped."""
    from gfuzzy.timespace.spacetime import split_edges

    rng = np.random.default_rng(3)
    verts = np.column_stack([rng.uniform(0, 5, 12), rng.uniform(0, 5, 12), rng.uniform(-math.pi, math.pi, 12)])
    edges = np.array([(i, (i * 5 + 3) % 12) for i in range(12) if i != (i * 5 + 3) % 12], dtype=np.int64)
    r, step = 0.3, 0.25
    lengths = metric_distance(verts[edges[:, 0]], verts[edges[:, 1]], r)
    cut = split_edges(verts, edges, lengths, step, len(verts))
    k, offs, inner, src, dst = cut.k, cut.offs, cut.inner, cut.src, cut.dst
    assert np.array_equal(k, split_counts(lengths, step))
    assert np.array_equal(np.diff(offs), k - 1)
    want = np.vstack([interpolate_segment(verts[e0], verts[e1], np.arange(1, n) / n)
                      for (e0, e1), n in zip(edges, k, strict=True) if n > 1])  # fmt: skip
    assert np.array_equal(inner, want)
    assert np.all((inner[:, 2] >= -math.pi) & (inner[:, 2] < math.pi))
    poses = np.vstack([verts, inner])
    moves = metric_distance(poses[src], poses[dst], r)
    assert len(src) == int(k.sum()) and np.all(moves <= step * (1 + 1e-12))


def test_a_leading_cut_takes_whole_steps_from_one_end():
    """split_edges(lead=): the same steps per edge, every move at most a step, but whole
    steps from the first end (1) or up to the second (-1), the remainder at the other."""
    from gfuzzy.timespace.spacetime import split_edges

    verts = np.array([[0.0, 0.0], [0.73, 0.0], [0.0, 0.35], [0.2, 0.0]])
    edges = np.array([(0, 1), (0, 2), (2, 1), (0, 3)], dtype=np.int64)
    step = 0.25
    lengths = metric_distance(verts[edges[:, 0]], verts[edges[:, 1]], 0.3)
    equal = split_edges(verts, edges, lengths, step, len(verts))
    cut = split_edges(verts, edges, lengths, step, len(verts), lead=np.array([1, -1, 0, 1]))
    for name in ("k", "offs", "a", "b", "j", "src", "dst"):
        assert np.array_equal(getattr(cut, name), getattr(equal, name))
    np.testing.assert_allclose(cut.inner[:2], [[0.25, 0.0], [0.5, 0.0]])  # 0.73 m: 0.25, 0.25, 0.23
    np.testing.assert_allclose(cut.inner[2], [0.0, 0.1])  # 0.35 m: 0.1, then 0.25 up to vertex 2
    assert np.array_equal(cut.inner[3:], equal.inner[3:])  # equal pieces where lead is 0
    poses = np.vstack([verts, cut.inner])
    assert np.all(metric_distance(poses[cut.src], poses[cut.dst], 0.3) <= step * (1 + 1e-12))


def test_a_leading_cut_leaves_no_hair_of_a_step():
    """An edge a hair (1e-10 m) over two whole steps keeps equal pieces: whole steps would
    leave a last piece of 1e-10 m, a step the robot stands in."""
    from gfuzzy.timespace.spacetime import leading_fractions

    k, j = np.array([3, 3]), np.array([1, 2])
    hair = np.full(2, 0.5 + 1e-10)
    np.testing.assert_allclose(leading_fractions(j / k, j, k, hair, 0.25, np.ones(2)), j / k)
    some = np.full(2, 0.52)  # a real remainder: whole steps from the first end
    np.testing.assert_allclose(leading_fractions(j / k, j, k, some, 0.25, np.ones(2)), j * 0.25 / 0.52)


def test_row_words_put_the_time_before_the_pose_words():
    robot = SimpleNamespace(shape="disc", kinematics="unicycle")
    assert row_words(3, robot) == "[t, x, y, heading] for this disc robot (unicycle)"
    assert row_words(2) == "[t, x, y] for a disc robot"
