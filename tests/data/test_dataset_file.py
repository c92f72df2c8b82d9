"""Tests of the dataset file: exact round trips, reproducible bytes, the Problem view, and every refusal."""

from __future__ import annotations

import dataclasses
import io
import json
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import pytest
from test_dataset_builder import build_grid

from drd_planner.bench.runner import run_benchmark
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.library import PathLibrary
from drd_planner.data.dataset_file import (
    FORMAT_NAME,
    FORMAT_VERSION,
    Dataset,
    load_dataset,
    load_dataset_problem,
    save_dataset,
)
from drd_planner.data.npz_format import read_checked_npz, write_checked_npz
from drd_planner.exceptions import DatasetError

Arrays = dict[str, npt.NDArray[Any]]


def tiny_dataset() -> Dataset:
    """A hand-made directed dataset: 0->1->3 and 0->2->3 (plus 1->2), four worlds, no optional arrays."""
    graph = ExplicitGraph(np.array([[0, 1], [1, 3], [0, 2], [2, 3], [1, 2]]), np.ones(5), 4, directed=True)
    library = PathLibrary((np.array([0, 1]), np.array([2, 3])), 5)
    x = np.array([[1, 1, 1, 1, 1], [1, 0, 1, 1, 0], [0, 1, 1, 0, 1], [1, 1, 0, 0, 0]], dtype=bool)
    return Dataset(
        graph=graph,
        start=0,
        goal=3,
        library=library,
        X=x,
        R=library.valid_paths(x),
        train_ids=np.array([0, 2, 3]),
        test_ids=np.array([1]),
        edge_costs=np.array([1.0, 2.0, 1.0, 0.5, 3.0]),
        world_seeds=np.array([11, 12, 13, 2**62]),
        domain="handmade",
        domain_spec={},
        world_model="fixed",
        seed=0,
    )


@pytest.fixture(scope="module")
def grid_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("grid") / "grid.npz"
    build_grid(out, workers=1, command="drd build-dataset --domain grid_test ...")
    return out


def assert_same(a: Dataset, b: Dataset) -> None:
    for f in ("edges", "lengths", "num_vertices", "directed"):
        assert np.array_equal(getattr(a.graph, f), getattr(b.graph, f)), f
    assert (a.graph.vertex_states is None) == (b.graph.vertex_states is None)
    if a.graph.vertex_states is not None:
        assert np.array_equal(a.graph.vertex_states, b.graph.vertex_states)
    assert a.library.num_paths == b.library.num_paths
    for p, q in zip(a.library.path_edges, b.library.path_edges, strict=True):
        assert np.array_equal(p, q)
    assert (a.library.vertex_paths is None) == (b.library.vertex_paths is None)
    if a.library.vertex_paths is not None and b.library.vertex_paths is not None:
        for p, q in zip(a.library.vertex_paths, b.library.vertex_paths, strict=True):
            assert np.array_equal(p, q)
    for f in ("X", "R", "train_ids", "test_ids", "edge_costs", "world_seeds"):
        x, y = getattr(a, f), getattr(b, f)
        assert x.dtype == y.dtype, f
        assert np.array_equal(x, y), f
    assert (a.edge_trajectories is None) == (b.edge_trajectories is None)
    if a.edge_trajectories is not None and b.edge_trajectories is not None:
        for p, q in zip(a.edge_trajectories, b.edge_trajectories, strict=True):
            assert p.shape == q.shape
            assert np.array_equal(p, q)
    for f in ("start", "goal", "domain", "domain_spec", "world_model", "seed", "world_model_params"):
        assert getattr(a, f) == getattr(b, f), f
    for f in ("check_metadata", "provenance", "software_version"):
        assert getattr(a, f) == getattr(b, f), f


# --------------------------------------------------------------------------------------------------
# Round trips


def test_round_trip_of_a_built_dataset(grid_file: Path, tmp_path: Path) -> None:
    ds = load_dataset(grid_file)
    assert ds.graph.vertex_states is not None
    assert ds.library.vertex_paths is not None
    assert ds.edge_trajectories is not None
    assert ds.edge_trajectories[0].shape == (3, 2)
    assert ds.provenance["command"] == "drd build-dataset --domain grid_test ..."
    again = tmp_path / "again.npz"
    save_dataset(again, ds)
    assert_same(load_dataset(again), ds)
    assert again.read_bytes() == grid_file.read_bytes()  # same contents, same bytes


def test_round_trip_without_optional_arrays(tmp_path: Path) -> None:
    ds = tiny_dataset()
    out = save_dataset(tmp_path / "tiny.npz", ds)
    back = load_dataset(out)
    assert_same(back, ds)
    assert back.graph.directed
    assert back.graph.vertex_states is None
    assert back.library.vertex_paths is None
    assert back.edge_trajectories is None
    with np.load(out, allow_pickle=False) as archive:
        assert not {"vertex_states", "vertex_paths", "traj_states"} & set(archive.files)


def test_file_is_a_plain_reproducible_npz(grid_file: Path) -> None:
    with zipfile.ZipFile(grid_file) as zf:
        infos = zf.infolist()
    names = [i.filename for i in infos]
    assert names == ["header.npy", *sorted(names[1:])]  # header first, arrays in sorted order
    assert all(i.date_time == (1980, 1, 1, 0, 0, 0) for i in infos)
    assert all(i.compress_type == zipfile.ZIP_DEFLATED for i in infos)
    with np.load(grid_file, allow_pickle=False) as archive:
        header = json.loads(archive["header"].tobytes())
        x_packed = archive["X_packed"]
    ds = load_dataset(grid_file)
    assert header["format"] == FORMAT_NAME
    assert header["format_version"] == FORMAT_VERSION
    assert header["num_worlds"] == 40
    assert header["num_edges"] == 42
    assert x_packed.dtype == np.uint8
    assert x_packed.shape == (40, 6)
    assert np.array_equal(np.packbits(ds.X, axis=1), x_packed)


def test_problem_view_matches_the_dataset(grid_file: Path) -> None:
    ds = load_dataset(grid_file)
    problem = load_dataset_problem(grid_file)
    worlds = problem.require_worlds()
    assert problem.name == "grid"
    assert problem.start == ds.start
    assert problem.goal == ds.goal
    assert problem.graph is not None
    assert np.array_equal(problem.graph.edges, ds.graph.edges)
    assert np.array_equal(worlds.X, ds.X)
    assert np.array_equal(worlds.R, ds.R)
    assert np.array_equal(worlds.train_ids, ds.train_ids)
    assert np.array_equal(worlds.test_ids, ds.test_ids)
    assert problem.library.num_paths == ds.library.num_paths
    assert all(np.array_equal(p, q) for p, q in zip(problem.library.path_edges, ds.library.path_edges, strict=True))
    assert problem.metadata["domain"] == "grid_test"
    assert problem.metadata["file"] == "grid.npz"
    assert len(problem.metadata["sha256"]) == 64
    # It runs in the benchmark like an authors' folder: every test world is solvable, so no failures.
    result = run_benchmark(problem, policies=["bisect"], progress=False)
    assert result.policies["bisect"].failures == 0
    assert len(result.policies["bisect"].checks) == ds.test_ids.size


# --------------------------------------------------------------------------------------------------
# Refusals: damaged bytes


def test_missing_and_foreign_files_are_refused(tmp_path: Path) -> None:
    with pytest.raises(DatasetError, match="dataset file not found"):
        load_dataset(tmp_path / "absent.npz")
    text = tmp_path / "text.npz"
    text.write_text("hello")
    with pytest.raises(DatasetError, match="not a readable dataset file"):
        load_dataset(text)
    plain = tmp_path / "plain.npz"
    np.savez(plain, a=np.arange(3))
    with pytest.raises(DatasetError, match="has no header"):
        load_dataset(plain)


def test_truncated_files_are_refused(tmp_path: Path) -> None:
    data = save_dataset(tmp_path / "t.npz", tiny_dataset()).read_bytes()
    cut = tmp_path / "cut.npz"
    for size in (0, 10, len(data) // 3, len(data) // 2, len(data) - 30, len(data) - 1):
        cut.write_bytes(data[:size])
        with pytest.raises(DatasetError):
            load_dataset(cut)


def test_every_flipped_byte_is_refused_or_harmless(tmp_path: Path) -> None:
    # A flip either breaks the file (refused with DatasetError, never another exception) or lands in a
    # zip field that does not change what is read (then the contents are exactly the original). Every
    # third byte keeps the run short; the file is ~2.9 kB, a quarter of it zip bookkeeping.
    original = tiny_dataset()
    data = save_dataset(tmp_path / "t.npz", original).read_bytes()
    bad = tmp_path / "bad.npz"
    refused, positions = 0, range(0, len(data), 3)
    for pos in positions:
        flipped = bytearray(data)
        flipped[pos] ^= 0x5A
        bad.write_bytes(bytes(flipped))
        try:
            loaded = load_dataset(bad)
        except DatasetError:
            refused += 1
            continue
        assert_same(loaded, original)
    assert refused > 0.6 * len(positions)


# --------------------------------------------------------------------------------------------------
# Refusals: well-formed files with wrong contents


def _rewrite(
    src: Path,
    dst: Path,
    *,
    arrays: Callable[[Arrays], None] | None = None,
    header: Callable[[dict[str, Any]], None] | None = None,
    format_name: str = FORMAT_NAME,
    format_version: int = FORMAT_VERSION,
) -> Path:
    """Copy a dataset file with edited arrays/header and *valid* checksums (only contents are wrong)."""
    head, arrs = read_checked_npz(
        src, format_name=FORMAT_NAME, format_version=FORMAT_VERSION, error=DatasetError, what="dataset file"
    )
    fields = {k: v for k, v in head.items() if k not in ("format", "format_version", "array_sha256", "payload_sha256")}
    if arrays is not None:
        arrays(arrs)
    if header is not None:
        header(fields)
    return write_checked_npz(
        dst,
        format_name=format_name,
        format_version=format_version,
        header=fields,
        arrays=arrs,
        error=DatasetError,
    )


def test_other_version_and_format_are_refused(grid_file: Path, tmp_path: Path) -> None:
    with pytest.raises(DatasetError, match="dataset file format version 2; this build reads version 1"):
        load_dataset(_rewrite(grid_file, tmp_path / "v2.npz", format_version=2))
    with pytest.raises(DatasetError, match=r"not a drd_planner dataset file \(format 'drd_planner.dataset'"):
        load_dataset(_rewrite(grid_file, tmp_path / "tree.npz", format_name="drd_planner.tree"))


def _replace_member(src: Path, dst: Path, name: str, data: bytes) -> None:
    buffer = io.BytesIO()
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as zout:
        for info in zin.infolist():
            zout.writestr(info, data if info.filename == name else zin.read(info.filename))
    dst.write_bytes(buffer.getvalue())


def _npy_bytes(arr: npt.NDArray[Any]) -> bytes:
    out = io.BytesIO()
    np.lib.format.write_array(out, arr, allow_pickle=False)
    return out.getvalue()


def test_tampered_header_and_arrays_are_refused(grid_file: Path, tmp_path: Path) -> None:
    with np.load(grid_file, allow_pickle=False) as archive:
        header = json.loads(archive["header"].tobytes())
        x_packed = archive["X_packed"].copy()
    header["world_model"] = "wall"
    bad = tmp_path / "header.npz"
    _replace_member(grid_file, bad, "header.npy", _npy_bytes(np.frombuffer(json.dumps(header).encode(), np.uint8)))
    with pytest.raises(DatasetError, match="payload checksum mismatch"):
        load_dataset(bad)
    _replace_member(grid_file, bad, "header.npy", _npy_bytes(np.frombuffer(b"{not json", np.uint8)))
    with pytest.raises(DatasetError, match="the header is corrupt"):
        load_dataset(bad)
    x_packed[3, 1] ^= 0x10
    _replace_member(grid_file, bad, "X_packed.npy", _npy_bytes(x_packed))
    with pytest.raises(DatasetError, match="checksum mismatch in array 'X_packed'"):
        load_dataset(bad)


def _flip_r(a: Arrays) -> None:
    a["R_packed"][0, 0] ^= 0x80


def _set_padding(a: Arrays) -> None:
    a["X_packed"][0, -1] |= 0x01  # E = 42: the last 6 bits of each row are padding


def _offsets_past_end(a: Arrays) -> None:
    a["path_offsets"][-1] += 1


@pytest.mark.parametrize(
    ("arrays", "header", "message"),
    [
        (_flip_r, None, "R does not match X and the library"),
        (_set_padding, None, "X_packed has non-zero padding bits"),
        (
            lambda a: a.update(X_packed=a["X_packed"][:, :5]),
            None,
            r"X_packed has shape \(40, 5\), expected \(40, 6\)",
        ),
        (lambda a: a.update(X_packed=a["X_packed"][:-1]), None, r"X_packed has shape \(39, 6\)"),
        (None, lambda h: h.update(num_worlds=41), r"X_packed has shape \(40, 6\), expected \(41, 6\)"),
        (None, lambda h: h.update(num_edges=41), "edges have shape"),
        (lambda a: a.pop("train_ids"), None, "lacks required arrays: train_ids"),
        (lambda a: a.update(extra=np.zeros(2)), None, "unexpected array 'extra'"),
        (lambda a: a.update(costs=a["costs"].astype(np.float32)), None, "'costs' has dtype float32"),
        (
            lambda a: a.pop("vertex_offsets"),
            None,
            "'vertex_paths' and 'vertex_offsets' must be stored together",
        ),
        (_offsets_past_end, None, "library path offsets do not partition"),
        (lambda a: a.update(test_ids=a["train_ids"][:2]), None, "train and test worlds overlap"),
        (
            lambda a: a.update(test_ids=np.array([40])),
            None,
            r"test ids must be sorted, distinct and in \[0, 40\)",
        ),
        (lambda a: a.update(world_seeds=a["world_seeds"][:3]), None, r"world seeds must be \(40,\)"),
        (lambda a: a.update(costs=-a["costs"]), None, "edge costs must be"),
        (lambda a: a.update(traj_offsets=a["traj_offsets"][:-1]), None, "edge trajectory offsets"),
        (lambda a: a.update(edges=a["edges"][[2, 1, 0, *range(3, 42)]]), None, "does not match its edge ids"),
        (None, lambda h: h.update(start=99), r"start vertex 99 outside \[0, 16\)"),
        (None, lambda h: h.update(goal=0), "start and goal are the same vertex"),
        (None, lambda h: h.update(seed="7"), "header field 'seed' must be an integer"),
        (None, lambda h: h.update(domain_spec=[1]), "header field 'domain_spec' must be an object"),
        (None, lambda h: h.pop("directed"), "KeyError"),
    ],
)
def test_inconsistent_contents_are_refused(
    grid_file: Path,
    tmp_path: Path,
    arrays: Callable[[Arrays], None] | None,
    header: Callable[[dict[str, Any]], None] | None,
    message: str,
) -> None:
    bad = _rewrite(grid_file, tmp_path / "bad.npz", arrays=arrays, header=header)
    with pytest.raises(DatasetError, match=message) as info:
        load_dataset(bad)
    assert str(bad) in str(info.value)


# --------------------------------------------------------------------------------------------------
# The Dataset type and saving


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"R": np.zeros((4, 2), dtype=bool)}, "R does not match"),
        ({"X": np.ones((4, 5), dtype=np.int8)}, "X must be bool"),
        ({"X": np.ones((4, 4), dtype=bool)}, r"X must be bool \(worlds, 5\)"),
        ({"test_ids": np.array([1, 1])}, "test ids must be sorted, distinct"),
        ({"train_ids": np.array([2, 0])}, "train ids must be sorted"),
        ({"world_seeds": np.array([1, 2, 3, -4])}, "world seeds must be non-negative"),
        ({"edge_costs": np.zeros(5)}, "edge costs must be"),
        ({"goal": 0}, "start and goal are the same vertex"),
        ({"edge_trajectories": (np.zeros((2, 2)),) * 4}, "need one trajectory per edge"),
        ({"edge_trajectories": (np.zeros((2, 2)),) * 4 + (np.zeros((2, 3)),)}, "same D"),
        (
            {"library": PathLibrary((np.array([0, 1]), np.array([2, 3])), 5, (np.array([0, 1, 3]),) * 2)},
            "library path 1: its vertex sequence does not match its edge ids",
        ),
    ],
)
def test_dataset_checks_its_invariants(change: dict[str, Any], message: str) -> None:
    with pytest.raises(DatasetError, match=message):
        dataclasses.replace(tiny_dataset(), **change)


def test_save_refuses_metadata_that_is_not_json(tmp_path: Path) -> None:
    for provenance in ({"when": object()}, {"nan": float("nan")}):
        with pytest.raises(DatasetError, match="not JSON-safe"):
            save_dataset(tmp_path / "x.npz", dataclasses.replace(tiny_dataset(), provenance=provenance))
    assert not list(tmp_path.iterdir())  # nothing half-written left behind
