"""The seam between a domain (graph + generative world models + edge checking) and everything else.

A *domain* owns an explicit graph (vertices as states, edges with lengths and, where the motion is
not a straight line, sampled trajectories), a fixed start and goal, a set of seeded world models,
and an edge checker per world. The dataset builder (``drd_planner.data.dataset_builder``) only
talks to this protocol: it rebuilds the domain in every worker from :meth:`Domain.spec` (a
JSON-able dict), regenerates each world from ``(model, seed)`` and asks the checker for every edge.
The ROS node uses the same checkers on scenes built from messages.

A domain that stores its built lattice (graph, start and goal vertices) as ``_lattice`` takes its
``lattice``, ``graph``, ``start`` and ``goal`` members from :class:`LatticeMembers`.

Domains are looked up by name in :data:`DOMAIN_CLASSES`, a typed mapping from name to domain class
(:class:`DomainClass`: each has ``from_spec``), whose classes are imported on first use so that importing
this module never pulls in FCL or a URDF parser.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping
from typing import TYPE_CHECKING, Any, Generic, Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.exceptions import ProblemError

if TYPE_CHECKING:
    from typing_extensions import TypeVar

    from drd_planner.domains.online import OnlineDomain

    #: The world type of a domain (a bare ``Domain`` is a domain of any world).
    W = TypeVar("W", default=Any)
else:
    from typing import TypeVar

    W = TypeVar("W")


@runtime_checkable
class EdgeChecker(Protocol):
    """Collision-checks the edges of one domain graph against one world (scene)."""

    def check(self, edge: int) -> bool:
        """True when ``edge`` (0-based id into the domain graph) is collision-free."""
        ...

    def check_many(self, edges: npt.ArrayLike) -> BoolArray:
        """(K,) bool, True where each of the (K,) edge ids is free (same answers as :meth:`check`)."""
        ...


class StartGoalGraph(Protocol):
    """An explicit graph with a start and a goal vertex: a domain, or the built lattice a domain stores."""

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


@runtime_checkable
class Domain(StartGoalGraph, Protocol[W]):
    """A planning domain: graph, start/goal, seeded world models (of type ``W``) and their edge checkers."""

    @property
    def name(self) -> str:
        """Registry name (a key of :data:`DOMAIN_CLASSES`)."""
        ...

    @property
    def world_models(self) -> tuple[str, ...]:
        """Names of the world models :meth:`make_world` accepts."""
        ...

    def spec(self) -> dict[str, Any]:
        """JSON-able parameters; ``domain_from_spec(self.name, self.spec())`` rebuilds an equal domain."""
        ...

    def make_world(self, model: str, seed: int) -> W:
        """The world (scene) of ``model`` drawn with ``seed``; same arguments, same world."""
        ...

    def checker(self, world: W) -> EdgeChecker:
        """An edge checker for ``world``."""
        ...

    def edge_trajectories(self) -> list[npt.NDArray[np.float64]] | None:
        """Per edge (graph order) a (K_e, D) array of sampled states along it, or None for straight lines."""
        ...

    def check_metadata(self) -> dict[str, Any]:
        """How edges are checked (resolution, margin, vehicle size; with units), for dataset metadata."""
        ...


#: The lattice type of a :class:`LatticeMembers` domain.
L = TypeVar("L", bound=StartGoalGraph)


class LatticeMembers(Generic[L]):
    """The lattice members of a domain that stores its built lattice as ``_lattice`` (the SE(2) and helicopter).

    The domain's class docstring says what the vertex states and the start and goal vertices are.
    """

    _lattice: L

    @property
    def lattice(self) -> L:
        """The built lattice (graph, start and goal, and what lies behind every edge)."""
        return self._lattice

    @property
    def graph(self) -> ExplicitGraph:
        """The directed lattice graph; ``vertex_states`` (V, D) are the lattice states."""
        return self._lattice.graph

    @property
    def start(self) -> int:
        """Start vertex id (the lattice's start)."""
        return self._lattice.start

    @property
    def goal(self) -> int:
        """Goal vertex id (the lattice's goal)."""
        return self._lattice.goal


#: A registered domain class (an :class:`~drd_planner.domains.online.OnlineDomain` with ``from_spec``).
DomainClass = type["OnlineDomain[Any]"]


class DomainRegistry(Mapping[str, DomainClass]):
    """Domain name -> domain class; a class is imported on first lookup (its module may need FCL).

    Args:
        targets: domain name -> ``(module, class name)``.
    """

    def __init__(self, targets: Mapping[str, tuple[str, str]]) -> None:
        self._targets = dict(targets)
        self._loaded: dict[str, DomainClass] = {}

    def __getitem__(self, name: str) -> DomainClass:
        loaded = self._loaded.get(name)
        if loaded is not None:
            return loaded
        module_name, class_name = self._targets[name]
        cls: DomainClass = getattr(importlib.import_module(module_name), class_name)
        self._loaded[name] = cls
        return cls

    def __iter__(self) -> Iterator[str]:
        return iter(self._targets)

    def __len__(self) -> int:
        return len(self._targets)

    def __contains__(self, name: object) -> bool:
        return name in self._targets

    def choices(self) -> str:
        """The registered names, sorted and comma-separated (for error messages)."""
        return ", ".join(sorted(self._targets))


#: The registered domains, by name.
DOMAIN_CLASSES = DomainRegistry(
    {
        "planar": ("drd_planner.domains.planar", "PlanarDomain"),
        "se2": ("drd_planner.domains.se2", "Se2Domain"),
        "helicopter": ("drd_planner.domains.helicopter", "HelicopterDomain"),
        "arm": ("drd_planner.domains.arm", "ArmDomain"),
    }
)


def domain_from_spec(name: str, spec: Mapping[str, Any] | None = None) -> OnlineDomain[Any]:
    """Build the domain ``name`` from its spec (its defaults when ``spec`` is None).

    Raises:
        ProblemError: unknown domain name (the valid ones named), or a domain class that cannot be imported.
    """
    if name not in DOMAIN_CLASSES:
        raise ProblemError(f"unknown domain {name!r}; known: {DOMAIN_CLASSES.choices()}")
    try:
        cls = DOMAIN_CLASSES[name]
    except (ImportError, AttributeError) as exc:
        raise ProblemError(f"domain {name!r} is not available: {exc}") from exc
    return cls.from_spec(dict(spec or {}))
