"""The known-free regions grown per free edge equal a search of every free edge, also after a free edge is blocked."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order

from drd_planner.core.free_reach import FreeReach


def searched(free: list[tuple[int, int]], n: int, start: int, goal: int, directed: bool) -> tuple[int, int]:
    """The two regions' sizes by a breadth-first search of the whole graph of free arcs."""
    arcs = free if directed else free + [(v, u) for u, v in free]
    rows = np.array([a for a, _ in arcs], dtype=np.int64)
    cols = np.array([b for _, b in arcs], dtype=np.int64)
    adjacency = sp.csr_array((np.ones(rows.size), (rows, cols)), shape=(n, n))
    ahead = breadth_first_order(adjacency, start, directed=True, return_predecessors=False)
    behind = breadth_first_order(adjacency.T.tocsr(), goal, directed=True, return_predecessors=False)
    return int(ahead.size), int(behind.size)


@pytest.mark.parametrize("directed", [False, True])
def test_the_regions_grow_and_shrink_as_a_whole_search_says(directed: bool) -> None:
    rng = np.random.default_rng(7)
    n = 50
    pairs = [(int(a), int(b)) for a, b in rng.integers(n, size=(300, 2))]  # parallel edges and self-loops kept
    reach = FreeReach(0, n - 1, directed=directed)
    free: list[tuple[int, int]] = []
    grew = shrank = False
    for step in range(400):
        if free and rng.random() < 0.15:  # a free edge blocked (a map update)
            gone = free.pop(int(rng.integers(len(free))))
            before = reach.sizes
            reach.remove(*gone)
            shrank |= reach.sizes < before
        else:
            edge = pairs[step % len(pairs)]
            free.append(edge)
            before = reach.sizes
            reach.add(*edge)
            grew |= reach.sizes > before
        assert reach.sizes == searched(free, n, 0, n - 1, directed)
    assert grew  # both directions were exercised
    assert shrank


def test_removing_an_edge_never_added_changes_nothing() -> None:
    reach = FreeReach(0, 2, directed=False)
    reach.add(0, 1)
    reach.remove(1, 2)
    assert reach.sizes == (2, 1)
    reach.add(1, 2)
    assert reach.sizes == (3, 3)
    reach.remove(0, 1)
    assert reach.sizes == (1, 2)
