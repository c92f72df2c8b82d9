"""A prior's domain, rebuilt from the spec the prior stores, and checked to build the prior's own graph."""

from __future__ import annotations

from typing import Any

import numpy as np

from drd_planner.domains.online import OnlineDomain
from drd_planner.exceptions import PriorFileError
from drd_planner.planner.prior import WorldPrior
from drd_planner.planning.domain_view import domain_from_stored_spec

__all__ = ["rebuild_domain", "same_graph"]


def rebuild_domain(prior: WorldPrior, name: str) -> OnlineDomain[Any]:
    """The prior's domain rebuilt from its stored spec, after checking it builds the prior's graph.

    Raises:
        PriorFileError: no domain spec, a spec that cannot be rebuilt (any exception), or a graph that
            differs from the stored one.
    """
    if not prior.domain_spec:
        raise PriorFileError(f"{name}: the prior has no domain spec (built from an authors' dataset?)")
    domain = domain_from_stored_spec(prior.domain, prior.domain_spec, label=name, error=PriorFileError)
    if not same_graph(domain, prior):
        raise PriorFileError(f"{name}: the stored graph does not match the graph of its domain spec")
    return domain


def same_graph(domain: OnlineDomain[Any], prior: WorldPrior) -> bool:
    """Whether the domain's graph is the prior's (edges, lengths, direction and vertex states)."""
    ours, theirs = domain.graph, prior.graph
    if (
        ours.edges.shape != theirs.edges.shape
        or not np.array_equal(ours.edges, theirs.edges)
        or not np.allclose(ours.lengths, theirs.lengths)
        or bool(ours.directed) != bool(theirs.directed)
    ):
        return False
    a, b = ours.vertex_states, theirs.vertex_states
    if a is None or b is None:
        return a is None and b is None
    return bool(a.shape == b.shape and np.allclose(a, b))
