"""Tests of where a dataset build's tasks run (the byte-identity across schedulers is in test_dataset_builder)."""

from __future__ import annotations

import multiprocessing
import subprocess
import sys

import pytest
from test_dataset_builder import GRID_FACTORY

from drd_planner.data.dataset_chunks import ChunkTask
from drd_planner.data.dataset_schedulers import choose_start_method, run_tasks
from drd_planner.data.seeding import world_seeds
from drd_planner.exceptions import DatasetError


def test_start_method_choice() -> None:
    with pytest.raises(DatasetError, match="start method 'teleport' is not available here"):
        choose_start_method("teleport")
    assert choose_start_method("spawn") == "spawn"
    # A fresh single-threaded interpreter (as under `drd build-dataset`) forks where it can.
    code = "from drd_planner.data.dataset_schedulers import choose_start_method as c; print(c())"
    fresh = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert fresh.stdout.strip() == ("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")


def _tasks(count: int) -> list[ChunkTask]:
    seeds = world_seeds(5, 2 * count)
    return [
        ChunkTask(
            index=i,
            first=2 * i,
            seeds=tuple(int(s) for s in seeds[2 * i : 2 * i + 2]),
            domain="grid_test",
            spec_json='{"block_probability": 0.25, "delay_s": 0.0, "size": 4}',
            factory=GRID_FACTORY,
            world_model="uniform",
            k=3,
        )
        for i in range(count)
    ]


def test_inline_and_pool_give_the_same_results() -> None:
    tasks = _tasks(3)
    inline = {r.index: r for r in run_tasks(tasks, workers=1, scheduler=None, method=None)}
    pooled = {r.index: r for r in run_tasks(tasks, workers=2, scheduler=None, method="spawn")}
    assert sorted(inline) == sorted(pooled) == [0, 1, 2]
    for i in inline:
        assert inline[i].x_packed.tobytes() == pooled[i].x_packed.tobytes()
        assert inline[i].paths() == pooled[i].paths()
