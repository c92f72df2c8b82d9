"""Why a plan failed, as a value: the causes by end, and the refusals that carry one."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drd_planner import Planner, PlanStatus
from drd_planner.domains.base import domain_from_spec
from drd_planner.planner import load_prior
from drd_planner.planner.cause import PlanCause
from drd_planner.planner.endpoints import QueryError

HELI_WIRES = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"


def test_causes_by_end() -> None:
    assert PlanCause.outside("start") is PlanCause.START_OUTSIDE
    assert PlanCause.outside("goal") is PlanCause.GOAL_OUTSIDE
    assert PlanCause.blocked("start") is PlanCause.START_BLOCKED
    assert PlanCause.blocked("goal") is PlanCause.GOAL_BLOCKED
    assert QueryError("why").cause is None
    assert QueryError("why", cause=PlanCause.GOAL_OUTSIDE).cause is PlanCause.GOAL_OUTSIDE


def test_a_state_outside_the_lattice_is_refused_with_its_end_as_the_cause() -> None:
    prior = load_prior(HELI_WIRES)
    planner = Planner(prior)
    domain = domain_from_spec(prior.domain, prior.domain_spec)
    oracle = domain.checker(domain.make_world("wires", 0))  # checks motions: off-graph states are joined
    states = prior.graph.vertex_states
    assert states is not None
    far = states[0] + np.array([1e5, 0.0, 0.0, 0.0])  # 100 km away
    start = planner.plan(far, 1, oracle)
    assert start.status is PlanStatus.REFUSED
    assert start.cause is PlanCause.START_OUTSIDE
    goal = planner.plan(0, far, oracle)
    assert goal.status is PlanStatus.REFUSED
    assert goal.cause is PlanCause.GOAL_OUTSIDE
    malformed = planner.plan(0, np.array([np.nan, 0.0, 0.0, 0.0]), oracle)
    assert malformed.status is PlanStatus.REFUSED
    assert malformed.cause is None
    planned = planner.plan(prior.trees[0].start, prior.trees[0].goal, oracle)
    assert planned.status in (PlanStatus.FOUND, PlanStatus.NO_PATH)
    assert planned.status is not PlanStatus.FOUND or planned.cause is None
