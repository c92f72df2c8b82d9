"""A tree built from one of our dataset files carries what the node needs to rebuild its domain."""

from pathlib import Path

import numpy as np
import pytest
from conftest import SHARED_DATA

from drd_planner.cli.main import main
from drd_planner.domains.base import domain_from_spec
from drd_planner.planner import load_tree_bundle


def test_tree_from_dataset_rebuilds_its_domain_and_checker(tmp_path: Path) -> None:
    dataset = tmp_path / "heli.npz"
    tree_path = tmp_path / "heli_tree.npz"
    spec = '{"lattice": {"x_range": [0.0, 300.0], "y_range": [-100.0, 100.0], "goal": [300.0, 0.0]}}'
    argv = ["build-dataset", "--domain", "helicopter", "--world-model", "wires", "--worlds", "24"]
    argv += ["--seed", "3", "--out", str(dataset), "--workers", "1", "--domain-spec", spec]
    assert main(argv) == 0
    assert main(["build-tree", "--dataset", str(dataset), "--out", str(tree_path), "--eta", "0.2"]) == 0
    bundle = load_tree_bundle(tree_path, expected_domain="helicopter")
    meta = bundle.problem.metadata
    domain = domain_from_spec(meta["domain"], meta["domain_spec"])
    graph = bundle.problem.graph
    assert np.array_equal(domain.graph.edges, graph.edges)
    assert np.allclose(domain.graph.lengths, graph.lengths)
    assert meta["check_metadata"] == domain.check_metadata()
    # The rebuilt checker answers for the tree's root edge without any dataset code.
    root_edge = int(bundle.tree.edge[0])
    world = domain.make_world("wires", 0)
    assert isinstance(domain.checker(world).check(max(root_edge, 0)), bool)


def _shipped_trees() -> list[Path]:
    return sorted((Path(__file__).resolve().parents[2] / "trees").glob("*.npz"))


def test_shipped_trees_exist() -> None:
    names = {p.stem for p in _shipped_trees()}
    assert {"heli_lines", "heli_wires", "heli_terrain", "arm_table_clutter"} <= names


@pytest.mark.parametrize("path", _shipped_trees(), ids=lambda p: p.stem)
def test_shipped_tree_rebuilds_its_graph_from_the_stored_spec(path: Path) -> None:
    bundle = load_tree_bundle(path)
    meta = bundle.problem.metadata
    if meta["domain"] == "arm" and not (SHARED_DATA / "panda").is_dir():
        pytest.skip(f"shared Panda model {SHARED_DATA / 'panda'} not present (set DRD_SHARED_DATA)")
    domain = domain_from_spec(meta["domain"], meta["domain_spec"])
    assert np.array_equal(domain.graph.edges, bundle.problem.graph.edges)
    assert np.allclose(domain.graph.lengths, bundle.problem.graph.lengths)
    assert (domain.start, domain.goal) == (bundle.problem.start, bundle.problem.goal)
    assert meta["check_metadata"] == domain.check_metadata()
    assert 0.0 < bundle.eta <= 1.0
    assert bundle.tree.num_nodes >= 1
