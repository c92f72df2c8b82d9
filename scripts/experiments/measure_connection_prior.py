"""How well the prior estimates whether a new motion (an off-graph start or goal) is free.

    python scripts/experiments/measure_connection_prior.py [--models forest,one_wall,baffle] [--states 60] [--seed 7]

For each planar world model: a generated problem (300 worlds), random states near (but farther than the snap
tolerance from) the graph, the planner's straight-line motions to their nearest vertices, and for each
motion the fraction of training worlds in which it is free, estimated from the graph edges it overlaps, set
against the exact box test of the motion in the same worlds. Estimators: the planner's sample-weighted
majority vote (``imputed_outcomes``), "all matched edges free", the single most-matched edge, and the
training marginal of all edges. Prints mean absolute error, correlation and mean of each.
"""

from __future__ import annotations

import argparse

import numpy as np

from drd_planner import Planner, prior_from_problem
from drd_planner.data.planar_problem import make_planar_problem, planar_problem_worlds
from drd_planner.domains.planar import PlanarChecker
from drd_planner.planner.connect import EdgeSampleIndex, imputed_outcomes


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--models", default="forest,one_wall,baffle")
    parser.add_argument("--states", type=int, default=60)
    parser.add_argument("--seed", type=int, default=7)
    args = parser.parse_args()
    for model in args.models.split(","):
        problem = make_planar_problem(model=model, num_worlds=300, seed=5)
        boxes = planar_problem_worlds(problem)
        prior = prior_from_problem(problem, domain="planar")
        planner = Planner(prior)
        connector = planner.connector
        assert connector is not None and prior.worlds is not None and prior.graph.vertex_states is not None
        graph, states, x = prior.graph, prior.graph.vertex_states, prior.worlds
        index = EdgeSampleIndex(graph, None, position_dims=connector.position_dims)
        train = problem.require_worlds().train_ids
        checkers = [PlanarChecker(graph, boxes[h]) for h in train]
        rng = np.random.default_rng(args.seed)
        est: dict[str, list[float]] = {"vote (planner)": [], "all edges free": [], "most-matched edge": []}
        truth: list[float] = []
        for _ in range(args.states):
            while True:
                e = int(rng.integers(graph.num_edges))
                a, b = states[graph.edges[e]]
                p = a + rng.uniform(0.2, 0.8) * (b - a) + rng.normal(0.0, 0.03, 2)
                if np.min(np.linalg.norm(states - p, axis=1)) > planner.snap_tolerance:
                    break
            for motion in connector.connect(p, graph, outgoing=True):
                nearest = index.nearest_edges(motion.states)
                edges, counts = np.unique(nearest, return_counts=True)
                est["vote (planner)"].append(float(imputed_outcomes(index, x, motion.states).mean()))
                est["all edges free"].append(float(x[:, edges].all(axis=1).mean()))
                est["most-matched edge"].append(float(x[:, edges[np.argmax(counts)]].mean()))
                truth.append(float(np.mean([c.check_motion(motion.states) for c in checkers])))
        t = np.asarray(truth)
        print(f"{model}: {t.size} motions, true free fraction {t.mean():.2f}")
        marginal = float(x.mean())
        print(f"  {'training marginal':20s} MAE {np.abs(marginal - t).mean():.3f}")
        for name, values in est.items():
            v = np.asarray(values)
            print(
                f"  {name:20s} MAE {np.abs(v - t).mean():.3f}  corr {np.corrcoef(v, t)[0, 1]:.2f}  mean {v.mean():.2f}"
            )


if __name__ == "__main__":
    main()
