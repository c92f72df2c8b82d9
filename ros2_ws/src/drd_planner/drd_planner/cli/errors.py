"""How the command-line entry points end: an error is one line on stderr and exit status 2.

Both ``drd`` (:mod:`drd_planner.cli.main`) and the stand-alone dataset tool (:mod:`drd_planner.cli.build_dataset`)
run their chosen subcommand through :func:`run_command`, so a :class:`~drd_planner.exceptions.DrdError`
prints ``drd: error: <message>`` and returns 2, and Ctrl-C prints the caller's interrupt line and returns
130 (128 + SIGINT, as a shell reports it). Any other exception is a bug and keeps its traceback, a broken
safety invariant (:class:`~drd_planner.exceptions.InvariantError`, not a ``DrdError``) included.
"""

from __future__ import annotations

import argparse
import sys

from drd_planner.exceptions import DrdError

__all__ = ["ERROR_EXIT", "INTERRUPT_EXIT", "run_command"]

#: Exit status of a command that failed with a :class:`~drd_planner.exceptions.DrdError`.
ERROR_EXIT = 2

#: Exit status of a command interrupted by Ctrl-C (128 + SIGINT).
INTERRUPT_EXIT = 130


def run_command(args: argparse.Namespace, *, interrupted: str = "drd: interrupted") -> int:
    """Run the chosen subcommand ``args.func(args)`` (set by its parser) and return its exit status.

    Args:
        args: the parsed command line.
        interrupted: the line printed on stderr when the command is interrupted (Ctrl-C).

    Returns:
        The command's own status (as an int), :data:`ERROR_EXIT` after a ``DrdError`` (its message printed
        as ``drd: error: <message>``), or :data:`INTERRUPT_EXIT` after Ctrl-C.
    """
    try:
        return int(args.func(args))
    except DrdError as exc:
        print(f"drd: error: {exc}", file=sys.stderr)
        return ERROR_EXIT
    except KeyboardInterrupt:
        print(interrupted, file=sys.stderr)
        return INTERRUPT_EXIT
