r"""A complete small planar problem in memory, drawn exactly as ``drd build-dataset`` would draw it.

:func:`make_planar_problem` (``drd demo`` and many tests) samples its worlds, its library and its split
with the dataset pipeline's seeding (:mod:`drd_planner.data.seeding`) and checks every edge with the
dataset worker's :func:`~drd_planner.data.dataset_worker.check_all_edges`. So ``drd demo --model M
--worlds n --seed S`` plans on the same worlds, library and split as the dataset file of::

    drd build-dataset --domain planar --world-model M --worlds n --seed S --max-paths 100 \
        --domain-spec '{"seed": S, "keep_clear": true}'

(with the defaults of both; :func:`planar_recipe` gives that recipe for any problem it made).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.core.problem import Problem
from drd_planner.core.worlds import WorldDatabase
from drd_planner.data.dataset_options import DatasetRecipe
from drd_planner.data.dataset_worker import check_all_edges
from drd_planner.data.library_builder import build_path_library, split_worlds
from drd_planner.data.seeding import WORLD_SEED_RULE, library_seed, split_seed, world_seeds
from drd_planner.domains.planar import PlanarDomain, rgg_radius
from drd_planner.exceptions import DatasetError, ProblemError

__all__ = ["make_planar_problem", "planar_problem_worlds", "planar_recipe"]


def make_planar_problem(
    *,
    num_vertices: int = 100,
    model: str = "one_wall",
    num_worlds: int = 300,
    max_paths: int = 100,
    seed: int = 0,
    test_fraction: float = 0.1,
    eta: float = 1.0,
    k: int = 5,
) -> Problem:
    """A complete self-generated planar problem (graph, worlds, X, library, R, split), unit check costs.

    The graph comes from :func:`~drd_planner.domains.planar.random_geometric_graph` with ``seed``; world i
    is the domain's world of ``model`` drawn with ``world_seeds(seed, num_worlds)[i]``, and the library
    subsample and the split use ``library_seed(seed)`` and ``split_seed(seed)``
    (:mod:`drd_planner.data.seeding`), so the same arguments always give identical arrays, the same
    as the dataset file of :func:`planar_recipe` ``(problem)``. Random squares are kept off the start and goal vertices.

    Args:
        num_vertices: RGG vertex count N.
        model: world model (see :data:`~drd_planner.domains.planar_worlds.WORLD_MODELS`).
        num_worlds: n sampled worlds.
        max_paths: library size cap m.
        seed: master seed.
        test_fraction: share of worlds held out (drawn among worlds with a valid library path).
        eta: RGG radius multiplier.
        k: Yen's k per world.

    Raises:
        ProblemError: bad arguments, start/goal disconnected, or no world has a start-goal path.
    """
    domain = PlanarDomain(num_vertices=num_vertices, seed=seed, eta=eta, keep_clear=True)
    try:  # the recipe validates the counts, the seed and the fraction as build-dataset does
        DatasetRecipe(domain, model, num_worlds, seed, k=k, max_paths=max_paths, test_fraction=test_fraction)
    except DatasetError as exc:
        raise ProblemError(str(exc)) from exc
    if model not in domain.world_models:
        raise ProblemError(f"unknown planar world model {model!r}; choose one of {', '.join(domain.world_models)}")
    graph, start, goal = domain.graph, domain.start, domain.goal
    seeds = world_seeds(seed, num_worlds)
    x = check_all_edges(domain, model, tuple(int(s) for s in seeds))
    lib_seed, spl_seed = library_seed(seed), split_seed(seed)
    library = build_path_library(graph, x, start, goal, k=k, max_paths=max_paths, seed=lib_seed)
    r = library.valid_paths(x)
    train, test = split_worlds(r, test_fraction=test_fraction, seed=spl_seed)
    metadata: dict[str, Any] = {
        "domain": "planar",
        "domain_spec": domain.spec(),
        "world_model": model,
        "seed": seed,
        "num_vertices": num_vertices,
        "eta": eta,
        "radius": rgg_radius(num_vertices, eta=eta),
        "num_worlds": num_worlds,
        "k": k,
        "max_paths": max_paths,
        "test_fraction": test_fraction,
        "world_seed_rule": WORLD_SEED_RULE,
        "library_seed": lib_seed,
        "split_seed": spl_seed,
        "solvable_worlds": int(r.any(axis=1).sum()),
    }
    return Problem(
        name=f"planar_{model}_N{num_vertices}_seed{seed}",
        library=library,
        edge_costs=np.ones(graph.num_edges),
        graph=graph,
        start=start,
        goal=goal,
        worlds=WorldDatabase(x, r, train, test),
        metadata=metadata,
    )


def planar_problem_worlds(problem: Problem) -> list[FloatArray]:
    """The (k_h, 4) boxes of every world of a problem from :func:`make_planar_problem`, in world order.

    Raises:
        ProblemError: ``problem`` does not come from :func:`make_planar_problem`.
    """
    recipe = planar_recipe(problem)
    domain = recipe.domain
    assert isinstance(domain, PlanarDomain)
    return [domain.make_world(recipe.world_model, int(s)) for s in world_seeds(recipe.seed, recipe.num_worlds)]


def planar_recipe(problem: Problem) -> DatasetRecipe:
    """The dataset recipe whose file holds the same worlds, library and split as ``problem``.

    Raises:
        ProblemError: ``problem`` does not come from :func:`make_planar_problem`.
    """
    meta = _planar_metadata(problem)
    return DatasetRecipe(
        domain=PlanarDomain.from_spec(meta["domain_spec"]),
        world_model=str(meta["world_model"]),
        num_worlds=int(meta["num_worlds"]),
        seed=int(meta["seed"]),
        k=int(meta["k"]),
        max_paths=int(meta["max_paths"]),
        test_fraction=float(meta["test_fraction"]),
        include_trajectories=False,
    )


def _planar_metadata(problem: Problem) -> dict[str, Any]:
    meta = problem.metadata
    if meta.get("domain") != "planar" or "domain_spec" not in meta or "world_seed_rule" not in meta:
        raise ProblemError(f"problem {problem.name!r} does not come from make_planar_problem")
    return meta
