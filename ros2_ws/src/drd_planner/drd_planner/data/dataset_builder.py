"""Build a dataset file: check every edge on every sampled world in parallel, then library, R and split.

Pipeline (docs/architecture.md, "Data flow"; docs/algorithms.md, "Datasets"):

1. The worlds are cut into chunks of ``chunk_size`` consecutive world indices. Each chunk is one task
   (:class:`~drd_planner.data.dataset_chunks.ChunkTask`), evaluated by
   :func:`~drd_planner.data.dataset_worker.evaluate_chunk`: the worker rebuilds the domain from
   ``(name, spec)`` (once per worker process), regenerates each world from its seed, checks every edge and
   finds each world's k shortest free start-goal paths; it returns the packed rows of X and the chunk's
   distinct paths.
2. Each finished chunk is written to ``<out>.parts/chunk_NNNNNN.npz`` (checksummed, see
   :mod:`drd_planner.data.dataset_chunks`). A build that was interrupted resumes by skipping the chunks
   found there; chunk files of another build (other domain, spec, world model, seed, number of worlds,
   chunk size, k or software version) are refused, damaged ones are evaluated again.
3. The parent joins the chunks in world order, takes the union of the paths, sorts it by edge-id tuple,
   subsamples it uniformly to ``max_paths`` (same rule and result as
   :func:`~drd_planner.data.library_builder.build_path_library` on the full X), computes R from X, draws
   the split with :func:`~drd_planner.data.library_builder.split_worlds` and writes the dataset file.

Where the tasks run (:mod:`drd_planner.data.dataset_schedulers`): ``workers == 1`` in this process,
``workers > 1`` in a local process pool, ``scheduler="tcp://host:port"`` on a Dask cluster; the file is
byte-identical whichever is used, and also for any chunk size. Seeds follow
:mod:`drd_planner.data.seeding`.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import time
from collections.abc import Mapping, Sequence
from contextlib import closing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner import __version__
from drd_planner.arrays import IntArray
from drd_planner.core.library import PathLibrary
from drd_planner.data.dataset_chunks import (
    ChunkResult,
    ChunkTask,
    EdgeTuple,
    VertexTuple,
    chunk_path,
    load_chunk,
    parts_dir,
    remove_parts,
    save_chunk,
)
from drd_planner.data.dataset_file import Dataset, save_dataset
from drd_planner.data.dataset_options import ALL_WORLDS, BuildOptions, DatasetRecipe
from drd_planner.data.dataset_schedulers import run_tasks
from drd_planner.data.dataset_worker import PROCESS_DOMAINS, graph_digest
from drd_planner.data.domain_factory import factory_for, make_domain, world_model_params
from drd_planner.data.library_builder import split_worlds
from drd_planner.data.seeding import WORLD_SEED_RULE, library_seed, split_seed, world_seeds
from drd_planner.data.world_sources import ResolvedSource, resolve_source, source_spec_defaults
from drd_planner.domains.base import Domain
from drd_planner.exceptions import DatasetError
from drd_planner.progress import Progress

__all__ = ["FILE_WORLD_RULE", "BuildReport", "build_dataset", "library_from_union"]

#: How the worlds of a file source are numbered, as recorded in a dataset's provenance.
FILE_WORLD_RULE = "world h is the h-th world of world_source in file order (world_seeds[h] = h)"


def library_from_union(
    union: Sequence[tuple[EdgeTuple, VertexTuple]], *, num_edges: int, max_paths: int, seed: int
) -> PathLibrary:
    """The library from the sorted, distinct union of the worlds' k shortest paths.

    Keeps ``min(max_paths, len(union))`` paths drawn uniformly with ``numpy.random.default_rng(seed)``,
    in union order: the rule of :func:`~drd_planner.data.library_builder.build_path_library`.

    Raises:
        DatasetError: the union is empty (no world has a collision-free start-goal path).
    """
    if not union:
        raise DatasetError(
            "no world has a collision-free start-goal path, so the path library would be empty "
            "(check the world model, the graph's connectivity and the edge checker)"
        )
    keep = np.arange(len(union))
    if len(union) > max_paths:
        keep = np.sort(np.random.default_rng(seed).choice(len(union), size=max_paths, replace=False))
    chosen = [union[i] for i in keep.tolist()]
    return PathLibrary(
        tuple(np.array(e, dtype=np.int64) for e, _ in chosen),
        num_edges,
        tuple(np.array(v, dtype=np.int64) for _, v in chosen),
    )


@dataclass(frozen=True)
class BuildReport:
    """The outcome of :func:`build_dataset`.

    Attributes:
        out: the dataset file (written only when ``complete``).
        complete: False when the build stopped after ``max_chunks`` new chunks (run it again to resume).
        num_chunks: chunks in the whole build.
        resumed_chunks: chunks found finished in the resume directory.
        evaluated_chunks: chunks evaluated by this call.
        eval_seconds: wall time of the edge checks and per-world paths (seconds).
        total_seconds: wall time of the whole call (seconds).
        union_size: distinct k-shortest paths over all worlds (before subsampling); 0 when incomplete.
        dataset: the dataset written, or None when incomplete.
    """

    out: Path
    complete: bool
    num_chunks: int
    resumed_chunks: int
    evaluated_chunks: int
    eval_seconds: float
    total_seconds: float
    union_size: int = 0
    dataset: Dataset | None = field(default=None, repr=False)


def _canonical_json(obj: Any, what: str) -> str:
    try:
        return json.dumps(obj, sort_keys=True, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise DatasetError(f"{what} is not JSON-safe: {exc}") from exc


@dataclass(frozen=True)
class _Plan:
    """A validated build: the domain in hand, its canonical spec, the chunk tasks and the build key."""

    recipe: DatasetRecipe
    domain: Domain
    spec_json: str
    factory: str | None
    seeds: IntArray
    tasks: tuple[ChunkTask, ...]
    build_key: str
    graph_sha256: str
    source: ResolvedSource | None = None


def _user_spec(recipe: DatasetRecipe) -> dict[str, Any]:
    """The spec the user gave, under the values the recipe's file source sets for its domain (if any)."""
    assert isinstance(recipe.domain, str)
    given = dict(recipe.domain_spec or {})
    return given if recipe.source is None else {**source_spec_defaults(recipe.source, recipe.domain), **given}


def _recipe_domain(recipe: DatasetRecipe) -> Domain:
    """The recipe's domain: built from its name and spec, or the instance it holds."""
    if isinstance(recipe.domain, str):
        spec = recipe.domain_spec if recipe.source is None else _user_spec(recipe)
        return make_domain(recipe.domain, spec, factory=recipe.domain_factory)
    if recipe.domain_spec is not None:
        raise DatasetError("give domain_spec only with a domain name, not with a domain instance")
    return recipe.domain


def _with_source(recipe: DatasetRecipe, probe: Domain) -> tuple[Domain, ResolvedSource]:
    """The recipe's file source resolved against ``probe`` (the domain of the user's spec), and the domain.

    The domain is ``probe`` itself, or the domain of the spec the source completes (start, goal, extra states,
    terrain keys).
    """
    assert recipe.source is not None
    user_spec = _user_spec(recipe) if isinstance(recipe.domain, str) else dict(probe.spec())
    wanted = None if recipe.num_worlds == ALL_WORLDS else recipe.num_worlds
    resolved = resolve_source(recipe.source, probe, user_spec, wanted)
    if resolved.spec is None:
        return probe, resolved
    factory = recipe.domain_factory if isinstance(recipe.domain, str) else factory_for(probe, None, True)
    return make_domain(probe.name, resolved.spec, factory=factory), resolved


def _check_domain(dom: Domain, world_model: str | None) -> None:
    if world_model is not None and world_model not in dom.world_models:
        raise DatasetError(
            f"unknown world model {world_model!r} for domain {dom.name!r}; choose one of: {', '.join(dom.world_models)}"
        )
    if int(dom.start) == int(dom.goal):
        raise DatasetError(f"domain {dom.name!r} has start == goal ({dom.start})")


def _plan(recipe: DatasetRecipe, options: BuildOptions) -> _Plan:
    dom, source = _recipe_domain(recipe), None
    if recipe.source is not None:
        dom, source = _with_source(recipe, dom)
    factory = factory_for(dom, recipe.domain_factory, options.parallel)
    spec_json = _canonical_json(dict(dom.spec()), f"domain {dom.name!r} spec")
    _check_domain(dom, recipe.world_model if source is None or source.seeded else None)
    g_digest = graph_digest(dom.graph)
    num_worlds = recipe.num_worlds if source is None else source.num_worlds
    settings: dict[str, Any] = {
        "domain": dom.name,
        "spec": json.loads(spec_json),
        "factory": factory,
        "world_model": recipe.world_model,
        "num_worlds": num_worlds,
        "seed": recipe.seed,
        "chunk_size": options.chunk_size,
        "k": recipe.k,
        "graph_sha256": g_digest,
        "software_version": __version__,
    }
    source_json = None
    if source is not None:
        source_json = _canonical_json(dict(source.worker_data), "world source")
        settings["source"] = json.loads(source_json)
    build_key = hashlib.sha256(_canonical_json(settings, "build settings").encode()).hexdigest()
    if source is None or source.seeded:
        seeds = world_seeds(recipe.seed, num_worlds)
    else:
        seeds = np.arange(num_worlds, dtype=np.int64)
    size = options.chunk_size
    tasks = tuple(
        ChunkTask(
            index=i,
            first=first,
            seeds=tuple(int(s) for s in seeds[first : first + size]),
            domain=dom.name,
            spec_json=spec_json,
            factory=factory,
            world_model=recipe.world_model,
            k=recipe.k,
            source_json=source_json,
        )
        for i, first in enumerate(range(0, num_worlds, size))
    )
    return _Plan(recipe, dom, spec_json, factory, seeds, tasks, build_key, g_digest, source)


def _finished_chunks(parts: Path, plan: _Plan) -> dict[int, ChunkResult]:
    """The chunks of this build already in the resume directory (damaged ones left out)."""
    found: dict[int, ChunkResult] = {}
    if not parts.is_dir():
        return found
    num_edges = plan.domain.graph.num_edges
    for task in plan.tasks:
        path = chunk_path(parts, task.index)
        if path.is_file():
            chunk = load_chunk(
                path,
                index=task.index,
                build_key=plan.build_key,
                num_worlds=len(task.seeds),
                num_edges=num_edges,
            )
            if chunk is not None:
                found[task.index] = chunk
    return found


def _evaluate(
    pending: Sequence[ChunkTask],
    plan: _Plan,
    parts: Path,
    results: dict[int, ChunkResult],
    options: BuildOptions,
) -> None:
    """Run ``pending`` where asked, saving each chunk file and adding it to ``results`` as it finishes."""
    if not pending:
        return
    parts.mkdir(parents=True, exist_ok=True)
    stream = run_tasks(pending, workers=options.workers, scheduler=options.scheduler, method=options.start_method)
    # Counted in worlds, announced at once: a chunk of arm worlds takes tens of seconds, and a build that said
    # nothing until its first chunk finished looked stuck (206 s of silence on 1000 arm worlds).
    total = sum(len(task.seeds) for task in plan.tasks)
    done = sum(len(plan.tasks[index].seeds) for index in results)
    bar = Progress(total, "edge checks", unit="world", enabled=options.progress, initial=done, announce=True)
    with closing(stream), bar:
        for result in stream:
            if result.graph_sha256 != plan.graph_sha256:
                raise DatasetError(
                    f"a worker rebuilt domain {plan.domain.name!r} with another graph from the same spec: the "
                    "domain is not reproducible from its spec (or the worker runs other software)"
                )
            save_chunk(parts, result, build_key=plan.build_key, num_worlds=len(plan.tasks[result.index].seeds))
            results[result.index] = result
            bar.update(len(plan.tasks[result.index].seeds))


def _path_union(plan: _Plan, results: Mapping[int, ChunkResult]) -> list[tuple[EdgeTuple, VertexTuple]]:
    """The distinct paths of all chunks, sorted by edge-id tuple (the first vertex path of each kept)."""
    union_map: dict[EdgeTuple, VertexTuple] = {}
    for task in plan.tasks:
        for edges, verts in results[task.index].paths():
            union_map.setdefault(edges, verts)
    return sorted(union_map.items())


def _assemble(plan: _Plan, results: Mapping[int, ChunkResult], command: str | None) -> Dataset:
    """Join the chunks in world order and derive the library, R and the split."""
    recipe, dom, graph = plan.recipe, plan.domain, plan.domain.graph
    packed = np.concatenate([results[t.index].x_packed for t in plan.tasks], axis=0)
    x = np.unpackbits(packed, axis=1, count=graph.num_edges).astype(bool)
    union = _path_union(plan, results)
    lib_seed, spl_seed = library_seed(recipe.seed), split_seed(recipe.seed)
    library = library_from_union(union, num_edges=graph.num_edges, max_paths=recipe.max_paths, seed=lib_seed)
    r = library.valid_paths(x)
    train, test = split_worlds(r, test_fraction=recipe.test_fraction, seed=spl_seed)
    trajectories = dom.edge_trajectories() if recipe.include_trajectories else None
    provenance: dict[str, Any] = {
        "builder": __name__,
        "command": command,
        "domain_factory": plan.factory,
        "k": recipe.k,
        "max_paths": recipe.max_paths,
        "test_fraction": recipe.test_fraction,
        "union_size": len(union),
        "library_seed": lib_seed,
        "split_seed": spl_seed,
        "world_seed_rule": WORLD_SEED_RULE,
        "solvable_worlds": int(r.any(axis=1).sum()),
        "graph_sha256": plan.graph_sha256,
    }
    model_params: dict[str, Any] = {}
    if plan.source is None or plan.source.seeded:
        model_params = world_model_params(dom, recipe.world_model)
    if plan.source is not None:
        provenance["world_source"] = dict(plan.source.provenance)
        if not plan.source.seeded:
            provenance["world_seed_rule"] = FILE_WORLD_RULE
    return Dataset(
        graph=graph,
        start=int(dom.start),
        goal=int(dom.goal),
        library=library,
        X=x,
        R=r,
        train_ids=train,
        test_ids=test,
        edge_costs=np.ones(graph.num_edges),
        world_seeds=plan.seeds,
        domain=dom.name,
        domain_spec=json.loads(plan.spec_json),
        world_model=recipe.world_model,
        seed=recipe.seed,
        world_model_params=model_params,
        check_metadata=dict(dom.check_metadata()),
        edge_trajectories=None if trajectories is None else tuple(trajectories),
        provenance=provenance,
    )


def build_dataset(out: str | Path, recipe: DatasetRecipe, options: BuildOptions | None = None) -> BuildReport:
    """Build (or resume building) the dataset ``recipe`` describes and write it to ``out``.

    Args:
        out: the dataset file to write (``.npz``); chunks go to :func:`parts_dir` ``(out)`` meanwhile.
        recipe: what the file holds (domain, world model, worlds, seed, library and split settings).
        options: how it is computed (workers or scheduler, chunk size, resume limits, progress,
            the recorded command); None: :class:`BuildOptions` defaults (one process).

    Returns:
        A :class:`BuildReport`.

    Raises:
        DatasetError: unknown domain or world model, chunks of another build in the resume directory, a
            scheduler that cannot be reached, or no world with a start-goal path.
    """
    opts = options if options is not None else BuildOptions()
    t_start = time.perf_counter()
    plan = _plan(recipe, opts)
    # The domain in hand serves the in-process path; worker processes rebuild it from (name, spec, factory).
    PROCESS_DOMAINS.remember(plan.domain, plan.spec_json, plan.factory)

    out_path = Path(out)
    parts = parts_dir(out_path)
    results = _finished_chunks(parts, plan)
    resumed = len(results)
    pending = [t for t in plan.tasks if t.index not in results][: opts.max_chunks]
    t_eval = time.perf_counter()
    _evaluate(pending, plan, parts, results, opts)
    report = BuildReport(
        out=out_path,
        complete=False,
        num_chunks=len(plan.tasks),
        resumed_chunks=resumed,
        evaluated_chunks=len(pending),
        eval_seconds=time.perf_counter() - t_eval,
        total_seconds=0.0,
    )
    if len(results) < len(plan.tasks):
        return dataclasses.replace(report, total_seconds=time.perf_counter() - t_start)
    dataset = _assemble(plan, results, opts.command)
    save_dataset(out_path, dataset)
    if not opts.keep_parts:
        remove_parts(parts, len(plan.tasks))
    return dataclasses.replace(
        report,
        complete=True,
        total_seconds=time.perf_counter() - t_start,
        union_size=int(dataset.provenance["union_size"]),
        dataset=dataset,
    )
