"""``planner_demo``: its flags, made into the options of the main job.

:class:`~drd_planner.ros.demo.PlannerDemoOptions` for :func:`~drd_planner.ros.demo.run_planner_demo` (the
planner node on a bundled bag, end to end).
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from drd_planner.cli.argtypes import add_prior_option

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The ``planner_demo`` argument parser."""
    parser = argparse.ArgumentParser(
        prog="planner_demo",
        description="The main job (planner_demo): the planner node on a bundled bag, end to end, no hardware.",
    )
    add_prior_option(
        parser,
        default="heli_lines",
        help="prior file or shipped tree name (default heli_lines; --tree: deprecated)",
    )
    parser.add_argument("--bag", default="heli_lines", help="bag file or bundled bag name (default heli_lines)")
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default ./out)")
    parser.add_argument("--rate", type=float, default=2.0, help="playback speed factor (default 2)")
    parser.add_argument("--seed", type=int, default=0, help="policy seed (default 0)")
    parser.add_argument("--no-pictures", action="store_true", help="skip the pictures (no matplotlib needed)")
    parser.add_argument(
        "--domain-id",
        type=int,
        default=None,
        help="ROS domain to run on (default: a private one where no other node is seen)",
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """``planner_demo``: 0 when every request got a verified plan, 1 if one did not, 2 on bad input."""
    args = build_parser().parse_args(argv)
    from drd_planner.ros.demo import PlannerDemoOptions, run_planner_demo

    return run_planner_demo(
        PlannerDemoOptions(
            prior=args.prior,
            bag=args.bag,
            out=args.out,
            rate=args.rate,
            seed=args.seed,
            pictures=not args.no_pictures,
            domain_id=args.domain_id,
        )
    )


if __name__ == "__main__":
    raise SystemExit(main())
