"""``drd demo``: its flags, made into :class:`~drd_planner.bench.planar_demo.DemoOptions`."""

from __future__ import annotations

import argparse
from typing import Any

from drd_planner.bench.planar_demo import DemoOptions, run_demo
from drd_planner.domains.planar import WORLD_MODELS as PLANAR_WORLD_MODELS

__all__ = ["add_demo_parser", "cmd_demo"]


def add_demo_parser(sub: Any) -> argparse.ArgumentParser:
    """Register ``demo`` on an ``add_subparsers()`` object; returns the new parser."""
    p: argparse.ArgumentParser = sub.add_parser("demo", help="self-contained demo on a generated planar problem")
    p.add_argument("--model", default="one_wall", choices=PLANAR_WORLD_MODELS, help="planar world model")
    p.add_argument("--worlds", type=int, default=300)
    p.add_argument("--episodes", type=int, default=3)
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=cmd_demo)
    return p


def cmd_demo(args: argparse.Namespace) -> int:
    """``drd demo``: generate a planar problem, build a tree, plan on a few held-out worlds."""
    return run_demo(DemoOptions(model=args.model, worlds=args.worlds, episodes=args.episodes, seed=args.seed))
