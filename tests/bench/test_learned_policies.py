"""The learned LazySP selectors join the planner's policy registry when the bench package is imported."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.bench.lazysp_imitation import IMITATION_POLICY
from drd_planner.bench.lazysp_learned import LEARNED_LAZYSP_POLICIES
from drd_planner.bench.learned_policies import TRAIN_WORLD_POLICIES, register_learned_policies
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.library import PathLibrary
from drd_planner.core.policies import CORE_POLICIES, POLICIES, PolicyContext, graph_policies
from drd_planner.exceptions import ProblemError
from drd_planner.planner.planner import PLAN_POLICIES

LEARNED = {"lazysp_posterior", "lazysp_posterior_delta", "lazysp_imitation"}


def test_learned_selectors_are_registered_graph_policies_of_the_bench_only() -> None:
    assert {*LEARNED_LAZYSP_POLICIES, IMITATION_POLICY} == LEARNED == TRAIN_WORLD_POLICIES
    assert LEARNED <= set(POLICIES)
    assert LEARNED <= set(graph_policies())
    assert not LEARNED & set(CORE_POLICIES)
    assert not LEARNED & set(PLAN_POLICIES)


def test_registering_again_changes_nothing() -> None:
    before = dict(POLICIES)
    graph_before = graph_policies()
    register_learned_policies()
    assert dict(POLICIES) == before
    assert graph_policies() == graph_before


def test_imitation_needs_a_model_of_its_own_type() -> None:
    graph = ExplicitGraph(np.array([(0, 1)]), np.array([1.0]), 2)
    lib = PathLibrary.from_sequences([[0]], 1)
    ctx = PolicyContext(
        lib,
        np.ones(1),
        np.full(1, 0.5),
        None,
        seed=0,
        graph=graph,
        start=0,
        goal=1,
        train_worlds=np.ones((3, 1), dtype=bool),
        imitation_model="not a model",
    )
    with pytest.raises(ProblemError, match="imitation_model"):
        POLICIES[IMITATION_POLICY](ctx)
