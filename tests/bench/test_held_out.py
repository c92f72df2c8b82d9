"""Held-out worlds and random queries on the shipped helicopter prior: free where they say they are."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from drd_planner.bench.held_out import WORLD_MODELS, held_out_worlds, new_queries, off_graph_queries
from drd_planner.core.lazysp import GraphArcs
from drd_planner.domains.base import domain_from_spec
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.prior_file import load_prior
from drd_planner.planner.query_library import ShortestPaths

PRIOR = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"


@pytest.fixture(scope="module")
def worlds() -> tuple[WorldPrior, Any, list[Any], dict[int, Any], list[Any]]:
    prior = load_prior(PRIOR)
    domain = domain_from_spec(prior.domain, prior.domain_spec)
    recipes, found, rows = held_out_worlds(domain, prior, WORLD_MODELS["heli_wires"], 2, 500)
    return prior, domain, found, rows, recipes


def test_held_out_worlds_free_the_stored_query(worlds: tuple[Any, ...]) -> None:
    prior, _, found, rows, recipes = worlds
    assert len(found) == len(recipes) == len(rows) == 2
    seeds = [r.seed for r in recipes]
    assert seeds == sorted(set(seeds))
    assert seeds[0] >= 500
    assert all(r.model == "wires" for r in recipes)
    paths = ShortestPaths(GraphArcs(prior.graph), prior.graph.lengths)
    stored = prior.trees[0]
    for row in rows.values():
        assert row.outcomes.shape == (prior.graph.num_edges,)
        assert paths.path(stored.start, stored.goal, row.outcomes) is not None


def test_new_queries_are_free_vertex_pairs(worlds: tuple[Any, ...]) -> None:
    prior, _, _, rows, _ = worlds
    queries = new_queries(prior, rows, 3, np.random.default_rng(0))
    assert len(queries) == 3
    paths = ShortestPaths(GraphArcs(prior.graph), prior.graph.lengths)
    for k, q in enumerate(queries):
        assert q.kind == "new"
        assert q.world == k % len(rows)
        assert q.start != q.goal
        assert paths.path(q.start, q.goal, rows[q.world].outcomes) is not None
    again = new_queries(prior, rows, 3, np.random.default_rng(0))
    assert [(q.start, q.goal) for q in again] == [(q.start, q.goal) for q in queries]


def test_off_graph_queries_are_states_inside_the_graphs_box(worlds: tuple[Any, ...]) -> None:
    prior, domain, found, rows, _ = worlds
    planner = Planner(prior, snap_tolerance=1e-6)
    (query,) = off_graph_queries(planner, domain, found, rows, 1, np.random.default_rng(1))
    states = prior.graph.vertex_states
    assert query.kind == "off_graph"
    assert query.world == 0
    for end in (query.start, query.goal):
        end = np.asarray(end)
        assert end.shape == (states.shape[1],)
        assert np.all(end >= states.min(axis=0))
        assert np.all(end <= states.max(axis=0))
