"""Query models from one prior: per-prior work done once, per-query work cached, BiSECt from the root at eta 1."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from conftest import REPO_ROOT

from drd_planner import prior_from_problem
from drd_planner.core.online_tree import LazyDirectTree
from drd_planner.core.root_tree import RootTree
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.planner import WorldPrior, load_prior
from drd_planner.planner.query_models import QueryModels
from drd_planner.planner.straight_connector import straight_connector


@pytest.fixture(scope="module")
def prior() -> WorldPrior:
    problem = make_planar_problem(model="forest", num_worlds=60, seed=5)
    return prior_from_problem(problem, domain="planar")


def test_per_prior_work_is_done_once_and_models_are_cached(prior: WorldPrior) -> None:
    models = QueryModels(dataclasses.replace(prior, eta=1.0), straight_connector(prior), expand_threshold=0.01)
    assert "edge_marginal" not in models.prior.__dict__
    models.warm_up()
    assert "edge_marginal" in models.prior.__dict__  # BiSECt's bias over the prior: no first query pays it
    search, columns = models.search, models.columns
    first = models.get(3, 40)
    assert models.search is search
    assert models.columns is columns
    assert isinstance(first.tree, RootTree)
    assert not first.reused
    again = models.get(3, 40)
    assert again.reused
    assert again.library is first.library
    assert models.cached_queries() == [(3, 40)]
    other_start = models.get(7, 40)  # the goal's trees are kept: only walked again
    assert other_start.library is not None


def test_a_switch_threshold_below_one_grows_a_direct_tree(prior: WorldPrior) -> None:
    models = QueryModels(dataclasses.replace(prior, eta=0.2), None, expand_threshold=0.01)
    model = models.get(3, 40)
    assert isinstance(model.tree, LazyDirectTree)
    models.drop_online()
    assert models.cached_queries() == []


def test_a_joined_query_keeps_the_priors_worlds_and_adds_only_its_columns(prior: WorldPrior) -> None:
    models = QueryModels(prior, straight_connector(prior), expand_threshold=0.01)
    states = prior.graph.vertex_states
    assert states is not None
    assert prior.worlds is not None
    start = (states[3] + states[4]) / 2 + 0.01
    model = models.get(np.asarray(start), 40)
    worlds = model.query.worlds
    assert model.query.connected
    assert worlds is not None
    assert worlds.base is prior.worlds
    assert worlds.num_edges == prior.graph.num_edges + len(model.query.motions)
    assert model.query.start_joins is not None
    assert model.query.goal_joins is None
    assert model.theta.shape == (worlds.num_edges,)
    expected = prior.alpha * worlds.dense.mean(axis=0) + (1 - prior.alpha) * 0.5
    assert np.allclose(model.theta, expected)


def test_warm_up_searches_the_stored_queries_goals() -> None:
    """A robot leaving the stored route asks for the stored goal's reverse trees first: made at configure."""
    shipped = load_prior(REPO_ROOT / "trees" / "heli_wires.npz")
    models = QueryModels(shipped, None, expand_threshold=0.01)
    assert models.search.goals_kept == ()
    models.warm_up()
    assert models.search.goals_kept == tuple(qt.goal for qt in shipped.trees) == (730,)
