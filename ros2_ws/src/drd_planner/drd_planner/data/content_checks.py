"""What a loaded tree or prior must satisfy before planning may use it, beyond its checksums.

Checksums only catch accidents: a crafted file recomputes them. So the loaders of tree files
(:mod:`drd_planner.data.tree_file`) and prior files (:mod:`drd_planner.planner.prior_file`) check here
that every header field has its type and a sane range, every float is finite and bounded, every index
points into what it indexes, and every library path is a walk from the query's start to its goal along
the graph's edges: a path that is not (for example a single edge far from the start) would be published
as a plan. Every check raises :class:`~drd_planner.exceptions.ProblemError` with what is wrong; the
loaders prefix the file.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.exceptions import ProblemError

__all__ = [
    "MAX_COORDINATE_M",
    "MAX_EDGE_COST",
    "MAX_EDGE_LENGTH",
    "MAX_STATE_DIMENSIONS",
    "MAX_TREE_NODES",
    "MAX_VERTICES",
    "MAX_WORLD_OUTCOMES",
    "check_bits",
    "check_graph_arrays",
    "check_tree_arrays",
    "check_walks",
    "header_dict",
    "header_fraction",
    "header_int",
    "header_number",
    "header_text",
]

MAX_COORDINATE_M = 1e6
"""Largest |value| of any vertex state component: metres for positions (1000 km), radians for angles.
The shipped graphs stay within 700 m (helicopter) and 3.9 rad (arm)."""

MAX_EDGE_LENGTH = 1e7
"""Largest edge length (domain length unit); the shipped edges are at most 207 m or 3.4 rad long."""

MAX_EDGE_COST = 1e9
"""Largest cost of checking one edge (the benchmarks use 1); bounded so that sums stay finite."""

MAX_VERTICES = 10_000_000
"""Most vertices a graph may declare (the shipped graphs have 489-731; the authors' largest 6780)."""

MAX_STATE_DIMENSIONS = 64
"""Most components of a vertex state (the helicopter has 4, the Panda arm 7)."""

MAX_TREE_NODES = 1_000_000
"""Most nodes of one decision tree (``build_tree`` stops at 100 000; the shipped trees have 11-67)."""

MAX_WORLD_OUTCOMES = 2**29
"""Most training-world outcomes (worlds x edges) one file may unpack to booleans: 512 MiB. The shipped
files hold at most 5.4 million (1800 worlds x 3012 edges)."""


def _fail(message: str) -> ProblemError:
    return ProblemError(message)


def header_int(header: Mapping[str, Any], key: str, *, low: int, high: int) -> int:
    """``header[key]`` as an int in [low, high] (a JSON bool or float is refused)."""
    value = header.get(key)
    if type(value) is not int or not low <= value <= high:
        raise _fail(f"header field {key!r} must be an integer in [{low}, {high}], got {_show(value)}")
    return value


def header_number(
    header: Mapping[str, Any], key: str, *, low: float, high: float, optional: bool = False
) -> float | None:
    """``header[key]`` as a finite float in (low, high] (None allowed when ``optional``)."""
    value = header.get(key)
    if value is None and optional:
        return None
    if not isinstance(value, int | float) or isinstance(value, bool) or not low < float(value) <= high:
        raise _fail(f"header field {key!r} must be a number in ({low}, {high}], got {_show(value)}")
    return float(value)


def header_fraction(header: Mapping[str, Any], key: str) -> float:
    """``header[key]`` as a number in (0, 1] (eta, alpha)."""
    value = header_number(header, key, low=0.0, high=1.0)
    assert value is not None
    return value


def header_dict(header: Mapping[str, Any], key: str) -> dict[str, Any]:
    """``header[key]`` as a dict ({} when absent or null)."""
    value = header.get(key)
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise _fail(f"header field {key!r} must be an object, got {type(value).__name__}")
    return value


def header_text(header: Mapping[str, Any], key: str, *, max_chars: int = 256) -> str:
    """``header[key]`` as a non-empty string of at most ``max_chars`` characters."""
    value = header.get(key)
    if not isinstance(value, str) or not 0 < len(value) <= max_chars:
        raise _fail(f"header field {key!r} must be a name of 1 to {max_chars} characters, got {_show(value)}")
    return value


def _show(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 60 else f"{text[:57]}..."


def _finite_within(arr: npt.NDArray[Any], name: str, low: float, high: float) -> None:
    """Refuse NaN, infinities and values outside [low, high]."""
    if arr.size and not (np.all(np.isfinite(arr)) and arr.min() >= low and arr.max() <= high):
        raise _fail(f"{name} must be finite and within [{low:g}, {high:g}]")


def check_graph_arrays(
    edges: npt.NDArray[Any],
    lengths: npt.NDArray[Any],
    costs: npt.NDArray[Any],
    vertex_states: npt.NDArray[Any] | None,
    num_vertices: int,
) -> None:
    """Shapes, index ranges and finite bounded values of a graph's arrays (before it is built)."""
    if edges.ndim != 2 or edges.shape[1] != 2 or edges.shape[0] == 0:
        raise _fail(f"graph edges must have shape (E >= 1, 2), got {edges.shape}")
    num_edges = edges.shape[0]
    if edges.min() < 0 or edges.max() >= num_vertices:
        raise _fail(f"graph edges name vertices outside [0, {num_vertices})")
    for name, arr, high in (("edge lengths", lengths, MAX_EDGE_LENGTH), ("edge costs", costs, MAX_EDGE_COST)):
        if arr.shape != (num_edges,):
            raise _fail(f"{name} must have shape ({num_edges},), got {arr.shape}")
        _finite_within(arr, name, 0.0, high)
    if np.any(costs <= 0):
        raise _fail("edge costs must be positive")
    if vertex_states is not None:
        if vertex_states.ndim != 2 or vertex_states.shape[0] != num_vertices:
            raise _fail(f"vertex states must have shape ({num_vertices}, d), got {vertex_states.shape}")
        if not 1 <= vertex_states.shape[1] <= MAX_STATE_DIMENSIONS:
            raise _fail(f"vertex states must have 1 to {MAX_STATE_DIMENSIONS} components")
        _finite_within(vertex_states, "vertex states", -MAX_COORDINATE_M, MAX_COORDINATE_M)


def check_walks(
    graph: ExplicitGraph,
    path_edges: Sequence[IntArray],
    start: int,
    goal: int,
    vertex_paths: Sequence[IntArray] | None = None,
) -> None:
    """Every library path is a walk from ``start`` to ``goal`` along the graph (and matches its vertices).

    Edge ids must already be known to index the graph (:class:`~drd_planner.core.library.PathLibrary`).
    """
    for label, v in (("start", start), ("goal", goal)):
        if not 0 <= v < graph.num_vertices:
            raise _fail(f"the {label} vertex {v} is outside the graph's {graph.num_vertices} vertices")
    if start == goal:
        raise _fail(f"the start and goal are the same vertex {start}")
    sizes = np.array([p.size for p in path_edges], dtype=np.int64)
    flat = np.concatenate(path_edges).astype(np.int64)
    n = flat.size
    last = np.cumsum(sizes) - 1
    is_last = np.zeros(n, dtype=bool)
    is_last[last] = True
    is_first = np.zeros(n, dtype=bool)
    is_first[last - sizes + 1] = True
    a, b = graph.edges[flat, 0], graph.edges[flat, 1]
    if graph.directed:
        before, after = a, b
        ok = np.ones(n, dtype=bool)
    else:
        # The vertex between two consecutive edges is the one they share: distinct undirected edges share
        # at most one (the graph has no duplicate edges); -1 when they share none.
        a0, b0, a1, b1 = a[:-1], b[:-1], a[1:], b[1:]
        after = np.empty(n, dtype=np.int64)
        after[:-1] = np.where((a0 == a1) | (a0 == b1), a0, np.where((b0 == a1) | (b0 == b1), b0, -1))
        after[is_last] = goal
        before = np.empty(n, dtype=np.int64)
        before[1:] = after[:-1]
        before[is_first] = start
        ok = (b == before) & (a == after)
    ok |= (a == before) & (b == after)
    ok &= np.where(is_first, before == start, True) & np.where(is_last, after == goal, True)
    ok[:-1] &= (after[:-1] == before[1:]) | is_last[:-1]
    if not ok.all():
        path = int(np.searchsorted(last, np.flatnonzero(~ok)[0]))
        raise _fail(
            f"library path {path} is not a walk from the start vertex {start} to the goal vertex {goal} "
            "along the graph's edges"
        )
    if vertex_paths is not None:
        expected = np.insert(before, last + 1, goal)
        given = [np.asarray(v, dtype=np.int64) for v in vertex_paths]
        if len(given) != len(path_edges) or any(v.size != s + 1 for v, s in zip(given, sizes.tolist(), strict=True)):
            raise _fail("the library's vertex paths do not match its edge paths")
        if not np.array_equal(np.concatenate(given), expected):
            raise _fail("the library's vertex paths do not follow its edge paths")


def check_tree_arrays(
    a: Mapping[str, npt.NDArray[Any]], num_edges: int, num_paths: int, library_edges: IntArray
) -> None:
    """The nodes of a decision tree index what they name: edges, children, paths, leaf-bias columns.

    ``a`` holds ``node_edge``, ``node_children``, ``node_num_active``, ``node_active_fraction``,
    ``node_best_path``, ``library_edges`` and ``free_fraction``; ``library_edges`` is the library's own.
    """
    edge, children = a["node_edge"], a["node_children"]
    if edge.ndim != 1 or not 1 <= edge.shape[0] <= MAX_TREE_NODES:
        raise _fail(f"the tree must have 1 to {MAX_TREE_NODES} nodes, got node_edge of shape {edge.shape}")
    n = edge.shape[0]
    for name in ("node_num_active", "node_active_fraction", "node_best_path"):
        if a[name].shape != (n,):
            raise _fail(f"tree {name} has shape {a[name].shape}, expected ({n},)")
    if edge.min() < -1 or edge.max() >= num_edges:
        raise _fail(f"tree node edges do not index the graph's {num_edges} edges")
    _check_children(children, edge)
    best = a["node_best_path"]
    if best.min() < -1 or best.max() >= num_paths:
        raise _fail(f"tree best paths do not index the library's {num_paths} paths")
    if a["node_num_active"].min() < 0:
        raise _fail("tree node world counts must not be negative")
    _finite_within(a["node_active_fraction"], "tree node active fractions", 0.0, 1.0)
    lib = a["library_edges"]
    if lib.ndim != 1 or not np.array_equal(lib, library_edges):
        raise _fail("the tree's library edges do not match its library paths")
    if a["free_fraction"].shape != (n, lib.size):
        raise _fail(f"the leaf bias table has shape {a['free_fraction'].shape}, expected ({n}, {lib.size})")
    _finite_within(a["free_fraction"], "the leaf bias table", 0.0, 1.0)


def _check_children(children: npt.NDArray[Any], edge: npt.NDArray[Any]) -> None:
    """(n, 2) child ids (-1: none) form a tree over the n nodes: each child after its parent, one parent each."""
    n = edge.shape[0]
    if children.shape != (n, 2) or children.min() < -1 or children.max() >= n:
        raise _fail("tree node children do not index the node table")
    ids = np.arange(n)[:, None]
    if np.any((children != -1) & (children <= ids)):
        raise _fail("tree node children must come after their parent (the tree would loop)")
    used = children[children != -1]
    if np.unique(used).size != used.size:
        raise _fail("a tree node children entry names a node that has another parent")
    if np.any((edge == -1)[:, None] & (children != -1)):
        raise _fail("a tree leaf (no edge) has children")


def check_bits(bits: npt.NDArray[np.uint8], rows: int, cols: int, name: str) -> None:
    """``bits`` is (rows, ceil(cols / 8)) packed booleans and unpacks to at most MAX_WORLD_OUTCOMES."""
    if rows * cols > MAX_WORLD_OUTCOMES:
        raise _fail(f"{name} holds {rows} x {cols} outcomes; at most {MAX_WORLD_OUTCOMES} are read")
    if bits.shape != (rows, (cols + 7) // 8):
        raise _fail(f"{name} has shape {bits.shape}, expected ({rows}, {(cols + 7) // 8})")
