"""The searched worlds' reverse-tree rows, each kept over just the vertices its search covered.

A search of n worlds over k of the graph's B vertices (a short query's ellipse is a small part of the graph)
writes n rows of k distances and next hops: one *segment*. Each world points at its latest row. A distance is
known (finite, or inf: the vertex cannot reach the goal in that world) or unknown (NaN in a row, or a vertex the
world's segment did not cover): an unknown vertex reads as distance inf with no next hop, and
:meth:`TreeRows.known_at` tells the two apart. Rows are stored flat, so a query pays for what it searched, not
for n x B.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.planner.union_paths import NO_HOP

__all__ = ["COMPACT_SEGMENTS", "COMPACT_SLACK", "TreeRows"]

#: Rows are compacted (replaced rows dropped) when the stored entries exceed twice the live ones plus this.
COMPACT_SLACK = 1 << 16
#: ... or when there are more segments than this (each holds a (B,) column map).
COMPACT_SEGMENTS = 64


class TreeRows:
    """Each search world's latest reverse-tree row, over the vertices its search covered.

    Args:
        num_worlds: W.
        block: B, the vertices a row could cover.

    Attributes:
        segment: (W,) the search that wrote each world's row (-1: not searched).
        radius: (W,) how far each world was searched: every vertex whose distance is at most this has it known
            (inf: the whole graph; 0 where not searched, or where only the known vertices are exact).
    """

    def __init__(self, num_worlds: int, block: int) -> None:
        self.block = block
        self.segment = np.full(num_worlds, -1, dtype=np.int64)
        self.radius = np.zeros(num_worlds)
        self._base = np.zeros(num_worlds, dtype=np.int64)  # where each world's row starts in the flat arrays
        self._local = np.zeros((0, block), dtype=np.int32)  # (S, B) each segment's column of a vertex, -1: none
        self._width = np.zeros(0, dtype=np.int64)  # (S,) each segment's row length
        # Flat rows after one unknown entry (what an uncovered vertex's lookup reads).
        self._dist = np.full(1, np.nan)
        self._hop = np.full(1, NO_HOP, dtype=np.int32)

    @property
    def searched(self) -> BoolArray:
        """(W,) whether each world has a row."""
        return np.asarray(self.segment >= 0, dtype=bool)

    def add(
        self, worlds: IntArray, vertices: IntArray, dist: FloatArray, hop: npt.NDArray[np.int32], radius: float
    ) -> None:
        """New rows of ``worlds`` (n,) over ``vertices`` (k,): ``dist`` (n, k) and ``hop`` (n, k) graph vertices.

        ``dist`` is NaN where a distance is not known. A world's earlier row, if any, is replaced.
        """
        n, k = dist.shape
        local = np.full((1, self.block), -1, dtype=np.int32)
        local[0, vertices] = np.arange(k)
        self.segment[worlds] = self._local.shape[0]
        self._base[worlds] = self._dist.size + k * np.arange(n)
        self.radius[worlds] = radius
        self._local = np.concatenate([self._local, local])
        self._width = np.append(self._width, k)
        self._dist = np.concatenate([self._dist, np.asarray(dist, dtype=np.float64).ravel()])
        self._hop = np.concatenate([self._hop, np.asarray(hop, dtype=np.int32).ravel()])
        live = int(self._width[self.segment[self.segment >= 0]].sum())
        if self._dist.size > 2 * live + COMPACT_SLACK or self._local.shape[0] > COMPACT_SEGMENTS:
            self._compact()

    @property
    def stored_entries(self) -> int:
        """How many distances the rows hold (replaced rows until the next compaction included)."""
        return int(self._dist.size - 1)

    def _compact(self) -> None:
        """Keep only the rows worlds read (a replaced row's entries and unreferenced segments dropped)."""
        live = np.flatnonzero(self.segment >= 0)
        kept = np.unique(self.segment[live])
        dist, hop = [self._dist[:1]], [self._hop[:1]]
        at = 1
        segment, base = self.segment.copy(), self._base.copy()
        for new, old in enumerate(kept.tolist()):
            worlds = live[self.segment[live] == old]
            k = int(self._width[old])
            cells = (self._base[worlds][:, None] + np.arange(k)[None, :]).ravel()
            dist.append(self._dist[cells])
            hop.append(self._hop[cells])
            segment[worlds] = new
            base[worlds] = at + k * np.arange(worlds.size)
            at += k * worlds.size
        self.segment, self._base = segment, base
        self._local, self._width = self._local[kept], self._width[kept]
        self._dist, self._hop = np.concatenate(dist), np.concatenate(hop)

    def dist_at(self, vertices: IntArray) -> FloatArray:
        """(W, m) each world's known distance of ``vertices`` (m,) to the goal (inf where not known)."""
        stored = self._stored(vertices)
        return np.where(np.isnan(stored), np.inf, stored)

    def known_at(self, vertices: IntArray) -> BoolArray:
        """(W, m) whether each world's distance of ``vertices`` (m,) is known (inf included: it cannot reach)."""
        return np.asarray(~np.isnan(self._stored(vertices)), dtype=bool)

    def dist_of(self, worlds: IntArray, at: IntArray) -> FloatArray:
        """(n,) the known distance of vertex ``at[i]`` in world ``worlds[i]`` (each searched; inf if not known)."""
        col = self._local[self.segment[worlds], at]
        known = col >= 0
        stored = np.where(known, self._dist[np.where(known, self._base[worlds] + col, 0)], np.inf)
        return np.where(np.isnan(stored), np.inf, stored)

    def _stored(self, vertices: IntArray) -> FloatArray:
        """(W, m) the stored distances of ``vertices`` (m,): NaN where not known."""
        vertices = np.asarray(vertices, dtype=np.int64)
        out = np.full((self.segment.size, vertices.size), np.nan)
        has = np.flatnonzero(self.segment >= 0)
        if has.size:
            col = self._local[self.segment[has][:, None], vertices[None, :]]  # (h, m)
            known = col >= 0
            at = self._base[has][:, None] + col
            out[has] = np.where(known, self._dist[np.where(known, at, 0)], np.nan)
        return out

    def hop_of(self, worlds: IntArray, at: IntArray) -> npt.NDArray[np.int32]:
        """(n,) the next hop from vertex ``at[i]`` in world ``worlds[i]`` (:data:`NO_HOP` where not known)."""
        col = self._local[self.segment[worlds], at]
        known = col >= 0
        hop = np.where(known, self._hop[np.where(known, self._base[worlds] + col, 0)], NO_HOP)
        return np.asarray(hop, dtype=np.int32)
