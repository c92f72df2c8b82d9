"""``drd_replay``: its flags, made into the options of a replay.

:class:`~drd_planner.ros.replay.ReplayOptions` for :func:`~drd_planner.ros.replay.replay_command`.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from drd_planner.cli.argtypes import bounded_float

__all__ = ["build_parser", "main"]

_positive = bounded_float(above=0.0)
_seconds = bounded_float(at_least=0.0)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``drd_replay``."""
    parser = argparse.ArgumentParser(
        prog="drd_replay",
        description="Replay a rosbag2 MCAP bag of maps and requests into a running drd_planner node "
        "and record its outputs.",
    )
    parser.add_argument("bag", help="the bag: an .mcap file, a rosbag2 folder, or a shipped bag's name")
    parser.add_argument("--record", metavar="OUT.mcap", help="write the planner's outputs to this MCAP file")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --record file")
    parser.add_argument("--rate", type=_positive, default=1.0, help="playback speed factor (default 1)")
    parser.add_argument("--settle", type=_seconds, default=2.0, help="seconds to keep listening after the last message")
    parser.add_argument("--wait", type=_seconds, default=5.0, help="seconds to wait for the node's subscriptions first")
    parser.add_argument("--namespace", default=None, help="the planner node's namespace")
    return parser


def _say(line: str) -> None:
    """A progress line on stdout, flushed (the replay runs for a while)."""
    print(line, flush=True)


def main(argv: Sequence[str] | None = None) -> int:
    """``drd_replay``: errors (missing or corrupt bag, existing --record file) print one line and exit 2."""
    args = build_parser().parse_args(argv)
    from drd_planner.ros.replay import ReplayOptions, replay_command

    options = ReplayOptions(
        record=args.record,
        overwrite=args.overwrite,
        rate=args.rate,
        settle=args.settle,
        wait=args.wait,
        namespace=args.namespace,
        log=_say,
        require_listener=True,
    )
    return replay_command(args.bag, options)


if __name__ == "__main__":
    raise SystemExit(main())
