"""Tests of building domains by name or factory, the per-process domain keeper and world-model params."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest
from test_dataset_builder import GRID_FACTORY, GridDomain

from drd_planner.data.domain_factory import DomainFactory, factory_for, make_domain, world_model_params
from drd_planner.domains.planar import PlanarDomain
from drd_planner.exceptions import DatasetError

SPEC = '{"block_probability": 0.25, "delay_s": 0.0, "size": 4}'


def test_make_domain_from_the_registry_and_from_a_factory() -> None:
    assert make_domain("planar", {"num_vertices": 30}).spec() == PlanarDomain(num_vertices=30).spec()
    rebuilt = make_domain("grid_test", GridDomain().spec(), factory=GRID_FACTORY)
    assert np.array_equal(rebuilt.graph.edges, GridDomain().graph.edges)
    with pytest.raises(DatasetError, match="builds domain 'grid_test', not 'other'"):
        make_domain("other", {}, factory=GRID_FACTORY)


def test_domain_factory_keeps_one_domain() -> None:
    factory = DomainFactory()
    first = factory.domain("grid_test", SPEC, GRID_FACTORY)
    assert factory.domain("grid_test", SPEC, GRID_FACTORY) is first
    other = factory.domain("grid_test", SPEC.replace('"size": 4', '"size": 5'), GRID_FACTORY)
    assert other is not first
    assert other.graph.num_vertices == 25
    assert factory.domain("grid_test", SPEC, GRID_FACTORY) is not first  # only the last one is kept


def test_factory_for() -> None:
    assert factory_for(PlanarDomain(), None, parallel=True) is None  # registered: workers use the registry
    assert factory_for(GridDomain(), None, parallel=True) == GRID_FACTORY.replace(
        "test_dataset_builder", GridDomain.__module__
    )
    assert factory_for(PlanarDomain(), "a.b:C", parallel=True) == "a.b:C"

    class Local(GridDomain):
        pass

    assert factory_for(Local(), None, parallel=False) is None
    with pytest.raises(DatasetError, match="worker processes cannot rebuild it"):
        factory_for(Local(), None, parallel=True)


@dataclasses.dataclass
class _Params:
    density: float
    sizes: np.ndarray


def test_world_model_params() -> None:
    assert world_model_params(GridDomain(), "uniform") == {"block_probability": 0.25}

    class WithDataclass(GridDomain):
        def world_model_params(self, model: str) -> Any:
            return _Params(0.5, np.array([1, 2]))

    assert world_model_params(WithDataclass(), "uniform") == {"density": 0.5, "sizes": [1, 2]}

    class WithObject(GridDomain):
        def world_model_params(self, model: str) -> Any:
            return {"f": object}

    assert set(world_model_params(WithObject(), "uniform")) == {"repr"}
