"""The decision-tree file: everything the planner needs online, nothing it must recompute.

Format: a NumPy ``.npz`` archive read by :mod:`drd_planner.data.safe_npz` (never a pickle; sizes,
shapes and dtypes checked before anything is unpacked or allocated). It holds plain numeric arrays plus
``header``, a uint8 array of UTF-8 JSON with the format name and version, the domain, parameters,
provenance, and a SHA-256 per array and over the whole payload. Since anyone who edits a file can
recompute those, the contents are validated too (:mod:`drd_planner.data.content_checks`,
:mod:`drd_planner.data.spec_limits`): finite bounded values, every index in range, library paths that
walk from the start to the goal, a domain spec that rebuilds within budget. A file that is corrupt,
crafted, of another format version, or built for another domain is refused with one
:class:`TreeFileError` that names the file and says what is wrong.

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
from drd_planner.core.region_rule import DEFAULT_REGION_RULE, check_region_rule
from drd_planner.core.tree import DecisionTree
from drd_planner.data.content_checks import (
    MAX_VERTICES,
    MAX_WORLD_OUTCOMES,
    check_bits,
    check_graph_arrays,
    check_tree_arrays,
    check_walks,
    header_dict,
    header_fraction,
    header_int,
    header_number,
    header_text,
)
from drd_planner.data.npz_format import NpzFormat, building_for_domain
from drd_planner.data.ragged import pack_ragged, unpack_ragged
from drd_planner.data.safe_npz import refusing, short
from drd_planner.data.spec_limits import check_domain_spec
from drd_planner.exceptions import ProblemError, TreeFileError

FORMAT_NAME = "drd_planner.tree"
FORMAT_VERSION = 2
#: Versions this build reads.
READABLE_VERSIONS = (1, 2)
_FORMAT = NpzFormat(FORMAT_NAME, FORMAT_VERSION, TreeFileError, "tree file", READABLE_VERSIONS)

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
#: Largest pseudo count (kappa) of the posterior leaf, in worlds.
MAX_PSEUDO_COUNT = 1e9
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
    arrays["path_edges"], arrays["path_offsets"] = pack_ragged(problem.library.path_edges, np.int64)
    if graph.vertex_states is not None:
        arrays["vertex_states"] = graph.vertex_states
    if problem.library.vertex_paths is not None:
        arrays["vertex_paths"], arrays["vertex_offsets"] = pack_ragged(problem.library.vertex_paths, np.int64)
    if tree.world_free is not None:
        arrays["world_free_bits"] = np.packbits(tree.world_free, axis=1)
        if tree.world_weights is not None:
            arrays["world_weights"] = tree.world_weights
    elif bundle.pseudo_count is not None:
        raise TreeFileError("a posterior leaf (pseudo_count) needs a tree that carries its training worlds")
    arrays = {k: np.ascontiguousarray(v, dtype=ARRAY_DTYPES[k]) for k, v in arrays.items()}
    header = {
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
    }
    return _FORMAT.write(path, header, arrays)


def load_tree(path: str | Path, *, expected_domain: str | None = None) -> TreeBundle:
    """Read and verify a tree file.

    Everything is checked before planning may use it, since a crafted file recomputes its checksums:
    sizes before reading (:mod:`~drd_planner.data.safe_npz`), header fields, finite bounded values,
    every index, library paths that walk from the start to the goal, and a sane domain spec
    (:mod:`~drd_planner.data.content_checks`, :mod:`~drd_planner.data.spec_limits`).

    Raises:
        TreeFileError: missing, a directory, unreadable, beyond the size limits, corrupt (checksum),
            other format or version, built for another domain than ``expected_domain``, or
            inconsistent; the message names the file and what is wrong. Nothing else escapes.
    """
    src = Path(path)
    header, contents = _FORMAT.read(src)
    with refusing(TreeFileError, src, "tree file"):
        missing = [k for k in _REQUIRED if k not in contents]
        if missing:
            raise TreeFileError(f"{src} lacks required arrays: {', '.join(missing)}")
        for name, arr in contents.items():
            want = ARRAY_DTYPES.get(name)
            if want is None or arr.dtype != np.dtype(want):
                raise TreeFileError(f"{src}: array {name!r} has unexpected dtype {arr.dtype}")
        for a, b in (("vertex_paths", "vertex_offsets"), ("world_weights", "world_free_bits")):
            if a in contents and b not in contents:
                raise TreeFileError(f"{src}: array {a!r} needs {b!r}")
        with building_for_domain(src, header, error=TreeFileError, expected_domain=expected_domain):
            return _bundle_from(contents, header)


def check_bundle_fits(bundle: TreeBundle, problem: Problem) -> None:
    """Raise TreeFileError unless ``bundle`` was built for ``problem``'s graph and library.

    Sizes are not enough: two datasets can share a graph and library size but not their paths.
    """
    theirs, ours = bundle.problem, problem
    same = (
        theirs.num_edges == ours.num_edges
        and theirs.num_paths == ours.num_paths
        and all(np.array_equal(a, b) for a, b in zip(theirs.library.path_edges, ours.library.path_edges, strict=True))
        and (theirs.graph is None or ours.graph is None or np.array_equal(theirs.graph.edges, ours.graph.edges))
    )
    if not same:
        raise TreeFileError(
            f"tree {bundle.problem.name!r} was built for another graph or path library than {ours.name!r}"
        )


def checked_graph(header: dict[str, Any], c: dict[str, npt.NDArray[Any]], domain_spec: Any) -> ExplicitGraph:
    """The graph of a tree or prior file, its header fields, arrays and domain spec checked first.

    ``header`` holds ``num_vertices``, ``directed`` and ``domain``; ``c`` the arrays ``edges`` (E, 2),
    ``lengths`` (E,), ``costs`` (E,) and optionally ``vertex_states`` (V, d).

    Raises:
        ValueError, DrdError: a header field or an array out of range, or a domain spec beyond budget.
    """
    num_vertices = header_int(header, "num_vertices", low=1, high=MAX_VERTICES)
    directed = header.get("directed")
    if not isinstance(directed, bool):
        raise ValueError(f"header field 'directed' must be true or false, got {short(directed, 40)}")
    domain = header_text(header, "domain")
    edges, lengths, states = c["edges"], c["lengths"], c.get("vertex_states")
    check_graph_arrays(edges, lengths, c["costs"], states, num_vertices)
    check_domain_spec(domain, domain_spec, num_edges=int(edges.shape[0]), mean_edge_length=float(lengths.mean()))
    return ExplicitGraph(edges, lengths, num_vertices, directed, states)


def decision_tree(
    a: dict[str, npt.NDArray[Any]],
    library: PathLibrary,
    info: dict[str, Any],
    world_free: npt.NDArray[np.bool_] | None,
    world_weights: npt.NDArray[np.float64] | None,
) -> DecisionTree:
    """The decision tree of the node arrays ``a`` (``node_*``, ``library_edges``, ``free_fraction``).

    Check the arrays first with :func:`~drd_planner.data.content_checks.check_tree_arrays`.

    Raises:
        ProblemError: ``info`` names a region rule that does not exist.
    """
    rule = info.get("region_rule", DEFAULT_REGION_RULE)
    if not isinstance(rule, str):
        raise ProblemError(f"the tree's region rule must be a string, got {short(rule, 40)}")
    check_region_rule(rule)
    return DecisionTree(
        edge=a["node_edge"],
        children=a["node_children"],
        num_active=a["node_num_active"],
        active_fraction=a["node_active_fraction"],
        library_edges=a["library_edges"],
        free_fraction=a["free_fraction"],
        best_path=a["node_best_path"],
        num_edges=library.num_edges,
        num_paths=library.num_paths,
        info=info,
        world_free=world_free,
        world_weights=world_weights,
    )


def _bundle_from(c: dict[str, npt.NDArray[Any]], header: dict[str, Any]) -> TreeBundle:
    metadata = header_dict(header, "problem_metadata")
    graph = checked_graph(header, c, metadata.get("domain_spec"))
    num_vertices = graph.num_vertices
    path_edges = unpack_ragged(c["path_edges"], c["path_offsets"], None, "path", TreeFileError)
    vertex_paths = None
    if "vertex_paths" in c:
        vertex_paths = unpack_ragged(c["vertex_paths"], c["vertex_offsets"], None, "vertex path", TreeFileError)
    library = PathLibrary(path_edges, graph.num_edges, vertex_paths)
    start = header_int(header, "start", low=0, high=num_vertices - 1)
    goal = header_int(header, "goal", low=0, high=num_vertices - 1)
    check_walks(graph, library.path_edges, start, goal, vertex_paths)
    problem = Problem(
        name=header_text(header, "name"),
        library=library,
        edge_costs=c["costs"],
        graph=graph,
        start=start,
        goal=goal,
        metadata=dict(metadata),
    )
    check_tree_arrays(c, graph.num_edges, library.num_paths, library.library_edges)
    tree = decision_tree(c, library, header_dict(header, "tree_info"), _world_free(c, header), c.get("world_weights"))
    kappa = header_number(header, "pseudo_count", low=0.0, high=MAX_PSEUDO_COUNT, optional=True)
    if kappa is not None and tree.world_free is None:
        raise ValueError("pseudo_count is set but the file has no training worlds")
    return TreeBundle(
        problem=problem,
        tree=tree,
        domain=header_text(header, "domain"),
        eta=header_fraction(header, "eta"),
        alpha=header_fraction(header, "alpha"),
        pseudo_count=kappa,
        provenance=header_dict(header, "provenance"),
    )


def _world_free(c: dict[str, npt.NDArray[Any]], header: dict[str, Any]) -> npt.NDArray[np.bool_] | None:
    """The (n, K) training-world outcomes unpacked from ``world_free_bits`` (None if absent)."""
    if "world_free_bits" not in c:
        if "world_weights" in c:
            raise ValueError("world_weights without world_free_bits")
        return None
    bits = c["world_free_bits"]
    k = c["library_edges"].size
    n = header_int(header, "num_train_worlds", low=1, high=MAX_WORLD_OUTCOMES)
    check_bits(bits, n, k, "world_free_bits")
    weights = c.get("world_weights")
    if weights is not None and (weights.shape != (n,) or not np.all(np.isfinite(weights)) or np.any(weights < 0)):
        raise ValueError("world_weights must be n finite non-negative values")
    return np.unpackbits(bits, axis=1, count=k).view(np.bool_)
