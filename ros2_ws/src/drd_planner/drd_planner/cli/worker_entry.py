"""What the OMPL worker processes' entry points share: the result file's error line, and leaving with ``os._exit``.

OMPL's Python bindings can crash while the interpreter tears down, so a worker writes everything, flushes and
leaves with ``os._exit`` (:mod:`drd_planner.cli.ompl_worker`, :mod:`drd_planner.cli.rrt_connect_worker`).
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import IO, NoReturn

__all__ = ["exit_after", "write_result"]


def write_result(path: Path, work: Callable[[IO[str]], None]) -> None:
    """Run ``work`` on the result file at ``path``; an exception is written there as one JSON line, then raised."""
    with path.open("w") as out:
        try:
            work(out)
        except Exception as exc:
            out.write(json.dumps({"error": f"{type(exc).__name__}: {exc}"}) + "\n")
            out.flush()
            raise


def exit_after(name: str, work: Callable[[], None]) -> NoReturn:
    """Run ``work``, report an exception on stderr as ``name: Type: text``, flush and ``os._exit`` (0 or 1)."""
    code = 0
    try:
        work()
    except Exception as exc:
        sys.stderr.write(f"{name}: {type(exc).__name__}: {exc}\n")
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)  # skip interpreter teardown, where the OMPL bindings crash
