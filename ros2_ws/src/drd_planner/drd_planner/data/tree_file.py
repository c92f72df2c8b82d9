"""The decision-tree file: everything the planner needs online, nothing it must recompute.

Format: a NumPy ``.npz`` archive read with ``allow_pickle=False`` (loading never executes code).
It holds plain numeric arrays plus ``header``, a uint8 array of UTF-8 JSON with the format name
and version, the domain, parameters, provenance, and a SHA-256 per array and over the whole
payload. A file that is corrupt, of another format version, or built for another domain is refused
with a :class:`TreeFileError` that says which.

Arrays: graph (``edges`` (E, 2), ``lengths`` (E,), optional ``vertex_states`` (V, d)), edge
``costs`` (E,), library (``path_edges`` concatenated with ``path_offsets`` (m + 1,), optional
``vertex_paths`` / ``vertex_offsets``), tree nodes (``node_edge``, ``node_children`` (N, 2),
``node_num_active``, ``node_active_fraction``, ``node_best_path``), leaf bias
(``library_edges`` (K,), ``free_fraction`` (N, K) float32); since version 2 also the training worlds'
library-edge outcomes for the posterior leaf (``world_free_bits`` (n, ceil(K / 8)) uint8, rows of
``numpy.packbits``, and optional ``world_weights`` (n,)) and the leaf's ``pseudo_count`` in the header.
Version 1 files still load; they have no training worlds, so their leaf bias stays fixed.
"""

from __future__ import annotations

import io
import itertools
import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner import __version__
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.library import PathLibrary
from drd_planner.core.policies import DEFAULT_ALPHA, DEFAULT_ETA
from drd_planner.core.problem import Problem
from drd_planner.core.tree import DecisionTree
from drd_planner.data.npz_format import array_digest, payload_digest
from drd_planner.exceptions import DrdError, TreeFileError

FORMAT_NAME = "drd_planner.tree"
FORMAT_VERSION = 2
#: Versions this build reads.
READABLE_VERSIONS = (1, 2)

_REQUIRED = {
    "edges": np.int64,
    "lengths": np.float64,
    "costs": np.float64,
    "path_edges": np.int64,
    "path_offsets": np.int64,
    "node_edge": np.int32,
    "node_children": np.int32,
    "node_num_active": np.int32,
    "node_active_fraction": np.float64,
    "node_best_path": np.int32,
    "library_edges": np.int64,
    "free_fraction": np.float32,
}
_OPTIONAL = {
    "vertex_states": np.float64,
    "vertex_paths": np.int64,
    "vertex_offsets": np.int64,
    "world_free_bits": np.uint8,
    "world_weights": np.float64,
}
#: dtype of every array a tree file may hold (the prior file stores each of its trees with the same dtypes).
ARRAY_DTYPES: dict[str, npt.DTypeLike] = {**_REQUIRED, **_OPTIONAL}


@dataclass(frozen=True)
class TreeBundle:
    """A decision tree with the problem it was built for.

    Attributes:
        problem: graph, library, costs, start and goal (no world database).
        tree: the DiRECt tree.
        domain: the domain name (``planar``, ``gccd``, ``helicopter``, ``arm``, ...).
        eta: switch threshold to BiSECt.
        alpha: weight of the data term in the leaf bias.
        pseudo_count: kappa of the posterior leaf, or None for the paper's fixed leaf bias.
        provenance: JSON-safe build information (dataset, seed, command, timings).
    """

    problem: Problem
    tree: DecisionTree
    domain: str
    eta: float = DEFAULT_ETA
    alpha: float = DEFAULT_ALPHA
    pseudo_count: float | None = None
    provenance: dict[str, Any] = field(default_factory=dict)


def _concat(seqs: tuple[npt.NDArray[np.int64], ...]) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    offsets = np.concatenate([[0], np.cumsum([s.size for s in seqs])]).astype(np.int64)
    return np.concatenate(seqs).astype(np.int64), offsets


def save_tree(path: str | Path, bundle: TreeBundle) -> Path:
    """Write ``bundle`` to ``path`` (``.npz``); returns the path written."""
    problem, tree = bundle.problem, bundle.tree
    if problem.graph is None:
        raise TreeFileError("a tree file needs the problem's graph")
    graph = problem.graph
    arrays: dict[str, npt.NDArray[Any]] = {
        "edges": graph.edges,
        "lengths": graph.lengths,
        "costs": problem.edge_costs,
        "node_edge": tree.edge,
        "node_children": tree.children,
        "node_num_active": tree.num_active,
        "node_active_fraction": tree.active_fraction,
        "node_best_path": tree.best_path,
        "library_edges": tree.library_edges,
        "free_fraction": tree.free_fraction,
    }
    arrays["path_edges"], arrays["path_offsets"] = _concat(problem.library.path_edges)
    if graph.vertex_states is not None:
        arrays["vertex_states"] = graph.vertex_states
    if problem.library.vertex_paths is not None:
        arrays["vertex_paths"], arrays["vertex_offsets"] = _concat(problem.library.vertex_paths)
    if tree.world_free is not None:
        arrays["world_free_bits"] = np.packbits(tree.world_free, axis=1)
        if tree.world_weights is not None:
            arrays["world_weights"] = tree.world_weights
    elif bundle.pseudo_count is not None:
        raise TreeFileError("a posterior leaf (pseudo_count) needs a tree that carries its training worlds")
    arrays = {k: np.ascontiguousarray(v, dtype=({**_REQUIRED, **_OPTIONAL})[k]) for k, v in arrays.items()}
    digests = {k: array_digest(k, v) for k, v in arrays.items()}
    header = {
        "format": FORMAT_NAME,
        "format_version": FORMAT_VERSION,
        "software_version": __version__,
        "domain": bundle.domain,
        "name": problem.name,
        "num_vertices": graph.num_vertices,
        "directed": graph.directed,
        "start": problem.start,
        "goal": problem.goal,
        "eta": bundle.eta,
        "alpha": bundle.alpha,
        "pseudo_count": bundle.pseudo_count,
        "num_train_worlds": None if tree.world_free is None else int(tree.world_free.shape[0]),
        "tree_info": tree.info,
        "problem_metadata": problem.metadata,
        "provenance": bundle.provenance,
        "array_sha256": digests,
    }
    header = json.loads(json.dumps(header, sort_keys=True))  # exactly what a reader will see
    header["payload_sha256"] = payload_digest(digests, header)
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    header_bytes = np.frombuffer(json.dumps(header, sort_keys=True).encode(), dtype=np.uint8)
    buffer = io.BytesIO()
    np.savez_compressed(buffer, header=header_bytes, **arrays)  # type: ignore[arg-type]
    out.write_bytes(buffer.getvalue())
    return out


def load_tree(path: str | Path, *, expected_domain: str | None = None) -> TreeBundle:
    """Read and verify a tree file.

    Raises:
        TreeFileError: missing, unreadable, corrupt (checksum), other format or version, or built
            for another domain than ``expected_domain``.
    """
    src = Path(path)
    if not src.is_file():
        raise TreeFileError(f"tree file not found: {src}")
    try:
        with np.load(src, allow_pickle=False) as archive:
            contents = {k: archive[k] for k in archive.files}
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        raise TreeFileError(f"{src} is not a readable tree file ({exc})") from exc
    if "header" not in contents:
        raise TreeFileError(f"{src} has no header: not a drd_planner tree file")
    try:
        header = json.loads(contents.pop("header").tobytes().decode())
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise TreeFileError(f"{src}: the header is corrupt ({exc})") from exc
    if not isinstance(header, dict) or header.get("format") != FORMAT_NAME:
        raise TreeFileError(f"{src} is not a drd_planner tree file")
    version = header.get("format_version")
    if version not in READABLE_VERSIONS:
        raise TreeFileError(
            f"{src} has tree format version {version}; this build reads versions "
            f"{', '.join(str(v) for v in READABLE_VERSIONS)}"
        )
    digests = header.get("array_sha256")
    if not isinstance(digests, dict) or set(digests) != set(contents):
        raise TreeFileError(f"{src} is corrupt: its arrays do not match the header's list")
    for name, arr in contents.items():
        if array_digest(name, arr) != digests[name]:
            raise TreeFileError(f"{src} is corrupt: checksum mismatch in array {name!r}")
    if payload_digest(digests, header) != header.get("payload_sha256"):
        raise TreeFileError(f"{src} is corrupt: payload checksum mismatch")
    missing = [k for k in _REQUIRED if k not in contents]
    if missing:
        raise TreeFileError(f"{src} lacks required arrays: {', '.join(missing)}")
    for name, arr in contents.items():
        want = {**_REQUIRED, **_OPTIONAL}.get(name)
        if want is None or arr.dtype != np.dtype(want):
            raise TreeFileError(f"{src}: array {name!r} has unexpected dtype {arr.dtype}")
    domain = str(header.get("domain"))
    if expected_domain is not None and domain != expected_domain:
        raise TreeFileError(f"{src} was built for domain {domain!r}, not {expected_domain!r}")
    try:
        return _bundle_from(contents, header)
    except (DrdError, KeyError, TypeError, ValueError, IndexError) as exc:
        raise TreeFileError(f"{src} is inconsistent: {exc}") from exc


def check_bundle_fits(bundle: TreeBundle, problem: Problem) -> None:
    """Raise TreeFileError unless ``bundle`` was built for ``problem``'s graph and library.

    Sizes are not enough: two datasets can share a graph and library size but not their paths.
    """
    theirs, ours = bundle.problem, problem
    same = (
        theirs.num_edges == ours.num_edges
        and theirs.num_paths == ours.num_paths
        and all(
            np.array_equal(a, b)
            for a, b in zip(theirs.library.path_edges, ours.library.path_edges, strict=True)
        )
        and (
            theirs.graph is None or ours.graph is None or np.array_equal(theirs.graph.edges, ours.graph.edges)
        )
    )
    if not same:
        raise TreeFileError(
            f"tree {bundle.problem.name!r} was built for another graph or path library than {ours.name!r}"
        )


def _split(flat: npt.NDArray[np.int64], offsets: npt.NDArray[np.int64]) -> tuple[npt.NDArray[np.int64], ...]:
    if offsets.ndim != 1 or offsets[0] != 0 or offsets[-1] != flat.size or np.any(np.diff(offsets) < 0):
        raise ValueError("path offsets do not partition the concatenated paths")
    return tuple(flat[a:b] for a, b in itertools.pairwise(offsets))


def _bundle_from(c: dict[str, npt.NDArray[Any]], header: dict[str, Any]) -> TreeBundle:
    graph = ExplicitGraph(
        c["edges"],
        c["lengths"],
        int(header["num_vertices"]),
        bool(header["directed"]),
        c.get("vertex_states"),
    )
    vertex_paths = None
    if "vertex_paths" in c:
        vertex_paths = _split(c["vertex_paths"], c["vertex_offsets"])
    library = PathLibrary(_split(c["path_edges"], c["path_offsets"]), graph.num_edges, vertex_paths)
    problem = Problem(
        name=str(header["name"]),
        library=library,
        edge_costs=c["costs"],
        graph=graph,
        start=header["start"],
        goal=header["goal"],
        metadata=dict(header.get("problem_metadata") or {}),
    )
    n_nodes = c["node_edge"].shape[0]
    children = c["node_children"]
    if children.shape != (n_nodes, 2) or children.max(initial=-1) >= n_nodes or children.min(initial=-1) < -1:
        raise ValueError("node children do not index the node table")
    edge = c["node_edge"]
    if edge.max(initial=-1) >= graph.num_edges or edge.min(initial=-1) < -1:
        raise ValueError("node edges do not index the graph")
    if c["free_fraction"].shape != (n_nodes, c["library_edges"].size):
        raise ValueError("leaf bias table has the wrong shape")
    if c["node_best_path"].max(initial=-1) >= library.num_paths:
        raise ValueError("best paths do not index the library")
    tree = DecisionTree(
        edge=edge,
        children=children,
        num_active=c["node_num_active"],
        active_fraction=c["node_active_fraction"],
        library_edges=c["library_edges"],
        free_fraction=c["free_fraction"],
        best_path=c["node_best_path"],
        num_edges=graph.num_edges,
        num_paths=library.num_paths,
        info=dict(header.get("tree_info") or {}),
        world_free=_world_free(c, header),
        world_weights=c.get("world_weights"),
    )
    kappa = header.get("pseudo_count")
    if kappa is not None and (tree.world_free is None or not float(kappa) > 0):
        raise ValueError("pseudo_count is set but the file has no training worlds, or it is not positive")
    return TreeBundle(
        problem=problem,
        tree=tree,
        domain=str(header["domain"]),
        eta=float(header["eta"]),
        alpha=float(header["alpha"]),
        pseudo_count=None if kappa is None else float(kappa),
        provenance=dict(header.get("provenance") or {}),
    )


def _world_free(c: dict[str, npt.NDArray[Any]], header: dict[str, Any]) -> npt.NDArray[np.bool_] | None:
    """The (n, K) training-world outcomes unpacked from ``world_free_bits`` (None if absent)."""
    if "world_free_bits" not in c:
        if "world_weights" in c:
            raise ValueError("world_weights without world_free_bits")
        return None
    bits = c["world_free_bits"]
    k = c["library_edges"].size
    n = header.get("num_train_worlds")
    if bits.ndim != 2 or not isinstance(n, int) or bits.shape != (n, (k + 7) // 8):
        raise ValueError("world_free_bits has the wrong shape for the library and num_train_worlds")
    weights = c.get("world_weights")
    if weights is not None and (
        weights.shape != (n,) or np.any(weights < 0) or not np.all(np.isfinite(weights))
    ):
        raise ValueError("world_weights must be n finite non-negative values")
    return np.unpackbits(bits, axis=1, count=k).astype(bool)
