"""Tests of the parallel dataset builder on a tiny exact grid domain (no FCL).

The grid domain below is a real domain (it satisfies the ``Domain`` protocol): a size x size grid of
cells with 4- and 8-neighbour edges; a world blocks a seeded random subset of cells; an edge is free iff
both its cells are free. The other dataset test modules import it from here.
"""

from __future__ import annotations

import dataclasses
import json
import multiprocessing
import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import pytest

from drd_planner.core.graph import ExplicitGraph
from drd_planner.data.dataset_builder import build_dataset
from drd_planner.data.dataset_chunks import parts_dir
from drd_planner.data.dataset_file import load_dataset
from drd_planner.data.dataset_options import BuildOptions, DatasetRecipe
from drd_planner.data.domain_factory import make_domain
from drd_planner.data.library_builder import build_path_library, split_worlds
from drd_planner.data.seeding import derived_seed, world_seeds
from drd_planner.domains.base import Domain, EdgeChecker
from drd_planner.exceptions import DatasetError

GRID_FACTORY = "test_dataset_builder:GridDomain"
HERE = Path(__file__).resolve().parent


@dataclass(frozen=True)
class GridWorld:
    """(V,) bool: which cells are blocked."""

    blocked: npt.NDArray[np.bool_]


class GridChecker:
    """Exact edge checks: free iff both end cells are free; ``delay_s`` per batch mimics slow checks."""

    def __init__(self, edges: npt.NDArray[np.int64], world: GridWorld, delay_s: float) -> None:
        self._free = ~(world.blocked[edges[:, 0]] | world.blocked[edges[:, 1]])
        self._delay_s = delay_s

    def check(self, edge: int) -> bool:
        return bool(self._free[edge])

    def check_many(self, edges: npt.ArrayLike) -> npt.NDArray[np.bool_]:
        if self._delay_s:
            time.sleep(self._delay_s)
        return np.asarray(self._free[np.asarray(edges, dtype=np.int64)], dtype=bool)


class GridDomain:
    """A size x size grid, start in one corner and goal in the opposite one; two world models."""

    world_models = ("uniform", "wall")

    def __init__(self, size: int = 4, block_probability: float = 0.25, delay_s: float = 0.0) -> None:
        if size < 2:
            raise ValueError("size must be at least 2")
        self.size, self.block_probability, self.delay_s = size, block_probability, delay_s
        cells = [(x, y) for y in range(size) for x in range(size)]
        index = {c: i for i, c in enumerate(cells)}
        edges, lengths = [], []
        for (x, y), i in index.items():
            for dx, dy in ((1, 0), (0, 1), (1, 1), (-1, 1)):
                j = index.get((x + dx, y + dy))
                if j is not None:
                    edges.append((i, j))
                    lengths.append(float(np.hypot(dx, dy)))
        self._graph = ExplicitGraph(
            np.array(edges), np.array(lengths), len(cells), False, np.array(cells, dtype=np.float64)
        )

    @classmethod
    def from_spec(cls, spec: dict[str, Any]) -> GridDomain:
        return cls(**spec)

    @property
    def name(self) -> str:
        return "grid_test"

    @property
    def graph(self) -> ExplicitGraph:
        return self._graph

    @property
    def start(self) -> int:
        return 0

    @property
    def goal(self) -> int:
        return self.size * self.size - 1

    def spec(self) -> dict[str, Any]:
        return {"size": self.size, "block_probability": self.block_probability, "delay_s": self.delay_s}

    def make_world(self, model: str, seed: int) -> GridWorld:
        rng = np.random.default_rng(seed)
        n = self.size * self.size
        if model == "uniform":
            blocked = rng.random(n) < self.block_probability
        elif model == "wall":
            blocked = np.zeros(n, dtype=bool)
            column = int(rng.integers(1, self.size - 1))
            gap = int(rng.integers(self.size))
            blocked[[y * self.size + column for y in range(self.size) if y != gap]] = True
        else:
            raise ValueError(f"unknown world model {model!r}")
        blocked[[self.start, self.goal]] = False
        return GridWorld(blocked)

    def checker(self, world: GridWorld) -> EdgeChecker:
        return GridChecker(self._graph.edges, world, self.delay_s)

    def edge_trajectories(self) -> list[npt.NDArray[np.float64]]:
        states = self._graph.vertex_states
        assert states is not None
        a, b = states[self._graph.edges[:, 0]], states[self._graph.edges[:, 1]]
        return [np.linspace(p, q, 3) for p, q in zip(a, b, strict=True)]

    def check_metadata(self) -> dict[str, Any]:
        return {"method": "exact cell occupancy", "resolution": 0.0, "margin": 0.0, "unit": "cell"}

    def world_model_params(self, model: str) -> dict[str, Any]:
        return {"block_probability": self.block_probability} if model == "uniform" else {"gap": 1}


def grid_x(domain: GridDomain, model: str, seeds: npt.NDArray[np.int64]) -> npt.NDArray[np.bool_]:
    """X computed directly, world by world, without the builder."""
    edges = np.arange(domain.graph.num_edges)
    return np.array([domain.checker(domain.make_world(model, int(s))).check_many(edges) for s in seeds])


def build_grid(out: Path, **kwargs: Any) -> Any:
    settings: dict[str, Any] = {
        "domain": "grid_test",
        "domain_factory": GRID_FACTORY,
        "world_model": "uniform",
        "num_worlds": 40,
        "seed": 7,
        "chunk_size": 6,
        "max_paths": 30,
        "progress": False,
        **kwargs,
    }
    return build_with(out, settings)


_OPTION_FIELDS = {f.name for f in dataclasses.fields(BuildOptions)}


def build_with(out: Path, settings: dict[str, Any]) -> Any:
    """``build_dataset`` with the recipe's and the options' fields given in one mapping."""
    options = BuildOptions(**{k: v for k, v in settings.items() if k in _OPTION_FIELDS})
    recipe = DatasetRecipe(**{k: v for k, v in settings.items() if k not in _OPTION_FIELDS})
    return build_dataset(out, recipe, options)


# --------------------------------------------------------------------------------------------------
# Seeds and the test domain itself


def test_grid_domain_satisfies_the_protocol() -> None:
    domain = GridDomain()
    assert isinstance(domain, Domain)
    assert isinstance(domain.checker(domain.make_world("uniform", 1)), EdgeChecker)
    assert domain.graph.num_edges == 42  # 24 axis-aligned + 18 diagonal edges on 4 x 4
    rebuilt = make_domain("grid_test", domain.spec(), factory=GRID_FACTORY)
    assert np.array_equal(rebuilt.graph.edges, domain.graph.edges)


# --------------------------------------------------------------------------------------------------
# The build: contents, and identical bytes whichever way it runs


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("ref") / "grid.npz"
    report = build_grid(out, workers=1)
    assert report.complete
    assert report.evaluated_chunks == 7
    assert report.resumed_chunks == 0
    assert not parts_dir(out).exists()  # chunk files are removed after a complete build
    return out


def test_build_contents_follow_the_recipe(reference: Path) -> None:
    ds = load_dataset(reference)
    domain = GridDomain()
    seeds = world_seeds(7, 40)
    assert np.array_equal(ds.world_seeds, seeds)
    assert np.array_equal(ds.X, grid_x(domain, "uniform", seeds))
    library_seed, split_seed = derived_seed(7, 1), derived_seed(7, 2)
    # The chunked library equals the one-shot library builder on the full X.
    expected = build_path_library(domain.graph, ds.X, domain.start, domain.goal, k=5, max_paths=30, seed=library_seed)
    assert ds.library.num_paths == 30 < ds.provenance["union_size"]
    for got, want in zip(ds.library.path_edges, expected.path_edges, strict=True):
        assert np.array_equal(got, want)
    assert expected.vertex_paths is not None
    assert ds.library.vertex_paths is not None
    for got, want in zip(ds.library.vertex_paths, expected.vertex_paths, strict=True):
        assert np.array_equal(got, want)
    assert np.array_equal(ds.R, expected.valid_paths(ds.X))
    train, test = split_worlds(ds.R, test_fraction=0.1, seed=split_seed)
    assert np.array_equal(ds.train_ids, train)
    assert np.array_equal(ds.test_ids, test)
    assert test.size == 4
    assert ds.R[test].any(axis=1).all()
    assert ds.domain == "grid_test"
    assert ds.world_model == "uniform"
    assert ds.seed == 7
    assert ds.domain_spec == domain.spec()
    assert ds.check_metadata == domain.check_metadata()
    assert ds.world_model_params == {"block_probability": 0.25}
    assert ds.edge_trajectories is not None
    assert len(ds.edge_trajectories) == 42
    assert ds.provenance["library_seed"] == library_seed
    assert ds.provenance["split_seed"] == split_seed
    assert ds.provenance["domain_factory"] == GRID_FACTORY
    assert np.array_equal(ds.edge_costs, np.ones(42))


@pytest.mark.parametrize("method", ["spawn", "fork"])
def test_two_local_workers_give_identical_bytes(reference: Path, tmp_path: Path, method: str) -> None:
    if method not in multiprocessing.get_all_start_methods():
        pytest.skip(f"no {method!r} start method on this platform")
    out = tmp_path / "grid.npz"
    report = build_grid(out, workers=2, start_method=method)
    assert report.complete
    assert report.evaluated_chunks == 7
    assert out.read_bytes() == reference.read_bytes()


def test_chunk_size_does_not_change_the_file(reference: Path, tmp_path: Path) -> None:
    out = tmp_path / "grid.npz"
    build_grid(out, workers=1, chunk_size=40)
    assert out.read_bytes() == reference.read_bytes()


def test_dask_local_cluster_gives_identical_bytes(reference: Path, tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        out = tmp_path / "grid.npz"
        report = build_grid(out, scheduler=cluster.scheduler_address)
        assert report.complete
        assert report.evaluated_chunks == 7
    assert load_dataset(out).X.tobytes() == load_dataset(reference).X.tobytes()
    assert out.read_bytes() == reference.read_bytes()


def test_domain_instance_without_factory(reference: Path, tmp_path: Path) -> None:
    # A Domain instance: its class (importable, with from_spec) is what workers rebuild.
    out = tmp_path / "grid.npz"
    report = build_with(
        out,
        {
            "domain": GridDomain(),
            "world_model": "uniform",
            "num_worlds": 40,
            "seed": 7,
            "chunk_size": 6,
            "max_paths": 30,
            "workers": 2,
            "progress": False,
        },
    )
    assert report.complete
    assert out.read_bytes() == reference.read_bytes()


# --------------------------------------------------------------------------------------------------
# Resume


def test_resume_after_a_stop_gives_the_identical_file(reference: Path, tmp_path: Path) -> None:
    out = tmp_path / "grid.npz"
    first = build_grid(out, workers=1, max_chunks=3)
    assert not first.complete
    assert first.dataset is None
    assert not out.exists()
    assert sorted(p.name for p in parts_dir(out).iterdir()) == [f"chunk_00000{i}.npz" for i in range(3)]
    second = build_grid(out, workers=2, max_chunks=2)
    assert not second.complete
    assert second.resumed_chunks == 3
    assert second.evaluated_chunks == 2
    last = build_grid(out, workers=2)
    assert last.complete
    assert last.resumed_chunks == 5
    assert last.evaluated_chunks == 2
    assert out.read_bytes() == reference.read_bytes()


def test_resume_reevaluates_a_damaged_chunk(reference: Path, tmp_path: Path) -> None:
    out = tmp_path / "grid.npz"
    build_grid(out, workers=1, keep_parts=True)
    out.unlink()
    chunk = parts_dir(out) / "chunk_000002.npz"
    chunk.write_bytes(chunk.read_bytes()[:100])  # as if the machine died while writing it
    (parts_dir(out) / "chunk_000004.npz").unlink()
    report = build_grid(out, workers=1)
    assert report.resumed_chunks == 5
    assert report.evaluated_chunks == 2
    assert out.read_bytes() == reference.read_bytes()


def test_resume_refuses_chunks_of_another_build(tmp_path: Path) -> None:
    out = tmp_path / "grid.npz"
    build_grid(out, workers=1, max_chunks=1)
    with pytest.raises(DatasetError, match="chunks of another build"):
        build_grid(out, workers=1, seed=8)
    # Library size and split do not affect the chunks: those settings may change on resume.
    assert build_grid(out, workers=1, max_paths=10, test_fraction=0.2).complete


def test_resume_after_killing_the_build_process(reference: Path, tmp_path: Path) -> None:
    # A real interruption: run the CLI (2 forked workers) in a child process group with slow checks and
    # SIGKILL the whole group mid-build.
    out = tmp_path / "grid.npz"
    slow = {"block_probability": 0.25, "delay_s": 0.08, "size": 4}
    spec = json.dumps(slow)
    argv = [
        sys.executable, "-m", "drd_planner.cli.build_dataset", "build-dataset",
        "--domain", "grid_test", "--domain-factory", GRID_FACTORY, "--domain-spec", spec,
        "--world-model", "uniform", "--worlds", "40", "--seed", "7", "--chunk-size", "6",
        "--max-paths", "30", "--workers", "2", "--out", str(out),
    ]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HERE), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
    parts = parts_dir(out)
    try:
        deadline = time.monotonic() + 60
        while len(list(parts.glob("chunk_*.npz"))) < 2:
            assert proc.poll() is None, proc.stderr.read().decode() if proc.stderr else ""
            assert time.monotonic() < deadline, "the build wrote no chunks in 60 s"
            time.sleep(0.05)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    assert not out.exists()
    done = len(list(parts.glob("chunk_*.npz")))
    assert 2 <= done < 7
    report = build_grid(out, workers=2, domain_spec=slow)
    assert report.complete
    assert report.resumed_chunks == done
    assert report.evaluated_chunks == 7 - done
    ds, ref = load_dataset(out), load_dataset(reference)
    assert ds.X.tobytes() == ref.X.tobytes()
    assert np.array_equal(ds.R, ref.R)
    assert np.array_equal(ds.test_ids, ref.test_ids)
    assert ds.domain_spec == slow  # the only difference from the reference


# --------------------------------------------------------------------------------------------------
# Refusals


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"world_model": "moon"}, "unknown world model 'moon'.*uniform, wall"),
        ({"num_worlds": 0}, "num_worlds must be a positive integer"),
        ({"chunk_size": 0}, "chunk_size must be a positive integer"),
        ({"workers": 0}, "workers must be a positive integer"),
        ({"seed": -1}, "seed must be a non-negative integer"),
        ({"test_fraction": 1.5}, r"test fraction must lie in \[0, 1\]"),
        ({"domain": "nope", "domain_factory": None}, "unknown domain 'nope'; known: "),
        ({"domain_factory": "no_such_module:X"}, "cannot be imported"),
        ({"domain_factory": "test_dataset_builder"}, "must look like"),
        ({"domain_spec": {"size": 1}}, "cannot be built from its spec: size must be at least 2"),
        ({"domain_spec": {"colour": 3}}, "cannot be built from its spec"),
    ],
)
def test_bad_arguments_are_refused(tmp_path: Path, kwargs: dict[str, Any], message: str) -> None:
    with pytest.raises(DatasetError, match=message):
        build_grid(tmp_path / "x.npz", **kwargs)
    assert not (tmp_path / "x.npz").exists()


def test_no_solvable_world_is_refused(tmp_path: Path) -> None:
    with pytest.raises(DatasetError, match="no world has a collision-free start-goal path"):
        build_grid(tmp_path / "x.npz", domain_spec={"block_probability": 1.0}, num_worlds=4)


def test_unreachable_scheduler_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import drd_planner.data.dataset_schedulers as schedulers

    monkeypatch.setattr(schedulers, "DASK_CONNECT_TIMEOUT_S", 1.0)
    with pytest.raises(DatasetError, match=r"cannot connect to the Dask scheduler at 'tcp://127\.0\.0\.1:9'"):
        build_grid(tmp_path / "x.npz", scheduler="tcp://127.0.0.1:9", num_worlds=4)


# --------------------------------------------------------------------------------------------------
# The seeded path is untouched by world sources


SEEDED_PROVENANCE = {
    "builder", "command", "domain_factory", "k", "max_paths", "test_fraction", "union_size", "library_seed",
    "split_seed", "world_seed_rule", "solvable_worlds", "graph_sha256",
}  # fmt: skip


def test_a_seeded_build_records_no_source(reference: Path) -> None:
    ds = load_dataset(reference)
    assert set(ds.provenance) == SEEDED_PROVENANCE
    assert ds.provenance["world_seed_rule"].startswith("SeedSequence(seed, spawn_key=(0, i))")


def test_seeded_chunk_tasks_carry_no_source() -> None:
    from drd_planner.data.dataset_builder import _plan

    recipe = DatasetRecipe("grid_test", "uniform", 10, 7, domain_factory=GRID_FACTORY)
    plan = _plan(recipe, BuildOptions(chunk_size=4))
    assert [t.source_json for t in plan.tasks] == [None, None, None]
    assert plan.source is None
    assert plan.tasks[0].seeds == tuple(int(s) for s in world_seeds(7, 10)[:4])


def test_progress_is_announced_at_once_and_counted_in_worlds(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 33 item 14: an arm build said nothing for 206 s, until its first chunk of worlds was checked."""
    build_grid(tmp_path / "d.npz", progress=True)
    lines = capsys.readouterr().err.splitlines()
    # before any chunk is checked
    assert lines
    assert lines[0] == "edge checks: 40 worlds"
