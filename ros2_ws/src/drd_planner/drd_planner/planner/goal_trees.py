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

**A goal off the graph** is the extra vertex ``B - 1`` of each block; the motions joining it (their vertex,
length and imputed outcome per world) are written into the block graph's spare arcs for that search only.

The search worlds: the distinct training worlds (rows compared through a 64-bit hash, then exactly) in a
seeded order, the first W of them.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.lazysp import GraphArcs
from drd_planner.exceptions import ProblemError

__all__ = [
    "GOAL_JOIN_SLOTS",
    "GOAL_TREES_KEPT",
    "SEARCH_WORLDS",
    "GoalJoins",
    "GoalTree",
    "SearchWorlds",
    "distinct_rows",
]

#: The most training worlds searched for a query's library (the sample's size).
SEARCH_WORLDS = 256
#: Motions into an off-graph goal a search can take (spare arcs of each block's goal vertex).
GOAL_JOIN_SLOTS = 64
#: Goals whose trees a :class:`SearchWorlds` keeps (least recently used dropped first).
GOAL_TREES_KEPT = 8
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
    multipliers = (
        np.random.default_rng(0x5EED).integers(1, 2**63, size=as_words.shape[1], dtype=np.uint64) | 1
    )
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
class GoalJoins:
    """The motions joining an off-graph goal to the graph, for a search from it.

    Attributes:
        vertices: (k,) the graph vertex each motion comes from.
        lengths: (k,) their lengths (the graph's unit).
        free: (W, k) bool: whether each motion counts as free in each search world (imputed).
    """

    vertices: IntArray
    lengths: FloatArray
    free: BoolArray


@dataclass(frozen=True)
class GoalTree:
    """The reverse shortest-path trees of one goal in every search world.

    Attributes:
        goal: the goal's vertex in a block (``B - 1`` for an off-graph goal).
        dist: (W, B) distance of each vertex to the goal in each world (inf: it cannot reach it).
        hop: (W, B) the next vertex on its shortest free path to the goal (:data:`NO_HOP` at the goal or
            where the goal is unreachable).
    """

    goal: int
    dist: FloatArray
    hop: IntArray

    def walks(self, starts: IntArray) -> list[IntArray | None]:
        """Per world the vertex sequence from ``starts[w]`` to the goal, or None when it cannot reach it.

        Args:
            starts: (W,) a start vertex per world (the same one, or each world's best join).
        """
        num = self.dist.shape[0]
        rows = np.arange(num)
        reach = np.isfinite(self.dist[rows, starts])
        cur = np.where(reach, starts, self.goal)
        steps = [cur]
        while True:
            moving = cur != self.goal
            if not moving.any():
                break
            nxt = cur.copy()
            nxt[moving] = self.hop[rows[moving], cur[moving]]
            if np.any(nxt[moving] == NO_HOP):  # never: a finite distance has a complete walk
                raise ProblemError("a reverse shortest-path tree has a broken walk")
            cur = nxt
            steps.append(cur)
        table = np.stack(steps, axis=1)  # (W, L + 1), the goal repeated after each walk's end
        out: list[IntArray | None] = []
        for w in range(num):
            if not reach[w]:
                out.append(None)
                continue
            seq = table[w]
            end = int(np.argmax(seq == self.goal))
            out.append(np.asarray(seq[: end + 1], dtype=np.int64))
        return out


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
        graph = sp.csr_array((data, (rows, cols)), shape=(num * block, num * block))
        graph.sort_indices()
        self._graph = graph
        # Where each block's spare arcs sit in the CSR arrays (its goal vertex's row: all of that row).
        goal_rows = np.arange(num) * block + v
        self._slots = graph.indptr[goal_rows][:, None] + np.arange(self.slots)[None, :]
        self._trees: OrderedDict[int, GoalTree] = OrderedDict()

    @property
    def num_worlds(self) -> int:
        """W, the worlds searched."""
        return int(self.worlds.size)

    @property
    def goals_kept(self) -> tuple[int, ...]:
        """The graph goals whose reverse trees are kept, least recently used first."""
        return tuple(self._trees)

    def tree(self, goal: int) -> GoalTree:
        """The reverse trees of a graph vertex ``goal`` (kept for the next query to the same goal)."""
        known = self._trees.get(int(goal))
        if known is not None:
            self._trees.move_to_end(int(goal))
            return known
        if not 0 <= int(goal) < self.arcs.num_vertices:
            raise ProblemError(f"goal vertex {goal} outside [0, {self.arcs.num_vertices})")
        tree = self._search(int(goal))
        self._trees[int(goal)] = tree
        while len(self._trees) > GOAL_TREES_KEPT:
            self._trees.popitem(last=False)
        return tree

    def forget_trees(self) -> None:
        """Drop the reverse trees kept for past goals (the next query to any goal searches anew)."""
        self._trees.clear()

    def joined_tree(self, joins: GoalJoins) -> GoalTree:
        """The reverse trees of an off-graph goal joined by ``joins`` (not kept: the goal is a state)."""
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
        return self._search(self.block - 1, graph)

    def _search(self, goal: int, graph: sp.csr_array | None = None) -> GoalTree:
        num, block = self.num_worlds, self.block
        sources = np.arange(num) * block + goal
        dist, pred, _ = dijkstra(
            self._graph if graph is None else graph,
            directed=True,
            indices=sources,
            min_only=True,
            return_predecessors=True,
        )
        dist = np.asarray(dist, dtype=np.float64).reshape(num, block)
        hop = np.asarray(pred, dtype=np.int64).reshape(num, block)
        local = hop - (np.arange(num) * block)[:, None]
        hop = np.where(hop >= 0, local, NO_HOP)
        return GoalTree(goal, dist, hop)
