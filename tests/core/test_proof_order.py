"""Tests of the kept proof order: after any sequence of outcomes and biases it equals a new one, and its choice
equals the argmax of the per-check scores over every alive path."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from drd_planner.core import proof_order
from drd_planner.core.library import PathLibrary
from drd_planner.core.path_rows import PathRows, library_rows
from drd_planner.core.proof_order import ProofOrder
from drd_planner.core.region_rule import region_scores


def _library(seed: int, num_edges: int = 24, num_paths: int = 30) -> PathLibrary:
    rng = np.random.default_rng(seed)
    paths = [rng.choice(num_edges, size=int(rng.integers(1, 7)), replace=False) for _ in range(num_paths)]
    paths += [paths[3][::-1].copy(), paths[7].copy()]  # the same edge sets again: exact ties
    return PathLibrary(tuple(paths), num_edges)


def _best_order_cost(todo: list[int], theta: np.ndarray, costs: np.ndarray) -> float:
    """The cheapest expected cost of checking ``todo`` until the first blocked edge (brute force)."""
    best = np.inf
    for order in itertools.permutations(todo):
        total, reach = 0.0, 1.0
        for e in order:
            total += reach * costs[e]
            reach *= theta[e]
        best = min(best, total)
    return float(best)


def _case(seed: int, offset: int) -> tuple[PathLibrary, PathRows, np.random.Generator, np.ndarray, np.ndarray]:
    """A random library, its rows, a generator seeded ``offset + seed``, (E,) costs with ties and (E,) theta."""
    library = _library(seed)
    rng = np.random.default_rng(offset + seed)
    costs = rng.uniform(0.5, 3.0, library.num_edges)
    costs[rng.choice(library.num_edges, 4, replace=False)] = 1.0  # equal keys: ties by edge id
    return library, library_rows(library), rng, costs, rng.uniform(0.05, 0.95, library.num_edges)


@pytest.mark.parametrize("seed", range(6))
def test_updates_reach_what_a_new_order_computes(seed: int) -> None:
    library, rows, rng, costs, theta = _case(seed, 100)
    kept = ProofOrder(rows, theta, costs)
    checked = np.zeros(library.num_edges, dtype=bool)
    alive = np.ones(library.num_paths, dtype=bool)
    for step, edge in enumerate(rng.permutation(library.num_edges)[:16].tolist()):
        kept.mark_checked(edge, library.paths_through(edge))
        checked[edge] = True
        if rng.random() < 0.3:
            alive[library.paths_through(edge)] = False  # blocked: those paths are no longer asked for
        if step % 3 == 1:  # a new bias for every edge (the posterior leaf), some values unchanged
            theta = np.where(rng.random(library.num_edges) < 0.8, rng.uniform(0.05, 0.95), theta)
            kept.set_theta(theta)
        if step % 2 == 0:  # ask for some paths only: the others stay out of date until asked
            kept.costs(alive & (rng.random(library.num_paths) < 0.5))
        got = kept.costs(alive)
        fresh = ProofOrder(rows, theta, costs, checked=checked).costs(alive)
        assert got.tolist() == fresh.tolist()  # bit for bit
        for i in np.flatnonzero(alive).tolist():
            todo = [e for e in library.path_edges[i].tolist() if not checked[e]]
            assert got[i] == pytest.approx(_best_order_cost(todo, theta, costs), rel=1e-12)
        assert not got[~alive].any()


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("bounds", [False, True])
def test_best_path_is_the_argmax_of_the_scores_of_every_alive_path(
    seed: int, bounds: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    if bounds:  # the bounds of the module docstring even for a few short paths, and no Python floats
        monkeypatch.setattr(proof_order, "_SCORE_ALL_SLOTS", 0)
        monkeypatch.setattr(proof_order, "_SCALAR_SLOTS", 0)
    library = _library(seed, num_paths=60)
    rows = library_rows(library)
    rng = np.random.default_rng(200 + seed)
    costs = rng.uniform(0.5, 3.0, library.num_edges)
    theta = rng.uniform(0.3, 0.99, library.num_edges)
    kept = ProofOrder(rows, theta, costs)
    checked = np.zeros(library.num_edges, dtype=bool)
    alive = np.ones(library.num_paths, dtype=bool)
    log_theta = np.log(theta)
    for edge in rng.permutation(library.num_edges)[:14].tolist():
        through = library.paths_through(edge)
        kept.mark_checked(edge, through)
        checked[edge] = True
        if rng.random() < 0.25:
            alive[through] = False
        if rng.random() < 0.5:
            theta = rng.uniform(0.3, 0.99, library.num_edges)
            log_theta = np.log(theta)
            kept.set_theta(theta)
        log_p = np.array([sum(log_theta[e] for e in p.tolist() if not checked[e]) for p in library.path_edges])
        left = np.array([not checked[p].all() for p in library.path_edges])
        paths = np.flatnonzero(alive & left)  # a proven path ends the episode before any selection
        if paths.size == 0:
            break
        scores = region_scores("per_check", np.where(alive & left, log_p, -np.inf), kept.costs(alive & left))
        assert kept.best_path(log_p[paths], paths) == int(np.argmax(scores))
    # Exact ties (the repeated paths) go to the lower path index.
    fresh = ProofOrder(rows, theta, costs)
    everything = np.arange(library.num_paths)
    log_p = np.array([log_theta[p].sum() for p in library.path_edges])
    log_p[-2:] = log_p[[3, 7]]
    log_p[[3, 7]] += 5.0  # the repeated pairs score best
    log_p[-2:] += 5.0
    full = fresh.costs(np.ones(library.num_paths, dtype=bool))
    assert full[-2:].tolist() == full[[3, 7]].tolist()
    assert fresh.best_path(log_p, everything) == int(np.argmax(region_scores("per_check", log_p, full)))
    assert fresh.best_path(log_p[[3, library.num_paths - 2]], np.array([3, library.num_paths - 2])) == 3


def test_a_checked_edge_costs_nothing_more_and_a_path_with_nothing_left_costs_zero() -> None:
    library = PathLibrary((np.array([0, 1]), np.array([1, 2, 3])), 4)
    theta, costs = np.full(4, 0.5), np.array([1.0, 2.0, 4.0, 8.0])
    order = ProofOrder(library_rows(library), theta, costs)
    both = np.ones(2, dtype=bool)
    # Path 0: key c / (1 - theta) puts edge 0 (2) before edge 1 (4): 1 + 0.5 * 2.
    assert order.costs(both).tolist() == [2.0, 2.0 + 0.5 * 4.0 + 0.25 * 8.0]
    order.mark_checked(0, library.paths_through(0))
    order.mark_checked(1, library.paths_through(1))
    assert order.costs(both).tolist() == [0.0, 4.0 + 0.5 * 8.0]
    assert order.best_path(np.array([0.0, -1.0]), np.array([0, 1])) == 0  # nothing left: +inf


@pytest.mark.parametrize("seed", range(4))
def test_a_few_paths_summed_in_python_floats_equal_the_columns_bit_for_bit(seed: int) -> None:
    library, rows, rng, costs, theta = _case(seed, 300)
    checked = rng.random(library.num_edges) < 0.3
    every = np.ones(library.num_paths, dtype=bool)
    assert every.sum() * rows.table.shape[0] > proof_order._SCALAR_SLOTS  # all at once: the columns
    columns = ProofOrder(rows, theta, costs, checked=checked).costs(every)
    one_by_one = ProofOrder(rows, theta, costs, checked=checked)
    assert rows.table.shape[0] <= proof_order._SCALAR_SLOTS
    for i in range(library.num_paths):  # one at a time: Python floats
        alone = np.zeros(library.num_paths, dtype=bool)
        alone[i] = True
        assert one_by_one.costs(alone)[i] == columns[i]
