"""The plan's stages after the library: which growth a query gets, and the oracle under a motion dispatch."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drd_planner.core.episode import TableOracle
from drd_planner.planner import load_prior
from drd_planner.planner.graph_stage import GraphStage, unwrapped_oracle
from drd_planner.planner.join_growth import JoinGrowth
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.query_graph import MotionDispatch

PRIOR = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"
START = np.array([212.0, 33.0, 60.0, 2.9])  # off the lattice: joined by motions


@pytest.fixture(scope="module")
def prior() -> WorldPrior:
    return load_prior(PRIOR)


def test_join_growth_is_only_for_queries_with_off_graph_states(prior: WorldPrior) -> None:
    planner = Planner(prior, snap_tolerance=1e-6)
    stage = planner._graph_stage()
    model = planner.query_model(0, int(prior.trees[0].goal))
    assert not model.query.connected
    assert stage.growth_kind(model) is None
    connected = planner.query_model(START, int(prior.trees[0].goal))
    assert stage.growth_kind(connected) is JoinGrowth
    assert isinstance(stage.growth_of(connected, JoinGrowth), JoinGrowth)
    planner.growth = None  # growth off: no kind, no growth
    off = planner._graph_stage()
    assert isinstance(off, GraphStage)
    assert off.growth_kind(connected) is None
    assert off.growth_of(connected, JoinGrowth) is None


def test_the_oracle_under_a_motion_dispatch_is_the_one_given(prior: WorldPrior) -> None:
    table = TableOracle(np.ones(prior.graph.num_edges, dtype=bool))
    assert unwrapped_oracle(table) is table
    assert unwrapped_oracle(MotionDispatch(table, {})) is table  # type: ignore[arg-type]
