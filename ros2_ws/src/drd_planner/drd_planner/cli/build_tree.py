"""``drd build-tree``: its flags, made into :class:`~drd_planner.planner.prior_build.BuildTreeOptions`."""

from __future__ import annotations

import argparse
from typing import Any

from drd_planner.cli.argtypes import eta_arg, query_arg
from drd_planner.cli.shared_flags import (
    add_kappa_option,
    add_tree_options,
    leaf_choice,
    problem_source,
    tree_settings,
)
from drd_planner.planner.prior_build import BuildTreeOptions, write_prior

__all__ = ["add_build_tree_parser", "build_tree_options", "cmd_build_tree"]


def add_build_tree_parser(sub: Any) -> argparse.ArgumentParser:
    """Register ``build-tree`` on an ``add_subparsers()`` object; returns the new parser."""
    p: argparse.ArgumentParser = sub.add_parser(
        "build-tree", help="write a world prior (any query) with the dataset's DiRECt tree and --query trees"
    )
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--gccd", metavar="DIR", help="authors'-format dataset folder")
    source.add_argument("--dataset", metavar="FILE", help="dataset file written by drd build-dataset")
    source.add_argument("--prior", metavar="FILE", help="add --query trees to this prior file")
    p.add_argument("--out", required=True, help="prior file to write (.npz)")
    p.add_argument(
        "--query",
        type=query_arg,
        action="append",
        default=None,
        metavar="START,GOAL",
        help="also precompute a tree for this query: vertex ids, or states as space-separated numbers (repeatable)",
    )
    p.add_argument(
        "--eta",
        type=eta_arg,
        default=None,
        help="switch threshold stored in the file; 'auto' (default) validates it on held-out training worlds",
    )
    add_kappa_option(p)
    p.add_argument("--seed", type=int, default=0, help="seed of the validation hold-out")
    add_tree_options(p)
    p.set_defaults(func=cmd_build_tree)
    return p


def build_tree_options(args: argparse.Namespace) -> BuildTreeOptions:
    """The parsed ``build-tree`` flags as options."""
    return BuildTreeOptions(
        out=args.out,
        source=None if args.prior else problem_source(args),
        prior=args.prior,
        queries=tuple(args.query or ()),
        leaf=leaf_choice(args),
        tree=tree_settings(args),
    )


def cmd_build_tree(args: argparse.Namespace) -> int:
    """``drd build-tree``: write a world prior with the dataset's DiRECt tree and any ``--query`` trees."""
    return write_prior(build_tree_options(args))
