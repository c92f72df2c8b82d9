"""Connecting a start or goal state that lies off the graph: new motions to nearby vertices.

A state farther than the snap tolerance from every vertex is joined to its nearest vertices by new
edges, the domain's own kind of motion (:data:`CONNECTORS`, by domain name):

- arm and planar graphs: straight segments in the state space (joint space for the arm);
- helicopter lattice ((x, y, z, heading) states): a Dubins curve of the lattice's turning radius in the
  plane with the altitude changing linearly along it.

A state with no vertex within the connector's reach is refused. A connector that can join a state to any
vertex it names (:class:`VertexJoins`: the helicopter's) also joins an off-graph start straight to a goal
vertex, and a start vertex straight to an off-graph goal, when such a motion exists: for a robot a few metres
off the lattice with its goal in reach, that one motion is often the whole plan.

**Free probability of a new edge.** The training worlds never checked it, so its outcome in each training
world is imputed from the graph edges it overlaps: every sample along the motion is matched to the
nearest point sampled along any graph edge, and the new edge counts as free in a world when the edges of
at least half of its samples are free there (a sample-weighted majority vote, :func:`imputed_outcomes`).
The new edge then is an ordinary column of the query's world matrix: the library, DiRECt and BiSECt use it
like any edge, and it is checked like any edge (the oracle's ``check_motion``).

Measured by ``scripts/experiments/measure_connection_prior.py`` (planar Forest / OneWall / Baffle worlds, 240 motions
each, against the exact box test in the 270 training worlds): mean absolute error of the imputed free
fraction 0.13 / 0.17 / 0.09 (correlation 0.92 / 0.73 / 0.88); the training marginal of all edges is off by
0.18 / 0.39 / 0.17; requiring *every* matched edge free was off by 0.40 / 0.44 / 0.32 (graph edges are longer
than the motions, so it is far too pessimistic). The vote still errs on the blocked side (0.56 against a true
0.69 on Forest), which only makes the planner check a new motion a little earlier.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from scipy.sparse import csr_array
from scipy.spatial import cKDTree

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.world_columns import WorldColumns
from drd_planner.exceptions import ProblemError
from drd_planner.planner.prior import WorldPrior

#: Vertices a new state is joined to (each a new edge), at most.
DEFAULT_NEIGHBOURS = 4
#: Points sampled along each straight graph edge for the imputation index.
POINTS_PER_EDGE = 8


@runtime_checkable
class MotionOracle(Protocol):
    """An edge oracle that can also check a motion that is not a graph edge."""

    def check(self, edge: int) -> bool:
        """True when graph edge ``edge`` is collision-free."""
        ...

    def check_motion(self, states: FloatArray) -> bool:
        """True when the motion through the (K, D) states (in order) is collision-free."""
        ...


@runtime_checkable
class MotionExplainer(Protocol):
    """Optional: an oracle that says in words what blocks a motion (for the reasons of failed plans).

    The planner uses it only to word the reason of a NO_PATH result (:mod:`drd_planner.planner.no_path`),
    never to decide anything, and its answers are not checks of the plan (not in the log, not cached):

    - when every edge joining the start (or goal) was checked blocked, it asks whether that state itself is
      blocked: ``explain_motion`` of the (1, D) state ("" means free, anything else is quoted as the cause);
      without this protocol, ``check_motion`` of it;
    - with this protocol it also explains the (up to 8 shortest) blocked motions joining that end (up to 8 other
      blocked edges around the smaller known-reachable side when neither end is walled in), counted per cause, with the
      ``" at sample ..."`` suffix dropped: so a cause should read the same for every motion it blocks.

    ``states`` are the (K, D) states a motion is checked at: a motion off the graph as ``check_motion`` gets
    it, a graph edge's stored trajectory, or the straight segment between its vertex states at the connector's
    resolution. Implementations: the arm's :meth:`ArmEdgeChecker.explain_motion
    <drd_planner.domains.arm_checker.ArmEdgeChecker.explain_motion>` (spheres and meshes). Another domain
    implements it on its edge checker (the object whose ``check_motion`` the oracle calls); the node's
    :class:`~drd_planner.planning.snapshot_oracle.SnapshotOracle` forwards it to the snapshot's checker (and
    answers ``"blocked"`` / "" from ``check_motion`` when the checker has none).
    """

    def explain_motion(self, states: FloatArray) -> str:
        """What blocks the motion through the (K, D) states (in order; K = 1: one state), in a short phrase.

        Name the first blocked sample's cause as a user would fix it: the obstacle by its scene name (e.g.
        ``scene object 'Can1' (panda_hand)``), or the robot's own rule (``self-collision (panda_link1 touches
        panda_link7)``, ``below the floor (...)``, ``outside the joint limits (...)``); for K > 1 add where
        (``at sample 3 of 21``). Return "" when the motion is free. It may be slow (it runs after a failure)
        but must not change what ``check``/``check_motion`` answer afterwards.
        """
        ...


@dataclass(frozen=True)
class Motion:
    """A new edge between a query state and a graph vertex.

    Attributes:
        vertex: the graph vertex at the other end.
        states: (K, D) states along it, from its tail to its head (the query state first for a start).
        length: its length in the graph's unit.
    """

    vertex: int
    states: FloatArray
    length: float


class QueryConnector(Protocol):
    """Joins an off-graph state to nearby vertices of a graph with the domain's motions."""

    @property
    def reach(self) -> float:
        """The farthest vertex (in state distance) a state is joined to."""
        ...

    @property
    def position_dims(self) -> int:
        """How many leading state dimensions are positions (used to match motions to graph edges)."""
        ...

    def connect(self, state: FloatArray, graph: ExplicitGraph, *, outgoing: bool) -> list[Motion]:
        """Motions from ``state`` to vertices (``outgoing``) or from vertices to ``state``; [] if none."""
        ...


@runtime_checkable
class VertexJoins(Protocol):
    """A connector that joins a state to any vertices it is given (not only its nearest ones)."""

    def motions_to(
        self, state: FloatArray, graph: ExplicitGraph, vertices: IntArray, *, outgoing: bool
    ) -> list[Motion]:
        """The motions joining ``state`` and those of ``vertices`` it can join (in their order).

        From the state if ``outgoing``, else into it; a vertex no motion of the domain joins is left out.
        """
        ...


class NearestVertices:
    """A KD-tree over a graph's vertex states (their first ``dims`` columns), rebuilt for another graph."""

    def __init__(self, dims: int | None = None) -> None:
        self._dims = dims
        self._built: tuple[ExplicitGraph, cKDTree] | None = None

    def query(self, graph: ExplicitGraph, point: FloatArray, k: int, reach: float) -> list[tuple[float, int]]:
        """Up to ``k`` (distance, vertex) pairs within ``reach`` of ``point``, nearest first."""
        if self._built is None or self._built[0] is not graph:
            states = vertex_states_of(graph)
            self._built = (graph, cKDTree(states if self._dims is None else states[:, : self._dims]))
        k = min(k, graph.num_vertices)
        dist, idx = self._built[1].query(point, k=k, distance_upper_bound=reach)
        pairs = zip(np.atleast_1d(dist).tolist(), np.atleast_1d(idx).tolist(), strict=True)
        return [(float(d), int(v)) for d, v in pairs if np.isfinite(d)]


def vertex_states_of(graph: ExplicitGraph) -> FloatArray:
    """The graph's (V, D) vertex states, or ProblemError when it has none."""
    if graph.vertex_states is None:
        raise ProblemError("this graph has no vertex states; states cannot be connected to it")
    return graph.vertex_states


class EdgeSampleIndex:
    """Points sampled along every graph edge, for matching a new motion to the graph edges it overlaps.

    Args:
        graph: the graph (vertex states needed when ``trajectories`` is None).
        trajectories: per edge (K_e, D) states, or None for straight segments between vertex states.
        position_dims: how many leading dimensions are compared.
    """

    def __init__(
        self, graph: ExplicitGraph, trajectories: tuple[FloatArray, ...] | None, *, position_dims: int
    ) -> None:
        if trajectories is not None:
            points = np.concatenate(trajectories)
            owner = np.repeat(np.arange(graph.num_edges), [t.shape[0] for t in trajectories])
        else:
            states = vertex_states_of(graph)
            t = np.linspace(0.0, 1.0, POINTS_PER_EDGE)[None, :, None]
            a, b = states[graph.edges[:, 0]][:, None, :], states[graph.edges[:, 1]][:, None, :]
            points = (a + t * (b - a)).reshape(-1, states.shape[1])
            owner = np.repeat(np.arange(graph.num_edges), POINTS_PER_EDGE)
        self._dims = min(position_dims, points.shape[1])
        self._tree = cKDTree(points[:, : self._dims])
        self._owner = owner.astype(np.int64)

    def nearest_edges(self, states: FloatArray) -> IntArray:
        """(K,) the graph edge nearest to each sample of a motion ((K, D) states)."""
        _, nearest = self._tree.query(np.asarray(states)[:, : self._dims])
        return np.asarray(self._owner[np.atleast_1d(nearest)], dtype=np.int64)


def imputed_outcomes(index: EdgeSampleIndex, worlds: BoolArray, states: FloatArray) -> BoolArray:
    """(n,) the new motion's imputed outcome in each training world (see the module doc).

    Free where the graph edges nearest to at least half of the motion's (K, D) samples are free.
    """
    nearest = index.nearest_edges(states)
    return np.asarray(worlds[:, nearest].mean(axis=1) >= 0.5, dtype=bool)


@functools.lru_cache(maxsize=4096)
def _voting_samples(count: int) -> IntArray:
    """(<= POINTS_PER_EDGE,) the indices of the evenly spread samples, of a motion's ``count``, that vote.

    Kept per count (read-only): a query's motions ask for a few dozen counts again and again.
    """
    chosen = np.asarray(np.unique(np.linspace(0, count - 1, POINTS_PER_EDGE).round().astype(np.int64)), dtype=np.int64)
    chosen.setflags(write=False)
    return chosen


def imputed_columns(index: EdgeSampleIndex, worlds: BoolArray | WorldColumns, motions: list[FloatArray]) -> BoolArray:
    """(n, M) imputed outcomes of M motions in the n training worlds, all motions' samples matched at once.

    The sample-weighted majority vote of :func:`imputed_outcomes` over at most
    :data:`POINTS_PER_EDGE` evenly spread samples of each motion (as many as
    the index has along each graph edge). ``worlds``: the (n, E) outcomes, or the same as packed columns
    (faster: the nearest edges' columns are read, not gathered).
    """
    if not motions:
        n = worlds.num_worlds if isinstance(worlds, WorldColumns) else worlds.shape[0]
        return np.zeros((n, 0), dtype=bool)
    points = [m[_voting_samples(m.shape[0])] for m in motions]
    counts = np.array([m.shape[0] for m in points])
    nearest = index.nearest_edges(np.concatenate(points))
    # Per motion, the number of its samples whose nearest edge is free in each world: a sparse (M, U) count
    # matrix over the U distinct nearest edges times their (U, n) outcomes (never an (n, sum K) copy).
    edges, column = np.unique(nearest, return_inverse=True)
    owner = np.repeat(np.arange(len(points)), counts)
    samples = csr_array(
        (np.ones(nearest.size, dtype=np.float32), (owner, column.ravel())), shape=(len(points), edges.size)
    )
    rows = worlds.rows_of(edges) if isinstance(worlds, WorldColumns) else worlds[:, edges].T
    free = np.asarray(samples @ rows.astype(np.float32)).T
    return np.asarray(free >= 0.5 * counts, dtype=bool)


def imputed_shares(
    index: EdgeSampleIndex, columns: WorldColumns, points: FloatArray, weights: FloatArray | None = None
) -> FloatArray:
    """(M,) the (weighted) share of training worlds in which each of M motions is imputed free.

    The same numbers as ``np.average(imputed_columns(index, columns, list(points)), axis=0, weights=weights)``
    for motions sampled at the same number of points (K), counted bit-parallel on the packed columns
    (:meth:`~drd_planner.core.world_columns.WorldColumns.at_least`) instead of through an (M, n) matrix: the
    ranking of every join of a lattice state (thousands of motions, 2700 worlds) in tens of milliseconds.

    Args:
        index: points along the prior's graph edges.
        columns: the training worlds, packed.
        points: (M, K, D) samples of each motion.
        weights: (n,) the worlds' weights (None: uniform).
    """
    samples = np.asarray(points, dtype=np.float64)
    if samples.ndim != 3:
        raise ProblemError(f"motion samples of shape (M, K, D) expected, got {samples.shape}")
    m, k = samples.shape[0], samples.shape[1]
    if m == 0:
        return np.zeros(0)
    chosen = _voting_samples(k)
    nearest = index.nearest_edges(samples[:, chosen].reshape(-1, samples.shape[2])).reshape(m, chosen.size)
    free = columns.at_least(nearest, -(-chosen.size // 2))  # free >= 0.5 * count, count an integer
    if weights is None:
        return np.asarray(np.bitwise_count(free).sum(axis=1, dtype=np.int64) / columns.num_worlds, dtype=np.float64)
    rows = np.unpackbits(free.view(np.uint8), axis=1, bitorder="little", count=columns.num_worlds).astype(bool)
    return np.asarray(np.average(rows.T, axis=0, weights=weights), dtype=np.float64)


def _straight(prior: WorldPrior) -> QueryConnector | None:
    from drd_planner.planner.straight_connector import straight_connector

    return straight_connector(prior)


def _arm(prior: WorldPrior) -> QueryConnector | None:
    """Straight joint-space motions, with the arm's sampler of valid configurations (roadmap growth)."""
    from drd_planner.domains.arm_sampler import arm_state_sampler
    from drd_planner.planner.straight_connector import straight_connector

    try:
        sampler = arm_state_sampler(prior.domain_spec)
    except ProblemError:  # robot files not on this machine: plan without growth
        sampler = None
    return straight_connector(prior, sampler=sampler)


def _dubins(prior: WorldPrior) -> QueryConnector | None:
    from drd_planner.planner.dubins_connector import dubins_connector

    return dubins_connector(prior)


#: Domain name -> the connector of its priors (None: states off the graph are refused).
CONNECTORS: Mapping[str, Callable[[WorldPrior], QueryConnector | None]] = {
    "arm": _arm,
    "planar": _straight,
    "gccd": _straight,
    "helicopter": _dubins,
}


def connector_for(prior: WorldPrior) -> QueryConnector | None:
    """The connector registered for the prior's domain (None for a domain without one)."""
    factory = CONNECTORS.get(prior.domain)
    return None if factory is None else factory(prior)
