"""What travels between the dataset builder and its workers, and the chunk files of the resume folder.

A :class:`ChunkTask` names consecutive worlds of one build; a worker answers it with a
:class:`ChunkResult` (the chunk's rows of X, bit-packed, and its worlds' distinct k shortest paths).
Each finished result is written to ``<out>.parts/chunk_NNNNNN.npz``, a checksummed file of
:mod:`drd_planner.data.npz_format` tagged with the build's key, so that an interrupted build resumes
by loading the chunks it finds there.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner import __version__
from drd_planner.arrays import IntArray
from drd_planner.data.npz_format import NpzFormat
from drd_planner.data.ragged import pack_ragged
from drd_planner.exceptions import DatasetError

__all__ = [
    "CHUNK_FORMAT",
    "CHUNK_FORMAT_VERSION",
    "ChunkResult",
    "ChunkTask",
    "EdgeTuple",
    "VertexTuple",
    "chunk_path",
    "load_chunk",
    "pack_paths",
    "parts_dir",
    "remove_parts",
    "save_chunk",
]

#: A path as its edge ids, and as its vertex ids (start first).
EdgeTuple = tuple[int, ...]
VertexTuple = tuple[int, ...]

CHUNK_FORMAT = "drd_planner.dataset_chunk"
CHUNK_FORMAT_VERSION = 1
_FORMAT = NpzFormat(CHUNK_FORMAT, CHUNK_FORMAT_VERSION, DatasetError, "dataset chunk file")

_LOG = logging.getLogger(__name__)
_ARRAYS = ("x_packed", "path_edges", "path_offsets", "vertex_paths", "vertex_offsets")


@dataclass(frozen=True)
class ChunkTask:
    """One work unit: consecutive worlds ``first .. first + len(seeds) - 1`` of one build.

    Attributes:
        index: chunk number (0-based).
        first: index of the chunk's first world.
        seeds: the chunk's world seeds (see :func:`~drd_planner.data.seeding.world_seeds`), or with a file
            source that is not seeded, the worlds' 0-based indices in the source.
        domain: domain name.
        spec_json: the domain spec as canonical JSON (sorted keys).
        factory: "module:attribute" that rebuilds the domain, or None for the registry.
        world_model: world model name.
        k: Yen's k per world.
        source_json: the world source's ``worker_data`` as canonical JSON (files with their SHA-256; see
            :mod:`drd_planner.data.world_sources`), or None: worlds drawn from ``world_model``.
    """

    index: int
    first: int
    seeds: tuple[int, ...]
    domain: str
    spec_json: str
    factory: str | None
    world_model: str
    k: int
    source_json: str | None = None


@dataclass(frozen=True)
class ChunkResult:
    """What a worker returns for one chunk.

    Attributes:
        index: chunk number.
        x_packed: (c, ceil(E / 8)) uint8, ``np.packbits`` of the chunk's c rows of X along edges.
        path_edges: the chunk's distinct k-shortest paths' edge ids, concatenated (int64).
        path_offsets: (p + 1,) int64 offsets of the p paths into ``path_edges``.
        vertex_paths: the same paths as vertex ids (start first), concatenated (int64).
        vertex_offsets: (p + 1,) int64 offsets into ``vertex_paths``.
        graph_sha256: digest of the graph the worker used (see
            :func:`~drd_planner.data.dataset_worker.graph_digest`).
        seconds: wall time of the task in seconds.
    """

    index: int
    x_packed: npt.NDArray[np.uint8]
    path_edges: IntArray
    path_offsets: IntArray
    vertex_paths: IntArray
    vertex_offsets: IntArray
    graph_sha256: str
    seconds: float = 0.0

    def paths(self) -> list[tuple[EdgeTuple, VertexTuple]]:
        """The chunk's paths as ``(edge ids, vertex ids)`` tuples."""
        e_off, v_off = self.path_offsets.tolist(), self.vertex_offsets.tolist()
        edges, verts = self.path_edges.tolist(), self.vertex_paths.tolist()
        return [
            (tuple(edges[e_off[j] : e_off[j + 1]]), tuple(verts[v_off[j] : v_off[j + 1]]))
            for j in range(len(e_off) - 1)
        ]


def pack_paths(
    paths: Sequence[tuple[EdgeTuple, VertexTuple]],
) -> tuple[IntArray, IntArray, IntArray, IntArray]:
    """``(path_edges, path_offsets, vertex_paths, vertex_offsets)`` of ``paths``, as in :class:`ChunkResult`."""
    path_edges, path_offsets = pack_ragged([e for e, _ in paths], np.int64)
    vertex_paths, vertex_offsets = pack_ragged([v for _, v in paths], np.int64)
    return path_edges, path_offsets, vertex_paths, vertex_offsets


def parts_dir(out: str | Path) -> Path:
    """The resume directory of a build writing ``out``: ``<out>.parts`` next to it."""
    out_path = Path(out)
    return out_path.with_name(out_path.name + ".parts")


def chunk_path(parts: Path, index: int) -> Path:
    """The file of chunk ``index`` in the resume directory ``parts``."""
    return parts / f"chunk_{index:06d}.npz"


def save_chunk(parts: Path, result: ChunkResult, *, build_key: str, num_worlds: int) -> None:
    """Write ``result`` (a chunk of ``num_worlds`` worlds of build ``build_key``) to its chunk file."""
    arrays: dict[str, npt.NDArray[Any]] = {
        "x_packed": result.x_packed,
        "path_edges": result.path_edges,
        "path_offsets": result.path_offsets,
        "vertex_paths": result.vertex_paths,
        "vertex_offsets": result.vertex_offsets,
    }
    header = {
        "build_key": build_key,
        "index": result.index,
        "num_worlds": num_worlds,
        "graph_sha256": result.graph_sha256,
        "seconds": result.seconds,
        "software_version": __version__,
    }
    _FORMAT.write(chunk_path(parts, result.index), header, arrays)


def load_chunk(path: Path, *, index: int, build_key: str, num_worlds: int, num_edges: int) -> ChunkResult | None:
    """A finished chunk, or None when the file is damaged (it is then evaluated again).

    Raises:
        DatasetError: the chunk belongs to another build.
    """
    try:
        header, arrays = _FORMAT.read(path)
    except DatasetError as exc:
        _LOG.warning("ignoring damaged chunk file (it will be evaluated again): %s", exc)
        return None
    if header.get("build_key") != build_key:
        raise DatasetError(
            f"{path.parent} holds chunks of another build (other domain, spec, world model, seed, number "
            "of worlds, chunk size, k or software version); delete that folder or choose another output file"
        )
    want_x = (num_worlds, (num_edges + 7) // 8)
    if header.get("index") != index or set(arrays) != set(_ARRAYS) or arrays["x_packed"].shape != want_x:
        _LOG.warning("ignoring chunk file with unexpected contents (it will be evaluated again): %s", path)
        return None
    return ChunkResult(
        index=index,
        x_packed=arrays["x_packed"].astype(np.uint8),
        path_edges=arrays["path_edges"].astype(np.int64),
        path_offsets=arrays["path_offsets"].astype(np.int64),
        vertex_paths=arrays["vertex_paths"].astype(np.int64),
        vertex_offsets=arrays["vertex_offsets"].astype(np.int64),
        graph_sha256=str(header.get("graph_sha256")),
        seconds=float(header.get("seconds", 0.0)),
    )


def remove_parts(parts: Path, num_chunks: int) -> None:
    """Delete a build's ``num_chunks`` chunk files, and the folder when nothing else is in it."""
    for i in range(num_chunks):
        chunk_path(parts, i).unlink(missing_ok=True)
    try:
        parts.rmdir()
    except OSError:
        _LOG.warning("left %s in place: it holds files this build did not write", parts)
