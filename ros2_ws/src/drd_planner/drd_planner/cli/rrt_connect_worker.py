"""The OMPL RRT-Connect worker process's entry point: ``python -m drd_planner.cli.rrt_connect_worker``.

:mod:`drd_planner.bench.rrt_connect` starts it (OMPL's Python bindings can crash at interpreter exit); the work
is :mod:`drd_planner.bench.rrt_connect_worker`'s.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from drd_planner.bench.rrt_connect_worker import run_tasks

__all__ = ["main"]


def main(argv: list[str] | None = None) -> None:
    """Entry point: ``--config C --result OUT``; never returns (``os._exit``)."""
    parser = argparse.ArgumentParser(prog="python -m drd_planner.cli.rrt_connect_worker")
    parser.add_argument("--config", type=Path, required=True)
    parser.add_argument("--result", type=Path, required=True)
    args = parser.parse_args(argv)
    code = 0
    try:
        with args.result.open("w") as out:
            try:
                run_tasks(args.config, out)
            except Exception as exc:
                out.write(json.dumps({"error": f"{type(exc).__name__}: {exc}"}) + "\n")
                out.flush()
                raise
    except Exception as exc:
        sys.stderr.write(f"rrt_connect_worker: {type(exc).__name__}: {exc}\n")
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)  # skip interpreter teardown, where the OMPL bindings crash


if __name__ == "__main__":
    main()
