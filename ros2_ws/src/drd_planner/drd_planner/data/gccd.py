"""Importer for the authors' dataset folders (``graph_collision_checking_dataset`` format).

A folder holds ``graph.txt`` (``NumVertices:``, ``NumEdges:``, then ``id parent child length``
rows, 1-based), ``path_library.dat`` (one path per line, 1-based vertex ids), ``start_idx.dat``,
``goal_idx.dat``, ``coll_check_results.mat`` (X, worlds x graph rows, 1 = free),
``world_library_assignment.mat`` (R, worlds x paths), ``train_id.mat`` and ``test_id.mat``
(1-based). Optional: ``coord_set.dat`` (2D vertex x y) and ``vertex_coordinates.txt`` (id x y z).

Undirected graphs store both directions as separate rows (and X columns). They are merged into one
test per undirected edge exactly as the authors' ``remove_redundant_edges.m`` does: the row with
parent > child (the lower triangle of the adjacency matrix) is kept and the merged test is free if
either stored direction is free (``merge="or"``; ``merge="and"`` is the conservative choice).
R is recomputed from the merged X and the library so that "path valid" always means "every merged
test free"; how many entries differ from the stored R is recorded in the metadata.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.library import PathLibrary
from drd_planner.core.problem import Problem
from drd_planner.core.worlds import WorldDatabase
from drd_planner.data.matfile import load_mat_variable
from drd_planner.exceptions import DatasetError, ProblemError

REQUIRED_FILES = (
    "graph.txt",
    "path_library.dat",
    "start_idx.dat",
    "goal_idx.dat",
    "coll_check_results.mat",
    "train_id.mat",
    "test_id.mat",
)


@dataclass(frozen=True)
class RawGraph:
    """``graph.txt`` as stored: (M,) 0-based parents, children and lengths, in row order."""

    num_vertices: int
    parents: IntArray
    children: IntArray
    lengths: npt.NDArray[np.float64]


def read_graph_txt(path: Path) -> RawGraph:
    """Parse ``graph.txt``; any malformed line raises DatasetError naming the file and line."""
    if not path.is_file():
        raise DatasetError(f"missing file: {path}")
    lines = path.read_text().splitlines()
    header: dict[str, int] = {}
    body_start = 0
    for i, line in enumerate(lines[:2]):
        key, sep, value = line.partition(":")
        if not sep:
            raise DatasetError(f"{path}: line {i + 1} should be 'NumVertices: N' or 'NumEdges: M'")
        try:
            header[key.strip()] = int(value)
        except ValueError:
            raise DatasetError(f"{path}: line {i + 1}: {value.strip()!r} is not an integer") from None
        body_start = i + 1
    if set(header) != {"NumVertices", "NumEdges"}:
        raise DatasetError(f"{path}: the first two lines must give NumVertices and NumEdges")
    rows = [ln for ln in lines[body_start:] if ln.strip()]
    if len(rows) != header["NumEdges"]:
        raise DatasetError(f"{path}: NumEdges is {header['NumEdges']} but {len(rows)} edge rows follow")
    fields = [ln.split() for ln in rows]
    bad = next((i for i, f in enumerate(fields) if len(f) != 4), None)
    if bad is not None:
        raise DatasetError(f"{path}: line {body_start + bad + 1} must be 'id parent child length' (4 numbers)")
    try:
        table = np.array(fields, dtype=np.float64).reshape(-1, 4)
    except ValueError:
        raise DatasetError(f"{path}: every edge row must be 'id parent child length' (4 numbers)") from None
    nv = header["NumVertices"]
    parents = table[:, 1].astype(np.int64) - 1
    children = table[:, 2].astype(np.int64) - 1
    if table.size and (min(parents.min(), children.min()) < 0 or max(parents.max(), children.max()) >= nv):
        raise DatasetError(f"{path}: vertex ids must lie in 1..{nv}")
    loops = np.flatnonzero(parents == children)
    if loops.size:
        raise DatasetError(f"{path}: line {body_start + int(loops[0]) + 1} is a self-loop, which is not an edge")
    if not np.all(np.isfinite(table[:, 3])) or np.any(table[:, 3] < 0):
        raise DatasetError(f"{path}: edge lengths must be finite and non-negative")
    return RawGraph(nv, parents, children, table[:, 3].copy())


def _read_int(path: Path) -> int:
    if not path.is_file():
        raise DatasetError(f"missing file: {path}")
    try:
        return int(path.read_text().split()[0])
    except (ValueError, IndexError):
        raise DatasetError(f"{path}: expected one integer") from None


def _read_vertex_paths(path: Path, num_vertices: int) -> list[IntArray]:
    if not path.is_file():
        raise DatasetError(f"missing file: {path}")
    paths = []
    for i, line in enumerate(path.read_text().splitlines()):
        if not line.strip():
            continue
        try:
            seq = np.array([int(v) for v in line.split()], dtype=np.int64) - 1
        except ValueError:
            raise DatasetError(f"{path}: line {i + 1} is not a list of vertex ids") from None
        if seq.size < 2 or seq.min() < 0 or seq.max() >= num_vertices:
            raise DatasetError(f"{path}: line {i + 1} must list at least 2 vertex ids in 1..{num_vertices}")
        paths.append(seq)
    if not paths:
        raise DatasetError(f"{path}: the path library is empty")
    return paths


def _read_ids(path: Path, name: str, n: int) -> IntArray:
    ids = load_mat_variable(path, name).astype(np.int64).ravel() - 1
    if ids.size and (ids.min() < 0 or ids.max() >= n):
        raise DatasetError(f"{path}: world ids must lie in 1..{n}")
    return ids


def _read_vertex_states(folder: Path, num_vertices: int) -> npt.NDArray[np.float64] | None:
    coord = folder / "coord_set.dat"
    verts = folder / "vertex_coordinates.txt"
    try:
        if coord.is_file():
            states = np.loadtxt(coord, delimiter=",", ndmin=2)
        elif verts.is_file():
            states = np.loadtxt(verts, ndmin=2)[:, 1:]
        else:
            return None
    except ValueError as exc:
        raise DatasetError(f"cannot read vertex coordinates in {folder}: {exc}") from exc
    if states.shape[0] != num_vertices:
        raise DatasetError(f"{folder}: vertex coordinates list {states.shape[0]} vertices, graph has {num_vertices}")
    return np.asarray(states, dtype=np.float64)


def merge_directions(raw: RawGraph) -> tuple[IntArray, IntArray]:
    """Pair each stored row with its reverse.

    Returns:
        keep: (E,) row index kept for each merged edge (parent > child when both directions exist).
        partner: (E,) row index of the reverse direction, or -1 for one-way rows.
    """
    index = {(int(p), int(c)): i for i, (p, c) in enumerate(zip(raw.parents, raw.children, strict=False))}
    keep, partner = [], []
    for i, (p, c) in enumerate(zip(raw.parents.tolist(), raw.children.tolist(), strict=False)):
        j = index.get((c, p))
        if j is None:
            keep.append(i)
            partner.append(-1)
        elif p > c:
            keep.append(i)
            partner.append(j)
    return np.array(keep, dtype=np.int64), np.array(partner, dtype=np.int64)


def _merged_outcomes(
    path: Path, num_rows: int, keep: IntArray, partner: IntArray, merge: Literal["or", "and"]
) -> BoolArray:
    """X (n, E) of the merged edges: stored rows ``keep``, each merged with its ``partner`` row (-1: none).

    Raises:
        DatasetError: the stored matrix is not (n, num_rows) zeros and ones.
    """
    x_raw = load_mat_variable(path, "coll_check_results")
    if x_raw.ndim != 2 or x_raw.shape[1] != num_rows:
        raise DatasetError(f"{path}: expected worlds x {num_rows} columns, got {x_raw.shape}")
    if not np.isin(x_raw, (0, 1)).all():
        raise DatasetError(f"{path}: entries must be 0 or 1")
    x_raw = x_raw.astype(bool)
    x = x_raw[:, keep]
    paired = partner >= 0
    if paired.any():
        other = x_raw[:, partner[paired]]
        x[:, paired] = (x[:, paired] | other) if merge == "or" else (x[:, paired] & other)
    return x


def _read_library(path: Path, graph: ExplicitGraph) -> PathLibrary:
    """The library of ``path_library.dat`` (1-based vertex paths) on ``graph``."""
    vertex_paths = _read_vertex_paths(path, graph.num_vertices)
    try:
        edge_paths = tuple(graph.vertex_path_to_edges(p) for p in vertex_paths)
        return PathLibrary(edge_paths, graph.num_edges, tuple(vertex_paths))
    except ProblemError as exc:
        raise DatasetError(f"{path}: {exc}") from exc


def _stored_r_mismatches(stored: Path, r: BoolArray) -> int | None:
    """How many entries of the stored R differ from ``r`` (None when the folder has no stored R)."""
    if not stored.is_file():
        return None
    r_stored = load_mat_variable(stored, "world_library_assignment")
    if r_stored.shape != r.shape:
        raise DatasetError(f"{stored}: expected {r.shape} (worlds x paths), got {r_stored.shape}")
    return int((r_stored.astype(bool) != r).sum())


def load_gccd_folder(folder: str | Path, *, merge: Literal["or", "and"] = "or") -> Problem:
    """Load an authors'-format dataset folder as a :class:`Problem` (unit edge costs).

    Raises:
        DatasetError: a file is missing or malformed; the message names it.
    """
    root = Path(folder)
    if not root.is_dir():
        raise DatasetError(f"dataset folder not found: {root}")
    missing = [f for f in REQUIRED_FILES if not (root / f).is_file()]
    if missing:
        raise DatasetError(f"{root}: missing file(s): {', '.join(missing)}")
    raw = read_graph_txt(root / "graph.txt")
    keep, partner = merge_directions(raw)
    x = _merged_outcomes(root / "coll_check_results.mat", raw.parents.size, keep, partner, merge)
    paired = partner >= 0
    one_way = int((~paired).sum())
    directed = not paired.any()
    edges = np.stack([raw.parents[keep], raw.children[keep]], axis=1)
    states = _read_vertex_states(root, raw.num_vertices)
    try:
        graph = ExplicitGraph(edges, raw.lengths[keep], raw.num_vertices, directed, states)
    except ProblemError as exc:
        raise DatasetError(f"{root / 'graph.txt'}: {exc}") from exc
    start = _read_int(root / "start_idx.dat") - 1
    goal = _read_int(root / "goal_idx.dat") - 1
    library = _read_library(root / "path_library.dat", graph)
    n = x.shape[0]
    r = library.valid_paths(x)
    stored_r_mismatch = _stored_r_mismatches(root / "world_library_assignment.mat", r)
    train = _read_ids(root / "train_id.mat", "train_id", n)
    test = _read_ids(root / "test_id.mat", "test_id", n)
    try:
        worlds = WorldDatabase(x, r, train, test)
    except ProblemError as exc:
        raise DatasetError(f"{root}: {exc}") from exc
    metadata = {
        "source": "gccd",
        "folder": root.name,
        "merge": merge,
        "stored_rows": int(raw.parents.size),
        "one_way_rows": one_way,
        "stored_R_mismatches": stored_r_mismatch,
        "sha256": folder_digest(root),
    }
    return Problem(
        name=root.name,
        library=library,
        edge_costs=np.ones(graph.num_edges),
        graph=graph,
        start=start,
        goal=goal,
        worlds=worlds,
        metadata=metadata,
    )


def folder_digest(root: Path) -> str:
    """SHA-256 over the required files' names and bytes (identifies the dataset in provenance)."""
    h = hashlib.sha256()
    for name in REQUIRED_FILES:
        h.update(name.encode())
        h.update((root / name).read_bytes())
    return h.hexdigest()
