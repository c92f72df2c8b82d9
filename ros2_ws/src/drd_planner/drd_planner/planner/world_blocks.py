"""Reverse shortest-path trees of several search worlds in one scipy call, on a graph of just what they need.

The worlds searched, each a block of one block-diagonal graph of their free arcs reversed: vertex v of the r-th
world searched is ``r * n + local(v)``. A Dijkstra from the goal's copy in every block at once (``min_only``: the
blocks do not touch, so each vertex's distance is its own world's) computes their trees in C. A block holds only
the vertices whose distance to the goal over the **union** (the arcs free in any search world, a lower bound of
every world's) is within the search's limit: no world can reach another one within it, so a short query's
search is small whatever the graph's size. Worlds alike on every arc of the search (common for a short query,
whose few arcs few obstacles touch) share one block, and their rows are copied from it: the same distances and
next hops (on the shipped priors and three authors' sets, 1 422 planned episodes gave the same checks), in
fewer blocks. The vertex ``B - 1`` (``B = V + 1``) stands for an off-graph goal, whose motions are its arcs
for that search only.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra

from drd_planner.arrays import BoolArray, FloatArray, IntArray, row_groups
from drd_planner.core.lazysp import GraphArcs
from drd_planner.planner.union_paths import NO_HOP, JoinMotions, UnionTree

__all__ = ["WorldBlocks"]


class WorldBlocks:
    """W worlds' free arcs, reversed, ready to be cut into blocks; their weakly connected parts; the union.

    Args:
        arcs: the graph's arcs.
        arc_length: (A,) positive arc lengths (a zero length nudged up: csgraph reads 0 as "no arc").
        free: (W, A) bool, arc a free in world c.
        slots: the most motions into an off-graph goal.
    """

    def __init__(self, arcs: GraphArcs, arc_length: FloatArray, free: BoolArray, slots: int) -> None:
        num = free.shape[0]
        v = arcs.num_vertices
        block = v + 1
        self.block = block
        self.num_worlds = num
        self.slots = slots
        # Reversed arcs (head -> tail) in order of their head: a block's CSR rows.
        order = np.argsort(arcs.v, kind="stable")
        self._head, self._tail, self._length = arcs.v[order], arcs.u[order], arc_length[order]
        self._free = np.ascontiguousarray(free[:, order])  # (W, A)
        # The weakly connected parts of each world's free arcs: (W, B) labels.
        copies, which = np.nonzero(free)
        rows, cols = arcs.v[which] + copies * block, arcs.u[which] + copies * block
        arcs_only = sp.coo_array((np.ones(which.size, dtype=np.int8), (rows, cols)), shape=(num * block, num * block))
        _, labels = connected_components(arcs_only, directed=True, connection="weak")
        self.parts = np.asarray(labels, dtype=np.int32).reshape(num, block)
        # Every reversed arc in one graph (rows: heads), then the goal vertex's row of spare arcs (the last row):
        # a union search writes the weights (inf deletes an arc) and the off-graph goal's motions.
        self._anywhere_forward: BoolArray = np.asarray(free.any(axis=0), dtype=bool)
        self._anywhere = self._anywhere_forward[order]
        self._union_weights = np.where(self._anywhere, self._length, np.inf)  # the arcs free in no world deleted
        counts = np.bincount(self._head, minlength=block)
        counts[block - 1] += slots
        self._indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
        self._indices = np.concatenate([self._tail, np.arange(slots)]).astype(np.int32)
        # The arcs forward (rows: tails, as the graph's arcs are sorted), rows for the goal vertex (none) and for
        # an extra start vertex ``B`` whose arcs are an off-graph start's motions.
        self._forward_length = arc_length
        self._forward_indptr = np.concatenate([arcs.indptr, [arcs.indptr[-1]]]).astype(np.int64)
        self._forward_indices = arcs.v.astype(np.int32)

    def union_tree(self, goal: int, joins: JoinMotions | None = None) -> UnionTree:
        """The goal's reverse shortest-path tree over the arcs free in any world.

        ``joins``: the motions into the off-graph goal ``B - 1`` (those free in any world are arcs).
        """
        spare = np.full(self.slots, np.inf)
        indices = self._indices
        if joins is not None:
            k = int(joins.vertices.size)
            indices = indices.copy()
            indices[indices.size - self.slots : indices.size - self.slots + k] = joins.vertices
            spare[:k] = np.where(joins.free.any(axis=0), joins.lengths, np.inf)
        data = np.concatenate([self._union_weights, spare])
        union = sp.csr_array((data, indices, self._indptr), shape=(self.block, self.block))
        dist, pred = dijkstra(union, directed=True, indices=goal, return_predecessors=True)
        hop = np.asarray(pred, dtype=np.int32)
        np.maximum(hop, NO_HOP, out=hop)  # scipy's -9999 where there is no predecessor
        return UnionTree(int(goal), np.asarray(dist, dtype=np.float64), hop)

    def union_from(self, vertices: IntArray, lengths: FloatArray, usable: BoolArray) -> FloatArray:
        """(B,) each vertex's distance from a start over the arcs free in any world (inf for the goal vertex).

        Args:
            vertices: (k,) where the start's motions reach the graph (the start itself: one, of length 0).
            lengths: (k,) their lengths.
            usable: (k,) whether each is free in any world.
        """
        k = int(vertices.size)
        extra = self.block  # the start's own vertex, after the goal's
        data = np.concatenate([np.where(self._anywhere_forward, self._forward_length, np.inf), lengths])
        data[data.size - k :][~usable] = np.inf
        indices = np.concatenate([self._forward_indices, vertices.astype(np.int32)])
        indptr = np.concatenate([self._forward_indptr, [self._forward_indptr[-1] + k]])
        graph = sp.csr_array((data, indices, indptr), shape=(extra + 1, extra + 1))
        dist = dijkstra(graph, directed=True, indices=extra)
        return np.asarray(dist[:extra], dtype=np.float64)

    def search(
        self,
        union: UnionTree,
        worlds: IntArray,
        *,
        limit: float,
        joins: JoinMotions | None = None,
        within: BoolArray | None = None,
    ) -> tuple[IntArray, FloatArray, npt.NDArray[np.int32]]:
        """Dijkstra from the union tree's goal in each of ``worlds`` (R,) as far as ``limit``.

        Args:
            union: the goal's union tree (its goal: a graph vertex, or ``B - 1`` joined by ``joins``).
            worlds: (R,) indices of the worlds to search.
            limit: how far (the graph's unit; inf: the whole graph).
            joins: the motions into an off-graph goal, ``free`` (W, k) over all W worlds.
            within: (B,) the vertices searched (None: all those whose union distance is within ``limit``); a
                shortest path through others is not found.

        Returns:
            (k,) the vertices searched, (R, k) their distance to the goal (inf beyond ``limit`` or unreachable)
            and (R, k) int32 next hop (a graph vertex; :data:`NO_HOP` where there is none).
        """
        count = int(worlds.size)
        if within is None:  # no world reaches another vertex within the limit
            within = np.isfinite(union.dist) & (union.dist <= limit)
        if not within[union.goal]:  # nothing to search (a limit below the goal's own ellipse)
            return np.zeros(0, dtype=np.int64), np.zeros((count, 0)), np.zeros((count, 0), dtype=np.int32)
        kept = np.flatnonzero(within)
        local = np.full(self.block, -1, dtype=np.int64)
        local[kept] = np.arange(kept.size)
        size = int(kept.size)
        arcs = np.flatnonzero(within[self._head] & within[self._tail])  # in order of their head
        row, col, length = local[self._head[arcs]], local[self._tail[arcs]], self._length[arcs]
        free = self._free[worlds] if arcs.size == self._free.shape[1] else self._free[worlds][:, arcs]  # (R, a)
        if joins is not None:  # the goal's motions: its row, the last one (B - 1 is the largest vertex)
            reach = within[joins.vertices]
            row = np.concatenate([row, np.full(int(reach.sum()), local[union.goal])])
            col = np.concatenate([col, local[joins.vertices[reach]]])
            length = np.concatenate([length, joins.lengths[reach]])
            free = np.concatenate([free, joins.free[worlds][:, reach]], axis=1)
        # Worlds alike on every arc searched have the same tree: one block per distinct row, copied back.
        first, group = row_groups(free)
        blocks = int(first.size)
        graph = _block_graph(free[first], row, col, length, size)
        sources = np.arange(blocks) * size + local[union.goal]
        dist_local, pred, _ = dijkstra(
            graph, directed=True, indices=sources, min_only=True, return_predecessors=True, limit=limit
        )
        pred = pred.reshape(blocks, size) - (np.arange(blocks) * size)[:, None]
        hop = np.where(pred >= 0, kept[np.clip(pred, 0, max(size - 1, 0))], NO_HOP).astype(np.int32)
        dist = np.asarray(dist_local, dtype=np.float64).reshape(blocks, size)
        return kept, dist[group], hop[group]


def _block_graph(free: BoolArray, row: IntArray, col: IntArray, length: FloatArray, size: int) -> sp.csr_array:
    """The block-diagonal CSR graph of each block's free arcs: block r's vertex i is ``r * size + i``.

    Args:
        free: (blocks, a) bool, arc j free in block r.
        row: (a,) each arc's local row (its head), non-decreasing: a block's arcs are already in CSR order.
        col: (a,) each arc's local column (its tail).
        length: (a,) arc lengths.
        size: vertices per block.

    The row pointers are read off one running count of free arcs at each row's first arc (no per-arc sort or
    bincount): a third of the time of building it from the free arcs' coordinates on Baffle's 200-world searches.
    Memory beyond ``free``: the running count (4 bytes per entry) and 8 bytes per free arc.
    """
    blocks, count = free.shape
    running = np.zeros(free.size + 1, dtype=np.int32)
    np.cumsum(free.ravel(), out=running[1:])
    row_start = np.searchsorted(row, np.arange(size))  # (size,) each row's first arc
    at = (np.arange(blocks)[:, None] * count + row_start[None, :]).ravel()
    indptr = np.concatenate([running[at], running[-1:]])
    block, arc = np.divmod(np.flatnonzero(free), count)  # the free arcs, by block then by row: CSR order
    indices = (col[arc] + block * size).astype(np.int32)
    return sp.csr_array((length[arc], indices, indptr), shape=(blocks * size,) * 2)
