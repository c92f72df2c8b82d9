"""Roadmap helpers: segment counts and the interior samples of straight joint-space edges."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.arm_roadmap import EdgeSamples, graph_states, segment_counts
from drd_planner.exceptions import ProblemError


def test_segment_counts_keep_every_joint_step_within_the_resolution() -> None:
    a = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]])
    b = np.array([[0.1, 0.0], [0.35, -0.1], [0.0, 0.0]])
    assert segment_counts(a, b, 0.1).tolist() == [1, 4, 1]


def test_edge_samples_are_interior_and_in_bisection_order() -> None:
    states = np.array([[0.0, 0.0], [0.4, 0.0], [0.4, 0.05]])
    graph = ExplicitGraph(np.array([[0, 1], [1, 2]]), np.array([0.4, 0.05]), 3, vertex_states=states)
    samples = EdgeSamples.of_graph(graph, 0.1)
    assert samples.offsets.tolist() == [0, 3, 3]
    assert samples.fractions[0] == pytest.approx(0.5)  # the middle first
    assert sorted(samples.fractions.tolist()) == pytest.approx([0.25, 0.5, 0.75])
    q = samples.configurations(graph, 0)
    assert q.shape == (3, 2) and np.all((q[:, 0] > 0) & (q[:, 0] < 0.4))
    with pytest.raises(ProblemError, match="resolution"):
        EdgeSamples.of_graph(graph, 0.0)
    with pytest.raises(ProblemError, match="vertex states"):
        graph_states(ExplicitGraph(np.array([[0, 1]]), np.array([1.0]), 2))
