"""Tests of the decision-tree file: exact round trip, identical plans, and every refusal."""

from __future__ import annotations

import dataclasses
import io
import json
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from drd_planner.core.episode import TableOracle, run_episode
from drd_planner.core.policies import DirectBisectPolicy
from drd_planner.core.problem import Problem
from drd_planner.core.tree import DecisionTree, build_tree
from drd_planner.data.npz_format import array_digest, payload_digest
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.data.tree_file import FORMAT_VERSION, TreeBundle, load_tree, save_tree
from drd_planner.exceptions import ProblemError, TreeFileError

TREE_ARRAYS = (
    "edge",
    "children",
    "num_active",
    "active_fraction",
    "library_edges",
    "free_fraction",
    "best_path",
)


@pytest.fixture(scope="module")
def planar() -> tuple[Problem, DecisionTree]:
    problem = make_planar_problem(num_worlds=120, max_paths=40, seed=3)
    return problem, build_tree(problem, progress=False)


@pytest.fixture(scope="module")
def bundle(planar: tuple[Problem, DecisionTree]) -> TreeBundle:
    problem, tree = planar
    return TreeBundle(
        problem=dataclasses.replace(problem, worlds=None),
        tree=tree,
        domain="planar",
        eta=0.15,
        alpha=0.9,
        provenance={"command": "pytest", "seed": 3, "nested": {"a": [1, 2]}},
    )


@pytest.fixture
def saved(tmp_path: Path, bundle: TreeBundle) -> Path:
    return save_tree(tmp_path / "sub" / "tree.npz", bundle)


def _read_npz(path: Path) -> dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as archive:
        return {k: archive[k] for k in archive.files}


def _header(arrays: dict[str, np.ndarray]) -> dict[str, Any]:
    header = json.loads(arrays["header"].tobytes().decode())
    assert isinstance(header, dict)
    return header


def _write_npz(path: Path, arrays: dict[str, np.ndarray], header: dict[str, Any] | None = None) -> None:
    out = dict(arrays)
    if header is not None:
        out["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    np.savez(path, **out)  # type: ignore[arg-type]


def _rechecksum(arrays: dict[str, np.ndarray]) -> None:
    """Recompute the header's checksums in place so that only the content is wrong."""
    header = _header(arrays)
    digests = {k: array_digest(k, v) for k, v in arrays.items() if k != "header"}
    header["array_sha256"] = digests
    header["payload_sha256"] = payload_digest(digests, header)
    arrays["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)


def _refused(path: Path, *words: str, expected_domain: str | None = None) -> str:
    with pytest.raises(TreeFileError) as info:
        load_tree(path, expected_domain=expected_domain)
    message = str(info.value)
    assert "\n" not in message
    for word in words:
        assert word in message, message
    return message


# --------------------------------------------------------------------------------------------------
# Round trip
# --------------------------------------------------------------------------------------------------


def test_round_trip_is_exact(saved: Path, bundle: TreeBundle) -> None:
    loaded = load_tree(saved)
    assert loaded.domain == "planar"
    assert loaded.eta == bundle.eta
    assert loaded.alpha == bundle.alpha
    assert loaded.provenance == bundle.provenance
    tree, orig = loaded.tree, bundle.tree
    for name in TREE_ARRAYS:
        a, b = getattr(tree, name), getattr(orig, name)
        assert a.dtype == b.dtype, name
        np.testing.assert_array_equal(a, b, err_msg=name)
    assert tree.num_edges == orig.num_edges
    assert tree.num_paths == orig.num_paths
    assert tree.info == orig.info
    assert tree.num_nodes == orig.num_nodes
    assert tree.depth() == orig.depth()

    problem, source = loaded.problem, bundle.problem
    assert problem.worlds is None
    assert problem.name == source.name
    assert (problem.start, problem.goal) == (source.start, source.goal)
    assert problem.metadata == source.metadata
    np.testing.assert_array_equal(problem.edge_costs, source.edge_costs)
    assert problem.graph is not None
    assert source.graph is not None
    assert problem.graph.num_vertices == source.graph.num_vertices
    assert problem.graph.directed == source.graph.directed
    np.testing.assert_array_equal(problem.graph.edges, source.graph.edges)
    np.testing.assert_array_equal(problem.graph.lengths, source.graph.lengths)
    assert source.graph.vertex_states is not None
    np.testing.assert_array_equal(problem.graph.vertex_states, source.graph.vertex_states)
    assert problem.library.num_edges == source.library.num_edges
    assert problem.library.num_paths == source.library.num_paths
    for a, b in zip(problem.library.path_edges, source.library.path_edges, strict=True):
        np.testing.assert_array_equal(a, b)
    assert problem.library.vertex_paths is not None
    assert source.library.vertex_paths is not None
    for a, b in zip(problem.library.vertex_paths, source.library.vertex_paths, strict=True):
        np.testing.assert_array_equal(a, b)


def test_saved_file_is_deterministic(tmp_path: Path, bundle: TreeBundle) -> None:
    a = _read_npz(save_tree(tmp_path / "a.npz", bundle))
    b = _read_npz(save_tree(tmp_path / "b.npz", bundle))
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k])
    header = _header(a)
    assert header["format_version"] == FORMAT_VERSION
    assert header["domain"] == "planar"


def test_loaded_tree_plans_identically(saved: Path, bundle: TreeBundle, planar: tuple[Problem, DecisionTree]) -> None:
    problem, tree = planar
    loaded = load_tree(saved, expected_domain="planar")
    worlds = problem.require_worlds()
    assert worlds.test_ids.size > 0
    for world in worlds.test_ids:
        logs = []
        for t, lib, costs in (
            (tree, problem.library, problem.edge_costs),
            (loaded.tree, loaded.problem.library, loaded.problem.edge_costs),
        ):
            policy = DirectBisectPolicy(t, lib, costs, eta=bundle.eta, alpha=bundle.alpha)
            result = run_episode(lib, costs, policy, TableOracle(worlds.X[world]))
            logs.append(
                (
                    [(c.edge, c.free, c.stage) for c in result.checks],
                    result.status,
                    result.path_index,
                )
            )
        assert logs[0] == logs[1], f"world {world}"


def test_bundle_without_graph_cannot_be_saved(tmp_path: Path, bundle: TreeBundle) -> None:
    no_graph = dataclasses.replace(bundle, problem=dataclasses.replace(bundle.problem, graph=None))
    with pytest.raises(TreeFileError, match="graph"):
        save_tree(tmp_path / "t.npz", no_graph)


# --------------------------------------------------------------------------------------------------
# Refusals
# --------------------------------------------------------------------------------------------------


def test_missing_file_is_refused(tmp_path: Path) -> None:
    _refused(tmp_path / "nothing.npz", "not found", "nothing.npz")


def test_random_bytes_are_refused(tmp_path: Path) -> None:
    path = tmp_path / "junk.npz"
    path.write_bytes(np.random.default_rng(0).integers(0, 256, 4096, dtype=np.uint8).tobytes())
    _refused(path, "not a readable tree file")


def test_empty_file_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "empty.npz"
    path.write_bytes(b"")
    _refused(path, "empty.npz")


@pytest.mark.parametrize("keep", [0.5, 0.9])
def test_truncated_file_is_refused(saved: Path, keep: float) -> None:
    data = saved.read_bytes()
    saved.write_bytes(data[: int(len(data) * keep)])
    _refused(saved, "not a readable tree file")


def test_zip_member_bit_flip_is_refused(saved: Path) -> None:
    # Flip a byte inside the compressed data: the zip CRC (or the inflater) catches it.
    data = bytearray(saved.read_bytes())
    data[len(data) // 3] ^= 0xFF
    saved.write_bytes(bytes(data))
    with pytest.raises(TreeFileError):
        load_tree(saved)


def test_checksum_mismatch_is_refused(saved: Path) -> None:
    arrays = _read_npz(saved)
    arrays["node_active_fraction"] = arrays["node_active_fraction"].copy()
    arrays["node_active_fraction"][0] *= 0.5
    _write_npz(saved, arrays)  # the original header, untouched
    _refused(saved, "checksum mismatch", "node_active_fraction")


def test_payload_checksum_mismatch_is_refused(saved: Path) -> None:
    arrays = _read_npz(saved)
    header = _header(arrays)
    header["payload_sha256"] = "0" * 64
    del arrays["header"]
    _write_npz(saved, arrays, header)
    _refused(saved, "payload checksum mismatch")


def test_extra_array_is_refused(saved: Path) -> None:
    arrays = _read_npz(saved)
    arrays["smuggled"] = np.zeros(3)
    _write_npz(saved, arrays)
    _refused(saved, "corrupt")


def test_missing_array_is_refused(saved: Path) -> None:
    arrays = _read_npz(saved)
    del arrays["free_fraction"]
    _write_npz(saved, arrays)
    _refused(saved, "corrupt")


def test_missing_array_with_recomputed_checksums_is_refused(saved: Path) -> None:
    arrays = _read_npz(saved)
    del arrays["free_fraction"]
    _rechecksum(arrays)
    _write_npz(saved, arrays)
    _refused(saved, "lacks required arrays", "free_fraction")


def test_wrong_dtype_is_refused(saved: Path) -> None:
    arrays = _read_npz(saved)
    arrays["node_edge"] = arrays["node_edge"].astype(np.int64)
    _rechecksum(arrays)
    _write_npz(saved, arrays)
    _refused(saved, "node_edge", "dtype")


def test_header_missing_is_refused(saved: Path) -> None:
    arrays = _read_npz(saved)
    del arrays["header"]
    _write_npz(saved, arrays)
    _refused(saved, "no header")


def test_header_not_json_is_refused(saved: Path) -> None:
    arrays = _read_npz(saved)
    arrays["header"] = np.frombuffer(b"{not json", dtype=np.uint8)
    _write_npz(saved, arrays)
    _refused(saved, "header is corrupt")


def test_header_not_utf8_is_refused(saved: Path) -> None:
    arrays = _read_npz(saved)
    arrays["header"] = np.frombuffer(b"\xff\xfe\x00{", dtype=np.uint8)
    _write_npz(saved, arrays)
    _refused(saved, "header is corrupt")


def test_header_of_another_format_is_refused(saved: Path) -> None:
    arrays = _read_npz(saved)
    header = _header(arrays)
    header["format"] = "something.else"
    del arrays["header"]
    _write_npz(saved, arrays, header)
    _refused(saved, "not a drd_planner tree file")


def test_header_json_list_is_refused(saved: Path) -> None:
    arrays = _read_npz(saved)
    arrays["header"] = np.frombuffer(b"[1, 2]", dtype=np.uint8)
    _write_npz(saved, arrays)
    _refused(saved, "not a drd_planner tree file")


def test_another_format_version_is_refused(saved: Path) -> None:
    arrays = _read_npz(saved)
    header = _header(arrays)
    header["format_version"] = 999
    del arrays["header"]
    _write_npz(saved, arrays, header)  # checksums still match the arrays
    _refused(saved, "version 999", "versions 1, 2")


def test_another_domain_is_refused(saved: Path) -> None:
    _refused(saved, "'planar'", "'arm'", expected_domain="arm")
    assert load_tree(saved, expected_domain="planar").domain == "planar"


@pytest.mark.parametrize(
    ("array", "corrupt", "words"),
    [
        ("node_children", lambda a: a.__setitem__((0, 1), a.shape[0] + 5), ("inconsistent", "children")),
        ("node_children", lambda a: a.__setitem__((0, 0), -7), ("inconsistent", "children")),
        ("node_edge", lambda a: a.__setitem__(0, 10**6), ("inconsistent", "edges")),
        ("node_best_path", lambda a: a.__setitem__(0, 10**6), ("inconsistent", "best paths")),
        ("path_offsets", lambda a: a.__setitem__(-1, a[-1] + 3), ("inconsistent", "offsets")),
        ("path_edges", lambda a: a.__setitem__(0, 10**6), ("inconsistent",)),
        ("costs", lambda a: a.__setitem__(0, -1.0), ("inconsistent", "costs")),
    ],
)
def test_inconsistent_arrays_are_refused(saved: Path, array: str, corrupt: Any, words: tuple[str, ...]) -> None:
    arrays = _read_npz(saved)
    arrays[array] = arrays[array].copy()
    corrupt(arrays[array])
    _rechecksum(arrays)
    _write_npz(saved, arrays)
    _refused(saved, *words)


def test_free_fraction_of_wrong_shape_is_refused(saved: Path) -> None:
    arrays = _read_npz(saved)
    arrays["free_fraction"] = arrays["free_fraction"][:, :-1].copy()
    _rechecksum(arrays)
    _write_npz(saved, arrays)
    _refused(saved, "inconsistent", "leaf bias")


_UNPICKLED: list[str] = []


def _trip() -> str:
    _UNPICKLED.append("unpickled")
    return "payload"


class _Canary:
    """Unpickling this object appends to _UNPICKLED."""

    def __reduce__(self) -> tuple[Any, tuple[()]]:
        return (_trip, ())


@pytest.mark.parametrize("name", ["node_edge", "smuggled"])
def test_object_arrays_are_never_unpickled(saved: Path, name: str) -> None:
    arrays = _read_npz(saved)
    payload = np.empty(2, dtype=object)
    payload[0], payload[1] = _Canary(), _Canary()
    arrays[name] = payload
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)  # type: ignore[arg-type]
    saved.write_bytes(buffer.getvalue())
    with zipfile.ZipFile(saved) as zf:
        assert f"{name}.npy" in zf.namelist()
    _UNPICKLED.clear()
    with pytest.raises(TreeFileError):
        load_tree(saved)
    assert _UNPICKLED == []


def test_edited_header_field_is_refused(tmp_path: Path, bundle: TreeBundle) -> None:
    """The payload checksum covers header fields too (start, goal, eta, alpha, domain, ...)."""
    path = tmp_path / "tree.npz"
    save_tree(path, bundle)
    with np.load(path, allow_pickle=False) as archive:
        arrays = {k: archive[k] for k in archive.files}
    header = json.loads(arrays["header"].tobytes().decode())
    header["eta"] = 0.9
    arrays["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    np.savez(path, **arrays)  # type: ignore[arg-type]
    _refused(path, "payload checksum")


# --------------------------------------------------------------------------------------------------
# Format version 2: the training worlds of the posterior leaf
# --------------------------------------------------------------------------------------------------


def test_training_worlds_and_pseudo_count_round_trip(
    tmp_path: Path, bundle: TreeBundle, planar: tuple[Problem, DecisionTree]
) -> None:
    problem, tree = planar
    assert tree.world_free is not None
    worlds = problem.require_worlds()
    np.testing.assert_array_equal(tree.world_free, worlds.X[np.ix_(worlds.train_ids, tree.library_edges)])
    posterior = dataclasses.replace(bundle, pseudo_count=12.5)
    loaded = load_tree(save_tree(tmp_path / "p.npz", posterior))
    assert loaded.pseudo_count == 12.5
    assert loaded.tree.world_free is not None
    assert loaded.tree.world_free.dtype == np.bool_
    np.testing.assert_array_equal(loaded.tree.world_free, tree.world_free)
    assert loaded.tree.world_weights is None
    for world in worlds.test_ids[:10]:
        logs = []
        for t in (tree, loaded.tree):
            policy = DirectBisectPolicy(t, problem.library, problem.edge_costs, eta=0.15, pseudo_count=12.5)
            result = run_episode(problem.library, problem.edge_costs, policy, TableOracle(worlds.X[world]))
            logs.append([(c.edge, c.free, c.stage) for c in result.checks])
        assert logs[0] == logs[1]


def _as_version_1(path: Path) -> None:
    arrays = _read_npz(path)
    header = _header(arrays)
    del arrays["header"], arrays["world_free_bits"]
    header["format_version"] = 1
    for key in ("pseudo_count", "num_train_worlds"):
        header.pop(key)
    digests = {k: array_digest(k, v) for k, v in arrays.items()}
    header["array_sha256"] = digests
    header["payload_sha256"] = payload_digest(digests, header)
    _write_npz(path, arrays, header)


def test_version_1_file_loads_with_a_fixed_leaf(saved: Path, planar: tuple[Problem, DecisionTree]) -> None:
    problem, _ = planar
    _as_version_1(saved)
    loaded = load_tree(saved)
    assert loaded.tree.world_free is None
    assert loaded.pseudo_count is None
    DirectBisectPolicy(loaded.tree, problem.library, problem.edge_costs, eta=1.0)  # the paper's leaf works
    with pytest.raises(ProblemError, match="format version 1"):
        DirectBisectPolicy(loaded.tree, problem.library, problem.edge_costs, eta=1.0, pseudo_count=5.0)


def test_packed_training_worlds_of_wrong_shape_are_refused(saved: Path) -> None:
    arrays = _read_npz(saved)
    arrays["world_free_bits"] = arrays["world_free_bits"][:-1].copy()
    _rechecksum(arrays)
    _write_npz(saved, arrays)
    _refused(saved, "inconsistent", "world_free_bits")


def test_pseudo_count_without_training_worlds_is_refused(tmp_path: Path, bundle: TreeBundle) -> None:
    bare = dataclasses.replace(bundle, tree=dataclasses.replace(bundle.tree, world_free=None), pseudo_count=5.0)
    with pytest.raises(TreeFileError, match="training worlds"):
        save_tree(tmp_path / "bare.npz", bare)


def test_brackets_inside_header_strings_are_not_nesting(tmp_path: Path, bundle: TreeBundle) -> None:
    """The JSON depth limit counts arrays and objects, not brackets quoted in strings."""
    text = '[{"quoted \\" [[[' + "[" * 500
    provenance = {"note": text, "nested": [[[[[[1]]]]]], "seed": 2**63 - 1}
    loaded = load_tree(save_tree(tmp_path / "t.npz", dataclasses.replace(bundle, provenance=provenance)))
    assert loaded.provenance == provenance


def test_library_paths_must_walk_from_start_to_goal(saved: Path) -> None:
    """Issue 19 item 8: paths cut down to single edges (checksums recomputed) are refused."""
    arrays = _read_npz(saved)
    offsets = arrays["path_offsets"]
    arrays["path_edges"] = arrays["path_edges"][offsets[1:] - 1].copy()  # each path's last edge only
    arrays["path_offsets"] = np.arange(offsets.size, dtype=np.int64)
    for name in ("vertex_paths", "vertex_offsets"):
        arrays.pop(name, None)
    lib = np.unique(arrays["path_edges"])
    cols = np.searchsorted(arrays["library_edges"], lib)
    free = np.unpackbits(arrays["world_free_bits"], axis=1, count=arrays["library_edges"].size)
    arrays["world_free_bits"] = np.packbits(free[:, cols], axis=1)
    arrays["library_edges"] = lib
    arrays["free_fraction"] = arrays["free_fraction"][:, cols].copy()
    _rechecksum(arrays)
    _write_npz(saved, arrays)
    _refused(saved, "inconsistent", "not a walk from the start vertex")
