"""Tests of the in-memory planar problem: its contents, determinism, and the dataset pipeline's seeding."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drd_planner.core.problem import Problem
from drd_planner.data.dataset_builder import build_dataset
from drd_planner.data.dataset_file import load_dataset
from drd_planner.data.planar_problem import make_planar_problem, planar_problem_worlds, planar_recipe
from drd_planner.data.seeding import library_seed, split_seed, world_seeds
from drd_planner.domains.planar import WORLD_MODELS, PlanarDomain, edge_free_matrix, random_geometric_graph
from drd_planner.exceptions import ProblemError


def small(seed: int = 0, model: str = "one_wall") -> Problem:
    """A small self-generated problem."""
    return make_planar_problem(num_vertices=60, model=model, num_worlds=40, max_paths=30, seed=seed)


def test_make_planar_problem_defaults() -> None:
    p = make_planar_problem()
    w = p.require_worlds()
    assert p.graph is not None
    assert p.graph.num_vertices == 100
    assert w.X.shape == (300, p.graph.num_edges)
    assert p.num_paths == 100
    assert w.R.shape == (300, 100)
    assert w.test_ids.size == 30
    assert w.train_ids.size == 270
    assert p.metadata["domain"] == "planar"
    assert p.metadata["world_model"] == "one_wall"
    assert p.metadata["seed"] == 0


@pytest.mark.parametrize("model", WORLD_MODELS)
def test_make_planar_problem_is_consistent(model: str) -> None:
    p = small(model=model)
    w = p.require_worlds()
    assert p.graph is not None
    assert p.start is not None
    assert p.goal is not None
    g, s, t = random_geometric_graph(60, seed=0)
    assert np.array_equal(p.graph.edges, g.edges)
    assert (p.start, p.goal) == (s, t)
    assert np.array_equal(w.R, p.library.valid_paths(w.X))
    assert w.R[w.test_ids].any(axis=1).all()
    assert np.array_equal(np.union1d(w.train_ids, w.test_ids), np.arange(40))
    assert w.test_ids.size == min(4, int(w.R.any(axis=1).sum()))  # held out among solvable worlds
    assert np.array_equal(p.edge_costs, np.ones(p.num_edges))
    assert p.metadata["world_model"] == model
    assert p.metadata["domain"] == "planar"
    assert w.R.any(axis=0).all()


def test_make_planar_problem_determinism() -> None:
    a, b, c = small(seed=3), small(seed=3), small(seed=4)
    wa, wb, wc = a.require_worlds(), b.require_worlds(), c.require_worlds()
    assert np.array_equal(wa.X, wb.X)
    assert np.array_equal(wa.R, wb.R)
    assert np.array_equal(wa.train_ids, wb.train_ids)
    assert np.array_equal(wa.test_ids, wb.test_ids)
    assert all(np.array_equal(u, v) for u, v in zip(a.library.path_edges, b.library.path_edges, strict=True))
    assert a.metadata == b.metadata
    assert wa.X.shape != wc.X.shape or not np.array_equal(wa.X, wc.X)
    assert a.graph is not None
    assert c.graph is not None
    assert a.graph.vertex_states is not None
    assert c.graph.vertex_states is not None
    assert not np.array_equal(a.graph.vertex_states, c.graph.vertex_states)


def test_make_planar_problem_equals_the_dataset_file_of_its_recipe(tmp_path: Path) -> None:
    p = small(seed=3, model="forest")
    recipe = planar_recipe(p)
    report = build_dataset(tmp_path / "planar.npz", recipe)
    ds = load_dataset(report.out)
    w = p.require_worlds()
    assert np.array_equal(ds.X, w.X)
    assert np.array_equal(ds.R, w.R)
    assert np.array_equal(ds.train_ids, w.train_ids)
    assert np.array_equal(ds.test_ids, w.test_ids)
    assert all(np.array_equal(a, b) for a, b in zip(ds.library.path_edges, p.library.path_edges, strict=True))
    assert (
        ds.domain_spec
        == p.metadata["domain_spec"]
        == {**PlanarDomain().spec(), "num_vertices": 60, "seed": 3, "keep_clear": True}
    )
    assert np.array_equal(ds.world_seeds, world_seeds(3, 40))
    assert p.metadata["library_seed"] == library_seed(3)
    assert p.metadata["split_seed"] == split_seed(3)


def test_planar_problem_worlds_regenerate_x() -> None:
    p = small(seed=2, model="forest")
    boxes = planar_problem_worlds(p)
    assert p.graph is not None
    assert len(boxes) == 40
    assert np.array_equal(edge_free_matrix(p.graph, boxes), p.require_worlds().X)
    with pytest.raises(ProblemError, match="does not come from make_planar_problem"):
        planar_problem_worlds(Problem(name="x", library=p.library, edge_costs=p.edge_costs))


def test_bad_arguments_are_problem_errors() -> None:
    with pytest.raises(ProblemError, match="unknown planar world model 'moon'"):
        make_planar_problem(model="moon", num_worlds=3)
    with pytest.raises(ProblemError, match="num_worlds must be a positive integer"):
        make_planar_problem(num_worlds=0)
