"""The settings of a dataset build: what the file holds, and how it is computed.

:class:`DatasetRecipe` fixes what the file holds; :class:`BuildOptions` how it is computed.

A recipe fixes the dataset's bytes; the options (workers, scheduler, chunk size, resume limits, progress)
change only where and how fast the work runs. Both validate their fields when they are made.
"""

from __future__ import annotations

import json
import shlex
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from drd_planner.data.dataset_schedulers import choose_start_method
from drd_planner.domains.base import Domain
from drd_planner.exceptions import DatasetError

__all__ = ["BuildOptions", "DatasetRecipe"]


def _positive(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise DatasetError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


@dataclass(frozen=True)
class DatasetRecipe:
    """What a dataset file holds; the same recipe gives the same bytes however it is computed.

    Attributes:
        domain: a domain name (built with ``domain_spec``) or a :class:`Domain` instance (its
            ``spec()`` is what workers rebuild it from).
        world_model: one of the domain's ``world_models``.
        num_worlds: n sampled worlds.
        seed: non-negative base seed (world, library and split seeds derive from it).
        domain_spec: spec for a domain given by name (None: the domain's defaults).
        domain_factory: "module:attribute" that rebuilds the domain in workers, for domains outside the
            registry; derived from an instance's class when it has ``from_spec``.
        k: Yen's k per world.
        max_paths: library size cap m.
        test_fraction: share of all worlds held out for testing (drawn among solvable worlds).
        include_trajectories: store the domain's edge trajectories in the file.

    Raises:
        DatasetError: a count that is not a positive integer, a negative seed, or a test fraction
            outside [0, 1].
    """

    domain: str | Domain
    world_model: str
    num_worlds: int
    seed: int
    domain_spec: Mapping[str, Any] | None = None
    domain_factory: str | None = None
    k: int = 5
    max_paths: int = 500
    test_fraction: float = 0.1
    include_trajectories: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "num_worlds", _positive("num_worlds", self.num_worlds))
        object.__setattr__(self, "k", _positive("k", self.k))
        object.__setattr__(self, "max_paths", _positive("max_paths", self.max_paths))
        seed = self.seed
        if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
            raise DatasetError(f"seed must be a non-negative integer, got {seed!r}")
        object.__setattr__(self, "seed", int(seed))
        if not 0.0 <= float(self.test_fraction) <= 1.0:
            raise DatasetError(f"test fraction must lie in [0, 1], got {self.test_fraction}")
        object.__setattr__(self, "test_fraction", float(self.test_fraction))

    def command(self) -> str:
        """A ``drd build-dataset`` command line that recreates this dataset: only content-affecting options.

        ``--out``, ``--workers``, ``--scheduler`` and ``--chunk-size`` are left out, since they do not change
        the file's contents, so a dataset's bytes do not depend on how it was computed.
        """
        name = self.domain if isinstance(self.domain, str) else self.domain.name
        argv = ["drd", "build-dataset", "--domain", name, "--world-model", self.world_model]
        argv += [
            "--worlds",
            str(self.num_worlds),
            "--seed",
            str(self.seed),
            "--max-paths",
            str(self.max_paths),
        ]
        argv += ["--test-fraction", repr(float(self.test_fraction))]
        if self.k != 5:
            argv += ["--k", str(self.k)]
        if self.domain_spec:
            argv += ["--domain-spec", json.dumps(dict(self.domain_spec), sort_keys=True)]
        if self.domain_factory:
            argv += ["--domain-factory", self.domain_factory]
        return shlex.join(argv)


@dataclass(frozen=True)
class BuildOptions:
    """How a dataset is computed; none of these change the file's bytes.

    Attributes:
        workers: local processes (1: run in this process).
        scheduler: a Dask scheduler address; when given, tasks run on that cluster and ``workers`` is ignored.
        chunk_size: worlds per task and per chunk file.
        max_chunks: evaluate at most this many missing chunks, then stop without writing the file.
        keep_parts: keep the chunk files after writing the file (by default they are deleted).
        progress: progress over chunks on stderr (a bar on a terminal, plain lines otherwise; False: none).
        command: a command line that recreates the dataset, recorded in the provenance.
        start_method: multiprocessing start method of local workers (None: see
            :func:`~drd_planner.data.dataset_schedulers.choose_start_method`).

    Raises:
        DatasetError: a count that is not a positive integer, or a start method this platform lacks.
    """

    workers: int = 1
    scheduler: str | None = None
    chunk_size: int = 16
    max_chunks: int | None = None
    keep_parts: bool = False
    progress: bool | None = None
    command: str | None = None
    start_method: str | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "chunk_size", _positive("chunk_size", self.chunk_size))
        object.__setattr__(self, "workers", _positive("workers", self.workers))
        if self.max_chunks is not None:
            object.__setattr__(self, "max_chunks", _positive("max_chunks", self.max_chunks))
        if self.start_method is not None:
            choose_start_method(self.start_method)  # refuse an unknown method before any work

    @property
    def parallel(self) -> bool:
        """Whether tasks may run outside this process (a scheduler, or more than one worker)."""
        return self.scheduler is not None or self.workers > 1
