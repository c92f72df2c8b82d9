"""The known-free regions of a lazy search: what the start reaches, and what reaches the goal, over checked-free edges.

LazySP's ``balanced`` selector (:mod:`drd_planner.core.lazysp`) checks from the end of its path whose region is
smaller. The regions only grow while edges are checked free, so :class:`FreeReach` grows them with each free edge
(a search from the newly reached vertices only): over a whole search the work is that of one search over the
checked-free edges, not one per check. An edge once checked free and later blocked (a map update) shrinks them:
they are then searched again from scratch.
"""

from __future__ import annotations

__all__ = ["FreeReach"]


class FreeReach:
    """The vertices ``start`` reaches and those that reach ``goal`` over the edges added as free.

    Args:
        start: the start vertex (in its own region).
        goal: the goal vertex (in its own region).
        directed: edges are arcs ``u -> v`` only (else both ways).
    """

    def __init__(self, start: int, goal: int, *, directed: bool) -> None:
        self._start, self._goal, self._directed = int(start), int(goal), directed
        self._free: dict[tuple[int, int], int] = {}  # (u, v) -> how many free edges join them
        self._ahead: dict[int, list[int]] = {}
        self._behind: dict[int, list[int]] = {}
        self._from_start = {self._start}
        self._into_goal = {self._goal}

    @property
    def sizes(self) -> tuple[int, int]:
        """(vertices reachable from the start, vertices that reach the goal), the ends themselves included."""
        return len(self._from_start), len(self._into_goal)

    def add(self, u: int, v: int) -> None:
        """An edge ``u -> v`` (both ways when undirected) was checked free."""
        u, v = int(u), int(v)
        self._free[(u, v)] = self._free.get((u, v), 0) + 1
        for tail, head in self._arcs(u, v):
            self._ahead.setdefault(tail, []).append(head)
            self._behind.setdefault(head, []).append(tail)
            if tail in self._from_start and head not in self._from_start:
                _grow(self._from_start, self._ahead, head)
            if head in self._into_goal and tail not in self._into_goal:
                _grow(self._into_goal, self._behind, tail)

    def remove(self, u: int, v: int) -> None:
        """An edge ``u -> v`` added before is blocked now: the regions are searched again without it."""
        key = (int(u), int(v))
        left = self._free.get(key, 0) - 1
        if left < 0:
            return
        if left:
            self._free[key] = left
        else:
            del self._free[key]
        self._ahead, self._behind = {}, {}
        self._from_start, self._into_goal = {self._start}, {self._goal}
        edges, self._free = self._free, {}
        for (a, b), count in edges.items():
            for _ in range(count):
                self.add(a, b)

    def _arcs(self, u: int, v: int) -> tuple[tuple[int, int], ...]:
        return ((u, v),) if self._directed else ((u, v), (v, u))


def _grow(region: set[int], adjacency: dict[int, list[int]], first: int) -> None:
    """Add ``first`` and everything it reaches over ``adjacency`` (stopping at vertices already in) to ``region``."""
    region.add(first)
    todo = [first]
    while todo:
        for nxt in adjacency.get(todo.pop(), ()):
            if nxt not in region:
                region.add(nxt)
                todo.append(nxt)
