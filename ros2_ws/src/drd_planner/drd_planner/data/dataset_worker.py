"""The worker side of a dataset build: sample a chunk's worlds, check every edge, find their paths.

:func:`evaluate_chunk` runs in a worker process (a local process pool or a Dask worker) or in the
building process itself. It rebuilds the domain from the task's ``(name, spec, factory)`` once per
process (:data:`PROCESS_DOMAINS` keeps it), regenerates each world from its seed (or, with a world source
from files, opens the source once per process and takes each world from its files, checked against their
SHA-256: :mod:`drd_planner.data.world_sources`), runs ``checker(world).check_many(all edges)`` and then,
on the chunk's rows of X, Yen's k shortest loopless start-goal paths of every world
(:func:`~drd_planner.data.library_builder.k_shortest_paths_union`).
"""

from __future__ import annotations

import hashlib
import time
from collections.abc import Iterable

import numpy as np

from drd_planner.arrays import BoolArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.data.dataset_chunks import ChunkResult, ChunkTask, pack_paths
from drd_planner.data.domain_factory import DomainFactory
from drd_planner.data.library_builder import k_shortest_paths_union
from drd_planner.data.world_sources import PROCESS_SOURCES
from drd_planner.domains.base import Domain, EdgeChecker
from drd_planner.exceptions import DatasetError

__all__ = ["PROCESS_DOMAINS", "check_all_edges", "check_worlds", "evaluate_chunk", "graph_digest"]

#: This process's domains: the build's own domain in the building process (put there by the builder,
#: and inherited by forked workers), the one rebuilt from the task in any other worker process.
PROCESS_DOMAINS = DomainFactory()


def graph_digest(graph: ExplicitGraph) -> str:
    """SHA-256 (hex) of a graph's edges, lengths, size and direction (workers must rebuild this graph)."""
    h = hashlib.sha256()
    h.update(f"{graph.num_vertices}:{graph.directed}:".encode())
    h.update(np.ascontiguousarray(graph.edges, dtype=np.int64).tobytes())
    h.update(np.ascontiguousarray(graph.lengths, dtype=np.float64).tobytes())
    return h.hexdigest()


def check_worlds(domain: Domain, checkers: Iterable[EdgeChecker], count: int) -> BoolArray:
    """(count, E) bool X: row j is True where each edge is free for the j-th of ``count`` checkers.

    Raises:
        DatasetError: the domain's checker returns something other than (E,) bools, or there are fewer
            checkers than ``count``.
    """
    num_edges = domain.graph.num_edges
    all_edges = np.arange(num_edges, dtype=np.int64)
    rows = np.empty((count, num_edges), dtype=bool)
    j = 0
    for j, checker in enumerate(checkers, start=1):
        free = np.asarray(checker.check_many(all_edges))
        if free.shape != (num_edges,) or not (free.dtype == np.bool_ or np.isin(free, (0, 1)).all()):
            raise DatasetError(
                f"domain {domain.name!r}: check_many returned {free.dtype} {free.shape}, expected ({num_edges},) bool"
            )
        rows[j - 1] = free.astype(bool)
    if j != count:
        raise DatasetError(f"the world source gave {j} worlds where {count} were asked for")
    return rows


def check_all_edges(domain: Domain, world_model: str, seeds: tuple[int, ...]) -> BoolArray:
    """(len(seeds), E) bool X: row j is True where each edge is free in the world drawn with ``seeds[j]``.

    Raises:
        DatasetError: the domain's checker returns something other than (E,) bools.
    """
    checkers = (domain.checker(domain.make_world(world_model, int(seed))) for seed in seeds)
    return check_worlds(domain, checkers, len(seeds))


def evaluate_chunk(task: ChunkTask) -> ChunkResult:
    """Check every edge in every world of ``task`` and find each world's k shortest free paths.

    Runs in a worker (or in-process); the domain is rebuilt from the task's (name, spec) once per
    process. Deterministic: the result depends only on the task.

    Raises:
        DatasetError: the domain cannot be built, or its checker returns something other than (E,) bools.
    """
    t0 = time.perf_counter()
    domain = PROCESS_DOMAINS.domain(task.domain, task.spec_json, task.factory)
    if task.source_json is None:
        rows = check_all_edges(domain, task.world_model, task.seeds)
    else:
        worlds = PROCESS_SOURCES.worlds(task.source_json)
        rows = check_worlds(domain, worlds.checkers(domain, task.seeds), len(task.seeds))
    union = k_shortest_paths_union(domain.graph, rows, domain.start, domain.goal, k=task.k, progress=False)
    path_edges, path_offsets, vertex_paths, vertex_offsets = pack_paths(union)
    return ChunkResult(
        index=task.index,
        x_packed=np.packbits(rows, axis=1),
        path_edges=path_edges,
        path_offsets=path_offsets,
        vertex_paths=vertex_paths,
        vertex_offsets=vertex_offsets,
        graph_sha256=graph_digest(domain.graph),
        seconds=time.perf_counter() - t0,
    )
