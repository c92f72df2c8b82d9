"""The graph stage's edge probabilities and weights."""

from __future__ import annotations

import numpy as np

from drd_planner.core.graph import ExplicitGraph
from drd_planner.planner.graph_fallback import fallback_edge_weights, posterior_free_probability


def test_posterior_matches_a_brute_force_count() -> None:
    rng = np.random.default_rng(0)
    worlds = rng.random((60, 20)) < 0.6
    outcomes = {3: True, 7: False}
    theta = posterior_free_probability(worlds, None, outcomes, num_edges=20, alpha=1.0, pseudo_count=4.0)
    keep = worlds[:, 3] & ~worlds[:, 7]
    want = (worlds[keep].sum(axis=0) + 4.0 * worlds.mean(axis=0)) / (keep.sum() + 4.0)
    want[3], want[7] = 1.0, 0.0
    np.testing.assert_allclose(theta, want)
    weighted = posterior_free_probability(worlds, np.ones(60), outcomes, num_edges=20, alpha=1.0, pseudo_count=4.0)
    np.testing.assert_allclose(weighted, theta)
    # No world agrees with the outcome: only the (pseudo-counted) marginal remains.
    far = posterior_free_probability(
        worlds[:1], None, {1: not bool(worlds[0, 1])}, num_edges=20, alpha=1.0, pseudo_count=1.0
    )
    np.testing.assert_allclose(np.delete(far, 1), np.delete(worlds[0].astype(float), 1))


def test_weights_are_finite_and_prefer_likely_free_edges() -> None:
    graph = ExplicitGraph(np.array([[0, 1], [1, 2], [0, 2]]), np.array([1.0, 1.0, 1.0]), 3)
    weights = fallback_edge_weights(graph, np.array([0.9, 0.0, 0.1]))
    assert np.all(np.isfinite(weights))
    assert np.all(weights >= 0)
    assert weights[0] < weights[2]
    assert posterior_free_probability(None, None, {0: True}, num_edges=3, alpha=0.99, pseudo_count=1.0)[1] == 0.5
