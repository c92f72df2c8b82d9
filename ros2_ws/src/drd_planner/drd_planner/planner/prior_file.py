"""The world-prior file: one graph, its training worlds over every edge, and zero or more trees.

Format ``drd_planner.prior`` version 1: a checksummed ``.npz`` (:mod:`drd_planner.data.npz_format`;
read with ``allow_pickle=False``, so loading never executes code) with a JSON header (name, domain
and its spec, check metadata, switch threshold eta, alpha, kappa, online-library settings, one entry
per tree with its name, start, goal and build info, provenance, SHA-256 digests) and these arrays:

================== ======== ===============================================================
name               dtype    shape and meaning
================== ======== ===============================================================
edges              int64    (E, 2) vertex ids of each edge
lengths            float64  (E,) edge lengths in the domain's length unit
costs              float64  (E,) cost of checking each edge
worlds_bits        uint8    (n, ceil(E / 8)) ``np.packbits(X_train, axis=1)``; True = free
world_weights      float64  optional (n,) positive prior weights
vertex_states      float64  optional (V, d) vertex states
traj_states        float64  optional (K, D) states along every edge; ``traj_offsets`` (E + 1,)
t<i>_path_edges    int64    tree i's library paths concatenated; ``t<i>_path_offsets`` (m + 1,)
t<i>_vertex_paths  int64    optional, the same as vertex ids; ``t<i>_vertex_offsets``
t<i>_node_*        ...      tree i's nodes: ``edge`` int32 (N,), ``children`` int32 (N, 2),
                            ``num_active`` int32, ``active_fraction`` float64, ``best_path`` int32
t<i>_free_fraction float32  (N, K) leaf bias over ``t<i>_library_edges`` int64 (K,)
================== ======== ===============================================================

Tree files (``drd_planner.tree``, versions 1 and 2, as ``drd build-tree`` wrote them before) load as
a prior with one tree and no worlds over the other edges: they plan their own query only, and any
other query is refused with the command that rebuilds them.
"""

from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner import __version__
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.library import PathLibrary
from drd_planner.core.tree import DecisionTree
from drd_planner.data.npz_format import read_checked_npz, write_checked_npz
from drd_planner.data.ragged import pack_ragged, unpack_ragged
from drd_planner.data.tree_file import ARRAY_DTYPES as TREE_DTYPES
from drd_planner.data.tree_file import FORMAT_NAME as TREE_FORMAT_NAME
from drd_planner.data.tree_file import TreeBundle, load_tree
from drd_planner.exceptions import DrdError, PriorFileError
from drd_planner.planner.prior import QueryTree, WorldPrior

__all__ = ["FORMAT_NAME", "FORMAT_VERSION", "load_prior", "load_tree_bundle", "save_prior"]

FORMAT_NAME = "drd_planner.prior"
FORMAT_VERSION = 1

#: The arrays of one tree (library and nodes) and their dtypes, as in a tree file.
_NODE_ARRAYS: dict[str, npt.DTypeLike] = {
    name: TREE_DTYPES[name]
    for name in (
        "node_edge",
        "node_children",
        "node_num_active",
        "node_active_fraction",
        "node_best_path",
        "library_edges",
        "free_fraction",
        "path_edges",
        "path_offsets",
    )
}


def save_prior(path: str | Path, prior: WorldPrior) -> Path:
    """Write ``prior`` to ``path`` (``.npz``) atomically; returns the path written.

    Raises:
        PriorFileError: the prior has no training worlds over every edge (a tree file's prior).
    """
    if prior.worlds is None:
        raise PriorFileError(
            "a prior without training worlds over every edge cannot be saved as a prior file"
        )
    graph = prior.graph
    arrays: dict[str, npt.NDArray[Any]] = {
        "edges": graph.edges.astype(np.int64),
        "lengths": graph.lengths.astype(np.float64),
        "costs": prior.edge_costs.astype(np.float64),
        "worlds_bits": np.packbits(prior.worlds, axis=1),
    }
    if prior.world_weights is not None:
        arrays["world_weights"] = prior.world_weights.astype(np.float64)
    if graph.vertex_states is not None:
        arrays["vertex_states"] = graph.vertex_states.astype(np.float64)
    if prior.edge_trajectories is not None:
        arrays["traj_states"], arrays["traj_offsets"] = pack_ragged(prior.edge_trajectories, np.float64)
    trees = []
    for i, qt in enumerate(prior.trees):
        t = qt.tree
        node = {
            "node_edge": t.edge,
            "node_children": t.children,
            "node_num_active": t.num_active,
            "node_active_fraction": t.active_fraction,
            "node_best_path": t.best_path,
            "library_edges": t.library_edges,
            "free_fraction": t.free_fraction,
        }
        node["path_edges"], node["path_offsets"] = pack_ragged(qt.library.path_edges, np.int64)
        for name, arr in node.items():
            arrays[f"t{i}_{name}"] = np.ascontiguousarray(arr, dtype=_NODE_ARRAYS[name])
        if qt.library.vertex_paths is not None:
            arrays[f"t{i}_vertex_paths"], arrays[f"t{i}_vertex_offsets"] = pack_ragged(
                qt.library.vertex_paths, np.int64
            )
        trees.append({"name": qt.name, "start": qt.start, "goal": qt.goal, "info": t.info})
    header = {
        "software_version": __version__,
        "name": prior.name,
        "domain": prior.domain,
        "domain_spec": prior.domain_spec,
        "check_metadata": prior.check_metadata,
        "num_vertices": graph.num_vertices,
        "directed": graph.directed,
        "num_worlds": prior.num_worlds,
        "eta": prior.eta,
        "alpha": prior.alpha,
        "pseudo_count": prior.pseudo_count,
        "max_paths": prior.max_paths,
        "library_seed": prior.library_seed,
        "trees": trees,
        "provenance": prior.provenance,
    }
    return write_checked_npz(
        path,
        format_name=FORMAT_NAME,
        format_version=FORMAT_VERSION,
        header=header,
        arrays=arrays,
        error=PriorFileError,
    )


def _file_format(src: Path) -> str | None:
    """The ``format`` field of a drd_planner ``.npz`` header, or None when it cannot be read."""
    import json

    try:
        with np.load(src, allow_pickle=False) as archive:
            if "header" not in archive.files:
                return None
            raw = archive["header"]
        header = json.loads(raw.tobytes().decode())
    except (OSError, ValueError, zipfile.BadZipFile, EOFError, UnicodeDecodeError, KeyError):
        return None
    value = header.get("format") if isinstance(header, dict) else None
    return value if isinstance(value, str) else None


def load_prior(path: str | Path, *, expected_domain: str | None = None) -> WorldPrior:
    """Read and verify a prior file, or a tree file as a prior with one tree.

    Raises:
        PriorFileError: missing, unreadable, corrupt (checksum), another format or version, built for
            another domain than ``expected_domain``, or internally inconsistent (the message says which).
    """
    src = Path(path)
    if src.is_dir():
        raise PriorFileError(f"{src} is a directory, not a prior file")
    if src.is_file() and _file_format(src) == TREE_FORMAT_NAME:
        try:
            bundle = load_tree(src, expected_domain=expected_domain)
        except DrdError as exc:
            raise PriorFileError(str(exc)) from exc
        return prior_from_bundle(bundle)
    header, arrays = read_checked_npz(
        src,
        format_name=FORMAT_NAME,
        format_version=FORMAT_VERSION,
        error=PriorFileError,
        what="prior or tree file",
    )
    domain = str(header.get("domain"))
    if expected_domain is not None and domain != expected_domain:
        raise PriorFileError(f"{src} was built for domain {domain!r}, not {expected_domain!r}")
    try:
        return _prior_from(header, arrays)
    except PriorFileError as exc:
        raise PriorFileError(f"{src} is inconsistent: {exc}") from exc
    except (DrdError, KeyError, TypeError, ValueError, IndexError, OverflowError) as exc:
        raise PriorFileError(f"{src} is inconsistent: {exc}") from exc


def _array(arrays: dict[str, npt.NDArray[Any]], name: str, dtype: npt.DTypeLike) -> npt.NDArray[Any]:
    if name not in arrays:
        raise PriorFileError(f"the array {name!r} is missing")
    arr = arrays[name]
    if arr.dtype != np.dtype(dtype):
        raise PriorFileError(f"array {name!r} has dtype {arr.dtype}, expected {np.dtype(dtype)}")
    if arr.dtype.kind == "f" and not np.all(np.isfinite(arr)):
        raise PriorFileError(f"array {name!r} has a NaN or infinite value")
    return arr


def _prior_from(header: dict[str, Any], arrays: dict[str, npt.NDArray[Any]]) -> WorldPrior:
    graph = ExplicitGraph(
        _array(arrays, "edges", np.int64),
        _array(arrays, "lengths", np.float64),
        int(header["num_vertices"]),
        bool(header["directed"]),
        _array(arrays, "vertex_states", np.float64) if "vertex_states" in arrays else None,
    )
    num_edges = graph.num_edges
    n = int(header["num_worlds"])
    bits = _array(arrays, "worlds_bits", np.uint8)
    if bits.shape != (n, (num_edges + 7) // 8):
        raise PriorFileError(f"worlds_bits has shape {bits.shape}, expected ({n}, {(num_edges + 7) // 8})")
    worlds = np.unpackbits(bits, axis=1, count=num_edges).astype(bool)
    weights = _array(arrays, "world_weights", np.float64) if "world_weights" in arrays else None
    trajectories = None
    if "traj_states" in arrays:
        trajectories = unpack_ragged(
            _array(arrays, "traj_states", np.float64),
            _array(arrays, "traj_offsets", np.int64),
            num_edges,
            "edge trajectory",
            PriorFileError,
        )
    trees = tuple(
        _tree_from(arrays, i, entry, graph, worlds, weights) for i, entry in enumerate(header["trees"])
    )
    kappa = header.get("pseudo_count")
    return WorldPrior(
        name=str(header["name"]),
        domain=str(header["domain"]),
        graph=graph,
        edge_costs=_array(arrays, "costs", np.float64),
        worlds=worlds,
        world_weights=weights,
        trees=trees,
        eta=float(header["eta"]),
        alpha=float(header["alpha"]),
        pseudo_count=None if kappa is None else float(kappa),
        max_paths=int(header["max_paths"]),
        library_seed=int(header["library_seed"]),
        domain_spec=dict(header.get("domain_spec") or {}),
        check_metadata=dict(header.get("check_metadata") or {}),
        edge_trajectories=trajectories,
        provenance=dict(header.get("provenance") or {}),
    )


def _tree_from(
    arrays: dict[str, npt.NDArray[Any]],
    i: int,
    entry: dict[str, Any],
    graph: ExplicitGraph,
    worlds: npt.NDArray[np.bool_],
    weights: npt.NDArray[np.float64] | None,
) -> QueryTree:
    a = {name: _array(arrays, f"t{i}_{name}", dtype) for name, dtype in _NODE_ARRAYS.items()}
    offsets = a["path_offsets"]
    m = offsets.size - 1
    path_edges = unpack_ragged(a["path_edges"], offsets, m, f"tree {i} path", PriorFileError)
    vertex_paths = None
    if f"t{i}_vertex_paths" in arrays:
        vertex_paths = unpack_ragged(
            _array(arrays, f"t{i}_vertex_paths", np.int64),
            _array(arrays, f"t{i}_vertex_offsets", np.int64),
            m,
            f"tree {i} vertex path",
            PriorFileError,
        )
    library = PathLibrary(path_edges, graph.num_edges, vertex_paths)
    n_nodes = a["node_edge"].shape[0]
    children, edge = a["node_children"], a["node_edge"]
    if children.shape != (n_nodes, 2) or children.max(initial=-1) >= n_nodes or children.min(initial=-1) < -1:
        raise PriorFileError(f"tree {i}: node children do not index the node table")
    if edge.max(initial=-1) >= graph.num_edges or edge.min(initial=-1) < -1:
        raise PriorFileError(f"tree {i}: node edges do not index the graph")
    lib_edges = a["library_edges"]
    if not np.array_equal(lib_edges, library.library_edges):
        raise PriorFileError(f"tree {i}: its library edges do not match its paths")
    if a["free_fraction"].shape != (n_nodes, lib_edges.size):
        raise PriorFileError(f"tree {i}: the leaf bias table has the wrong shape")
    if a["node_best_path"].max(initial=-1) >= m or a["node_best_path"].min(initial=-1) < -1:
        raise PriorFileError(f"tree {i}: best paths do not index the library")
    for name in ("node_num_active", "node_active_fraction"):
        if a[name].shape != (n_nodes,):
            raise PriorFileError(f"tree {i}: {name} has the wrong shape")
    tree = DecisionTree(
        edge=edge,
        children=children,
        num_active=a["node_num_active"],
        active_fraction=a["node_active_fraction"],
        library_edges=lib_edges,
        free_fraction=a["free_fraction"],
        best_path=a["node_best_path"],
        num_edges=graph.num_edges,
        num_paths=m,
        info=dict(entry.get("info") or {}),
        world_free=np.ascontiguousarray(worlds[:, lib_edges]),
        world_weights=weights,
    )
    return QueryTree(str(entry["name"]), int(entry["start"]), int(entry["goal"]), library, tree)


def prior_from_bundle(bundle: TreeBundle) -> WorldPrior:
    """A tree file's bundle as a prior with one tree (no training worlds beyond its library edges)."""
    problem = bundle.problem
    if problem.graph is None or problem.start is None or problem.goal is None:
        raise PriorFileError("the tree file has no graph, start or goal")
    meta = problem.metadata
    return WorldPrior(
        name=problem.name,
        domain=bundle.domain,
        graph=problem.graph,
        edge_costs=problem.edge_costs,
        worlds=None,
        trees=(QueryTree(problem.name, int(problem.start), int(problem.goal), problem.library, bundle.tree),),
        eta=bundle.eta,
        alpha=bundle.alpha,
        pseudo_count=bundle.pseudo_count,
        domain_spec=dict(meta.get("domain_spec") or {}),
        check_metadata=dict(meta.get("check_metadata") or {}),
        provenance={**bundle.provenance, "loaded_from": "tree file"},
    )


def load_tree_bundle(path: str | Path, *, expected_domain: str | None = None, index: int = 0) -> TreeBundle:
    """The ``index``-th precomputed tree of a prior (or tree) file as a :class:`TreeBundle`.

    Raises:
        PriorFileError: as :func:`load_prior`, or the file has no such tree.
    """
    prior = load_prior(path, expected_domain=expected_domain)
    if not 0 <= index < len(prior.trees):
        raise PriorFileError(
            f"{path} holds {len(prior.trees)} precomputed trees; tree {index} does not exist "
            "(add one with `drd build-tree --prior FILE --query START,GOAL`)"
        )
    qt = prior.trees[index]
    return TreeBundle(
        problem=prior.query_problem(qt),
        tree=qt.tree,
        domain=prior.domain,
        eta=prior.eta,
        alpha=prior.alpha,
        pseudo_count=prior.pseudo_count,
        provenance=prior.provenance,
    )
