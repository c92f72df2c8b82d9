"""Tests of the chunk format: tasks, results and the chunk files of the resume folder."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drd_planner.data.dataset_chunks import (
    ChunkResult,
    chunk_path,
    load_chunk,
    pack_paths,
    parts_dir,
    remove_parts,
    save_chunk,
)
from drd_planner.exceptions import DatasetError

PATHS = [((0, 3, 5), (0, 1, 4, 7)), ((2,), (0, 7))]


def _result(index: int = 1) -> ChunkResult:
    x = np.array([[True, False, True], [False, False, True]])
    path_edges, path_offsets, vertex_paths, vertex_offsets = pack_paths(PATHS)
    return ChunkResult(
        index=index,
        x_packed=np.packbits(x, axis=1),
        path_edges=path_edges,
        path_offsets=path_offsets,
        vertex_paths=vertex_paths,
        vertex_offsets=vertex_offsets,
        graph_sha256="abc",
        seconds=0.5,
    )


def test_paths_round_trip_through_the_packed_arrays() -> None:
    result = _result()
    assert result.paths() == PATHS
    assert result.path_offsets.tolist() == [0, 3, 4]
    assert result.vertex_offsets.tolist() == [0, 4, 6]
    empty = pack_paths([])
    assert [a.tolist() for a in empty] == [[], [0], [], [0]]


def test_parts_dir_and_chunk_path() -> None:
    assert parts_dir("/tmp/x/data.npz") == Path("/tmp/x/data.npz.parts")
    assert chunk_path(Path("p"), 12) == Path("p/chunk_000012.npz")


def test_a_saved_chunk_loads_back(tmp_path: Path) -> None:
    save_chunk(tmp_path, _result(), build_key="k1", num_worlds=2)
    loaded = load_chunk(chunk_path(tmp_path, 1), index=1, build_key="k1", num_worlds=2, num_edges=3)
    assert loaded is not None
    assert loaded.paths() == PATHS
    assert loaded.x_packed.tobytes() == _result().x_packed.tobytes()
    assert loaded.graph_sha256 == "abc"
    assert loaded.seconds == 0.5


def test_damaged_or_unexpected_chunks_are_ignored_and_foreign_ones_refused(tmp_path: Path) -> None:
    save_chunk(tmp_path, _result(), build_key="k1", num_worlds=2)
    path = chunk_path(tmp_path, 1)
    assert load_chunk(path, index=2, build_key="k1", num_worlds=2, num_edges=3) is None
    assert load_chunk(path, index=1, build_key="k1", num_worlds=3, num_edges=3) is None
    with pytest.raises(DatasetError, match="chunks of another build"):
        load_chunk(path, index=1, build_key="k2", num_worlds=2, num_edges=3)
    path.write_bytes(path.read_bytes()[:50])
    assert load_chunk(path, index=1, build_key="k1", num_worlds=2, num_edges=3) is None


def test_remove_parts_keeps_foreign_files(tmp_path: Path) -> None:
    parts = tmp_path / "out.npz.parts"
    for i in range(2):
        save_chunk(parts, _result(i), build_key="k", num_worlds=2)
    (parts / "notes.txt").write_text("mine")
    remove_parts(parts, 2)
    assert sorted(p.name for p in parts.iterdir()) == ["notes.txt"]
    (parts / "notes.txt").unlink()
    remove_parts(parts, 2)
    assert not parts.exists()
