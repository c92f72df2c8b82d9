"""LazySP on the full graph with its edge selectors (docs/algorithms.md, "LazySP and its selectors").

The loop (Dellin & Srinivasa, ICAPS 2016; the LEMUR code): find the shortest start-goal path in the
graph with every known-blocked edge deleted (unchecked edges count with their length, their optimistic
estimate); if all its edges were checked free it is the shortest feasible path and the episode ends;
otherwise a selector names one unchecked edge of it to check. A blocked outcome deletes the edge and
forces a re-plan; a free one leaves the path unchanged.

The answer is LazySP's own path, not a library path, so the policy implements
:class:`drd_planner.core.episode.GraphPathPolicy` and the runner stops only on that path (or on
start and goal being disconnected, or on the check budget, 1000 as in the authors' benchmark).

Selectors on the current path e_1..e_k: ``forward`` (first unchecked), ``reverse`` (last unchecked),
``alternate`` (forward, reverse, forward, ...: one toggle per selection), ``bisection`` (first edge
farthest, in edges, from any checked edge or a path end) and ``weightsamp`` (the unchecked path edge
that lies most often on shortest paths of sampled graphs; ties to the later edge).

``balanced`` (ours, not in LEMUR) checks from the end whose *known-free region* is smaller: forward when
no more vertices are reachable from the start over checked-free edges than reach the goal that way,
reverse otherwise. When one end is walled in, its region stays small, so the checks go to the wall
around it instead of exploring the other end's large region: it is the graph stage of
:class:`drd_planner.planner.Planner` (see :mod:`drd_planner.planner.graph_fallback` for measurements).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.free_reach import FreeReach
from drd_planner.core.graph import ExplicitGraph
from drd_planner.exceptions import ProblemError

#: The selectors, in the order of the registry names ``lazysp``, ``lazysp_reverse``, ...
SELECTORS: Final = ("forward", "reverse", "alternate", "bisection", "weightsamp", "balanced")
#: The authors' LazySP benchmark gives up after this many checks (``policyLazySPOrig.m``).
DEFAULT_MAX_CHECKS: Final = 1000
#: Sampled graphs per WeightSamp selection. LEMUR uses 1000; 100 keeps a selection near 10 ms on the
#: 2D graphs (all samples go through one batched Dijkstra) and ranks path edges almost identically.
DEFAULT_WEIGHTSAMP_NSAMPS: Final = 100
#: Samples per batched Dijkstra call in WeightSamp (bounds memory: batch x arcs floats).
WEIGHTSAMP_BATCH: Final = 100

_UNKNOWN, _BLOCKED, _FREE = -1, 0, 1


def lazysp_name(selector: str) -> str:
    """Registry name of a selector: ``lazysp`` for ``forward``, else ``lazysp_<selector>``."""
    return "lazysp" if selector == "forward" else f"lazysp_{selector}"


class GraphArcs:
    """The directed arcs of an explicit graph (two per undirected edge) and shortest paths over them.

    Arcs are stored in CSR order (sorted by tail vertex), so a weight per arc is directly the data
    array of the graph's CSR matrix.
    """

    def __init__(self, graph: ExplicitGraph) -> None:
        edges = graph.edges
        ids = np.arange(graph.num_edges, dtype=np.int64)
        u, v, e = edges[:, 0], edges[:, 1], ids
        if not graph.directed:
            u = np.concatenate([u, edges[:, 1]])
            v = np.concatenate([v, edges[:, 0]])
            e = np.concatenate([e, ids])
        n = graph.num_vertices
        keys = u * n + v
        order = np.argsort(keys)
        order = order[u[order] != v[order]]  # a self-loop is never on a shortest path
        self.num_vertices = n
        self.u, self.v, self.edge = u[order], v[order], e[order]
        self._keys = keys[order]
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(self.u, minlength=n))]).astype(np.int64)
        # One CSR structure for every shortest-path call: a call only writes the arc weights (inf deletes
        # an arc: Dijkstra never relaxes it), instead of building a sparse matrix each time.
        self._csr = sp.csr_array((np.zeros(self.u.size), self.v.copy(), self.indptr.copy()), shape=(n, n))

    @property
    def num_arcs(self) -> int:
        """Number of arcs."""
        return int(self.u.size)

    def edge_of(self, tail: IntArray, head: IntArray) -> IntArray:
        """Edge id of each arc ``tail -> head`` (every pair must be an arc)."""
        pos = np.searchsorted(self._keys, tail * self.num_vertices + head)
        return np.asarray(self.edge[pos], dtype=np.int64)

    def shortest_path(self, start: int, goal: int, edge_weights: FloatArray) -> IntArray | None:
        """Edge ids (start to goal) of a shortest path; arcs of edges weighted inf are deleted.

        Returns None when the goal is unreachable.
        """
        np.copyto(self._csr.data, np.asarray(edge_weights, dtype=np.float64)[self.edge])
        dist, pred = dijkstra(self._csr, directed=True, indices=start, return_predecessors=True)
        if not np.isfinite(dist[goal]):
            return None
        return self.walk_back(pred, start, goal)

    def walk_back(self, predecessors: npt.NDArray[np.int32], start: int, goal: int) -> IntArray:
        """Edge ids (start to goal) of the path in a Dijkstra predecessor array (goal reached)."""
        vertices = [goal]
        while vertices[-1] != start:
            vertices.append(int(predecessors[vertices[-1]]))
        seq = np.asarray(vertices[::-1], dtype=np.int64)
        return self.edge_of(seq[:-1], seq[1:])

    def deletion_lengths(
        self, start: int, goal: int, edge_weights: FloatArray, edges: IntArray
    ) -> tuple[float, FloatArray]:
        """Shortest start-goal length, and the same with each of ``edges`` deleted in turn.

        One batched Dijkstra over ``m + 1`` disjoint copies of the graph (copy 0 as weighted, copy
        ``j + 1`` without ``edges[j]``); arcs of edges weighted inf are deleted in every copy.

        Args:
            start: start vertex.
            goal: goal vertex.
            edge_weights: (E,) non-negative edge weights (inf: deleted), in length units.
            edges: (m,) edge ids to delete one at a time.

        Returns:
            The length without deletions and the (m,) lengths with ``edges[j]`` deleted; inf where
            the goal is unreachable.
        """
        dist, _ = self.deletion_search(start, edge_weights, np.concatenate([[-1], np.asarray(edges, np.int64)]))
        at_goal = dist[np.arange(dist.size // self.num_vertices) * self.num_vertices + goal]
        return float(at_goal[0]), np.asarray(at_goal[1:], dtype=np.float64)

    def deletion_paths(self, start: int, goal: int, edge_weights: FloatArray, edges: IntArray) -> list[IntArray | None]:
        """Per entry of ``edges`` the shortest start-goal path (edge ids) with that edge deleted.

        Same batched Dijkstra as :meth:`deletion_lengths`; an entry of -1 deletes nothing. None where
        the goal is unreachable.
        """
        dist, pred = self.deletion_search(start, edge_weights, edges, predecessors=True)
        n = self.num_vertices
        out: list[IntArray | None] = []
        for j in range(len(edges)):
            if np.isfinite(dist[j * n + goal]):
                out.append(self.walk_back(pred[j * n : (j + 1) * n] - j * n, start, goal))
            else:
                out.append(None)
        return out

    def deletion_search(
        self, start: int, edge_weights: FloatArray, edges: IntArray, *, predecessors: bool = False
    ) -> tuple[FloatArray, npt.NDArray[np.int32]]:
        """One Dijkstra over ``len(edges)`` disjoint copies of the graph, copy j without ``edges[j]``.

        Args:
            start: start vertex of every copy.
            edge_weights: (E,) non-negative edge weights (inf: deleted in every copy), in length units.
            edges: (m,) edge ids, -1 for a copy without a deletion.
            predecessors: also return the predecessor array (else an empty one).

        Returns:
            (m * V,) distances from ``start`` (copy j's vertex v at ``j * V + v``; inf: unreachable)
            and, when asked, the (m * V,) predecessors in the copies' shared numbering.
        """
        ids = np.asarray(edges, dtype=np.int64)
        copies, n = ids.size, self.num_vertices
        indices, indptr = self.batch_structure(copies, start)
        weights = np.tile(np.asarray(edge_weights, dtype=np.float64), (copies, 1))
        rows = np.flatnonzero(ids >= 0)
        weights[rows, ids[rows]] = np.inf
        data = np.concatenate([weights[:, self.edge].ravel(), np.ones(copies)])
        size = copies * n + 1
        csr = sp.csr_array((data, indices, indptr), shape=(size, size))
        if predecessors:
            dist, pred = dijkstra(csr, directed=True, indices=size - 1, return_predecessors=True)
        else:
            dist, pred = dijkstra(csr, directed=True, indices=size - 1), np.empty(0, dtype=np.int32)
        return np.asarray(dist[:-1] - 1.0), pred[:-1]  # the super-source's arcs weigh 1

    def batch_structure(self, copies: int, start: int) -> tuple[IntArray, IntArray]:
        """CSR ``(indices, indptr)`` of ``copies`` disjoint copies of the graph plus a super-source.

        The super-source is the last vertex, with one arc to each copy's ``start``. Arc data order:
        the arcs of copy 0 in CSR order, copy 1, ..., then the source's arcs.
        """
        n, a = self.num_vertices, self.num_arcs
        shift = np.arange(copies, dtype=np.int64)
        indices = np.concatenate([(self.v[None, :] + n * shift[:, None]).ravel(), n * shift + start])
        indptr = np.concatenate(
            [(self.indptr[None, :-1] + a * shift[:, None]).ravel(), [copies * a, copies * a + copies]]
        )
        return indices, indptr


def bisection_position(checked: BoolArray) -> int:
    """LEMUR's bisection selector: the first position with maximal distance to a checked edge.

    Distance counts edges along the path, is 0 on checked edges, and an end of the path counts as a
    checked edge just outside it (so an unchecked end edge has distance 1).
    """
    n = checked.size
    dist = np.zeros(n, dtype=np.int64)
    for i in range(n):
        dist[i] = 0 if checked[i] else (1 if i == 0 else dist[i - 1] + 1)
    for i in range(n - 1, -1, -1):
        rev = 0 if checked[i] else (1 if i == n - 1 else dist[i + 1] + 1)
        dist[i] = min(dist[i], rev)
    return int(np.argmax(dist))


@dataclass(frozen=True)
class LazySPSettings:
    """How :class:`LazySP` picks edges and when it gives up.

    Attributes:
        selector: one of :data:`SELECTORS`.
        max_checks: check budget the runner enforces (None: unlimited).
        nsamps: sampled graphs per selection (``weightsamp`` only).
        seed: seed of the sampler (``weightsamp`` only; the other selectors are deterministic).
    """

    selector: str = "forward"
    max_checks: int | None = DEFAULT_MAX_CHECKS
    nsamps: int = DEFAULT_WEIGHTSAMP_NSAMPS
    seed: int = 0


class LazySP:
    """LazySP on the full graph, a :class:`drd_planner.core.episode.GraphPathPolicy`.

    Args:
        graph: the explicit graph (one edge id per test; undirected edges are traversable both ways).
        start: start vertex.
        goal: goal vertex.
        settings: selector, check budget and WeightSamp sampling (None: :class:`LazySPSettings` defaults).
        name: registry name (default ``lazysp`` or ``lazysp_<selector>``).
        edge_weights: (E,) finite non-negative weights of the edges in the shortest-path search
            (default: the graph's lengths). Checked-free edges keep them, blocked ones are deleted.
        observations: outcomes already known (edge -> free), e.g. from an earlier stage of the same
            plan; they are never selected again.
        stage: the label of this policy's checks in the log (``lazysp``).
    """

    def __init__(
        self,
        graph: ExplicitGraph,
        start: int,
        goal: int,
        settings: LazySPSettings | None = None,
        *,
        name: str | None = None,
        edge_weights: npt.ArrayLike | None = None,
        observations: Mapping[int, bool] | None = None,
        stage: str = "lazysp",
    ) -> None:
        settings = settings or LazySPSettings()
        selector, nsamps = settings.selector, settings.nsamps
        if selector not in SELECTORS:
            raise ProblemError(f"unknown LazySP selector {selector!r}; known: {', '.join(SELECTORS)}")
        for label, vertex in (("start", start), ("goal", goal)):
            if not 0 <= int(vertex) < graph.num_vertices:
                raise ProblemError(f"LazySP {label} vertex {vertex} outside [0, {graph.num_vertices})")
        if nsamps < 1:
            raise ProblemError("LazySP weightsamp needs nsamps >= 1")
        self._arcs = GraphArcs(graph)
        self._lengths = np.asarray(graph.lengths, dtype=np.float64)
        if edge_weights is not None:
            weights = np.asarray(edge_weights, dtype=np.float64)
            if weights.shape != self._lengths.shape or not np.all(np.isfinite(weights) & (weights >= 0)):
                raise ProblemError(f"LazySP edge weights must be ({graph.num_edges},) finite and >= 0")
            self._lengths = weights.copy()
        self._stage = stage
        self._start = int(start)
        self._goal = int(goal)
        self._selector = selector
        self._max_checks = settings.max_checks
        self._nsamps = int(nsamps)
        self._rng = np.random.default_rng(settings.seed)
        self._name = name or lazysp_name(selector)
        self._outcome = np.full(graph.num_edges, _UNKNOWN, dtype=np.int8)
        self._weights = self._lengths.copy()  # lazy weights: inf once checked blocked
        self._path: IntArray | None = None
        self._stale = True
        self._forward_next = True
        self._batch: tuple[int, IntArray, IntArray] | None = None  # WeightSamp's block-graph structure
        self._edge_ends = graph.edges
        # the balanced selector's known-free regions, grown with each free outcome
        self._reach = FreeReach(self._start, self._goal, directed=graph.directed)
        for edge, free in (observations or {}).items():
            self.observe(int(edge), bool(free))

    @property
    def name(self) -> str:
        """Registry name."""
        return self._name

    @property
    def stage(self) -> str:
        """The label given at construction (``lazysp`` by default)."""
        return self._stage

    @property
    def stops_on_library_path(self) -> bool:
        """False: LazySP ends only when its own shortest path is checked free."""
        return False

    @property
    def max_checks(self) -> int | None:
        """The check budget (1000 by default, as in the authors' benchmark)."""
        return self._max_checks

    def proposed_path(self) -> IntArray | None:
        """Edge ids (start to goal, read-only) of the current lazy shortest path; None if disconnected."""
        if self._stale:
            self._path = self._arcs.shortest_path(self._start, self._goal, self._weights)
            if self._path is not None:
                self._path.setflags(write=False)
            self._stale = False
        return self._path

    def select(self) -> int | None:
        """An unchecked edge of the current path, or None when it is fully checked or there is none."""
        path = self.proposed_path()
        if path is None:
            return None
        checked = self._outcome[path] != _UNKNOWN
        if checked.all():
            return None
        return int(path[self._position(path, checked)])

    def observe(self, edge: int, free: bool) -> None:
        """Record the outcome; a blocked edge is deleted and the path re-planned on the next call."""
        before = self._outcome[edge]
        self._outcome[edge] = _FREE if free else _BLOCKED
        u, v = (int(x) for x in self._edge_ends[edge])
        if free:
            if before != _FREE:
                self._reach.add(u, v)
        else:
            if before == _FREE:  # observed free, then blocked (a later outcome wins)
                self._reach.remove(u, v)
            self._weights[edge] = np.inf
            self._stale = True

    def _position(self, path: IntArray, checked: BoolArray) -> int:
        """Position in ``path`` of the edge to check (``checked`` has an unchecked entry).

        The selector hook: subclasses (:mod:`drd_planner.bench.lazysp_learned`) override it.
        """
        open_pos = np.flatnonzero(~checked)
        if self._selector == "forward":
            return int(open_pos[0])
        if self._selector == "reverse":
            return int(open_pos[-1])
        if self._selector == "alternate":
            forward, self._forward_next = self._forward_next, not self._forward_next
            return int(open_pos[0] if forward else open_pos[-1])
        if self._selector == "bisection":
            return bisection_position(checked)
        if self._selector == "balanced":
            from_start, into_goal = self.known_free_reach()
            return int(open_pos[0] if from_start <= into_goal else open_pos[-1])
        counts = self.shortest_path_counts()[path[open_pos]]
        return int(open_pos[open_pos.size - 1 - int(np.argmax(counts[::-1]))])  # last maximum

    def known_free_reach(self) -> tuple[int, int]:
        """(vertices reachable from the start, vertices that reach the goal) over checked-free edges.

        Grown with each free outcome (:class:`~drd_planner.core.free_reach.FreeReach`), not searched per check.
        """
        return self._reach.sizes

    def shortest_path_counts(self) -> IntArray:
        """WeightSamp: how often each edge lies on the shortest path of ``nsamps`` sampled graphs.

        In each sample an unchecked edge is deleted with probability 1/2 and otherwise weighs
        U[1, 2); checked free edges keep their length and checked blocked ones stay deleted (LEMUR's
        ``sp_indicator_probability``). A batch of samples is one graph of disjoint copies plus a
        super-source joined to every copy's start, so one Dijkstra call solves the whole batch.
        """
        arcs = self._arcs
        n = arcs.num_vertices
        num_edges = self._lengths.size
        unknown = self._outcome == _UNKNOWN
        counts = np.zeros(num_edges, dtype=np.int64)
        done = 0
        while done < self._nsamps:
            k = min(WEIGHTSAMP_BATCH, self._nsamps - done)
            done += k
            if self._batch is None or self._batch[0] != k:
                self._batch = (k, *arcs.batch_structure(k, self._start))
            _, indices, indptr = self._batch
            draw = self._rng.random((k, num_edges))
            weight = np.where(unknown, np.where(draw > 0.5, np.inf, 1.0 + draw / 0.5), self._weights)
            # An arc of weight inf is never relaxed by scipy's Dijkstra: it acts as deleted.
            data = np.concatenate([weight[:, arcs.edge].ravel(), np.ones(k)])
            size = k * n + 1
            csr = sp.csr_array((data, indices, indptr), shape=(size, size))
            dist, pred = dijkstra(csr, directed=True, indices=size - 1, return_predecessors=True)
            heads = np.arange(k) * n + self._goal
            starts = np.arange(k) * n + self._start
            live = np.isfinite(dist[heads]) & (heads != starts)
            heads, starts = heads[live], starts[live]
            while heads.size:
                tails = pred[heads].astype(np.int64)
                counts += np.bincount(arcs.edge_of(tails % n, heads % n), minlength=num_edges)
                more = tails != starts
                heads, starts = tails[more], starts[more]
        return counts
