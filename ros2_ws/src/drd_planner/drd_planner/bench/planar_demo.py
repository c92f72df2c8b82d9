"""``drd demo``: a planar problem generated, its DiRECt tree built, plans on a few held-out worlds, as a library call.

The command line (:mod:`drd_planner.cli.demo`) makes a :class:`DemoOptions`; :func:`run_demo` prints the story.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drd_planner.core.episode import EpisodeResult
from drd_planner.core.problem import Problem
from drd_planner.planning.bag_command import print_check

__all__ = ["DemoOptions", "run_demo"]


@dataclass(frozen=True)
class DemoOptions:
    """One ``drd demo``.

    Attributes:
        model: the planar world model (:data:`drd_planner.domains.planar.WORLD_MODELS`).
        worlds: how many worlds to sample (training and test).
        episodes: how many test worlds to plan on with their check log printed.
        seed: the seed of the worlds and of the policies (test world k uses seed + k).
    """

    model: str = "one_wall"
    worlds: int = 300
    episodes: int = 3
    seed: int = 0


def print_episode(problem: Problem, result: EpisodeResult) -> None:
    """One episode's check log and outcome, one line each."""
    graph = problem.graph
    for k, rec in enumerate(result.checks):
        ends = None
        if graph is not None:
            u, v = graph.edges[rec.edge]
            ends = (int(u), int(v))
        print_check(k + 1, rec.edge, ends, rec.free, rec.stage)
    if result.success and result.path_edges is not None:
        which = "graph path" if result.path_index is None else f"path {result.path_index}"
        print(f"  -> {which} ({result.path_edges.size} edges) verified free after {result.num_checks} checks")
    else:
        print(f"  -> {result.status.value} after {result.num_checks} checks")


def run_demo(options: DemoOptions) -> int:
    """Generate a planar problem, build a tree, plan on a few held-out worlds, compare policies; status 0."""
    from drd_planner.bench.runner import run_benchmark
    from drd_planner.core.bisect import bias_from_worlds
    from drd_planner.core.episode import TableOracle, run_episode
    from drd_planner.core.policies import POLICIES, PolicyContext
    from drd_planner.core.tree import build_tree
    from drd_planner.data.planar_problem import make_planar_problem

    print(f"drd demo: planar '{options.model}' world model, {options.worlds} worlds, seed {options.seed}")
    problem = make_planar_problem(model=options.model, num_worlds=options.worlds, seed=options.seed)
    worlds = problem.require_worlds()
    assert problem.graph is not None
    print(
        f"graph: {problem.graph.num_vertices} vertices, {problem.num_edges} edges; library: {problem.num_paths} "
        f"paths; {worlds.train_ids.size} training / {worlds.test_ids.size} test worlds"
    )
    tree = build_tree(problem, progress=False)
    print(f"DiRECt tree: {tree.num_nodes} nodes, depth {tree.depth()}, built in {tree.info['build_seconds']:.2f} s")
    theta = bias_from_worlds(worlds.X[worlds.train_ids])
    for k, world in enumerate(worlds.test_ids[: options.episodes]):
        ctx = PolicyContext(problem.library, problem.edge_costs, theta, tree, options.seed + k)
        result = run_episode(
            problem.library, problem.edge_costs, POLICIES["direct_bisect"](ctx), TableOracle(worlds.X[world])
        )
        print(f"test world {int(world)} (direct_bisect):")
        print_episode(problem, result)
    policies = ["direct_bisect", "bisect", "bisect_all"]
    bench = run_benchmark(problem, policies=policies, tree=tree, seed=options.seed, progress=False)
    means = {p: float(np.mean(bench.policies[p].checks)) for p in policies}
    summary = ", ".join(f"{p} {v:.2f}" for p, v in means.items())
    print(
        f"mean checks over {len(bench.test_ids)} test worlds: {summary}; oracle bound "
        f"{np.nanmean(bench.lower_bound):.2f}"
    )
    return 0
