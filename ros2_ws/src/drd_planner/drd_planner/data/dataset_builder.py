"""Build a dataset file: check every edge on every sampled world in parallel, then library, R and split.

Pipeline (DESIGN.md section 3; ALGORITHMS.md section 6.1):

1. The worlds are cut into chunks of ``chunk_size`` consecutive world indices. Each chunk is one task:
   the worker rebuilds the domain from ``(name, spec)`` (once per worker process, then cached),
   regenerates each world from its seed, runs ``checker(world).check_many(all edges)`` and then, on
   the chunk's rows of X, Yen's k shortest loopless start-goal paths of every world
   (:func:`~drd_planner.data.library_builder.k_shortest_paths_union`). It returns the packed rows of X
   and the chunk's distinct paths.
2. Each finished chunk is written to ``<out>.parts/chunk_NNNNNN.npz`` (checksummed, see
   :mod:`drd_planner.data.npz_format`). A build that was interrupted resumes by skipping the chunks
   found there; chunk files of another build (other domain, spec, world model, seed, number of worlds,
   chunk size, k or software version) are refused, damaged ones are evaluated again.
3. The parent joins the chunks in world order, takes the union of the paths, sorts it by edge-id tuple,
   subsamples it uniformly to ``max_paths`` (same rule and result as
   :func:`~drd_planner.data.library_builder.build_path_library` on the full X), computes R from X, draws
   the split with :func:`~drd_planner.data.library_builder.split_worlds` and writes the dataset file.

Where the tasks run: ``workers == 1`` runs them in this process; ``workers > 1`` in a
``concurrent.futures.ProcessPoolExecutor`` (started with ``fork`` when this process is single-threaded,
else ``spawn``; see :func:`choose_start_method`). A process pool is the local default because it starts in
milliseconds (fork) to half a second (spawn), opens no network ports and needs no scheduler or nanny
processes; a ``distributed.LocalCluster`` costs a second or more of start-up, which matters when the
build itself takes seconds. ``scheduler="tcp://host:port"`` sends the same tasks to a Dask distributed
cluster (``distributed.Client(address)``), whose workers must have drd_planner (and the domain's
module) installed. All three run the same task function on the same chunks, so the file is
byte-identical whichever is used, and also for any chunk size.

Seeds (all from ``numpy.random.SeedSequence``; ``>> 1`` keeps them in [0, 2**63)):

* world i: ``SeedSequence(seed, spawn_key=(0, i)).generate_state(1, np.uint64)[0] >> 1``; it depends
  only on ``seed`` and ``i``, so the first n worlds are the same whatever the number of worlds;
* library subsample: the same with ``spawn_key=(1,)``; train/test split: ``spawn_key=(2,)``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib
import json
import logging
import multiprocessing
import threading
import time
import uuid
from collections.abc import Callable, Generator, Mapping, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from contextlib import closing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner import __version__
from drd_planner.arrays import IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.library import PathLibrary
from drd_planner.data.dataset_file import Dataset, save_dataset
from drd_planner.data.library_builder import k_shortest_paths_union, split_worlds
from drd_planner.data.npz_format import read_checked_npz, write_checked_npz
from drd_planner.domains.base import DOMAIN_CLASSES, Domain, domain_from_spec
from drd_planner.exceptions import DatasetError, DrdError
from drd_planner.progress import Progress

__all__ = [
    "BuildReport",
    "ChunkResult",
    "ChunkTask",
    "build_dataset",
    "choose_start_method",
    "derived_seed",
    "evaluate_chunk",
    "graph_digest",
    "library_from_union",
    "make_domain",
    "parts_dir",
    "world_model_params",
    "world_seeds",
]

EdgeTuple = tuple[int, ...]
VertexTuple = tuple[int, ...]

CHUNK_FORMAT = "drd_planner.dataset_chunk"
CHUNK_FORMAT_VERSION = 1
DASK_CONNECT_TIMEOUT_S = 10.0

_LOG = logging.getLogger(__name__)
_WORLD_STREAM, _LIBRARY_STREAM, _SPLIT_STREAM = 0, 1, 2


# --------------------------------------------------------------------------------------------------
# Seeds


def derived_seed(seed: int, *spawn_key: int) -> int:
    """A seed in [0, 2**63) derived from ``seed`` and ``spawn_key`` (see the module docstring)."""
    state = np.random.SeedSequence(seed, spawn_key=spawn_key).generate_state(1, dtype=np.uint64)
    return int(state[0]) >> 1


def world_seeds(seed: int, num_worlds: int) -> IntArray:
    """(num_worlds,) int64 seeds of the worlds 0..num_worlds-1; world i's seed depends on (seed, i) only."""
    if seed < 0:
        raise DatasetError(f"seed must be non-negative, got {seed}")
    return np.array([derived_seed(seed, _WORLD_STREAM, i) for i in range(num_worlds)], dtype=np.int64)


# --------------------------------------------------------------------------------------------------
# Domains in workers


def make_domain(name: str, spec: Mapping[str, Any] | None = None, *, factory: str | None = None) -> Domain:
    """Build domain ``name`` from ``spec``: from the registry, or from ``factory`` ("module:attribute").

    ``factory`` names a class with a ``from_spec(spec) -> Domain`` classmethod or a callable
    ``(spec) -> Domain``; it lets a domain outside :data:`~drd_planner.domains.base.DOMAIN_CLASSES`
    (a plugin, a test domain) be rebuilt in worker processes.

    Raises:
        DatasetError: unknown name, a factory that cannot be imported, a spec the domain rejects, or a
            factory whose domain has another name.
    """
    spec_dict = dict(spec or {})
    if factory is None:
        if name not in DOMAIN_CLASSES:
            raise DatasetError(f"unknown domain {name!r}; known: {', '.join(sorted(DOMAIN_CLASSES))}")
        build: Callable[[dict[str, Any]], Domain] = lambda s: domain_from_spec(name, s)  # noqa: E731
    else:
        module_name, sep, attr = factory.partition(":")
        if not sep or not module_name or not attr:
            raise DatasetError(f"domain factory must look like 'package.module:Name', got {factory!r}")
        try:
            target = getattr(importlib.import_module(module_name), attr)
        except (ImportError, AttributeError) as exc:
            raise DatasetError(f"domain factory {factory!r} cannot be imported: {exc}") from exc
        build = getattr(target, "from_spec", target)
    try:
        domain = build(spec_dict)
    except DatasetError:
        raise
    except (DrdError, TypeError, ValueError, KeyError) as exc:
        raise DatasetError(f"domain {name!r} cannot be built from its spec: {exc}") from exc
    if domain.name != name:
        raise DatasetError(f"domain factory {factory!r} builds domain {domain.name!r}, not {name!r}")
    return domain


#: Per-process cache: (name, canonical spec JSON, factory) -> domain. Workers build each domain once.
_DOMAIN_CACHE: dict[tuple[str, str, str | None], Domain] = {}


def _cached_domain(name: str, spec_json: str, factory: str | None) -> Domain:
    key = (name, spec_json, factory)
    domain = _DOMAIN_CACHE.get(key)
    if domain is None:
        domain = make_domain(name, json.loads(spec_json), factory=factory)
        _DOMAIN_CACHE.clear()  # one build at a time per process: keep memory bounded
        _DOMAIN_CACHE[key] = domain
    return domain


def graph_digest(graph: ExplicitGraph) -> str:
    """SHA-256 (hex) of a graph's edges, lengths, size and direction (workers must rebuild this graph)."""
    h = hashlib.sha256()
    h.update(f"{graph.num_vertices}:{graph.directed}:".encode())
    h.update(np.ascontiguousarray(graph.edges, dtype=np.int64).tobytes())
    h.update(np.ascontiguousarray(graph.lengths, dtype=np.float64).tobytes())
    return h.hexdigest()


# --------------------------------------------------------------------------------------------------
# One chunk of worlds


@dataclass(frozen=True)
class ChunkTask:
    """One work unit: consecutive worlds ``first .. first + len(seeds) - 1`` of one build.

    Attributes:
        index: chunk number (0-based).
        first: index of the chunk's first world.
        seeds: the chunk's world seeds (see :func:`world_seeds`).
        domain: domain name.
        spec_json: the domain spec as canonical JSON (sorted keys).
        factory: "module:attribute" that rebuilds the domain, or None for the registry.
        world_model: world model name.
        k: Yen's k per world.
    """

    index: int
    first: int
    seeds: tuple[int, ...]
    domain: str
    spec_json: str
    factory: str | None
    world_model: str
    k: int


@dataclass(frozen=True)
class ChunkResult:
    """What a worker returns for one chunk.

    Attributes:
        index: chunk number.
        x_packed: (c, ceil(E / 8)) uint8, ``np.packbits`` of the chunk's c rows of X along edges.
        path_edges: the chunk's distinct k-shortest paths' edge ids, concatenated (int64).
        path_offsets: (p + 1,) int64 offsets of the p paths into ``path_edges``.
        vertex_paths: the same paths as vertex ids (start first), concatenated (int64).
        vertex_offsets: (p + 1,) int64 offsets into ``vertex_paths``.
        graph_sha256: :func:`graph_digest` of the graph the worker used.
        seconds: wall time of the task in seconds.
    """

    index: int
    x_packed: npt.NDArray[np.uint8]
    path_edges: IntArray
    path_offsets: IntArray
    vertex_paths: IntArray
    vertex_offsets: IntArray
    graph_sha256: str
    seconds: float = 0.0

    def paths(self) -> list[tuple[EdgeTuple, VertexTuple]]:
        """The chunk's paths as ``(edge ids, vertex ids)`` tuples."""
        e_off, v_off = self.path_offsets.tolist(), self.vertex_offsets.tolist()
        edges, verts = self.path_edges.tolist(), self.vertex_paths.tolist()
        return [
            (tuple(edges[e_off[j] : e_off[j + 1]]), tuple(verts[v_off[j] : v_off[j + 1]]))
            for j in range(len(e_off) - 1)
        ]


def _concat(seqs: Sequence[tuple[int, ...]]) -> tuple[IntArray, IntArray]:
    offsets = np.concatenate([[0], np.cumsum([len(s) for s in seqs], dtype=np.int64)]).astype(np.int64)
    flat = np.fromiter((v for s in seqs for v in s), dtype=np.int64, count=int(offsets[-1]))
    return flat, offsets


def evaluate_chunk(task: ChunkTask) -> ChunkResult:
    """Check every edge in every world of ``task`` and find each world's k shortest free paths.

    Runs in a worker (or in-process); the domain is rebuilt from the task's (name, spec) once per
    process. Deterministic: the result depends only on the task.

    Raises:
        DatasetError: the domain cannot be built, or its checker returns something other than (E,) bools.
    """
    t0 = time.perf_counter()
    domain = _cached_domain(task.domain, task.spec_json, task.factory)
    graph = domain.graph
    num_edges = graph.num_edges
    all_edges = np.arange(num_edges, dtype=np.int64)
    rows = np.empty((len(task.seeds), num_edges), dtype=bool)
    for j, seed in enumerate(task.seeds):
        world = domain.make_world(task.world_model, int(seed))
        free = np.asarray(domain.checker(world).check_many(all_edges))
        if free.shape != (num_edges,) or not (free.dtype == np.bool_ or np.isin(free, (0, 1)).all()):
            raise DatasetError(
                f"domain {task.domain!r}: check_many returned {free.dtype} {free.shape}, expected ({num_edges},) bool"
            )
        rows[j] = free.astype(bool)
    union = k_shortest_paths_union(graph, rows, domain.start, domain.goal, k=task.k, progress=False)
    path_edges, path_offsets = _concat([e for e, _ in union])
    vertex_paths, vertex_offsets = _concat([v for _, v in union])
    return ChunkResult(
        index=task.index,
        x_packed=np.packbits(rows, axis=1),
        path_edges=path_edges,
        path_offsets=path_offsets,
        vertex_paths=vertex_paths,
        vertex_offsets=vertex_offsets,
        graph_sha256=graph_digest(graph),
        seconds=time.perf_counter() - t0,
    )


# --------------------------------------------------------------------------------------------------
# Chunk files (the resume directory)


def parts_dir(out: str | Path) -> Path:
    """The resume directory of a build writing ``out``: ``<out>.parts`` next to it."""
    out_path = Path(out)
    return out_path.with_name(out_path.name + ".parts")


def _chunk_path(parts: Path, index: int) -> Path:
    return parts / f"chunk_{index:06d}.npz"


def _save_chunk(parts: Path, result: ChunkResult, *, build_key: str, num_worlds: int) -> None:
    arrays: dict[str, npt.NDArray[Any]] = {
        "x_packed": result.x_packed,
        "path_edges": result.path_edges,
        "path_offsets": result.path_offsets,
        "vertex_paths": result.vertex_paths,
        "vertex_offsets": result.vertex_offsets,
    }
    header = {
        "build_key": build_key,
        "index": result.index,
        "num_worlds": num_worlds,
        "graph_sha256": result.graph_sha256,
        "seconds": result.seconds,
        "software_version": __version__,
    }
    write_checked_npz(
        _chunk_path(parts, result.index),
        format_name=CHUNK_FORMAT,
        format_version=CHUNK_FORMAT_VERSION,
        header=header,
        arrays=arrays,
        error=DatasetError,
    )


def _load_chunk(
    path: Path, *, index: int, build_key: str, num_worlds: int, num_edges: int
) -> ChunkResult | None:
    """A finished chunk, or None when the file is damaged (it is then evaluated again).

    Raises:
        DatasetError: the chunk belongs to another build.
    """
    try:
        header, arrays = read_checked_npz(
            path,
            format_name=CHUNK_FORMAT,
            format_version=CHUNK_FORMAT_VERSION,
            error=DatasetError,
            what="dataset chunk file",
        )
    except DatasetError as exc:
        _LOG.warning("ignoring damaged chunk file (it will be evaluated again): %s", exc)
        return None
    if header.get("build_key") != build_key:
        raise DatasetError(
            f"{path.parent} holds chunks of another build (other domain, spec, world model, seed, number "
            "of worlds, chunk size, k or software version); delete that folder or choose another output file"
        )
    want_x = (num_worlds, (num_edges + 7) // 8)
    names = ("x_packed", "path_edges", "path_offsets", "vertex_paths", "vertex_offsets")
    if header.get("index") != index or set(arrays) != set(names) or arrays["x_packed"].shape != want_x:
        _LOG.warning("ignoring chunk file with unexpected contents (it will be evaluated again): %s", path)
        return None
    return ChunkResult(
        index=index,
        x_packed=arrays["x_packed"].astype(np.uint8),
        path_edges=arrays["path_edges"].astype(np.int64),
        path_offsets=arrays["path_offsets"].astype(np.int64),
        vertex_paths=arrays["vertex_paths"].astype(np.int64),
        vertex_offsets=arrays["vertex_offsets"].astype(np.int64),
        graph_sha256=str(header.get("graph_sha256")),
        seconds=float(header.get("seconds", 0.0)),
    )


# --------------------------------------------------------------------------------------------------
# Where the tasks run


def _run_inline(tasks: Sequence[ChunkTask]) -> Generator[ChunkResult, None, None]:
    for task in tasks:
        yield evaluate_chunk(task)


def choose_start_method(requested: str | None = None) -> str:
    """The multiprocessing start method for local workers.

    ``fork`` when the platform has it and this process runs a single thread (then forking is safe, and
    workers start in milliseconds with the modules and the domain already loaded); otherwise ``spawn``
    (fresh interpreters that import drd_planner and rebuild the domain from its spec, about half a
    second each). ``requested`` forces one of ``multiprocessing.get_all_start_methods()``.
    """
    methods = multiprocessing.get_all_start_methods()
    if requested is not None:
        if requested not in methods:
            raise DatasetError(
                f"start method {requested!r} is not available here; choose one of: {', '.join(methods)}"
            )
        return requested
    return "fork" if "fork" in methods and threading.active_count() == 1 else "spawn"


def _run_pool(
    tasks: Sequence[ChunkTask], workers: int, method: str | None
) -> Generator[ChunkResult, None, None]:
    """Start the pool and submit every task now (before any other thread exists), then drain it."""
    context = multiprocessing.get_context(choose_start_method(method))
    executor = ProcessPoolExecutor(max_workers=min(workers, len(tasks)), mp_context=context)
    try:
        futures = [executor.submit(evaluate_chunk, task) for task in tasks]
    except BaseException:
        executor.shutdown(wait=True, cancel_futures=True)
        raise
    return _drain(executor, futures)


def _drain(
    executor: ProcessPoolExecutor, futures: list[Future[ChunkResult]]
) -> Generator[ChunkResult, None, None]:
    try:
        for future in as_completed(futures):
            try:
                result = future.result()
            except BrokenProcessPool as exc:
                raise DatasetError(
                    f"a worker process died ({exc}); finished chunks are kept: run the same build again to resume"
                ) from exc
            yield result
    finally:
        executor.shutdown(wait=True, cancel_futures=True)


def _run_dask(tasks: Sequence[ChunkTask], address: str) -> Generator[ChunkResult, None, None]:
    try:
        from distributed import Client
        from distributed import as_completed as dask_as_completed
    except ImportError as exc:  # pragma: no cover - dask[distributed] is a declared dependency
        raise DatasetError(f"--scheduler needs dask[distributed]: {exc}") from exc
    try:
        client = Client(address, timeout=DASK_CONNECT_TIMEOUT_S, set_as_default=False)  # type: ignore[no-untyped-call]
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        raise DatasetError(f"cannot connect to the Dask scheduler at {address!r}: {exc}") from exc
    try:
        run = uuid.uuid4().hex[:12]
        futures = [
            client.submit(evaluate_chunk, task, key=f"drd-chunk-{run}-{task.index}", pure=False)
            for task in tasks
        ]
        for future in dask_as_completed(futures, loop=client.loop):  # type: ignore[no-untyped-call]
            try:
                result: ChunkResult = future.result()
            except DrdError:
                raise
            except Exception as exc:  # a worker without drd_planner or the domain's module, a lost worker
                raise DatasetError(
                    f"a task failed on the Dask cluster at {address}: {type(exc).__name__}: {exc} "
                    "(its workers need drd_planner and the domain's module; finished chunks are kept)"
                ) from exc
            future.release()
            yield result
    finally:
        client.close()  # type: ignore[no-untyped-call]


# --------------------------------------------------------------------------------------------------
# Library from the chunks' paths


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


# --------------------------------------------------------------------------------------------------
# The build


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


def _positive(name: str, value: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise DatasetError(f"{name} must be a positive integer, got {value!r}")


def _factory_for(domain: Domain, factory: str | None, parallel: bool) -> str | None:
    """The factory workers use to rebuild ``domain`` (None: the registry)."""
    if factory is not None:
        return factory
    cls = type(domain)
    path = f"{cls.__module__}:{cls.__qualname__}"
    if DOMAIN_CLASSES.get(domain.name) == path:
        return None
    if hasattr(cls, "from_spec") and "<locals>" not in cls.__qualname__:
        return path
    if parallel:
        raise DatasetError(
            f"domain {domain.name!r} ({path}) is not registered and has no importable from_spec: "
            "worker processes cannot rebuild it; pass domain_factory='module:attribute'"
        )
    return None


def _canonical_json(obj: Any, what: str) -> str:
    try:
        return json.dumps(obj, sort_keys=True, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise DatasetError(f"{what} is not JSON-safe: {exc}") from exc


@dataclass(frozen=True)
class _Plan:
    """A validated build: the domain in hand, its canonical spec, the chunk tasks and the build key."""

    domain: Domain
    spec_json: str
    factory: str | None
    world_model: str
    seed: int
    seeds: IntArray
    tasks: tuple[ChunkTask, ...]
    build_key: str
    graph_sha256: str


def _plan(
    *,
    domain: str | Domain,
    domain_spec: Mapping[str, Any] | None,
    domain_factory: str | None,
    world_model: str,
    num_worlds: int,
    seed: int,
    chunk_size: int,
    k: int,
    parallel: bool,
) -> _Plan:
    if isinstance(domain, str):
        dom = make_domain(domain, domain_spec, factory=domain_factory)
    else:
        if domain_spec is not None:
            raise DatasetError("give domain_spec only with a domain name, not with a domain instance")
        dom = domain
    factory = _factory_for(dom, domain_factory, parallel)
    spec_json = _canonical_json(dict(dom.spec()), f"domain {dom.name!r} spec")
    if world_model not in dom.world_models:
        raise DatasetError(
            f"unknown world model {world_model!r} for domain {dom.name!r}; "
            f"choose one of: {', '.join(dom.world_models)}"
        )
    if int(dom.start) == int(dom.goal):
        raise DatasetError(f"domain {dom.name!r} has start == goal ({dom.start})")
    g_digest = graph_digest(dom.graph)
    settings = {
        "domain": dom.name,
        "spec": json.loads(spec_json),
        "factory": factory,
        "world_model": world_model,
        "num_worlds": num_worlds,
        "seed": seed,
        "chunk_size": chunk_size,
        "k": k,
        "graph_sha256": g_digest,
        "software_version": __version__,
    }
    build_key = hashlib.sha256(_canonical_json(settings, "build settings").encode()).hexdigest()
    seeds = world_seeds(seed, num_worlds)
    tasks = tuple(
        ChunkTask(
            index=i,
            first=first,
            seeds=tuple(int(s) for s in seeds[first : first + chunk_size]),
            domain=dom.name,
            spec_json=spec_json,
            factory=factory,
            world_model=world_model,
            k=k,
        )
        for i, first in enumerate(range(0, num_worlds, chunk_size))
    )
    return _Plan(dom, spec_json, factory, world_model, seed, seeds, tasks, build_key, g_digest)


def _finished_chunks(parts: Path, plan: _Plan) -> dict[int, ChunkResult]:
    """The chunks of this build already in the resume directory (damaged ones left out)."""
    found: dict[int, ChunkResult] = {}
    if not parts.is_dir():
        return found
    num_edges = plan.domain.graph.num_edges
    for task in plan.tasks:
        path = _chunk_path(parts, task.index)
        if path.is_file():
            chunk = _load_chunk(
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
    *,
    workers: int,
    scheduler: str | None,
    method: str | None,
    progress: bool | None,
) -> None:
    """Run ``pending`` where asked, saving each chunk file and adding it to ``results`` as it finishes."""
    if not pending:
        return
    parts.mkdir(parents=True, exist_ok=True)
    if scheduler is not None:
        stream = _run_dask(pending, scheduler)
    elif workers > 1 and len(pending) > 1:
        stream = _run_pool(pending, workers, method)
    else:
        stream = _run_inline(pending)
    total, done = len(plan.tasks), len(results)
    bar = Progress(total, "edge checks", unit="chunk", enabled=progress, initial=done)
    with closing(stream), bar:
        for result in stream:
            if result.graph_sha256 != plan.graph_sha256:
                raise DatasetError(
                    f"a worker rebuilt domain {plan.domain.name!r} with another graph from the same spec: the "
                    "domain is not reproducible from its spec (or the worker runs other software)"
                )
            _save_chunk(
                parts, result, build_key=plan.build_key, num_worlds=len(plan.tasks[result.index].seeds)
            )
            results[result.index] = result
            bar.update(1)


def _json_default(obj: Any) -> Any:
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return dataclasses.asdict(obj)
    if isinstance(obj, np.ndarray | np.generic):
        return obj.tolist()
    if isinstance(obj, Mapping):
        return dict(obj)
    raise TypeError(f"{type(obj).__name__} is not JSON-safe")


def world_model_params(domain: Domain, model: str) -> dict[str, Any]:
    """The world model's parameters as JSON-safe data, when the domain reports them (else ``{}``).

    The protocol has no accessor for them, so this looks, in order, for ``domain.world_model_params(model)``,
    ``domain.model_params(model)`` (a mapping or a dataclass), and ``spec()["models"][model]``; values that
    cannot be written as JSON are recorded as their ``repr``.
    """
    for attr in ("world_model_params", "model_params"):
        method = getattr(domain, attr, None)
        if callable(method):
            params: Any = method(model)
            break
    else:
        models = domain.spec().get("models")
        params = models.get(model, {}) if isinstance(models, Mapping) else {}
    try:
        data = json.loads(json.dumps(params, default=_json_default, sort_keys=True, allow_nan=False))
    except (TypeError, ValueError):
        return {"repr": repr(params)}
    return data if isinstance(data, dict) else {"value": data}


def _assemble(
    plan: _Plan,
    results: Mapping[int, ChunkResult],
    *,
    k: int,
    max_paths: int,
    test_fraction: float,
    include_trajectories: bool,
    command: str | None,
) -> Dataset:
    """Join the chunks in world order and derive the library, R and the split."""
    dom, graph = plan.domain, plan.domain.graph
    chunks = [results[t.index] for t in plan.tasks]
    packed = np.concatenate([c.x_packed for c in chunks], axis=0)
    x = np.unpackbits(packed, axis=1, count=graph.num_edges).astype(bool)
    union_map: dict[EdgeTuple, VertexTuple] = {}
    for chunk in chunks:
        for edges, verts in chunk.paths():
            union_map.setdefault(edges, verts)
    union = sorted(union_map.items())
    library_seed = derived_seed(plan.seed, _LIBRARY_STREAM)
    split_seed = derived_seed(plan.seed, _SPLIT_STREAM)
    library = library_from_union(union, num_edges=graph.num_edges, max_paths=max_paths, seed=library_seed)
    r = library.valid_paths(x)
    train, test = split_worlds(r, test_fraction=test_fraction, seed=split_seed)
    trajectories = dom.edge_trajectories() if include_trajectories else None
    provenance: dict[str, Any] = {
        "builder": __name__,
        "command": command,
        "domain_factory": plan.factory,
        "k": k,
        "max_paths": max_paths,
        "test_fraction": test_fraction,
        "union_size": len(union),
        "library_seed": library_seed,
        "split_seed": split_seed,
        "world_seed_rule": "SeedSequence(seed, spawn_key=(0, i)).generate_state(1, uint64)[0] >> 1",
        "solvable_worlds": int(r.any(axis=1).sum()),
        "graph_sha256": plan.graph_sha256,
    }
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
        world_model=plan.world_model,
        seed=plan.seed,
        world_model_params=world_model_params(dom, plan.world_model),
        check_metadata=dict(dom.check_metadata()),
        edge_trajectories=None if trajectories is None else tuple(trajectories),
        provenance=provenance,
    )


def _remove_parts(parts: Path, num_chunks: int) -> None:
    """Delete this build's chunk files, and the folder when nothing else is in it."""
    for i in range(num_chunks):
        _chunk_path(parts, i).unlink(missing_ok=True)
    try:
        parts.rmdir()
    except OSError:
        _LOG.warning("left %s in place: it holds files this build did not write", parts)


def build_dataset(
    out: str | Path,
    *,
    domain: str | Domain,
    world_model: str,
    num_worlds: int,
    seed: int,
    domain_spec: Mapping[str, Any] | None = None,
    domain_factory: str | None = None,
    workers: int = 1,
    scheduler: str | None = None,
    chunk_size: int = 16,
    k: int = 5,
    max_paths: int = 500,
    test_fraction: float = 0.1,
    include_trajectories: bool = True,
    max_chunks: int | None = None,
    keep_parts: bool = False,
    progress: bool | None = None,
    command: str | None = None,
    start_method: str | None = None,
) -> BuildReport:
    """Build (or resume building) a dataset file for ``domain`` and write it to ``out``.

    Args:
        out: the dataset file to write (``.npz``); chunks go to :func:`parts_dir` ``(out)`` meanwhile.
        domain: a domain name (built with ``domain_spec``) or a :class:`Domain` instance (its
            ``spec()`` is what workers rebuild it from).
        world_model: one of the domain's ``world_models``.
        num_worlds: n sampled worlds.
        seed: non-negative base seed (world, library and split seeds derive from it).
        domain_spec: spec for a domain given by name (None: the domain's defaults).
        domain_factory: "module:attribute" that rebuilds the domain in workers, for domains outside the
            registry; derived from an instance's class when it has ``from_spec``.
        workers: local processes (1: run in this process).
        scheduler: a Dask scheduler address; when given, tasks run on that cluster and ``workers`` is ignored.
        chunk_size: worlds per task and per chunk file.
        k: Yen's k per world.
        max_paths: library size cap m.
        test_fraction: share of all worlds held out for testing (drawn among solvable worlds).
        include_trajectories: store the domain's edge trajectories in the file.
        max_chunks: evaluate at most this many missing chunks, then stop without writing ``out``.
        keep_parts: keep the chunk files after writing ``out`` (by default they are deleted).
        progress: progress over chunks on stderr (a bar on a terminal, plain lines otherwise; False: none).
        command: a command line that recreates the dataset, recorded in the provenance.
        start_method: multiprocessing start method of local workers (None: see :func:`choose_start_method`).

    Returns:
        A :class:`BuildReport`.

    Raises:
        DatasetError: bad arguments, unknown domain or world model, chunks of another build in the
            resume directory, a scheduler that cannot be reached, or no world with a start-goal path.
    """
    t_start = time.perf_counter()
    for name, value in (("num_worlds", num_worlds), ("chunk_size", chunk_size), ("workers", workers)):
        _positive(name, value)
    _positive("k", k)
    _positive("max_paths", max_paths)
    if max_chunks is not None:
        _positive("max_chunks", max_chunks)
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise DatasetError(f"seed must be a non-negative integer, got {seed!r}")
    if not 0.0 <= float(test_fraction) <= 1.0:
        raise DatasetError(f"test fraction must lie in [0, 1], got {test_fraction}")
    if start_method is not None:
        choose_start_method(start_method)  # refuse an unknown method before any work
    plan = _plan(
        domain=domain,
        domain_spec=domain_spec,
        domain_factory=domain_factory,
        world_model=world_model,
        num_worlds=int(num_worlds),
        seed=int(seed),
        chunk_size=int(chunk_size),
        k=int(k),
        parallel=scheduler is not None or workers > 1,
    )
    # The domain in hand serves the in-process path; worker processes rebuild it from (name, spec, factory).
    _DOMAIN_CACHE.clear()
    _DOMAIN_CACHE[(plan.domain.name, plan.spec_json, plan.factory)] = plan.domain

    out_path = Path(out)
    parts = parts_dir(out_path)
    results = _finished_chunks(parts, plan)
    resumed = len(results)
    pending = [t for t in plan.tasks if t.index not in results][:max_chunks]
    t_eval = time.perf_counter()
    _evaluate(
        pending,
        plan,
        parts,
        results,
        workers=workers,
        scheduler=scheduler,
        method=start_method,
        progress=progress,
    )
    eval_seconds = time.perf_counter() - t_eval
    report = BuildReport(
        out=out_path,
        complete=False,
        num_chunks=len(plan.tasks),
        resumed_chunks=resumed,
        evaluated_chunks=len(pending),
        eval_seconds=eval_seconds,
        total_seconds=0.0,
    )
    if len(results) < len(plan.tasks):
        return dataclasses.replace(report, total_seconds=time.perf_counter() - t_start)
    dataset = _assemble(
        plan,
        results,
        k=int(k),
        max_paths=int(max_paths),
        test_fraction=float(test_fraction),
        include_trajectories=include_trajectories,
        command=command,
    )
    save_dataset(out_path, dataset)
    if not keep_parts:
        _remove_parts(parts, len(plan.tasks))
    return dataclasses.replace(
        report,
        complete=True,
        total_seconds=time.perf_counter() - t_start,
        union_size=int(dataset.provenance["union_size"]),
        dataset=dataset,
    )
