"""Search worlds whose shortest free path is the union graph's, found without searching them.

The arcs free in any search world make the *union graph*; its distance to a goal is a lower bound of every
world's (a world's free arcs are a subgraph). Take the union's shortest path P from a start. An arc is *tight*
when its length plus its head's union distance equals its tail's union distance (within
:data:`TIGHT_TOLERANCE`): every shortest path of a world in which P is free (so the world's distance equals the
union's) is made of tight arcs only. So where P's arcs are free in a world and every *other* tight arc leaving a
vertex of P is blocked there, the walk from the start can only follow P: P is that world's **unique** shortest
free path, and the world's own Dijkstra search would return exactly P. Those worlds need no search; a robot's
short query on a prior whose worlds mostly agree resolves most of its worlds this way (measured in the
results' "Time to a verified plan").

An off-graph goal is the extra vertex of the graph (joined by motions): its motions are arcs into it, with their
own outcomes per world.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.lazysp import GraphArcs

__all__ = ["NO_HOP", "TIGHT_TOLERANCE", "JoinMotions", "UnionTree", "follows_union"]

#: A reverse tree's next hop where there is none (the goal itself, or a vertex that cannot reach it).
NO_HOP = -1
#: Relative tolerance of "tight" (an arc on some shortest path): sums of lengths along different paths that are
#: equal in exact arithmetic may differ by rounding; treating near-equal as equal only withholds the shortcut.
TIGHT_TOLERANCE = 1e-9


@dataclass(frozen=True)
class UnionTree:
    """The reverse shortest-path tree of a goal over the arcs free in any search world.

    Attributes:
        goal: the goal vertex (the extra vertex ``B - 1`` of a block for an off-graph goal).
        dist: (B,) each vertex's distance to the goal over the union (inf: no world reaches it); a lower bound of
            every world's distance.
        hop: (B,) int32 next vertex towards the goal (:data:`NO_HOP` at the goal and where it cannot be reached).
    """

    goal: int
    dist: FloatArray
    hop: npt.NDArray[np.int32]

    def walk(self, start: int) -> IntArray:
        """The union's shortest path from ``start`` as vertices (start first, goal last); empty if unreachable."""
        if not np.isfinite(self.dist[start]):
            return np.zeros(0, dtype=np.int64)
        seq = [int(start)]
        hop = self.hop
        while seq[-1] != self.goal:
            seq.append(int(hop[seq[-1]]))
        return np.asarray(seq, dtype=np.int64)


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

    def same_as(self, other: JoinMotions) -> bool:
        """Whether ``other`` holds the same motions with the same outcomes."""
        pairs = ((self.vertices, other.vertices), (self.lengths, other.lengths), (self.free, other.free))
        return all(np.array_equal(a, b) for a, b in pairs)


def follows_union(
    union: UnionTree,
    start: int,
    arcs: GraphArcs,
    arc_length: FloatArray,
    free: BoolArray,
    anywhere: BoolArray,
    goal_joins: JoinMotions | None = None,
) -> BoolArray:
    """(W,) whether each world's shortest free path from ``start`` is, uniquely, the union's.

    Args:
        union: the goal's union tree (over the arcs free in any of the W worlds, goal motions included).
        start: a graph vertex.
        arcs: the graph's arcs.
        arc_length: (A,) their lengths as the union search used them.
        free: (W, E) bool, edge e free in world w.
        anywhere: (E,) bool, edge e free in any of the W worlds.
        goal_joins: the motions into an off-graph goal (``union.goal`` is then their common head).

    Returns:
        All False where the union does not reach the goal from ``start``, or ``start`` is the goal.
    """
    num = free.shape[0]
    walk = union.walk(int(start))
    if walk.size < 2:
        return np.zeros(num, dtype=bool)
    dist = union.dist
    tails = walk[:-1]
    heads = walk[1:]
    tol = TIGHT_TOLERANCE * max(1.0, float(dist[start]))
    bound = dist[tails] + tol  # (L,) a tight arc out of tails[i] is at most this long with its head's distance
    # Every graph arc out of the walk's vertices (CSR rows), with the step it leaves from.
    first, last = arcs.indptr[tails], arcs.indptr[tails + 1]
    counts = last - first
    step = np.repeat(np.arange(tails.size), counts)
    pos = np.repeat(first - np.cumsum(counts) + counts, counts) + np.arange(int(counts.sum()))
    head = arcs.v[pos]
    edge = arcs.edge[pos]
    tight = arc_length[pos] + dist[head] <= bound[step]
    # The path's own arc per step: the first tight arc, free in some world, to the walk's next vertex.
    candidate = np.flatnonzero(tight & (head == heads[step]) & anywhere[edge])
    candidate = candidate[np.r_[True, step[candidate][1:] != step[candidate][:-1]]] if candidate.size else candidate
    graph_steps = tails.size if goal_joins is None else tails.size - 1
    taken = step[candidate]
    if not np.array_equal(taken, np.arange(graph_steps)):  # a step the graph's arcs do not make (never, but safe)
        return np.zeros(num, dtype=bool)
    on_path = np.zeros(pos.size, dtype=bool)
    on_path[candidate] = True
    ok = free[:, edge[candidate]].all(axis=1) & ~free[:, edge[tight & ~on_path]].any(axis=1)
    if goal_joins is not None:
        ok &= _goal_motions_follow(goal_joins, tails, bound)
    return np.asarray(ok, dtype=bool)


def _goal_motions_follow(goal_joins: JoinMotions, tails: IntArray, bound: FloatArray) -> BoolArray:
    """(W,) where the walk's last motion into the goal is free and every other tight motion into it is blocked."""
    step_of = {int(v): i for i, v in enumerate(tails.tolist())}  # a shortest walk visits each vertex once
    index = np.array([step_of.get(int(v), -1) for v in goal_joins.vertices.tolist()], dtype=np.int64)
    tight = (index >= 0) & (goal_joins.lengths <= bound[np.maximum(index, 0)])  # the goal's distance is 0
    chosen = np.flatnonzero(tight & (index == tails.size - 1) & goal_joins.free.any(axis=0))
    if chosen.size == 0:  # the union's last step is not a motion out of the walk's last vertex (never, but safe)
        return np.zeros(goal_joins.free.shape[0], dtype=bool)
    others = tight.copy()
    others[chosen[0]] = False
    return np.asarray(goal_joins.free[:, chosen[0]] & ~goal_joins.free[:, others].any(axis=1), dtype=bool)
