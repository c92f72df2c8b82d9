"""Every search world's shortest free path to a goal, from any start: reverse shortest-path trees, batched.

A query's path library (:mod:`~drd_planner.planner.query_library`) is the distinct shortest free paths of a
seeded sample of the training worlds. A robot's goal changes rarely while its start changes with every
replan, so the searches run from the goal: one reverse shortest-path tree per search world gives every start's
shortest free path to that goal by following next hops, and the trees are kept per goal.

**One scipy call for all worlds.** The W search worlds' free arcs, reversed, are the blocks of one
block-diagonal graph built once per prior (:class:`SearchWorlds`): vertex v of world c is ``c * B + v``. A
Dijkstra from the goal's copy in every block at once (``min_only``: the blocks do not touch, so each vertex's
distance is its own world's) computes all W trees in C: about 0.1 ms per world on the real-scale helicopter
lattice (3935 vertices, 20 999 edges), against 0.17 ms for one search and the Python around it.

**Searched only as far as the start.** A search for a start s explores, in every world, only the vertices at
most ``FIRST_RADIUS`` times s's distance to the goal over the arcs free in any search world (a lower bound of every
world's): on short queries a small part of the graph. Within that radius the distances and next hops are
exactly those of an unbounded search; a world whose start lies beyond it (a long detour) is searched again
without bound, as is every world a later start of the same goal is not covered in (:meth:`GoalTree.covers`).
A start in another weakly connected part of a world's free arcs than the goal (computed once per prior) cannot
reach it there, so that world needs no second search for it (most of them: a start walled in by blocked edges).
So a replan from along the route walks the kept trees, and any start gets the same paths as unbounded trees.

**A goal off the graph** is the extra vertex ``B - 1`` of each block; the motions joining it (their vertex,
length and imputed outcome per world) are written into the block graph's spare arcs for that search only (as
far as the start needs, like a graph goal; its trees are not kept).

The search worlds: the distinct training worlds (rows compared through a 64-bit hash, then exactly) in a
seeded order, the first W of them.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.lazysp import GraphArcs
from drd_planner.exceptions import ProblemError

__all__ = [
    "FIRST_RADIUS",
    "GOAL_JOIN_SLOTS",
    "GOAL_TREES_KEPT",
    "SEARCH_WORLDS",
    "GoalTree",
    "JoinMotions",
    "SearchWorlds",
    "distinct_rows",
]

#: The most training worlds searched for a query's library (the sample's size).
SEARCH_WORLDS = 256
#: Motions into an off-graph goal a search can take (spare arcs of each block's goal vertex).
GOAL_JOIN_SLOTS = 64
#: Goals whose trees a :class:`SearchWorlds` keeps (least recently used dropped first).
GOAL_TREES_KEPT = 8
#: A new goal's first search radius, as a multiple of the start's distance over the arcs free in any search world.
FIRST_RADIUS = 1.25
#: A reverse tree's next hop where there is none (the goal itself, or a vertex that cannot reach it).
NO_HOP = -1


def distinct_rows(x: npt.ArrayLike) -> IntArray:
    """(d,) sorted indices of the first occurrence of every distinct row of an (n, E) bool matrix.

    Rows are compared through a 64-bit hash of their packed bits, then exactly within each equal-hash group
    (so a hash collision never merges two different rows).
    """
    rows = np.asarray(x, dtype=bool)
    n = rows.shape[0]
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    packed = np.packbits(rows, axis=1)
    width = (packed.shape[1] + 7) // 8 * 8
    words = np.zeros((n, width), dtype=np.uint8)
    words[:, : packed.shape[1]] = packed
    as_words = words.view(np.uint64)
    multipliers = np.random.default_rng(0x5EED).integers(1, 2**63, size=as_words.shape[1], dtype=np.uint64) | 1
    with np.errstate(over="ignore"):
        digest = (as_words * multipliers).sum(axis=1, dtype=np.uint64)
    order = np.lexsort((np.arange(n), digest))
    first: list[int] = []
    start = 0
    while start < n:
        stop = start + 1
        while stop < n and digest[order[stop]] == digest[order[start]]:
            stop += 1
        group = order[start:stop].tolist()
        kept: list[int] = []
        for index in group:  # exact comparison inside a hash group (almost always of one row)
            if not any(np.array_equal(words[index], words[other]) for other in kept):
                kept.append(index)
        first.extend(kept)
        start = stop
    return np.sort(np.asarray(first, dtype=np.int64))


@dataclass(frozen=True)
class JoinMotions:
    """The motions joining an off-graph state (a goal, or a start) to the graph.

    Attributes:
        vertices: (k,) the graph vertex at each motion's other end.
        lengths: (k,) their lengths (the graph's unit).
        free: (W, k) bool: whether each motion counts as free in each search world (imputed).
    """

    vertices: IntArray
    lengths: FloatArray
    free: BoolArray


@dataclass(frozen=True)
class GoalTree:
    """The reverse shortest-path trees of one goal in every search world (searched as far as ``radius``).

    Attributes:
        goal: the goal's vertex in a block (``B - 1`` for an off-graph goal).
        dist: (W, B) distance of each vertex to the goal in each world (inf: it cannot reach it, or lies beyond
            the world's radius).
        hop: (W, B) int32, the next vertex on its shortest free path to the goal (:data:`NO_HOP` at the goal,
            where the goal is unreachable, or beyond the radius).
        radius: (W,) how far each world was searched (the graph's length unit; inf: the whole graph). Within it
            ``dist`` and ``hop`` are those of an unbounded search. :meth:`SearchWorlds.tree` widens the rows of a
            kept tree in place (to inf) when a later start needs it; rows never change otherwise.
        parts: (W, B) int32 label of each vertex's weakly connected part of each world's free arcs (vertices
            of different parts cannot reach each other), or None when unknown.
    """

    goal: int
    dist: FloatArray
    hop: npt.NDArray[np.int32]
    radius: FloatArray
    parts: npt.NDArray[np.int32] | None = None

    def covers(self, start: int | JoinMotions) -> BoolArray:
        """(W,) whether each world's shortest free path from ``start`` can be read off this tree.

        A vertex start is covered where it was reached, lies in another part than the goal (it cannot reach
        it), or the world was searched without bound. A joined start (``free`` (W, k)) is covered where no free
        motion's vertex beyond the radius (and in the goal's part) could beat the best one within it (the best
        free motion is then exactly chosen, :meth:`best_joins`).
        """
        whole = np.isinf(self.radius)
        if not isinstance(start, JoinMotions):
            vertex = int(start)
            cut = np.zeros_like(whole) if self.parts is None else self.parts[:, vertex] != self.parts[:, self.goal]
            return np.asarray(whole | cut | np.isfinite(self.dist[:, vertex]), dtype=bool)
        reached = np.isfinite(self.dist[:, start.vertices])  # (W, k)
        best = np.min(np.where(start.free & reached, start.lengths[None, :] + self.dist[:, start.vertices], np.inf), 1)
        open_ = start.free & ~reached
        if self.parts is not None:
            open_ &= self.parts[:, start.vertices] == self.parts[:, self.goal][:, None]
        # A motion to a vertex beyond the radius is at least its length plus the radius long.
        floor = np.where(open_, start.lengths[None, :] + self.radius[:, None], np.inf)
        return np.asarray(whole | (best <= floor.min(axis=1)), dtype=bool)

    def best_joins(self, start: JoinMotions) -> tuple[IntArray, BoolArray]:
        """Per world, the free motion with the shortest free path behind it (the first of equally short ones).

        Returns:
            (W,) the motion's index (0 where none), (W,) whether a free path exists.
        """
        behind = np.where(start.free, start.lengths[None, :] + self.dist[:, start.vertices], np.inf)
        choice = np.asarray(np.argmin(behind, axis=1), dtype=np.int64)
        reachable = np.isfinite(behind[np.arange(behind.shape[0]), choice])
        return choice, np.asarray(reachable, dtype=bool)

    def walks(self, starts: IntArray) -> list[IntArray | None]:
        """Per world the vertex sequence from ``starts[w]`` to the goal, or None when it cannot reach it.

        Args:
            starts: (W,) a start vertex per world (the same one, or each world's best join); each must be
                covered (:meth:`covers`).
        """
        table, lengths = self.walk_table(starts)
        return [None if n == 0 else np.asarray(table[w, :n], dtype=np.int64) for w, n in enumerate(lengths)]

    def walk_table(self, starts: IntArray) -> tuple[npt.NDArray[np.int32], IntArray]:
        """The walks of :meth:`walks` as one table.

        Returns:
            (W, L) int32 vertex sequences from ``starts[w]`` to the goal, the goal repeated after each walk's
            end, and (W,) each walk's vertex count (0 where the goal cannot be reached).
        """
        num = self.dist.shape[0]
        rows = np.arange(num)
        starts = np.asarray(starts, dtype=np.int64)
        reach = np.isfinite(self.dist[rows, starts])
        cur = np.where(reach, starts, self.goal).astype(np.int32)
        steps = [cur]
        count = reach.astype(np.int64)
        while True:
            moving = np.flatnonzero(cur != self.goal)
            if moving.size == 0:
                break
            nxt = cur.copy()
            nxt[moving] = self.hop[moving, cur[moving]]
            if np.any(nxt[moving] == NO_HOP):  # never: a finite distance has a complete walk
                raise ProblemError("a reverse shortest-path tree has a broken walk")
            count[moving] += 1
            cur = nxt
            steps.append(cur)
        return np.stack(steps, axis=1), count


class SearchWorlds:
    """A prior's search worlds and their reversed free arcs as one block-diagonal graph (built once).

    Args:
        arcs: the prior graph's arcs.
        lengths: (E,) edge lengths.
        worlds: (n, E) bool training worlds.
        seed: seed of the distinct worlds' order (the prior's library seed).
        count: how many distinct worlds to search, at most.
    """

    def __init__(
        self,
        arcs: GraphArcs,
        lengths: npt.ArrayLike,
        worlds: npt.ArrayLike,
        *,
        seed: int,
        count: int = SEARCH_WORLDS,
    ) -> None:
        x = np.asarray(worlds, dtype=bool)
        if count < 1:
            raise ProblemError(f"at least one search world is needed, got {count}")
        distinct = distinct_rows(x)
        order = distinct[np.random.default_rng(seed).permutation(distinct.size)]
        self.worlds: IntArray = np.asarray(order[:count], dtype=np.int64)
        self.arcs = arcs
        num = self.worlds.size
        v = arcs.num_vertices
        block = v + 1  # the last vertex of each block stands for an off-graph goal
        self.block = block
        arc_length = np.asarray(lengths, dtype=np.float64)[arcs.edge]
        arc_length = np.where(arc_length > 0, arc_length, np.finfo(np.float64).tiny)  # csgraph: 0 = no arc
        free = x[self.worlds][:, arcs.edge]  # (W, A): arc a is free in world c
        copies, which = np.nonzero(free)
        # Reversed arcs (head -> tail), then GOAL_JOIN_SLOTS spare arcs of weight inf per block from its goal
        # vertex (to its first vertices: distinct, so the CSR keeps them apart; never relaxed).
        self.slots = min(GOAL_JOIN_SLOTS, v)
        spare_rows = np.repeat(np.arange(num) * block + v, self.slots)
        spare_cols = (np.arange(num) * block)[:, None] + np.arange(self.slots)[None, :]
        rows = np.concatenate([arcs.v[which] + copies * block, spare_rows])
        cols = np.concatenate([arcs.u[which] + copies * block, spare_cols.ravel()])
        data = np.concatenate([arc_length[which], np.full(num * self.slots, np.inf)])
        self._graph = _csr32(data, rows, cols, num * block)
        # The weakly connected parts of each world's free arcs (the spare arcs left out): (W, B) labels.
        arcs_only = sp.coo_array(
            (np.ones(which.size, dtype=np.int8), (rows[: which.size], cols[: which.size])),
            shape=(num * block, num * block),
        )
        _, labels = connected_components(arcs_only, directed=True, connection="weak")
        self._parts = np.asarray(labels, dtype=np.int32).reshape(num, block)
        # Where each block's spare arcs sit in the CSR arrays (its goal vertex's row: all of that row).
        goal_rows = np.arange(num) * block + v
        self._slots = self._graph.indptr[goal_rows][:, None] + np.arange(self.slots)[None, :]
        # The arcs free in any search world, reversed, in one block with its spare arcs: distances on it bound
        # every world's from below.
        anywhere = free.any(axis=0)
        union_rows = np.concatenate([arcs.v[anywhere], np.full(self.slots, v)])
        union_cols = np.concatenate([arcs.u[anywhere], np.arange(self.slots)])
        union_data = np.concatenate([arc_length[anywhere], np.full(self.slots, np.inf)])
        self._union = _csr32(union_data, union_rows, union_cols, block)
        self._union_slots = self._union.indptr[v] + np.arange(self.slots)
        self._trees: OrderedDict[int, GoalTree] = OrderedDict()

    @property
    def num_worlds(self) -> int:
        """W, the worlds searched."""
        return int(self.worlds.size)

    @property
    def goals_kept(self) -> tuple[int, ...]:
        """The graph goals whose reverse trees are kept, least recently used first."""
        return tuple(self._trees)

    def tree(self, goal: int, start: int | JoinMotions | None = None) -> GoalTree:
        """The reverse trees of a graph vertex ``goal``, covering ``start`` in every world (kept per goal).

        Args:
            goal: the goal vertex.
            start: the start the trees are read for (a vertex, or the motions joining an off-graph start with
                ``free`` (W, k)); a new goal is searched as far as it needs (:data:`FIRST_RADIUS`), and the
                worlds a kept tree does not cover it in are searched again without bound. None: the whole graph.
        """
        goal = int(goal)
        known = self._trees.get(goal)
        if known is None:
            if not 0 <= goal < self.arcs.num_vertices:
                raise ProblemError(f"goal vertex {goal} outside [0, {self.arcs.num_vertices})")
            known = self._search(goal, self._graph, limit=self._first_radius(goal, start))
            self._trees[goal] = known
            while len(self._trees) > GOAL_TREES_KEPT:
                self._trees.popitem(last=False)
        else:
            self._trees.move_to_end(goal)
        if start is None:
            self._widen(known, ~np.isinf(known.radius))
        else:
            self._widen(known, ~known.covers(start))
        return known

    def forget_trees(self) -> None:
        """Drop the reverse trees kept for past goals (the next query to any goal searches anew)."""
        self._trees.clear()

    def joined_tree(self, joins: JoinMotions, start: int | JoinMotions | None = None) -> GoalTree:
        """The reverse trees of an off-graph goal joined by ``joins``, covering ``start`` (not kept).

        Searched as far as ``start`` needs (:data:`FIRST_RADIUS`), then again without bound in the worlds
        it does not cover; None: the whole graph.
        """
        k = int(joins.vertices.size)
        if k > self.slots:
            raise ProblemError(f"at most {self.slots} motions into a goal can be searched, got {k}")
        if joins.free.shape != (self.num_worlds, k):
            raise ProblemError(f"join outcomes must be ({self.num_worlds}, {k}), got {joins.free.shape}")
        # A copy of the arrays with the spare arcs filled in (the shared graph is never changed).
        data, indices = self._graph.data.copy(), self._graph.indices.copy()
        offsets = (np.arange(self.num_worlds) * self.block)[:, None]
        slots = self._slots[:, :k]
        indices[slots] = joins.vertices[None, :] + offsets
        data[slots] = np.where(joins.free, joins.lengths[None, :], np.inf)
        graph = sp.csr_array((data, indices, self._graph.indptr), shape=self._graph.shape)
        goal = self.block - 1
        # No parts: the goal's own vertex is joined only in this search (a start is never known to be cut off).
        tree = replace(self._search(goal, graph, limit=self._first_radius(goal, start, joins)), parts=None)
        if start is not None:
            self._widen(tree, ~tree.covers(start), graph)
        return tree

    def _first_radius(self, goal: int, start: int | JoinMotions | None, joins: JoinMotions | None = None) -> float:
        """How far a new goal's first search goes for ``start``: inf for the whole graph."""
        if start is None:
            return np.inf
        union = self._union
        if joins is not None:  # the goal's motions free in any search world, in the union's spare arcs
            data, indices = union.data.copy(), union.indices.copy()
            slots = self._union_slots[: joins.vertices.size]
            indices[slots] = joins.vertices
            data[slots] = np.where(joins.free.any(axis=0), joins.lengths, np.inf)
            union = sp.csr_array((data, indices, union.indptr), shape=union.shape)
        bound = dijkstra(union, directed=True, indices=goal)
        if isinstance(start, JoinMotions):
            near = float(np.min(start.lengths + bound[start.vertices], initial=np.inf))
        else:
            near = float(bound[int(start)])
        return FIRST_RADIUS * near  # inf where no world can reach the goal at all: search everything once

    def _widen(self, tree: GoalTree, worlds: BoolArray, graph: sp.csr_array | None = None) -> None:
        """Search ``worlds`` (W,) of a tree again without bound, in place (on ``graph``: a joined goal's)."""
        again = np.flatnonzero(worlds)
        if again.size == 0:
            return
        full = self._search(tree.goal, self._graph if graph is None else graph, limit=np.inf, worlds=again)
        tree.dist[again] = full.dist
        tree.hop[again] = full.hop
        tree.radius[again] = np.inf

    def _search(self, goal: int, graph: sp.csr_array, *, limit: float, worlds: IntArray | None = None) -> GoalTree:
        """Dijkstra from ``goal`` in each of ``worlds`` (all when None) as far as ``limit``.

        Returns the rows of those worlds only, in their order.
        """
        block = self.block
        chosen = np.arange(self.num_worlds) if worlds is None else worlds
        sources = chosen * block + goal
        dist, pred, _ = dijkstra(
            graph, directed=True, indices=sources, min_only=True, return_predecessors=True, limit=limit
        )
        if worlds is None:
            dist_rows = np.asarray(dist, dtype=np.float64).reshape(chosen.size, block)
            hop = np.asarray(pred, dtype=np.int32).reshape(chosen.size, block)
        else:  # only the chosen blocks: min_only searches never leave the blocks of their sources
            cells = (chosen * block)[:, None] + np.arange(block)[None, :]
            dist_rows = np.asarray(dist[cells], dtype=np.float64)
            hop = np.asarray(pred[cells], dtype=np.int32)
        hop -= (chosen * block)[:, None].astype(np.int32)  # in place: a block's own vertex numbers
        np.maximum(hop, NO_HOP, out=hop)  # no predecessor (scipy's -9999, now shifted): NO_HOP
        radius = np.full(chosen.size, limit, dtype=np.float64)
        return GoalTree(goal, dist_rows, hop, radius, None if worlds is not None else self._parts)


def _csr32(data: FloatArray, rows: npt.ArrayLike, cols: npt.ArrayLike, size: int) -> sp.csr_array:
    """A (size, size) CSR graph with int32 indices (what csgraph runs on: no conversion per search)."""
    graph = sp.csr_array((data, (rows, cols)), shape=(size, size))
    graph.sort_indices()
    return sp.csr_array((graph.data, graph.indices.astype(np.int32), graph.indptr.astype(np.int32)), shape=(size, size))
