"""Tests of the worker side of a dataset build (on the exact grid domain of test_dataset_builder)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from test_dataset_builder import GRID_FACTORY, GridDomain, grid_x

from drd_planner.data.dataset_chunks import ChunkTask
from drd_planner.data.dataset_worker import PROCESS_DOMAINS, check_all_edges, evaluate_chunk, graph_digest
from drd_planner.data.seeding import world_seeds
from drd_planner.exceptions import DatasetError


def test_evaluate_chunk_matches_direct_checks() -> None:
    domain = GridDomain()
    seeds = world_seeds(3, 5)
    task = ChunkTask(
        index=0,
        first=0,
        seeds=tuple(int(s) for s in seeds),
        domain="grid_test",
        spec_json='{"block_probability": 0.25, "delay_s": 0.0, "size": 4}',
        factory=GRID_FACTORY,
        world_model="uniform",
        k=5,
    )
    result = evaluate_chunk(task)
    x = np.unpackbits(result.x_packed, axis=1, count=domain.graph.num_edges).astype(bool)
    assert np.array_equal(x, grid_x(domain, "uniform", seeds))
    for edges, verts in result.paths():
        assert verts[0] == domain.start
        assert verts[-1] == domain.goal
        assert list(domain.graph.vertex_path_to_edges(verts)) == list(edges)


def test_the_process_keeps_the_domain_it_was_given() -> None:
    domain = GridDomain()
    spec_json = '{"block_probability": 0.25, "delay_s": 0.0, "size": 4}'
    PROCESS_DOMAINS.remember(domain, spec_json, GRID_FACTORY)
    assert PROCESS_DOMAINS.domain("grid_test", spec_json, GRID_FACTORY) is domain


def test_graph_digest_tells_graphs_apart() -> None:
    a, b = GridDomain(), GridDomain(size=5)
    assert graph_digest(a.graph) == graph_digest(GridDomain().graph) != graph_digest(b.graph)


def test_a_checker_with_the_wrong_shape_is_refused() -> None:
    class Short:
        def check_many(self, edges: Any) -> np.ndarray:
            return np.ones(3, dtype=bool)

    class Broken(GridDomain):
        def checker(self, world: Any) -> Any:  # type: ignore[override]
            return Short()

    with pytest.raises(DatasetError, match="check_many returned bool"):
        check_all_edges(Broken(), "uniform", (1, 2))
