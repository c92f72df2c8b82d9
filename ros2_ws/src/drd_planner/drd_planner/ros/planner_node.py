"""The ``planner_node`` console script: signals and ``--help`` first, then the (heavy) node.

A node started in the background from a shell script inherits SIGINT *ignored*; until rclpy installs
its handlers (after about a second of imports) such a signal was lost and the node ran on. Here
SIGINT and SIGTERM are handled before anything heavy is imported, so a signal at any moment of the start
ends the process (status 130 before the node runs, 0 once it spins).

While the node's modules are imported, a signal ends the process at once (``os._exit(130)``): nothing
is running yet that could lose work, and an exception raised into an import is not safe. A
KeyboardInterrupt raised inside a compiled extension's initialisation (manifold3d, imported by trimesh,
builds Python enums while it loads) aborted the interpreter (status -6); other imports swallowed it
(trimesh's optional imports catch ``BaseException``) or failed on half-way (scipy.ndimage raised a
NameError). Once the imports are done a signal raises KeyboardInterrupt; it is also recorded, and any
error of the start after a signal (rclpy's handler shuts the context down: creating the node then fails)
ends the process with status 130.

Usage::

    planner_node [--help] [--ros-args -p prior_paths:=[heli_wires] -p autostart:=true ...]
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Sequence
from types import FrameType

__all__ = ["main", "usage"]

USAGE = """usage: planner_node [-h] [--ros-args -p NAME:=VALUE ...]

The drd_planner lifecycle node: maps (obstacles, terrain, robot_description) in, lazily checked plans
out. Without autostart it waits for `ros2 lifecycle set <node> configure` and `activate`.

options:
  -h, --help    print this help and exit

parameters (--ros-args -p NAME:=VALUE, or a YAML file with --params-file):
"""


#: Signals received after the imports, before the node runs (a KeyboardInterrupt can be lost on the way).
_RECEIVED: list[int] = []
#: True while the node's modules are imported: a signal then ends the process at once.
_IMPORTING: list[bool] = [False]


def _interrupt(signum: int, frame: FrameType | None) -> None:
    if _IMPORTING[0]:
        os._exit(130)
    _RECEIVED.append(signum)
    raise KeyboardInterrupt


def usage() -> str:
    """The help text, with every parameter's default and description."""
    from drd_planner.ros.parameters import PARAMETERS

    lines = [USAGE]
    for spec in PARAMETERS:
        lines.append(f"  {spec.name} (default {spec.default!r}){' [read-only]' if spec.read_only else ''}")
        lines.append(f"      {spec.full_description}")
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``planner_node``; ``argv`` as in ``sys.argv`` (program name first). Returns the exit status."""
    signal.signal(signal.SIGINT, _interrupt)
    signal.signal(signal.SIGTERM, _interrupt)
    args = list(sys.argv if argv is None else argv)
    try:
        ours = args[1 : args.index("--ros-args")] if "--ros-args" in args else args[1:]
        if any(a in ("-h", "--help") for a in ours):
            print(usage(), end="")
            return 0
        if ours:
            print(f"{usage()}\nplanner_node: error: unrecognised arguments: {' '.join(ours)}", file=sys.stderr)
            return 2
        try:
            _IMPORTING[0] = True
            try:
                from drd_planner.ros.node_process import main as run_node
            finally:
                _IMPORTING[0] = False
            status = 130 if _RECEIVED else run_node(args)
        except Exception:
            # After a signal any error of the start is the signal's: an import it broke half-way, or the
            # node failing on the context rclpy's handler shut down.
            if not _RECEIVED:
                raise
            status = 130
        return status
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
