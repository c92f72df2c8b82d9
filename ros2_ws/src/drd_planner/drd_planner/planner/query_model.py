"""What one query needs before its first check: its graph, library, tree and bias (cached per query)."""

from __future__ import annotations

from dataclasses import dataclass

from drd_planner.arrays import FloatArray
from drd_planner.core.library import PathLibrary
from drd_planner.core.tree import TreeNodes
from drd_planner.planner.prior import QueryTree
from drd_planner.planner.probe import Probe
from drd_planner.planner.query_graph import QueryGraph

__all__ = ["QueryModel"]


@dataclass(frozen=True)
class QueryModel:
    """What one query needs before its first check (cached per query).

    Attributes:
        query: the graph, worlds and costs it plans over (the prior's, or with motions to off-graph states).
        library: its path library, or None when no training world has a free path (then the graph
            stage starts at once) or when it is not built yet (``library_pending``).
        tree: the precomputed tree, or one grown online; None without a library.
        theta: (E,) BiSECt's training bias.
        label: ``tree:<name>`` or ``online``.
        build_s: seconds it took to build.
        precomputed: the prior's tree it uses, or None for a model built online.
        reused: handed out from the planner's query cache (built by an earlier plan of the query).
        probe: the union path checked before the library is built (:mod:`~drd_planner.planner.probe`), or None.
        library_pending: the library is built only when a plan needs it, after the probe or the lead
            (:mod:`~drd_planner.planner.lead`).
    """

    query: QueryGraph
    library: PathLibrary | None
    tree: TreeNodes | None
    theta: FloatArray
    label: str
    build_s: float
    precomputed: QueryTree | None = None
    reused: bool = False
    probe: Probe | None = None
    library_pending: bool = False

    @property
    def start(self) -> int:
        """Start vertex id (in the query graph)."""
        return self.query.start

    @property
    def goal(self) -> int:
        """Goal vertex id (in the query graph)."""
        return self.query.goal
