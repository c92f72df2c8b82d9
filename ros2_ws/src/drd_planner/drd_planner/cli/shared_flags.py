"""Flags several ``drd`` subcommands share, and the typed options made from them.

- the dataset source ``--gccd DIR | --dataset FILE`` -> :class:`~drd_planner.data.problem_source.ProblemSource`
  (:func:`problem_source`);
- the tree flags (``--threshold``, ``--candidates``, ``--top-regions``, ``--colouring``, ``--region-rule``)
  -> :class:`~drd_planner.planner.build_settings.TreeSettings` (:func:`tree_settings`);
- ``--kappa`` (:func:`add_kappa_option`) with ``--eta``, ``--seed`` and ``--region-rule``
  -> :class:`~drd_planner.planner.build_settings.LeafChoice` (:func:`leaf_choice`).
"""

from __future__ import annotations

import argparse

from drd_planner.cli.argtypes import kappa_arg
from drd_planner.core.region_rule import DEFAULT_REGION_RULE, REGION_RULES
from drd_planner.core.switch_threshold import DEFAULT_PSEUDO_COUNTS
from drd_planner.core.tree import DEFAULT_EXPAND_THRESHOLD
from drd_planner.data.problem_source import ProblemSource
from drd_planner.planner.build_settings import LeafChoice, TreeSettings

__all__ = [
    "AUTO",
    "add_kappa_option",
    "add_tree_options",
    "kappas",
    "leaf_choice",
    "problem_source",
    "region_rules",
    "tree_settings",
]

#: ``--region-rule auto``: validate every region rule, each with its own eta and kappa.
AUTO = "auto"


def add_tree_options(parser: argparse.ArgumentParser) -> None:
    """Add the DiRECt tree flags (see :func:`tree_settings`)."""
    parser.add_argument(
        "--threshold",
        type=float,
        default=DEFAULT_EXPAND_THRESHOLD,
        help=f"expand nodes with at least this fraction (default {DEFAULT_EXPAND_THRESHOLD})",
    )
    parser.add_argument(
        "--candidates",
        choices=("max-prob-region", "all"),
        default="max-prob-region",
        help="tests DiRECt considers at a node (default: edges of the best-supported path)",
    )
    parser.add_argument("--top-regions", type=int, default=None, help="IncDRD: DiRECt on k regions only")
    parser.add_argument("--colouring", action="store_true", help="group never-overlapping regions into one ECD")
    parser.add_argument(
        "--region-rule",
        choices=(*REGION_RULES, AUTO),
        default=AUTO,
        help="which path the tree and BiSECt try to prove: the most probable (probability, the paper's), "
        "the most probable per expected check (per_check), or auto (default): each validated with its own "
        "eta and kappa, the paper's kept unless per_check needs fewer checks",
    )


def add_kappa_option(parser: argparse.ArgumentParser) -> None:
    """``--kappa``: the posterior leaf's pseudo-count; unset (None) means 'auto'."""
    parser.add_argument(
        "--kappa",
        type=kappa_arg,
        default=None,
        help="pseudo-count (in worlds) of the posterior leaf that keeps re-conditioning BiSECt's bias on the "
        "training worlds after the switch; 'none' keeps the paper's fixed leaf bias; 'auto' (default) "
        "validates it together with eta",
    )


def tree_settings(args: argparse.Namespace) -> TreeSettings:
    """The tree flags as settings (``--region-rule auto`` builds with the paper's rule until validated)."""
    return TreeSettings(
        expand_threshold=args.threshold,
        colouring=args.colouring,
        top_regions=args.top_regions,
        max_prob_region=args.candidates == "max-prob-region",
        region_rule=DEFAULT_REGION_RULE if args.region_rule == AUTO else args.region_rule,
    )


def region_rules(args: argparse.Namespace) -> tuple[str, ...]:
    """The region rules to validate: every one for ``--region-rule auto``, else the one given."""
    return REGION_RULES if args.region_rule == AUTO else (args.region_rule,)


def kappas(args: argparse.Namespace) -> tuple[float | None, ...]:
    """The ``--kappa`` candidates (the validated defaults when not given)."""
    return DEFAULT_PSEUDO_COUNTS if args.kappa is None else tuple(args.kappa)


def leaf_choice(args: argparse.Namespace) -> LeafChoice:
    """How eta, kappa and the region rule are chosen, from ``--eta``, ``--kappa``, ``--seed``, ``--region-rule``."""
    return LeafChoice(eta=args.eta, pseudo_counts=kappas(args), seed=args.seed, region_rules=region_rules(args))


def problem_source(args: argparse.Namespace) -> ProblemSource:
    """The dataset named by ``--gccd`` or ``--dataset`` (absent flags are None)."""
    return ProblemSource(gccd=getattr(args, "gccd", None), dataset=getattr(args, "dataset", None))
