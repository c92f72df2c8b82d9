"""One policy on one query at a check cost, on the shipped helicopter prior: vertex and off-graph queries."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drd_planner.bench.cost_episodes import (
    CostQuery,
    check_all_episode,
    full_row,
    lazysp_episode,
    plan_episode,
)
from drd_planner.domains.base import domain_from_spec
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.prior_file import load_prior

PRIOR = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"


@pytest.fixture(scope="module")
def setup() -> tuple[WorldPrior, Planner, object]:
    prior = load_prior(PRIOR)
    domain = domain_from_spec(prior.domain, prior.domain_spec)
    return prior, Planner(prior, snap_tolerance=1e-6), (domain, domain.make_world("wires", 3))


def _off_graph(prior: WorldPrior) -> CostQuery:
    states = prior.graph.vertex_states
    assert states is not None
    start = np.array([40.0, 17.0, 66.0, 0.2])  # between lattice points, levels and headings
    goal = np.array([655.0, -21.0, 64.0, 0.1])
    assert np.min(np.linalg.norm(states - start, axis=1)) > 1.0
    assert np.min(np.linalg.norm(states - goal, axis=1)) > 1.0
    return CostQuery("off_graph", start, goal, 0)


def test_each_policy_pays_the_cost_per_check_and_verifies(setup: tuple[WorldPrior, Planner, object]) -> None:
    prior, planner, (domain, world) = setup  # type: ignore[misc]
    stored = CostQuery("stored", prior.trees[0].start, prior.trees[0].goal, 0)
    for policy in ("direct_bisect", "bisect"):
        first = plan_episode(planner, stored, 0, domain.checker(world), 0.0, policy, 0)
        costly = plan_episode(planner, stored, 0, domain.checker(world), 2.0, policy, 0)
        assert first.checks == costly.checks  # same seed, same checks
        assert costly.time.cpu_ms >= 2.0 * costly.checks
    lazy = lazysp_episode(planner, stored, 0, domain.checker(world), 2.0)
    assert lazy.time.cpu_ms >= 2.0 * lazy.checks
    assert lazy.checks > 0


def test_off_graph_paths_start_at_the_state(setup: tuple[WorldPrior, Planner, object]) -> None:
    prior, planner, (domain, world) = setup  # type: ignore[misc]
    query = _off_graph(prior)
    graph = planner.query_graph(query.start, query.goal)
    assert graph.start >= prior.graph.num_vertices
    assert graph.goal >= prior.graph.num_vertices
    assert np.allclose(graph.new_states[graph.start], query.start)
    result = planner.plan(query.start, query.goal, domain.checker(world))
    if result.found:
        assert result.vertices[0] == result.start
        assert np.allclose(result.new_states[result.start], query.start)
    episode = plan_episode(planner, query, 1, domain.checker(world), 1.0, "direct_bisect", 0)
    assert episode.verified == result.found
    assert episode.time.cpu_ms >= 1.0 * episode.checks
    row = full_row(domain.checker(world), prior.graph.num_edges)
    every = check_all_episode(planner, query, 1, domain.checker(world), 1.0, row)
    assert every.checks == graph.graph.num_edges
    assert every.time.cpu_ms >= 1.0 * prior.graph.num_edges
    assert every.verified == result.found  # the planner finds a path exactly when one is free
