"""Held-out worlds and random queries on a shipped prior, for benchmarks on live worlds.

:func:`held_out_worlds` draws worlds of a prior's world model (seeds past its training worlds) in which the
prior's stored query has a free path, with every edge's outcome (check_all's rows); :func:`new_queries`
draws vertex pairs that the training worlds often connect and that are free in their world;
:func:`off_graph_queries` draws free states (not vertices) as start and goal that join the graph and have a
free path in their world. ``scripts/experiments/bench_check_cost.py`` and ``bench_query_cpu.py`` share them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from drd_planner.bench.cost_episodes import CostQuery, FullRow, full_row
from drd_planner.bench.world_recipes import WorldRecipe
from drd_planner.core.lazysp import GraphArcs
from drd_planner.planner.endpoints import QueryError
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.query_graph import MotionDispatch
from drd_planner.planner.query_library import ShortestPaths
from drd_planner.planner.query_sampling import REACH_SAMPLE, reachable_fraction

__all__ = ["WORLD_MODELS", "held_out_worlds", "new_queries", "off_graph_queries"]

#: The world model each shipped prior was built from (trees/README.md).
WORLD_MODELS = {
    "heli_wires": "wires",
    "heli_terrain": "terrain",
    "heli_lines": "corridors",
    "arm_table_clutter": "table_clutter",
}


def held_out_worlds(
    domain: Any, prior: WorldPrior, model: str, count: int, first_seed: int
) -> tuple[list[WorldRecipe], list[Any], dict[int, FullRow]]:
    """``count`` worlds where the stored query has a free path, their recipes and check_all's rows.

    Args:
        domain: the prior's domain (``domain_from_spec(prior.domain, prior.domain_spec)``).
        prior: the shipped prior; its first tree's query is the stored one.
        model: the domain's world model (:data:`WORLD_MODELS`).
        count: worlds wanted.
        first_seed: the first world seed tried; seeds go up by one, at most ``40 * count`` of them.

    Returns:
        The worlds' recipes, the worlds, and per world index its row of every edge's outcome
        (``FullRow.outcomes``: (E,) bool over the prior's graph edges, True = free).

    Raises:
        SystemExit: fewer than ``count`` of the seeds tried give a free stored query.
    """
    stored = prior.trees[0]
    recipes: list[WorldRecipe] = []
    worlds: list[Any] = []
    rows: dict[int, FullRow] = {}
    paths = ShortestPaths(GraphArcs(prior.graph), prior.graph.lengths)
    seed = first_seed
    while len(worlds) < count:
        if seed > first_seed + 40 * count:
            raise SystemExit(f"{prior.name}: fewer than {count} of {40 * count} worlds have a free stored query")
        world = domain.make_world(model, seed)
        row = full_row(domain.checker(world), prior.graph.num_edges)
        if paths.path(stored.start, stored.goal, row.outcomes) is not None:
            rows[len(worlds)] = row
            worlds.append(world)
            recipes.append(WorldRecipe(f"{model}:{seed}", model, model=model, seed=seed))
        seed += 1
    return recipes, worlds, rows


def new_queries(
    prior: WorldPrior, rows: dict[int, FullRow], count: int, rng: np.random.Generator, reach: float = 0.5
) -> list[CostQuery]:
    """Random vertex pairs connected in at least ``reach`` of a training sample and free in their world.

    Args:
        prior: the shipped prior (with its training worlds, (n_train, E) bool).
        rows: per world index, every edge's outcome (from :func:`held_out_worlds`).
        count: queries wanted (fewer when ``200 * count`` draws do not find them).
        rng: the random generator (draws the training sample, starts and goals).
        reach: least fraction of the ``REACH_SAMPLE`` training worlds in which the start reaches the goal.

    Returns:
        ``new`` queries (vertex ids), world ``k % len(rows)`` for the k-th.
    """
    assert prior.worlds is not None
    graph = prior.graph
    sample = prior.worlds[
        np.sort(rng.choice(prior.worlds.shape[0], min(REACH_SAMPLE, prior.worlds.shape[0]), replace=False))
    ]
    paths = ShortestPaths(GraphArcs(graph), graph.lengths)
    out: list[CostQuery] = []
    for _ in range(200 * count):
        if len(out) == count:
            break
        world = len(out) % len(rows)
        start = int(rng.integers(graph.num_vertices))
        fraction = reachable_fraction(graph, sample, start)
        fraction[start] = 0.0
        goals = np.flatnonzero(fraction >= reach)
        if goals.size == 0:
            continue
        goal = int(rng.choice(goals))
        if paths.path(start, goal, rows[world].outcomes) is not None:
            out.append(CostQuery("new", start, goal, world))
    return out


def off_graph_queries(
    planner: Planner,
    domain: Any,
    worlds: list[Any],
    rows: dict[int, FullRow],
    count: int,
    rng: np.random.Generator,
) -> list[CostQuery]:
    """Random free states (not vertices) as start and goal, joinable and with a free path in their world.

    Args:
        planner: the prior's planner (joins the states to the graph).
        domain: the prior's domain (its checker of each world).
        worlds: the worlds of :func:`held_out_worlds`.
        rows: per world index, every edge's outcome over the prior's graph.
        count: queries wanted (fewer when ``400 * count`` draws do not find them).
        rng: the random generator; states are uniform in the box of the graph's vertex states (D,).

    Returns:
        ``off_graph`` queries whose start and goal are (D,) states, world ``k % len(worlds)`` for the k-th.
    """
    states = planner.prior.graph.vertex_states
    assert states is not None
    low, high = states.min(axis=0), states.max(axis=0)
    checkers = [domain.checker(w) for w in worlds]  # one per world: building one costs more than many checks
    out: list[CostQuery] = []
    for _ in range(400 * count):
        if len(out) == count:
            break
        world = len(out) % len(worlds)
        checker = checkers[world]
        ends = [rng.uniform(low, high) for _ in range(2)]
        if not all(checker.check_motion(e[None, :]) for e in ends):
            continue
        try:
            query = planner.query_graph(ends[0], ends[1])
        except QueryError:
            continue
        if not query.connected or not (query.start_joins is not None and query.goal_joins is not None):
            continue  # a state snapped to a vertex
        target = MotionDispatch(checker, query.motions)
        extra = [bool(target.check(e)) for e in range(planner.prior.graph.num_edges, query.graph.num_edges)]
        outcomes = np.concatenate([rows[world].outcomes, np.array(extra, dtype=bool)])
        paths = ShortestPaths(GraphArcs(query.graph), query.graph.lengths)
        if paths.path(query.start, query.goal, outcomes) is not None:
            out.append(CostQuery("off_graph", ends[0], ends[1], world))
    return out
