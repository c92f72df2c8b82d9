"""The seam between a domain (graph + generative world models + edge checking) and everything else.

A *domain* owns an explicit graph (vertices as states, edges with lengths and, where the motion is
not a straight line, sampled trajectories), a fixed start and goal, a set of seeded world models,
and an edge checker per world. The dataset builder (``drd_planner.data.dataset_builder``) only
talks to this protocol: it rebuilds the domain in every worker from :meth:`Domain.spec` (a
JSON-able dict), regenerates each world from ``(model, seed)`` and asks the checker for every edge.
The ROS node uses the same checkers on scenes built from messages.

Domains are looked up by name in :data:`DOMAIN_CLASSES` (``"module:Class"`` strings, imported on
first use so that importing this module never pulls in FCL or a URDF parser).
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from typing import Any, Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.exceptions import ProblemError


@runtime_checkable
class EdgeChecker(Protocol):
    """Collision-checks the edges of one domain graph against one world (scene)."""

    def check(self, edge: int) -> bool:
        """True when ``edge`` (0-based id into the domain graph) is collision-free."""
        ...

    def check_many(self, edges: npt.ArrayLike) -> BoolArray:
        """(K,) bool, True where each of the (K,) edge ids is free (same answers as :meth:`check`)."""
        ...


@runtime_checkable
class Domain(Protocol):
    """A planning domain: graph, start/goal, seeded world models and their edge checkers."""

    @property
    def name(self) -> str:
        """Registry name (a key of :data:`DOMAIN_CLASSES`)."""
        ...

    @property
    def graph(self) -> ExplicitGraph:
        """The explicit graph; ``graph.vertex_states`` holds the vertex states."""
        ...

    @property
    def start(self) -> int:
        """Start vertex (0-based)."""
        ...

    @property
    def goal(self) -> int:
        """Goal vertex (0-based)."""
        ...

    @property
    def world_models(self) -> tuple[str, ...]:
        """Names of the world models :meth:`make_world` accepts."""
        ...

    def spec(self) -> dict[str, Any]:
        """JSON-able parameters; ``domain_from_spec(self.name, self.spec())`` rebuilds an equal domain."""
        ...

    def make_world(self, model: str, seed: int) -> Any:
        """The world (scene) of ``model`` drawn with ``seed``; same arguments, same world."""
        ...

    def checker(self, world: Any) -> EdgeChecker:
        """An edge checker for ``world``."""
        ...

    def edge_trajectories(self) -> list[npt.NDArray[np.float64]] | None:
        """Per edge (graph order) a (K_e, D) array of sampled states along it, or None for straight lines."""
        ...

    def check_metadata(self) -> dict[str, Any]:
        """How edges are checked (resolution, margin, vehicle size; with units), for dataset metadata."""
        ...


#: Domain name -> "module:Class"; the class must have a ``from_spec(spec: dict) -> Domain`` classmethod.
DOMAIN_CLASSES: Mapping[str, str] = {
    "planar": "drd_planner.domains.planar:PlanarDomain",
    "se2": "drd_planner.domains.se2:Se2Domain",
    "helicopter": "drd_planner.domains.helicopter:HelicopterDomain",
    "arm": "drd_planner.domains.arm:ArmDomain",
}


def domain_from_spec(name: str, spec: Mapping[str, Any] | None = None) -> Domain:
    """Build the domain ``name`` from its spec (its defaults when ``spec`` is None).

    Raises:
        ProblemError: unknown domain name, or a domain class that cannot be imported.
    """
    target = DOMAIN_CLASSES.get(name)
    if target is None:
        raise ProblemError(f"unknown domain {name!r}; known: {', '.join(sorted(DOMAIN_CLASSES))}")
    module_name, _, class_name = target.partition(":")
    try:
        cls = getattr(importlib.import_module(module_name), class_name)
    except (ImportError, AttributeError) as exc:
        raise ProblemError(f"domain {name!r} is not available: {exc}") from exc
    domain: Domain = cls.from_spec(dict(spec or {}))
    return domain
