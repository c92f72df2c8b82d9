"""A planning problem: graph, path library, edge costs and (optionally) a world database."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.library import PathLibrary
from drd_planner.core.worlds import WorldDatabase
from drd_planner.exceptions import ProblemError


@dataclass(frozen=True)
class Problem:
    """Everything a policy needs to know before the first check.

    Attributes:
        name: a label (dataset folder name, domain name).
        library: the m candidate paths over E tests.
        edge_costs: (E,) float64 positive cost of checking each edge (1 in every benchmark).
        graph: the explicit graph, when there is one (synthetic Bernoulli sets have none).
        start: start vertex id, or None.
        goal: goal vertex id, or None.
        worlds: the sampled-world database, or None.
        metadata: free-form JSON-safe provenance (domain, source, import statistics).
    """

    name: str
    library: PathLibrary
    edge_costs: FloatArray
    graph: ExplicitGraph | None = None
    start: int | None = None
    goal: int | None = None
    worlds: WorldDatabase | None = None
    metadata: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        costs = np.asarray(self.edge_costs, dtype=np.float64)
        num_edges = self.library.num_edges
        if costs.shape != (num_edges,):
            raise ProblemError(f"edge costs must have shape ({num_edges},), got {costs.shape}")
        if not np.all(np.isfinite(costs)) or np.any(costs <= 0):
            raise ProblemError("edge costs must be finite and positive")
        object.__setattr__(self, "edge_costs", costs)
        if self.graph is not None and self.graph.num_edges != num_edges:
            raise ProblemError(f"graph has {self.graph.num_edges} edges but the library indexes {num_edges}")
        if self.worlds is not None:
            if self.worlds.X.shape[1] != num_edges:
                raise ProblemError(f"world database has {self.worlds.X.shape[1]} edge columns, problem has {num_edges}")
            if self.worlds.R.shape[1] != self.library.num_paths:
                raise ProblemError(
                    f"world database has {self.worlds.R.shape[1]} path columns, library has {self.library.num_paths}"
                )

    @property
    def num_edges(self) -> int:
        """E."""
        return self.library.num_edges

    @property
    def num_paths(self) -> int:
        """M."""
        return self.library.num_paths

    def require_worlds(self) -> WorldDatabase:
        """The world database, or a clear error when the problem has none."""
        if self.worlds is None:
            raise ProblemError(f"problem {self.name!r} has no world database")
        return self.worlds
