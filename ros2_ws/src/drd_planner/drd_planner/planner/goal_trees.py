"""Every search world's shortest free path to a goal, from any start: reverse shortest-path trees, batched.

A query's path library (:mod:`~drd_planner.planner.query_library`) is the distinct shortest free paths of a
seeded sample of the training worlds. A robot's goal changes rarely while its start changes with every
replan, so the searches run from the goal: one reverse shortest-path tree per search world gives every start's
shortest free path to that goal by following next hops, and the trees are kept per goal.

**Most worlds need no search.** Where the shortest path over the arcs free in *any* search world (the union) is
free in a world and is its only shortest path there, it is that world's path
(:mod:`~drd_planner.planner.union_paths`): one search of the union per goal and a test per start resolve them.

**The others in one scipy call.** Their free arcs, reversed, are blocks of one block-diagonal graph
(:mod:`~drd_planner.planner.world_blocks`); a Dijkstra from the goal's copy in each of them at once computes their
trees in C, on a graph of just the blocks searched.

**Searched only where the start's path can be.** A world is searched first only in the ellipse of vertices
through which a path from the start of at most ``ELLIPSE_FACTORS[0]`` times the start's distance over the union
(a lower bound of every world's) could pass: on a robot's query a small part of the graph. A vertex whose
distance found there plus its union distance from the start is within the ellipse's length has its exact
distance and next hop; a world whose start is not among them (a long detour, or no path) is searched again in a
wider ellipse, then in every vertex the start can reach and the goal be reached from over the union (which
settles it: a path, or none). A start in another weakly connected part of a world's free arcs than the goal
(computed once per prior) cannot reach it there, so that world needs no search for it (most of them: a start
walled in by blocked edges). A later start of the same goal reads what is known, and searches only the worlds
it is not covered in (:meth:`GoalTree.covers`). So a replan from along the route walks the kept trees, and any
start gets the same paths as unbounded trees of every world.

**A goal off the graph** is the extra vertex ``B - 1`` of each block; the motions joining it (their vertex,
length and imputed outcome per world) are arcs into it for that query only (its trees are not kept).

The search worlds: the distinct training worlds (rows compared through a 64-bit hash, then exactly) in a
seeded order, the first W of them.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray, first_distinct_rows
from drd_planner.core.lazysp import GraphArcs
from drd_planner.exceptions import ProblemError
from drd_planner.planner.tree_rows import TreeRows
from drd_planner.planner.union_paths import NO_HOP, TIGHT_TOLERANCE, JoinMotions, UnionTree, follows_union
from drd_planner.planner.world_blocks import WorldBlocks

__all__ = [
    "ELLIPSE_FACTORS",
    "FOLLOW_UNION",
    "GOAL_JOIN_SLOTS",
    "GOAL_TREES_KEPT",
    "NO_HOP",
    "SEARCH_WORLDS",
    "GoalTree",
    "GoalWalks",
    "JoinMotions",
    "SearchWorlds",
]

#: The most training worlds searched for a query's library (the sample's size).
SEARCH_WORLDS = 256
#: Motions into an off-graph goal a search can take (spare arcs of each block's goal vertex).
GOAL_JOIN_SLOTS = 64
#: Goals whose trees a :class:`SearchWorlds` keeps (least recently used dropped first).
GOAL_TREES_KEPT = 8
#: How long a path a world's searches look for, in turn, as multiples of the start's distance over the arcs free in
#: any search world (each search covers the ellipse such paths could pass through; the last, inf, every vertex a
#: path from the start can pass through, which settles every world).
ELLIPSE_FACTORS = (1.25, 2.5, np.inf)
#: Read a world's path off the union where it is provably that world's only shortest path (False: search every
#: world; the paths are the same, only slower).
FOLLOW_UNION = True


@dataclass(frozen=True)
class GoalTree:
    """The reverse shortest-path trees of one goal: the union's, and those of the worlds that were searched.

    Attributes:
        goal: the goal's vertex in a block (``B - 1`` for an off-graph goal).
        union: the goal's tree over the arcs free in any search world (a lower bound of every world's distance).
        rows: the searched worlds' rows (distance to the goal and next hop of the vertices each search covered;
            every vertex within a world's ``radius`` is known, as in an unbounded search). Rows are searched again
            further when a later start needs it, and never change otherwise.
        parts: (W, B) int32 label of each vertex's weakly connected part of each world's free arcs (vertices
            of different parts cannot reach each other), or None when unknown.
        joins: the motions into an off-graph goal (None for a graph vertex).
    """

    goal: int
    union: UnionTree
    rows: TreeRows
    parts: npt.NDArray[np.int32] | None = None
    joins: JoinMotions | None = None

    @property
    def num_worlds(self) -> int:
        """W, the search worlds."""
        return int(self.rows.segment.size)

    def dist_at(self, vertices: IntArray) -> FloatArray:
        """(W, n) each world's searched distance of ``vertices`` (n,) to the goal (inf where not known)."""
        return self.rows.dist_at(vertices)

    def world_radius(self) -> FloatArray:
        """(W,) how far each world was searched (0 where it was not, or only its known vertices are exact)."""
        return self.rows.radius

    def covers(self, start: int | JoinMotions) -> BoolArray:
        """(W,) whether each world's shortest free path from ``start`` can be read off its searched tree.

        A vertex start is covered where its distance is known (a path, or none), it lies in another part than
        the goal or no world reaches the goal from it (it cannot reach it), or the world was searched without
        bound. A joined start (``free`` (W, k)) is covered where no free motion to a vertex of unknown distance
        (in the goal's part) could beat the best known one (the best free motion is then exactly chosen,
        :meth:`best_joins`).
        """
        whole = np.isinf(self.world_radius())
        if not isinstance(start, JoinMotions):
            vertex = int(start)
            cut = np.zeros_like(whole) if self.parts is None else self.parts[:, vertex] != self.parts[:, self.goal]
            nowhere = not np.isfinite(self.union.dist[vertex])
            return np.asarray(whole | cut | nowhere | self.rows.known_at(np.array([vertex]))[:, 0], dtype=bool)
        dist = self.dist_at(start.vertices)  # (W, k)
        best = np.min(np.where(start.free, start.lengths[None, :] + dist, np.inf), 1)
        open_ = start.free & ~self.rows.known_at(start.vertices)
        if self.parts is not None:
            open_ &= self.parts[:, start.vertices] == self.parts[:, self.goal][:, None]
        # A motion to a vertex of unknown distance is at least its length plus the radius (and its union distance).
        beyond = np.maximum(self.world_radius()[:, None], self.union.dist[start.vertices][None, :])
        floor = np.where(open_, start.lengths[None, :] + beyond, np.inf)
        return np.asarray(whole | (best <= floor.min(axis=1)), dtype=bool)

    def best_joins(self, start: JoinMotions) -> tuple[IntArray, BoolArray]:
        """Per world, the free motion with the shortest searched free path behind it (the first of equally short).

        Returns:
            (W,) the motion's index (0 where none), (W,) whether a free path exists.
        """
        behind = np.where(start.free, start.lengths[None, :] + self.dist_at(start.vertices), np.inf)
        choice = np.asarray(np.argmin(behind, axis=1), dtype=np.int64)
        reachable = np.isfinite(behind[np.arange(behind.shape[0]), choice])
        return choice, np.asarray(reachable, dtype=bool)

    def walks(self, starts: IntArray, via: BoolArray | None = None) -> list[IntArray | None]:
        """Per world the vertex sequence from ``starts[w]`` to the goal, or None when it cannot reach it.

        Args:
            starts: (W,) a start vertex per world (the same one, or each world's best join); each must be
                covered (:meth:`covers`) or read off the union (``via``).
            via: (W,) bool, the worlds whose walk follows the union's tree (None: none).
        """
        table, lengths = self.walk_table(starts, via)
        return [None if n == 0 else np.asarray(table[w, :n], dtype=np.int64) for w, n in enumerate(lengths)]

    def walk_table(self, starts: IntArray, via: BoolArray | None = None) -> tuple[npt.NDArray[np.int32], IntArray]:
        """The walks of :meth:`walks` as one table.

        Returns:
            (W, L) int32 vertex sequences from ``starts[w]`` to the goal, the goal repeated after each walk's
            end, and (W,) each walk's vertex count (0 where the goal cannot be reached).
        """
        num = self.num_worlds
        starts = np.asarray(starts, dtype=np.int64)
        union = np.zeros(num, dtype=bool) if via is None else np.asarray(via, dtype=bool)
        searched = np.flatnonzero(~union & self.rows.searched)
        reach = np.zeros(num, dtype=bool)
        reach[union] = np.isfinite(self.union.dist[starts[union]])
        reach[searched] = np.isfinite(self.rows.dist_of(searched, starts[searched]))
        cur = np.where(reach, starts, self.goal).astype(np.int32)
        steps = [cur]
        count = reach.astype(np.int64)
        while True:
            moving = cur != self.goal
            if not moving.any():
                break
            nxt = cur.copy()
            on_union = np.flatnonzero(moving & union)
            nxt[on_union] = self.union.hop[cur[on_union]]
            on_rows = np.flatnonzero(moving & ~union)
            nxt[on_rows] = self.rows.hop_of(on_rows, cur[on_rows].astype(np.int64))
            if np.any(nxt[moving] == NO_HOP):  # never: a finite distance has a complete walk
                raise ProblemError("a reverse shortest-path tree has a broken walk")
            count[moving] += 1
            cur = nxt
            steps.append(cur)
        return np.stack(steps, axis=1), count


@dataclass(frozen=True)
class GoalWalks:
    """Each search world's shortest free path from a start to a goal, as vertex walks.

    Attributes:
        table: (W, L) int32 vertex sequences (the start's graph vertex first), the goal repeated after each end.
        counts: (W,) each walk's vertex count (0: no free path in that world).
        choice: (W,) the motion a joined start takes in each world (0 for a graph vertex, or where no path).
    """

    table: npt.NDArray[np.int32]
    counts: IntArray
    choice: IntArray


class SearchWorlds:
    """A prior's search worlds, their block graph (built once) and the reverse trees of recent goals.

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
        distinct = first_distinct_rows(x)
        order = distinct[np.random.default_rng(seed).permutation(distinct.size)]
        self.worlds: IntArray = np.asarray(order[:count], dtype=np.int64)
        self.arcs = arcs
        v = arcs.num_vertices
        arc_length = np.asarray(lengths, dtype=np.float64)[arcs.edge]
        self._arc_length = np.where(arc_length > 0, arc_length, np.finfo(np.float64).tiny)  # csgraph: 0 = no arc
        self._free = np.ascontiguousarray(x[self.worlds])  # (W, E)
        self._anywhere: BoolArray = np.asarray(self._free.any(axis=0), dtype=bool)
        self.slots = min(GOAL_JOIN_SLOTS, v)
        self._blocks = WorldBlocks(arcs, self._arc_length, self._free[:, arcs.edge], self.slots)
        self.block = self._blocks.block
        self._trees: OrderedDict[int, GoalTree] = OrderedDict()
        self._last_joined: tuple[JoinMotions, UnionTree] | None = None

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
                ``free`` (W, k)): each world is covered or follows the union there (:meth:`walks_from`). None:
                every world searched without bound.
        """
        tree = self._kept(int(goal))
        self._cover(tree, start)
        return tree

    def joined_tree(self, joins: JoinMotions, start: int | JoinMotions | None = None) -> GoalTree:
        """The reverse trees of an off-graph goal joined by ``joins``, covering ``start`` (not kept).

        As :meth:`tree` otherwise.
        """
        tree = self._joined(joins)
        self._cover(tree, start)
        return tree

    def walks_from(self, goal: int | JoinMotions, start: int | JoinMotions) -> GoalWalks:
        """Every search world's shortest free path from ``start`` to ``goal`` (a vertex, or an off-graph goal's joins).

        A joined start takes, per world, the free motion with the shortest free path behind it (the first of
        equally short ones).
        """
        tree = self._joined(goal) if isinstance(goal, JoinMotions) else self._kept(int(goal))
        via, union_choice = self._cover(tree, start)
        if not isinstance(start, JoinMotions):
            table, counts = tree.walk_table(np.full(self.num_worlds, int(start)), via)
            return GoalWalks(table, counts, np.zeros(self.num_worlds, dtype=np.int64))
        choice, reachable = tree.best_joins(start)
        choice = np.where(via, union_choice, choice)
        reachable |= via
        table, counts = tree.walk_table(np.where(reachable, start.vertices[choice], tree.goal), via)
        return GoalWalks(table, np.where(reachable, counts, 0), choice)

    def union_walk(self, goal: int | JoinMotions, start: int | JoinMotions) -> tuple[IntArray, int]:
        """The shortest path from ``start`` to ``goal`` over the arcs (and motions) free in any search world.

        Returns its vertices, start first (a joined start: the vertex its motion reaches) and goal last (a joined
        goal: ``B - 1``), empty when no search world has a path; and the joined start's motion (-1 for a vertex).
        A graph goal's union tree is kept with its reverse trees.
        """
        union = self._joined_union(goal) if isinstance(goal, JoinMotions) else self._kept(goal).union
        if not isinstance(start, JoinMotions):
            return union.walk(int(start)), -1
        choice, _ = _best_join(union, start)
        if choice < 0:
            return np.zeros(0, dtype=np.int64), -1
        return union.walk(int(start.vertices[choice])), choice

    def drop_tree(self, goal: int) -> None:
        """Drop the reverse trees kept for one graph goal (none kept: nothing happens)."""
        self._trees.pop(goal, None)

    def forget_trees(self) -> None:
        """Drop the reverse trees kept for past goals (the next query to any goal searches anew)."""
        self._trees.clear()
        self._last_joined = None

    # ------------------------------------------------------------------------------------------------

    def _kept(self, goal: int) -> GoalTree:
        """A graph goal's kept tree (only its union's, when new)."""
        known = self._trees.get(goal)
        if known is not None:
            self._trees.move_to_end(goal)
            return known
        if not 0 <= goal < self.arcs.num_vertices:
            raise ProblemError(f"goal vertex {goal} outside [0, {self.arcs.num_vertices})")
        known = self._empty(self._blocks.union_tree(goal), self._blocks.parts, None)
        self._trees[goal] = known
        while len(self._trees) > GOAL_TREES_KEPT:
            self._trees.popitem(last=False)
        return known

    def _joined(self, joins: JoinMotions) -> GoalTree:
        """An off-graph goal's tree (only its union's). No parts: its vertex is joined only in this search."""
        return self._empty(self._joined_union(joins), None, joins)

    def _joined_union(self, joins: JoinMotions) -> UnionTree:
        """An off-graph goal's union tree; the last one is kept (a query's probe, then its library, asks for it)."""
        k = int(joins.vertices.size)
        if k > self.slots:
            raise ProblemError(f"at most {self.slots} motions into a goal can be searched, got {k}")
        if joins.free.shape != (self.num_worlds, k):
            raise ProblemError(f"join outcomes must be ({self.num_worlds}, {k}), got {joins.free.shape}")
        last = self._last_joined
        if last is not None and last[0].same_as(joins):
            return last[1]
        union = self._blocks.union_tree(self.block - 1, joins)
        self._last_joined = (joins, union)
        return union

    def _empty(self, union: UnionTree, parts: npt.NDArray[np.int32] | None, joins: JoinMotions | None) -> GoalTree:
        """A tree with no world searched yet."""
        return GoalTree(union.goal, union, TreeRows(self.num_worlds, self.block), parts, joins)

    def _cover(self, tree: GoalTree, start: int | JoinMotions | None) -> tuple[BoolArray, IntArray]:
        """Search what ``start`` needs: returns (W,) the worlds read off the union and (W,) a joined start's motion.

        Worlds that neither follow the union nor are covered by their searched tree are searched in the ellipses of
        the vertices through which a path of at most each of ``ELLIPSE_FACTORS`` times the start's union distance
        could pass (:meth:`_search_ellipse`), each only where the one before did not find the path; then, where
        none did, without bound.
        """
        num = self.num_worlds
        if start is None:
            self._search(tree, np.flatnonzero(~np.isinf(tree.world_radius())), np.inf)
            return np.zeros(num, dtype=bool), np.zeros(num, dtype=np.int64)
        pending = ~tree.covers(start)
        if FOLLOW_UNION:
            via, choice = self._follow(tree.union, start, pending, tree.joins)
        else:
            via, choice = np.zeros(num, dtype=bool), np.zeros(num, dtype=np.int64)
        pending &= ~via
        fresh = pending.copy()
        ahead: FloatArray | None = None  # each vertex's distance from the start over the union, once
        for factor in ELLIPSE_FACTORS:  # each world searched in a wider ellipse until its path is found
            if not fresh.any():
                break
            if ahead is None:
                ahead = self._ahead(tree, start)
            self._search_ellipse(tree, np.flatnonzero(fresh), factor, ahead)
            covered = tree.covers(start)
            pending &= ~covered
            fresh &= ~covered
        self._search(tree, np.flatnonzero(pending), np.inf)
        return via, choice

    def _follow(
        self, union: UnionTree, start: int | JoinMotions, among: BoolArray, joins: JoinMotions | None
    ) -> tuple[BoolArray, IntArray]:
        """(W,) the worlds of ``among`` whose path from ``start`` is uniquely ``union``'s, (W,) a joined start's motion.

        A vertex start: :func:`follows_union`. A joined start: in a world, the free motion whose length plus
        union distance is least by a margin, with the union's path behind it being that world's only shortest
        one, is the world's best join.
        """
        num = self.num_worlds
        if not isinstance(start, JoinMotions):
            follows = among & self._follows(union, int(start), joins)
            return follows, np.zeros(num, dtype=np.int64)
        bound = np.where(start.free, (start.lengths + union.dist[start.vertices])[None, :], np.inf)  # (W, k)
        choice = np.asarray(np.argmin(bound, axis=1), dtype=np.int64)
        rows = np.arange(num)
        best = bound[rows, choice]
        bound[rows, choice] = np.inf
        near = _union_distance(union, start)
        clear = among & np.isfinite(best) & (bound.min(axis=1) > best + TIGHT_TOLERANCE * max(1.0, near))
        follows = np.zeros(num, dtype=bool)
        for motion in np.unique(choice[clear]).tolist():
            these = clear & (choice == motion)
            follows[these] = self._follows(union, int(start.vertices[motion]), joins)[these]
        return follows, choice

    def _follows(self, union: UnionTree, vertex: int, joins: JoinMotions | None) -> BoolArray:
        """(W,) the worlds whose shortest path from ``vertex`` is, uniquely, ``union``'s (``joins``: into the goal)."""
        return follows_union(union, vertex, self.arcs, self._arc_length, self._free, self._anywhere, joins)

    def _ahead(self, tree: GoalTree, start: int | JoinMotions) -> FloatArray:
        """(B,) each vertex's distance from ``start`` over the union (the goal's: the start's union distance)."""
        if isinstance(start, JoinMotions):
            ahead = self._blocks.union_from(start.vertices, start.lengths, np.asarray(start.free.any(axis=0)))
        else:
            ahead = self._blocks.union_from(np.array([int(start)]), np.zeros(1), np.ones(1, dtype=bool))
        ahead[tree.goal] = _union_distance(tree.union, start)  # an off-graph goal has no arcs into it forward
        return ahead

    def _search_ellipse(self, tree: GoalTree, worlds: IntArray, factor: float, ahead: FloatArray) -> None:
        """Search ``worlds`` (n,) only where a path from the start of ``factor`` times its union distance can pass.

        That is the vertices v with d(start, v) + d(v, goal) <= L = ``factor`` times the start's union distance
        (d over the union; ``ahead`` (B,) from the start, :meth:`_ahead`). A vertex whose distance found there
        plus its union distance from the start is at most L has its exact distance and next hop (every vertex of
        its shortest path lies in the ellipse); the others are left unknown. With ``factor`` inf (or an ellipse
        that holds it all) the region is every vertex the start can reach and the goal can be reached from over
        the union: every path from the start lies in it, so every distance found is exact (inf: that vertex
        cannot reach the goal in that world). The rows keep radius 0 (no ball around the goal is complete), so
        other starts read them only where they are known.
        """
        limit = factor * float(ahead[tree.goal])
        region = np.isfinite(ahead) & np.isfinite(tree.union.dist)  # every vertex a path from the start can pass
        within = region if np.isinf(limit) else ahead + tree.union.dist <= limit
        if np.isinf(limit) or np.count_nonzero(within) == np.count_nonzero(region):
            limit, within = np.inf, region  # the ellipse is the whole region: search it for good
        vertices, dist, hop = self._blocks.search(tree.union, worlds, limit=limit, joins=tree.joins, within=within)
        if np.isfinite(limit):
            unknown = ~(dist + ahead[vertices][None, :] <= limit)
            dist[unknown] = np.nan
            hop[unknown] = NO_HOP
        tree.rows.add(worlds, vertices, dist, hop, 0.0)

    def _search(self, tree: GoalTree, worlds: IntArray, limit: float) -> None:
        """Search ``worlds`` (n,) of a tree as far as ``limit`` (every vertex within it), writing their rows."""
        if worlds.size == 0:
            return
        vertices, dist, hop = self._blocks.search(tree.union, worlds, limit=limit, joins=tree.joins)
        tree.rows.add(worlds, vertices, dist, hop, limit)


def _union_distance(union: UnionTree, start: int | JoinMotions) -> float:
    """A start's distance to the goal over a union (a joined start: its best motion free in any world)."""
    if not isinstance(start, JoinMotions):
        return float(union.dist[int(start)])
    return _best_join(union, start)[1]


def _best_join(union: UnionTree, start: JoinMotions) -> tuple[int, float]:
    """A joined start's motion, free in some world, of least length plus union distance, and that sum.

    The first such motion on ties; (-1, inf) when no motion free in some world reaches the goal.
    """
    behind = np.where(start.free.any(axis=0), start.lengths + union.dist[start.vertices], np.inf)
    if behind.size == 0 or not np.isfinite(behind.min()):
        return -1, float("inf")
    choice = int(np.argmin(behind))
    return choice, float(behind[choice])
