"""The OMPL RRT-Connect worker process's entry point: ``python -m drd_planner.cli.rrt_connect_worker``.

:mod:`drd_planner.bench.rrt_connect` starts it (OMPL's Python bindings can crash at interpreter exit); the work
is :mod:`drd_planner.bench.rrt_connect_worker`'s.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from drd_planner.bench.rrt_connect_worker import run_tasks
from drd_planner.cli.worker_entry import exit_after, write_result

__all__ = ["main"]


def main(argv: list[str] | None = None) -> None:
    """Entry point: ``--config C --result OUT``; never returns (``os._exit``)."""
    parser = argparse.ArgumentParser(prog="python -m drd_planner.cli.rrt_connect_worker")
    parser.add_argument("--config", type=Path, required=True)
    parser.add_argument("--result", type=Path, required=True)
    args = parser.parse_args(argv)
    exit_after("rrt_connect_worker", lambda: write_result(args.result, lambda out: run_tasks(args.config, out)))


if __name__ == "__main__":
    main()
