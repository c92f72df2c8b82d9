"""Hostile tree files: every one is refused with one clear error, within a small memory bound.

Each file is crafted byte by byte from a shipped tree with its checksums recomputed (``crafting.py``),
as an attacker would: only the loaders' own checks can catch it (issue 19, items 7, 8 and 14). Every
refusal must be the loader's error type (TreeFileError from ``load_tree``, PriorFileError from
``load_prior`` and ``load_tree_bundle``), one line, naming the file and what is wrong, never numpy's
advice to load pickles; zip bombs must be refused before they are unpacked.
"""

from __future__ import annotations

import os
import tracemalloc
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from crafting import (
    LOADERS,
    MEMORY_BOUND,
    Arrays,
    Craft,
    add_lying_member,
    add_object_array,
    add_text_member,
    add_zeros_bomb,
    corrupt_deflate,
    edit_member,
    huge_npy_header,
    npy_bytes,
    read_trusted,
    refusal,
    reverse_path,
    scale_lattice,
    set_field,
    set_item,
    shape_lie,
    single_edge_paths,
    tree_file_of,
)

from drd_planner.data.tree_file import load_tree
from drd_planner.exceptions import TreeFileError

DEEP = 100_000
TREE_CASES: dict[str, Craft] = {
    "deep_json": Craft(
        ("header is corrupt", "nested"),
        header=set_field(("provenance", "deep"), "@DEEP"),
        splice={"@DEEP": ("[" * DEEP + "]" * DEEP,) * 2},
    ),
    "huge_int": Craft(
        ("header is corrupt", "integer"),
        header=set_field(("provenance", "big"), "@BIG"),
        splice={"@BIG": ("9" * 5000,) * 2},
    ),
    "big_start": Craft(("header is corrupt", "integer"), header=set_field(("start",), 10**30)),
    "infinity": Craft(
        ("header is corrupt", "Infinity"), header=set_field(("eta",), "@X"), splice={"@X": ("Infinity",) * 2}
    ),
    "nan": Craft(("header is corrupt", "NaN"), header=set_field(("alpha",), "@X"), splice={"@X": ("NaN",) * 2}),
    "float_overflow": Craft(
        ("header is corrupt", "overflows"),
        header=set_field(("pseudo_count",), "@X"),
        splice={"@X": ("1e999", "Infinity")},
    ),
    "eta_out_of_range": Craft(("inconsistent", "'eta'"), header=set_field(("eta",), 5.0)),
    "num_vertices_float": Craft(("inconsistent", "num_vertices"), header=set_field(("num_vertices",), 731.0)),
    "domain_not_text": Craft(("inconsistent", "'domain'"), header=set_field(("domain",), ["helicopter"])),
    "corrupt_member": Craft(("edges", "corrupt"), members=corrupt_deflate),
    "encrypted_member": Craft(("costs.npy", "encrypted"), members=edit_member("costs.npy", flags=1)),
    "declared_3_gib": Craft(("bomb.npy", "unpacks to"), members=add_lying_member, bounded=True),
    "zip_bomb_200_mb": Craft(("bomb.npy", "unpacks to"), members=add_zeros_bomb, bounded=True),
    "npy_shape_lie": Craft(("node_edge", "declares shape"), members=shape_lie, bounded=True),
    "npy_header_huge": Craft(("costs", ".npy header of 60000 bytes"), members=huge_npy_header),
    "object_array": Craft(("smuggled", "dtype"), members=add_object_array),
    "not_npy_member": Craft(("notes.txt", ".npy"), members=add_text_member),
    "children_loop": Craft(("inconsistent", "children"), arrays=set_item("node_children", (0, 1), 0)),
    "child_shared": Craft(("inconsistent", "children"), arrays=set_item("node_children", (0, 1), 1)),
    "leaf_with_children": Craft(("inconsistent", "leaf"), arrays=set_item("node_edge", 0, -1)),
    "best_path_negative": Craft(("inconsistent", "best paths"), arrays=set_item("node_best_path", 0, -5)),
    "start_out_of_range": Craft(("inconsistent", "'start'"), header=set_field(("start",), 10**6)),
    "goal_negative": Craft(("inconsistent", "'goal'"), header=set_field(("goal",), -1)),
    "single_edge_paths": Craft(("inconsistent", "not a walk"), arrays=single_edge_paths()),
    "reversed_path": Craft(("inconsistent", "not a walk"), arrays=reverse_path),
    "vertex_path_mismatch": Craft(("inconsistent", "vertex paths"), arrays=set_item("vertex_paths", 3, 7)),
    "lattice_1e9_m": Craft(("inconsistent", "lattice"), header=scale_lattice),
    "tiny_sample_spacing": Craft(
        ("inconsistent", "samples per edge"),
        header=set_field(("problem_metadata", "domain_spec", "lattice", "sample_spacing"), 1e-9),
    ),
    "lattice_fine_grid": Craft(
        ("inconsistent", "lattice states"),
        header=set_field(("problem_metadata", "domain_spec", "lattice", "xy_spacing"), 0.5),
    ),
    "states_1e9_m": Craft(("inconsistent", "vertex states"), arrays=set_item("vertex_states", (slice(None), 0), 1e9)),
    "cost_1e308": Craft(("inconsistent", "edge costs"), arrays=set_item("costs", 0, 1e308)),
    "nan_leaf_bias": Craft(("inconsistent", "leaf bias"), arrays=set_item("free_fraction", (0, 0), np.nan)),
    "infinite_active_fraction": Craft(
        ("inconsistent", "active fractions"), arrays=set_item("node_active_fraction", 1, np.inf)
    ),
}


def _arm_spec(key: str, value: Any) -> Callable[[dict[str, Any]], None]:
    return set_field(("problem_metadata", "domain_spec", key), value)


ARM_CASES: dict[str, Craft] = {
    "urdf_is_a_device": Craft(
        ("inconsistent", "urdf_path", "not a regular file"), header=_arm_spec("urdf_path", "/dev/zero")
    ),
    "srdf_is_a_directory": Craft(
        ("inconsistent", "srdf_path", "not a regular file"), header=_arm_spec("srdf_path", "/")
    ),
    "roadmap_samples": Craft(("inconsistent", "num_samples"), header=_arm_spec("num_samples", 10**8)),
    "tiny_resolution": Craft(("inconsistent", "samples per edge"), header=_arm_spec("resolution", 1e-9)),
}


@pytest.fixture(scope="module")
def base_tree(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], Arrays]:
    return read_trusted(tree_file_of("heli_terrain", tmp_path_factory.mktemp("tree")))


def test_the_base_tree_loads_when_rewritten_unchanged(base_tree: tuple[dict[str, Any], Arrays], tmp_path: Path) -> None:
    """The crafting itself is faithful: with no edit the rewritten file loads."""
    path = Craft(()).write(base_tree, tmp_path / "same.npz")
    assert load_tree(path).problem.num_paths == base_tree[1]["path_offsets"].size - 1


@pytest.mark.parametrize("loader", list(LOADERS))
@pytest.mark.parametrize("case", list(TREE_CASES))
def test_crafted_tree_files_are_refused_clearly(
    base_tree: tuple[dict[str, Any], Arrays], tmp_path: Path, case: str, loader: str
) -> None:
    craft = TREE_CASES[case]
    path = craft.write(base_tree, tmp_path / f"{case}.npz")
    load, error = LOADERS[loader]
    if craft.bounded:
        tracemalloc.start()
        try:
            message = refusal(load, path, error)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        assert peak < MEMORY_BOUND, f"peak {peak / 2**20:.0f} MiB while refusing"
    else:
        message = refusal(load, path, error)
    for word in craft.words:
        assert word in message, message


@pytest.mark.parametrize("loader", list(LOADERS))
@pytest.mark.parametrize("case", list(ARM_CASES))
def test_crafted_arm_specs_are_refused_before_the_roadmap_is_built(tmp_path: Path, case: str, loader: str) -> None:
    base = read_trusted(tree_file_of("arm_table_clutter", tmp_path))
    path = ARM_CASES[case].write(base, tmp_path / f"{case}.npz")
    load, error = LOADERS[loader]
    message = refusal(load, path, error)
    for word in ARM_CASES[case].words:
        assert word in message, message


# --------------------------------------------------------------------------------------------------
# Paths that are not tree files at all (issue 19, item 14)
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("loader", list(LOADERS))
def test_a_directory_is_called_a_directory(tmp_path: Path, loader: str) -> None:
    folder = tmp_path / "trees.npz"
    folder.mkdir()
    load, error = LOADERS[loader]
    assert "is a directory" in refusal(load, folder, error)


def test_the_resolver_calls_a_directory_a_directory(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from drd_planner.planning.shipped import resolve_tree_path

    (tmp_path / "mytrees").mkdir()
    with pytest.raises(TreeFileError, match="is a directory") as info:
        resolve_tree_path(str(tmp_path / "mytrees"))
    assert "does not exist" not in str(info.value)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(TreeFileError, match="mytrees is a directory"):
        resolve_tree_path("mytrees")


NOT_NPZ: dict[str, tuple[bytes, str]] = {
    "text": (b"edges,lengths\n0,1\n", "holds text starting 'edges,lengths"),
    "npy": (npy_bytes(np.arange(3)), "is a single .npy array"),
    "empty": (b"", "is empty"),
    "gzip": (b"\x1f\x8b\x08\x00" + bytes(40), "gzip"),
    "binary": (bytes(range(200, 256)) * 4, "starts with the bytes c8 c9"),
}


@pytest.mark.parametrize("loader", list(LOADERS))
@pytest.mark.parametrize("kind", list(NOT_NPZ))
def test_files_that_are_not_npz_say_what_they_are(tmp_path: Path, kind: str, loader: str) -> None:
    data, found = NOT_NPZ[kind]
    path = tmp_path / f"{kind}.npz"
    path.write_bytes(data)
    load, error = LOADERS[loader]
    message = refusal(load, path, error)
    assert "is not a readable" in message, message
    assert ".npz (zip) archive" in message, message
    assert found in message, message


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes")
def test_a_named_pipe_is_refused_without_blocking(tmp_path: Path) -> None:
    from drd_planner.planning.shipped import resolve_tree_path

    pipe = tmp_path / "pipe.npz"
    os.mkfifo(pipe)
    assert "not a regular file" in refusal(load_tree, pipe, TreeFileError)
    with pytest.raises(TreeFileError, match="not a regular file"):
        resolve_tree_path(str(pipe))


def test_drd_prints_one_line_for_a_crafted_tree(
    base_tree: tuple[dict[str, Any], Arrays], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from drd_planner.cli.main import main

    path = TREE_CASES["deep_json"].write(base_tree, tmp_path / "deep.npz")
    assert main(["plan", "--bag", "heli_wires", "--tree", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("drd: error: "), err
    assert err.count("\n") == 1, err
    assert "deep.npz" in err, err


@pytest.mark.parametrize(
    "exc", [MemoryError(), RecursionError("deep"), OverflowError("big"), KeyError("k"), RuntimeError("odd")]
)
def test_the_last_line_of_defence_converts_anything(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, exc: BaseException
) -> None:
    """Whatever the explicit checks miss still leaves the loaders as their one error type."""
    from drd_planner.data import tree_file

    def explode(*args: object, **kwargs: object) -> None:
        raise exc

    monkeypatch.setattr(tree_file, "check_tree_arrays", explode)
    path = tree_file_of("heli_terrain", tmp_path)
    for loader in LOADERS:
        load, error = LOADERS[loader]
        refusal(load, path, error)
