"""The OMPL LazyPRM worker process's entry point: ``python -m drd_planner.cli.ompl_worker``.

:mod:`drd_planner.bench.ompl_peer` starts it (OMPL's Python bindings can crash at interpreter exit, so they run
in their own process); the work is :mod:`drd_planner.bench.ompl_worker`'s.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from drd_planner.bench.ompl_worker import probe, run_request
from drd_planner.cli.worker_entry import exit_after, write_result

__all__ = ["main"]


def main(argv: list[str] | None = None) -> None:
    """Entry point: ``--probe`` or ``--request R --config C --result OUT``; never returns (``os._exit``)."""
    parser = argparse.ArgumentParser(prog="python -m drd_planner.cli.ompl_worker")
    parser.add_argument("--probe", action="store_true")
    parser.add_argument("--request", type=Path)
    parser.add_argument("--config", type=Path)
    parser.add_argument("--result", type=Path)
    args = parser.parse_args(argv)

    def work() -> None:
        if args.probe:
            sys.stdout.write(json.dumps(probe()) + "\n")
            return
        if args.request is None or args.config is None or args.result is None:
            parser.error("--request, --config and --result are required")
        write_result(args.result, lambda out: run_request(args.request, args.config, out))

    exit_after("ompl_worker", work)


if __name__ == "__main__":
    main()
