"""The ``drd`` command line: build datasets and trees, benchmark policies, plan once, and a demo.

Each subcommand's flags live in its own module (:mod:`~drd_planner.cli.build_dataset`,
:mod:`~drd_planner.cli.build_tree`, :mod:`~drd_planner.cli.bench`, :mod:`~drd_planner.cli.plan`,
:mod:`~drd_planner.cli.demo`); :func:`main` parses and runs the chosen one through
:func:`~drd_planner.cli.errors.run_command`.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from drd_planner import __version__
from drd_planner.cli.bench import add_bench_parser
from drd_planner.cli.build_dataset import add_build_dataset_parser
from drd_planner.cli.build_tree import add_build_tree_parser
from drd_planner.cli.demo import add_demo_parser
from drd_planner.cli.errors import run_command
from drd_planner.cli.plan import add_plan_parser

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``drd``."""
    parser = argparse.ArgumentParser(prog="drd", description="DiRECt + BiSECt active edge evaluation.")
    parser.add_argument("--version", action="version", version=f"drd_planner {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    add_build_dataset_parser(sub)
    add_build_tree_parser(sub)
    add_bench_parser(sub)
    add_plan_parser(sub)
    add_demo_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; errors print one line and exit 2."""
    return run_command(build_parser().parse_args(argv))


if __name__ == "__main__":
    raise SystemExit(main())
