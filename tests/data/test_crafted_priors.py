"""Hostile prior files: refused with one PriorFileError naming the file and the fault, within a memory bound.

Crafted from a small saved prior with checksums recomputed (``crafting.py``); see ``test_crafted_files.py``
for the tree files (issue 19, items 7 and 8).
"""

from __future__ import annotations

import tracemalloc
from pathlib import Path
from typing import Any

import pytest
from crafting import (
    LOADERS,
    MEMORY_BOUND,
    Arrays,
    Craft,
    add_zeros_bomb,
    edit_member,
    read_trusted,
    refusal,
    set_field,
    set_item,
    single_edge_paths,
)

from drd_planner.planner.prior_file import load_prior

DEEP = 100_000

# --------------------------------------------------------------------------------------------------
# Prior files
# --------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def base_prior(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], Arrays]:
    from drd_planner.core.tree import build_tree
    from drd_planner.data.planar_problem import make_planar_problem
    from drd_planner.planner import QueryTree, prior_from_problem, save_prior

    problem = make_planar_problem(model="forest", num_worlds=60, seed=2)
    assert problem.start is not None
    assert problem.goal is not None
    own = QueryTree("own", problem.start, problem.goal, problem.library, build_tree(problem, progress=False))
    prior = prior_from_problem(problem, domain="planar", trees=(own,), eta=0.4)
    return read_trusted(save_prior(tmp_path_factory.mktemp("prior") / "prior.npz", prior))


def _helicopter_spec(header: dict[str, Any]) -> None:
    header["domain"] = "helicopter"
    header["domain_spec"] = {"lattice": {"x_range": [0, 10**9], "goal": [10**9, 0]}}


PRIOR_CASES: dict[str, Craft] = {
    "deep_json": Craft(
        ("header is corrupt", "nested"),
        header=set_field(("provenance", "deep"), "@DEEP"),
        splice={"@DEEP": ("[" * DEEP + "]" * DEEP,) * 2},
    ),
    "infinity": Craft(
        ("header is corrupt", "Infinity"), header=set_field(("eta",), "@X"), splice={"@X": ("Infinity",) * 2}
    ),
    "encrypted_member": Craft(("worlds_bits.npy", "encrypted"), members=edit_member("worlds_bits.npy", flags=1)),
    "zip_bomb_200_mb": Craft(("bomb.npy", "unpacks to"), members=add_zeros_bomb, bounded=True),
    "single_edge_paths": Craft(("tree 0", "not a walk"), arrays=single_edge_paths("t0_")),
    "children_loop": Craft(("tree 0", "children"), arrays=set_item("t0_node_children", (0, 1), 0)),
    "tree_start_out_of_range": Craft(("tree 0", "'start'"), header=set_field(("trees", 0, "start"), 10**6)),
    "trees_not_a_list": Craft(("'trees'",), header=set_field(("trees",), {"t0": 1})),
    "lattice_1e9_m": Craft(("inconsistent", "lattice"), header=_helicopter_spec),
    "dense_random_graph": Craft(
        ("inconsistent", "random geometric graph"),
        header=set_field(("domain_spec",), {"num_vertices": 1_000_000, "eta": 100.0}),
    ),
    "max_paths_huge": Craft(("inconsistent", "max_paths"), header=set_field(("max_paths",), 10**15)),
    "num_worlds_huge": Craft(("inconsistent", "worlds_bits"), header=set_field(("num_worlds",), 10**8)),
}


@pytest.mark.parametrize("loader", ["load_prior", "load_tree_bundle"])
@pytest.mark.parametrize("case", list(PRIOR_CASES))
def test_crafted_prior_files_are_refused_clearly(
    base_prior: tuple[dict[str, Any], Arrays], tmp_path: Path, case: str, loader: str
) -> None:
    craft = PRIOR_CASES[case]
    path = craft.write(base_prior, tmp_path / f"{case}.npz")
    load, error = LOADERS[loader]
    tracemalloc.start()
    try:
        message = refusal(load, path, error)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < MEMORY_BOUND, f"peak {peak / 2**20:.0f} MiB while refusing"
    for word in craft.words:
        assert word in message, message


def test_the_base_prior_loads_when_rewritten_unchanged(
    base_prior: tuple[dict[str, Any], Arrays], tmp_path: Path
) -> None:
    assert len(load_prior(Craft(()).write(base_prior, tmp_path / "same.npz")).trees) == 1
