"""``planner_demo``: its flags, made into the options of the main job.

:class:`~drd_planner.ros.demo.PlannerDemoOptions` for :func:`~drd_planner.ros.demo.run_planner_demo` (the
planner node on a bundled bag, end to end); with ``--site-file S`` (and ``--prior P``, a prior of that site)
:class:`~drd_planner.ros.site_demo.SiteDemoOptions` for :func:`~drd_planner.ros.site_demo.run_site_demo`
(the map server publishes the site's maps instead of a bag).
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
        help="prior file or shipped tree name (default heli_lines; --tree: deprecated)",
    )
    parser.add_argument("--bag", help="bag file or bundled bag name (default heli_lines)")
    parser.add_argument(
        "--site-file",
        help="site mode: the map server publishes this GIS site file's maps (no bag) and the node plans on "
        "--prior (required: a prior built from the site, drd build-tree); goals: the prior's query, then two far "
        "vertices",
    )
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
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.site_file is not None:
        if args.prior is None or args.bag is not None:
            parser.error(
                "--site-file needs --prior (a prior of that site) and takes no --bag (the maps are the site's)"
            )
        from drd_planner.ros.site_demo import SiteDemoOptions, run_site_demo

        return run_site_demo(
            SiteDemoOptions(
                prior=args.prior,
                site_file=args.site_file,
                out=args.out,
                rate=args.rate,
                seed=args.seed,
                pictures=not args.no_pictures,
                domain_id=args.domain_id,
            )
        )
    from drd_planner.ros.demo import PlannerDemoOptions, run_planner_demo

    return run_planner_demo(
        PlannerDemoOptions(
            prior=args.prior or "heli_lines",
            bag=args.bag or "heli_lines",
            out=args.out,
            rate=args.rate,
            seed=args.seed,
            pictures=not args.no_pictures,
            domain_id=args.domain_id,
        )
    )


if __name__ == "__main__":
    raise SystemExit(main())
