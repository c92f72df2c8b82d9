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
from drd_planner.data.world_sources import WorldSourceRequest
from drd_planner.domains.base import Domain
from drd_planner.exceptions import DatasetError

__all__ = ["ALL_WORLDS", "BuildOptions", "DatasetRecipe"]

#: ``num_worlds`` of a recipe with a file source that takes every world the files hold.
ALL_WORLDS = 0


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
        world_model: one of the domain's ``world_models``; with a ``source``, "" (the source names it:
            ``moveit_scenes``, ``map_bags`` or ``terrain``).
        num_worlds: n sampled worlds; with a file ``source``, the first n of its worlds, or
            :data:`ALL_WORLDS` (0) for every one.
        seed: non-negative base seed (world, library and split seeds derive from it).
        domain_spec: spec for a domain given by name (None: the domain's defaults).
        domain_factory: "module:attribute" that rebuilds the domain in workers, for domains outside the
            registry; derived from an instance's class when it has ``from_spec``.
        k: Yen's k per world.
        max_paths: library size cap m.
        test_fraction: share of all worlds held out for testing (drawn among solvable worlds).
        include_trajectories: store the domain's edge trajectories in the file.
        source: where the worlds come from (:mod:`drd_planner.data.world_sources`): None draws them from
            ``world_model``; a :class:`~drd_planner.data.world_sources.SceneFolder`,
            :class:`~drd_planner.data.world_sources.MapBags` or
            :class:`~drd_planner.data.world_sources.TerrainFile` takes them from the user's files.

    Raises:
        DatasetError: a count that is not a positive integer, a negative seed, a test fraction
            outside [0, 1], or a world model given with a file source.
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
    source: WorldSourceRequest | None = None

    def __post_init__(self) -> None:
        self._check_source()
        if self.source is None or self.num_worlds != ALL_WORLDS:
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

    def _check_source(self) -> None:
        """With a file source, the world model is the source's (refused when another one is given)."""
        if self.source is None:
            return
        label = self.source.world_model
        if self.world_model not in ("", label):
            flag = self.source.argv()[0]
            raise DatasetError(
                f"{flag} takes its worlds from files: leave out --world-model {self.world_model} "
                f"(the dataset's world model is {label!r})"
            )
        object.__setattr__(self, "world_model", label)

    def command(self) -> str:
        """A ``drd build-dataset`` command line that recreates this dataset: only content-affecting options.

        ``--out``, ``--workers``, ``--scheduler`` and ``--chunk-size`` are left out, since they do not change
        the file's contents, so a dataset's bytes do not depend on how it was computed. A file source is given
        by its flags with absolute paths; the files' SHA-256 are in the dataset's provenance (``world_source``),
        so whether the files are still the ones it was built from can be checked.
        """
        name = self.domain if isinstance(self.domain, str) else self.domain.name
        argv = ["drd", "build-dataset", "--domain", name]
        if self.source is None:
            argv += ["--world-model", self.world_model, "--worlds", str(self.num_worlds)]
        else:
            argv += self.source.argv()
            argv += ["--worlds", str(self.num_worlds)] if self.num_worlds != ALL_WORLDS else []
        argv += ["--seed", str(self.seed), "--max-paths", str(self.max_paths)]
        argv += ["--test-fraction", repr(float(self.test_fraction))]
        if self.k != 5:
            argv += ["--k", str(self.k)]
        if self.domain_spec:
            argv += ["--domain-spec", json.dumps(dict(self.domain_spec), sort_keys=True)]
        if self.domain_factory:
            argv += ["--domain-factory", self.domain_factory]
        if not self.include_trajectories:
            argv += ["--no-trajectories"]
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
