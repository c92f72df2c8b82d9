"""Tests of the planar domain: RGG, exact segment/box checks, world models, self-generated problems."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.problem import Problem
from drd_planner.domains.planar import (
    WORLD_MODELS,
    edge_free_matrix,
    make_planar_problem,
    one_wall_patterns,
    random_geometric_graph,
    rgg_radius,
    sample_worlds,
    segments_hit_boxes,
)
from drd_planner.exceptions import ProblemError

BOX = np.array([[0.25, 0.25, 0.5, 0.5]])


def hit(p0: tuple[float, float], p1: tuple[float, float], boxes: np.ndarray = BOX) -> bool:
    """Whether one segment hits any of the boxes."""
    return bool(segments_hit_boxes(np.array([p0]), np.array([p1]), boxes).any())


# --------------------------------------------------------------------------------------------------
# Segment / box


@pytest.mark.parametrize(
    ("p0", "p1", "expected"),
    [
        ((0.0, 0.375), (1.0, 0.375), True),  # straight through, horizontal
        ((0.375, 0.0), (0.375, 1.0), True),  # straight through, vertical (dx = 0)
        ((0.0, 0.0), (1.0, 1.0), True),  # diagonal, endpoints outside, box between
        ((1.0, 0.0), (0.0, 1.0), True),  # touches the far corner (0.5, 0.5) only
        ((0.0, 0.5), (0.5, 0.0), True),  # touches the corner (0.25, 0.25) only: closed box
        ((0.0, 0.49), (0.49, 0.0), False),  # just below that corner
        ((0.0, 0.5), (1.0, 0.5), True),  # slides along the top side
        ((0.3, 0.3), (0.4, 0.45), True),  # fully inside
        ((0.3, 0.3), (0.9, 0.9), True),  # starts inside
        ((0.0, 0.6), (1.0, 0.6), False),  # parallel miss above
        ((0.2, 0.0), (0.2, 1.0), False),  # parallel miss left
        ((0.0, 0.375), (0.2, 0.375), False),  # heads for the box but stops short
        ((0.6, 0.375), (0.9, 0.375), False),  # on the box's line, beyond it
        ((0.0, 0.75), (0.75, 0.0), True),  # crosses the box near its lower-right part
        ((0.0, 0.2), (0.2, 0.0), False),  # diagonal far below-left
        ((0.3, 0.3), (0.3, 0.3), True),  # degenerate: point inside
        ((0.1, 0.3), (0.1, 0.3), False),  # degenerate: point outside
    ],
)
def test_segment_box_hand_placed(p0: tuple[float, float], p1: tuple[float, float], expected: bool) -> None:
    assert hit(p0, p1) is expected
    assert hit(p1, p0) is expected  # direction does not matter


def test_segment_box_shapes_and_multiple_boxes() -> None:
    boxes = np.array([[0.25, 0.25, 0.5, 0.5], [0.7, 0.0, 0.8, 0.1]])
    p0 = np.array([[0.0, 0.375], [0.6, 0.05], [0.0, 0.9]])
    p1 = np.array([[1.0, 0.375], [0.9, 0.05], [1.0, 0.9]])
    out = segments_hit_boxes(p0, p1, boxes)
    assert out.shape == (3, 2) and out.dtype == bool
    assert out.tolist() == [[True, False], [False, True], [False, False]]
    assert segments_hit_boxes(p0, p1, np.zeros((0, 4))).shape == (3, 0)
    with pytest.raises(ProblemError):
        segments_hit_boxes(p0, p1, np.array([[0.5, 0.5, 0.4, 0.6]]))  # xmax < xmin


def test_segment_box_against_dense_sampling() -> None:
    rng = np.random.default_rng(123)
    num_seg, num_box, samples = 400, 30, 4001
    p0 = rng.random((num_seg, 2))
    p1 = rng.random((num_seg, 2))
    lo = rng.random((num_box, 2)) * 0.8
    boxes = np.concatenate([lo, lo + 0.02 + 0.2 * rng.random((num_box, 2))], axis=1)
    exact = segments_hit_boxes(p0, p1, boxes)
    t = np.linspace(0.0, 1.0, samples)
    pts = p0[:, None, :] + t[None, :, None] * (p1 - p0)[:, None, :]  # (S, samples, 2)
    step = np.linalg.norm(p1 - p0, axis=1) / (samples - 1)  # (S,)

    def sampled(margin: np.ndarray) -> np.ndarray:
        m = margin[:, None, None]
        x, y = pts[..., 0][..., None], pts[..., 1][..., None]
        inside = (
            (x >= boxes[:, 0] - m) & (x <= boxes[:, 2] + m) & (y >= boxes[:, 1] - m) & (y <= boxes[:, 3] + m)
        )
        return np.asarray(inside.any(axis=1))

    plain = sampled(np.zeros(num_seg))
    grown = sampled(step)
    assert not (plain & ~exact).any()  # a sampled point inside a box is a real hit
    assert not (exact & ~grown).any()  # a real hit is within one sample step of a sample
    assert (plain == exact).mean() > 0.995
    assert 0.1 < exact.mean() < 0.9  # the random cases exercise both answers


# --------------------------------------------------------------------------------------------------
# Random geometric graph


def test_rgg_radius_matches_the_released_graphs() -> None:
    assert rgg_radius(100) == pytest.approx(0.2966, abs=1e-4)
    assert rgg_radius(150) == pytest.approx(0.2525, abs=1e-4)
    assert rgg_radius(200) == pytest.approx(0.2249, abs=1e-4)
    assert rgg_radius(100, eta=2.0) == pytest.approx(2 * rgg_radius(100))


def test_rgg_edges_are_exactly_the_close_pairs() -> None:
    n = 120
    g, start, goal = random_geometric_graph(n, seed=7)
    pts = g.vertex_states
    assert pts is not None and pts.shape == (n, 2)
    assert ((pts >= 0) & (pts <= 1)).all()
    r = rgg_radius(n)
    dist = np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=2)
    iu, ju = np.triu_indices(n, k=1)
    close = dist[iu, ju] <= r
    expected = {(int(a), int(b)) for a, b in zip(iu[close], ju[close], strict=True)}
    got = [(int(a), int(b)) for a, b in g.edges]
    assert len(got) == len(set(got)) == len(expected)
    assert set(got) == expected
    assert all(u < v for u, v in got)
    assert got == sorted(got)
    assert np.allclose(g.lengths, dist[g.edges[:, 0], g.edges[:, 1]])
    assert not g.directed
    for eid, (u, v) in enumerate(got[:50]):
        assert g.edge_id(u, v) == g.edge_id(v, u) == eid  # symmetric lookup
    assert start == int(np.argmin(np.linalg.norm(pts, axis=1)))
    assert goal == int(np.argmin(np.linalg.norm(pts - 1, axis=1)))
    assert np.linalg.norm(pts[start]) < 0.3 and np.linalg.norm(pts[goal] - 1) < 0.3


def test_rgg_determinism_and_disconnection() -> None:
    a, sa, ga = random_geometric_graph(80, seed=1)
    b, sb, gb = random_geometric_graph(80, seed=1)
    c, _, _ = random_geometric_graph(80, seed=2)
    assert a.vertex_states is not None and b.vertex_states is not None and c.vertex_states is not None
    assert np.array_equal(a.edges, b.edges) and np.array_equal(a.vertex_states, b.vertex_states)
    assert (sa, ga) == (sb, gb)
    assert not np.array_equal(a.vertex_states, c.vertex_states)
    with pytest.raises(ProblemError, match="raise num_vertices or eta"):
        random_geometric_graph(60, seed=0, eta=0.2)
    with pytest.raises(ProblemError):
        random_geometric_graph(1, seed=0)


# --------------------------------------------------------------------------------------------------
# Edge outcomes


def test_edge_free_matrix_hand_graph() -> None:
    states = np.array([[0.1, 0.1], [0.9, 0.1], [0.1, 0.9], [0.9, 0.9], [0.5, 0.5]])
    edges = np.array([[0, 1], [0, 2], [1, 3], [2, 3], [0, 3], [4, 1]])
    lengths = np.linalg.norm(states[edges[:, 1]] - states[edges[:, 0]], axis=1)
    g = ExplicitGraph(edges, lengths, 5, vertex_states=states)
    worlds = [
        np.zeros((0, 4)),  # empty world: all free
        np.array([[0.4, 0.4, 0.6, 0.6]]),  # centre box: blocks the diagonal and vertex 4's edge
        np.array([[0.0, 0.0, 0.2, 0.2]]),  # covers vertex 0: its three edges are blocked
        np.array([[0.45, 0.0, 0.55, 0.1]]),  # touches the bottom edge (y = 0.1) from below
    ]
    x = edge_free_matrix(g, worlds)
    assert x.shape == (4, 6) and x.dtype == bool
    assert x.tolist() == [
        [True, True, True, True, True, True],
        [True, True, True, True, False, False],
        [False, False, True, True, False, True],
        [False, True, True, True, True, True],
    ]


def test_edge_free_matrix_matches_per_world_segment_test() -> None:
    g, _, _ = random_geometric_graph(60, seed=3)
    worlds = sample_worlds("forest", 5, seed=9)
    x = edge_free_matrix(g, worlds)
    assert g.vertex_states is not None
    p0, p1 = g.vertex_states[g.edges[:, 0]], g.vertex_states[g.edges[:, 1]]
    for h, boxes in enumerate(worlds):
        for e in range(0, g.num_edges, 7):
            assert x[h, e] == (not hit(tuple(p0[e]), tuple(p1[e]), boxes))
    assert 0.2 < x.mean() < 0.99
    with pytest.raises(ProblemError, match="vertex coordinates"):
        edge_free_matrix(ExplicitGraph(g.edges, g.lengths, g.num_vertices), worlds)


# --------------------------------------------------------------------------------------------------
# World models


@pytest.mark.parametrize("model", WORLD_MODELS)
def test_world_models_are_seeded_boxes(model: str) -> None:
    a = sample_worlds(model, 30, seed=4)
    b = sample_worlds(model, 30, seed=4)
    c = sample_worlds(model, 30, seed=5)
    assert len(a) == 30
    for w in a:
        assert w.ndim == 2 and w.shape[1] == 4 and w.dtype == np.float64
        assert (w[:, 2] > w[:, 0]).all() and (w[:, 3] > w[:, 1]).all()
    assert all(np.array_equal(u, v) for u, v in zip(a, b, strict=True))
    assert not all(u.shape == v.shape and np.array_equal(u, v) for u, v in zip(a, c, strict=True))


def _squares_of(w: np.ndarray) -> np.ndarray:
    """The 0.1 x 0.1 squares among a world's boxes."""
    side = np.stack([w[:, 2] - w[:, 0], w[:, 3] - w[:, 1]], axis=1)
    return np.asarray(w[np.isclose(side, 0.1).all(axis=1)])


def test_one_wall_structure() -> None:
    patterns = one_wall_patterns(17)
    assert 1 <= patterns.shape[0] <= 15 and patterns.shape[1] == 5
    assert (patterns.sum(axis=1) >= 2).all()
    worlds = sample_worlds("one_wall", 300, seed=8)
    ys = np.linspace(0.0005, 0.9995, 1000)
    seen_patterns = set()
    counts = []
    for w in worlds:
        wall = w[np.isclose(w[:, 0], 0.4) & np.isclose(w[:, 2], 0.6)]
        squares = _squares_of(w)
        assert len(wall) + len(squares) == len(w)
        counts.append(len(squares))
        blocked = np.asarray(((ys[:, None] >= wall[:, 1]) & (ys[:, None] <= wall[:, 3])).any(axis=1))
        open_len = (~blocked).mean()
        num_open = round(open_len / 0.1)
        assert 2 <= num_open <= 5
        assert open_len == pytest.approx(0.1 * num_open, abs=0.003)
        slot_mids = (np.arange(5) + 1) / 12 + np.arange(5) * 0.1 + 0.05
        seen_patterns.add(tuple((~blocked[np.searchsorted(ys, slot_mids)]).tolist()))
    assert 2 <= len(seen_patterns) <= 15
    assert np.mean(counts) == pytest.approx(8.0, abs=0.6)  # Poisson(8) forest


def test_forest_and_moving_wall_structure() -> None:
    extra = []
    for w in sample_worlds("forest", 300, seed=2):
        assert (np.isclose(w[:, 2] - w[:, 0], 0.1) & np.isclose(w[:, 3] - w[:, 1], 0.1)).all()
        centres = (w[:, :2] + w[:, 2:]) / 2
        assert ((centres >= 0.075 - 1e-12) & (centres <= 0.925 + 1e-12)).all()
        assert len(w) >= 12
        extra.append(len(w) - 12)
    assert np.mean(extra) == pytest.approx(4.0, abs=0.4)  # Poisson(4) uniform squares
    for w in sample_worlds("moving_wall", 100, seed=2):
        assert w.shape == (2, 4)
        assert np.allclose(w[:, 2] - w[:, 0], 0.15)
        xc = (w[0, 0] + w[0, 2]) / 2
        assert 0.2 <= xc <= 0.8
        assert w[0, 1] == 0.0 and w[1, 3] == 1.0
        assert w[1, 1] - w[0, 3] == pytest.approx(0.1)
        assert 0.2 <= (w[1, 1] + w[0, 3]) / 2 <= 0.8


def test_keep_clear_and_bad_model() -> None:
    points = np.array([[0.3, 0.3], [0.5, 0.5], [0.05, 0.05]])
    for model in ("one_wall", "forest"):
        for w in sample_worlds(model, 100, seed=6, keep_clear=points):
            sq = _squares_of(w)
            covered = (points[:, None, 0] >= sq[:, 0]) & (points[:, None, 0] <= sq[:, 2])
            covered &= (points[:, None, 1] >= sq[:, 1]) & (points[:, None, 1] <= sq[:, 3])
            assert not covered.any()
    with pytest.raises(ProblemError, match="unknown planar world model"):
        sample_worlds("two_wall", 3, seed=0)


# --------------------------------------------------------------------------------------------------
# Problems


def small(seed: int = 0, model: str = "one_wall") -> Problem:
    """A small self-generated problem."""
    return make_planar_problem(num_vertices=60, model=model, num_worlds=40, max_paths=30, seed=seed)


def test_make_planar_problem_defaults() -> None:
    p = make_planar_problem()
    w = p.require_worlds()
    assert p.graph is not None and p.graph.num_vertices == 100
    assert w.X.shape == (300, p.graph.num_edges)
    assert p.num_paths == 100 and w.R.shape == (300, 100)
    assert w.test_ids.size == 30 and w.train_ids.size == 270
    assert p.metadata["domain"] == "planar" and p.metadata["world_model"] == "one_wall"
    assert p.metadata["seed"] == 0


@pytest.mark.parametrize("model", WORLD_MODELS)
def test_make_planar_problem_is_consistent(model: str) -> None:
    p = small(model=model)
    w = p.require_worlds()
    assert p.graph is not None and p.start is not None and p.goal is not None
    g, s, t = random_geometric_graph(60, seed=0)
    assert np.array_equal(p.graph.edges, g.edges) and (p.start, p.goal) == (s, t)
    assert np.array_equal(w.R, p.library.valid_paths(w.X))
    assert w.R[w.test_ids].any(axis=1).all()
    assert np.array_equal(np.union1d(w.train_ids, w.test_ids), np.arange(40))
    assert w.test_ids.size == 4
    assert np.array_equal(p.edge_costs, np.ones(p.num_edges))
    assert p.metadata["world_model"] == model and p.metadata["domain"] == "planar"
    assert w.R.any(axis=0).all()


def test_make_planar_problem_determinism() -> None:
    a, b, c = small(seed=3), small(seed=3), small(seed=4)
    wa, wb, wc = a.require_worlds(), b.require_worlds(), c.require_worlds()
    assert np.array_equal(wa.X, wb.X) and np.array_equal(wa.R, wb.R)
    assert np.array_equal(wa.train_ids, wb.train_ids) and np.array_equal(wa.test_ids, wb.test_ids)
    assert all(np.array_equal(u, v) for u, v in zip(a.library.path_edges, b.library.path_edges, strict=True))
    assert a.metadata == b.metadata
    assert wa.X.shape != wc.X.shape or not np.array_equal(wa.X, wc.X)
    assert a.graph is not None and c.graph is not None
    assert a.graph.vertex_states is not None and c.graph.vertex_states is not None
    assert not np.array_equal(a.graph.vertex_states, c.graph.vertex_states)
