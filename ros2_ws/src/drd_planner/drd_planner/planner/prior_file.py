"""The world-prior file: one graph, its training worlds over every edge, and zero or more trees.

Format ``drd_planner.prior`` version 2 (version 1 still loads): a checksummed ``.npz``
(:mod:`drd_planner.data.npz_format`;
read by :mod:`drd_planner.data.safe_npz`, so loading never executes code and checks every size before
it allocates) with a JSON header (name, domain
and its spec, check metadata, switch threshold eta, alpha, kappa, the region rule of online trees
(``region_rule``, absent in older files: the paper's ``probability``), online-library settings, one entry
per tree with its name, start, goal, build info and, from version 2, its own ``leaf`` (eta and kappa
validated on that query, or null for the prior's), provenance, SHA-256 digests) and these arrays:

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

Loading validates what planning needs, not only the checksums a crafted file can recompute: header
fields in range, finite bounded arrays, every index, each tree's library paths as walks from its start to
its goal, and a domain spec within budget (:mod:`drd_planner.data.content_checks`,
:mod:`drd_planner.data.spec_limits`); every refusal is one :class:`PriorFileError`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner import __version__
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.library import PathLibrary
from drd_planner.core.region_rule import DEFAULT_REGION_RULE, REGION_RULES
from drd_planner.data.content_checks import (
    MAX_COORDINATE_M,
    MAX_WORLD_OUTCOMES,
    check_bits,
    check_tree_arrays,
    check_walks,
    header_dict,
    header_fraction,
    header_int,
    header_number,
    header_text,
)
from drd_planner.data.dataset_file import FORMAT_NAME as DATASET_FORMAT_NAME
from drd_planner.data.npz_format import building_for_domain, read_checked_npz, write_checked_npz
from drd_planner.data.ragged import pack_ragged, unpack_ragged
from drd_planner.data.safe_npz import (
    MAX_JSON_INT,
    check_source,
    parse_json_header,
    read_npz_arrays,
    refusing,
    short,
)
from drd_planner.data.tree_file import ARRAY_DTYPES as TREE_DTYPES
from drd_planner.data.tree_file import FORMAT_NAME as TREE_FORMAT_NAME
from drd_planner.data.tree_file import MAX_PSEUDO_COUNT, TreeBundle, checked_graph, decision_tree, load_tree
from drd_planner.exceptions import DrdError, PriorFileError
from drd_planner.planner.prior import LeafSetting, QueryTree, WorldPrior

__all__ = ["FORMAT_NAME", "FORMAT_VERSION", "load_prior", "load_tree_bundle", "save_prior"]

FORMAT_NAME = "drd_planner.prior"
FORMAT_VERSION = 2
#: Versions this reader accepts (version 1 has no per-tree ``leaf``).
READ_VERSIONS = (1, 2)

MAX_TREES = 1000
"""Most precomputed trees one prior file may hold (one per query; ``drd build-tree`` adds one at a time)."""

MAX_LIBRARY_PATHS = 1_000_000
"""Largest ``max_paths`` (m of the libraries built online; the default is 500)."""

_WHAT = "prior or tree file"

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
        raise PriorFileError("a prior without training worlds over every edge cannot be saved as a prior file")
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
        leaf = None if qt.leaf is None else {"eta": qt.leaf.eta, "pseudo_count": qt.leaf.pseudo_count}
        trees.append({"name": qt.name, "start": qt.start, "goal": qt.goal, "info": t.info, "leaf": leaf})
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
        "region_rule": prior.region_rule,
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
    try:
        raw = read_npz_arrays(src, error=PriorFileError, what=_WHAT, names=("header",))["header"]
        header = parse_json_header(raw, error=PriorFileError, src=src)
    except (DrdError, KeyError):
        return None
    value = header.get("format") if isinstance(header, dict) else None
    return value if isinstance(value, str) else None


def load_prior(path: str | Path, *, expected_domain: str | None = None) -> WorldPrior:
    """Read and verify a prior file, or a tree file as a prior with one tree.

    Everything is checked before planning may use it, since a crafted file recomputes its checksums:
    sizes before reading (:mod:`~drd_planner.data.safe_npz`), header fields, finite bounded values,
    every index, library paths that walk from each tree's start to its goal, and a sane domain spec.

    Raises:
        PriorFileError: missing, a directory, not an ``.npz`` file, beyond the size limits, corrupt
            (checksum), another format or version, built for another domain than ``expected_domain``,
            or internally inconsistent; the message names the file and says which. Nothing else escapes.
    """
    src = check_source(path, error=PriorFileError, what=_WHAT)
    found = _file_format(src)
    if found == DATASET_FORMAT_NAME:
        raise PriorFileError(
            f"{src} is a dataset file (drd build-dataset), not a prior: make the prior from it with "
            f"`drd build-tree --dataset {src} --out PRIOR.npz` and give that"
        )
    if found == TREE_FORMAT_NAME:
        try:
            bundle = load_tree(src, expected_domain=expected_domain)
        except DrdError as exc:
            raise PriorFileError(str(exc)) from exc
        with refusing(PriorFileError, src, _WHAT):
            return prior_from_bundle(bundle)
    header, arrays = read_checked_npz(
        src, format_name=FORMAT_NAME, format_version=READ_VERSIONS, error=PriorFileError, what=_WHAT
    )
    with refusing(PriorFileError, src, _WHAT):
        with building_for_domain(src, header, error=PriorFileError, expected_domain=expected_domain):
            return _prior_from(header, arrays)


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
    domain = header_text(header, "domain")
    spec = header_dict(header, "domain_spec")
    names = ("edges", "lengths", "costs", *(("vertex_states",) if "vertex_states" in arrays else ()))
    graph_arrays = {name: _array(arrays, name, TREE_DTYPES[name]) for name in names}
    costs = graph_arrays["costs"]
    graph = checked_graph(header, graph_arrays, spec)
    num_edges = graph.num_edges
    n = header_int(header, "num_worlds", low=1, high=MAX_WORLD_OUTCOMES)
    bits = _array(arrays, "worlds_bits", np.uint8)
    check_bits(bits, n, num_edges, "worlds_bits")
    worlds = np.unpackbits(bits, axis=1, count=num_edges).view(np.bool_)
    weights = _array(arrays, "world_weights", np.float64) if "world_weights" in arrays else None
    trajectories = None
    if "traj_states" in arrays:
        traj = _array(arrays, "traj_states", np.float64)
        if traj.ndim != 2 or not np.all(np.abs(traj) <= MAX_COORDINATE_M):
            raise PriorFileError(f"traj_states must be (K, D) states within +-{MAX_COORDINATE_M:g}")
        trajectories = unpack_ragged(
            traj, _array(arrays, "traj_offsets", np.int64), num_edges, "edge trajectory", PriorFileError
        )
    entries = header.get("trees")
    if not isinstance(entries, list) or len(entries) > MAX_TREES:
        raise PriorFileError(f"header field 'trees' must be a list of at most {MAX_TREES} trees")
    trees = tuple(_tree_from(arrays, i, entry, graph, worlds, weights) for i, entry in enumerate(entries))
    return WorldPrior(
        name=header_text(header, "name"),
        domain=domain,
        graph=graph,
        edge_costs=costs,
        worlds=worlds,
        world_weights=weights,
        trees=trees,
        eta=header_fraction(header, "eta"),
        alpha=header_fraction(header, "alpha"),
        pseudo_count=header_number(header, "pseudo_count", low=0.0, high=MAX_PSEUDO_COUNT, optional=True),
        region_rule=_region_rule(header.get("region_rule", DEFAULT_REGION_RULE), "the prior"),
        max_paths=header_int(header, "max_paths", low=1, high=MAX_LIBRARY_PATHS),
        library_seed=header_int(header, "library_seed", low=0, high=MAX_JSON_INT),
        domain_spec=spec,
        check_metadata=header_dict(header, "check_metadata"),
        edge_trajectories=trajectories,
        provenance=header_dict(header, "provenance"),
    )


def _tree_from(
    arrays: dict[str, npt.NDArray[Any]],
    i: int,
    entry: Any,
    graph: ExplicitGraph,
    worlds: npt.NDArray[np.bool_],
    weights: npt.NDArray[np.float64] | None,
) -> QueryTree:
    if not isinstance(entry, dict):
        raise PriorFileError(f"tree {i}: its header entry must be an object")
    try:
        name = header_text(entry, "name")
        start = header_int(entry, "start", low=0, high=graph.num_vertices - 1)
        goal = header_int(entry, "goal", low=0, high=graph.num_vertices - 1)
        a = {key: _array(arrays, f"t{i}_{key}", dtype) for key, dtype in _NODE_ARRAYS.items()}
        offsets = a["path_offsets"]
        m = offsets.size - 1
        if offsets.ndim != 1 or m < 1:
            raise PriorFileError("its path offsets must list at least one path")
        path_edges = unpack_ragged(a["path_edges"], offsets, m, "path", PriorFileError)
        vertex_paths = None
        if f"t{i}_vertex_paths" in arrays:
            vertex_paths = unpack_ragged(
                _array(arrays, f"t{i}_vertex_paths", np.int64),
                _array(arrays, f"t{i}_vertex_offsets", np.int64),
                m,
                "vertex path",
                PriorFileError,
            )
        library = PathLibrary(path_edges, graph.num_edges, vertex_paths)
        check_walks(graph, library.path_edges, start, goal, vertex_paths)
        check_tree_arrays(a, graph.num_edges, m, library.library_edges)
        leaf = _leaf_from(entry.get("leaf"))
        world_free = np.ascontiguousarray(worlds[:, a["library_edges"]])
        tree = decision_tree(a, library, header_dict(entry, "info"), world_free, weights)
    except DrdError as exc:
        raise PriorFileError(f"tree {i}: {exc}") from exc
    return QueryTree(name, start, goal, library, tree, leaf)


def _region_rule(value: Any, what: str) -> str:
    """A region rule from a header (PriorFileError naming the known ones when it is not one)."""
    if not isinstance(value, str) or value not in REGION_RULES:
        raise PriorFileError(f"{what}'s region rule must be one of {', '.join(REGION_RULES)}, got {short(value, 40)}")
    return value


def _leaf_from(entry: Any) -> LeafSetting | None:
    """A tree's own eta and kappa from its header entry (absent or null: the prior's)."""
    if entry is None:
        return None
    if not isinstance(entry, dict):
        raise PriorFileError(f"its 'leaf' must be an object with eta and pseudo_count, got {short(entry, 40)}")
    return LeafSetting(
        header_fraction(entry, "eta"),
        header_number(entry, "pseudo_count", low=0.0, high=MAX_PSEUDO_COUNT, optional=True),
    )


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
    with refusing(PriorFileError, Path(path), _WHAT):
        return _bundle_of(prior, path, index)


def _bundle_of(prior: WorldPrior, path: str | Path, index: int) -> TreeBundle:
    """The ``index``-th tree of a loaded prior as a bundle."""
    if not 0 <= index < len(prior.trees):
        raise PriorFileError(
            f"{path} holds {len(prior.trees)} precomputed trees; tree {index} does not exist "
            "(add one with `drd build-tree --prior FILE --query START,GOAL`)"
        )
    qt = prior.trees[index]
    leaf = prior.leaf_for(qt)
    return TreeBundle(
        problem=prior.query_problem(qt),
        tree=qt.tree,
        domain=prior.domain,
        eta=leaf.eta,
        alpha=prior.alpha,
        pseudo_count=leaf.pseudo_count,
        provenance=prior.provenance,
    )
