"""Typed settings of the offline tree builds: how DiRECt trees are grown and how a prior's leaf is chosen.

The commands that build trees (``drd build-tree``, ``drd bench``) take these instead of their flags:
:class:`TreeSettings` (``--threshold``, ``--candidates``, ``--top-regions``, ``--colouring``, the rule of
``--region-rule``) and :class:`LeafChoice` (``--eta``, ``--kappa``, ``--seed``, the rules ``--region-rule``
validates).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from drd_planner.core.problem import Problem
from drd_planner.core.region_rule import DEFAULT_REGION_RULE, REGION_RULES
from drd_planner.core.switch_threshold import DEFAULT_PSEUDO_COUNTS
from drd_planner.core.tree import DEFAULT_EXPAND_THRESHOLD
from drd_planner.planner.leaf_validation import PriorLeaf, TreeLeaf, leaf_from_options, tree_leaf_from_options

__all__ = ["LeafChoice", "TreeSettings"]


@dataclass(frozen=True)
class TreeSettings:
    """How a DiRECt tree is built (the keyword arguments of :func:`drd_planner.core.tree.build_tree`).

    Attributes:
        expand_threshold: expand a node while it holds at least this fraction of the training worlds (0..1).
        colouring: group never-overlapping regions into one ECD test.
        top_regions: IncDRD: run DiRECt on this many regions only (None: all).
        max_prob_region: consider only the edges of the best-supported path at a node (False: every edge).
        region_rule: which path the tree tries to prove (:mod:`drd_planner.core.region_rule`).
    """

    expand_threshold: float = DEFAULT_EXPAND_THRESHOLD
    colouring: bool = False
    top_regions: int | None = None
    max_prob_region: bool = True
    region_rule: str = DEFAULT_REGION_RULE

    def kwargs(self) -> dict[str, Any]:
        """The settings as keyword arguments of :func:`~drd_planner.core.tree.build_tree`."""
        return {
            "expand_threshold": self.expand_threshold,
            "colouring": self.colouring,
            "top_regions": self.top_regions,
            "max_prob_region": self.max_prob_region,
            "region_rule": self.region_rule,
        }


@dataclass(frozen=True)
class LeafChoice:
    """How a prior's switch threshold eta, leaf pseudo-count kappa and region rule are chosen.

    Attributes:
        eta: the switch threshold (a fraction of worlds in (0, 1]); None validates it on held-out worlds.
        pseudo_counts: the kappa candidates (in worlds; None: the paper's fixed leaf bias); one fixes it.
        seed: seed of the validation's hold-out and random queries.
        region_rules: the region rules to validate (one: that rule, not validated).
    """

    eta: float | None = None
    pseudo_counts: tuple[float | None, ...] = DEFAULT_PSEUDO_COUNTS
    seed: int = 0
    region_rules: tuple[str, ...] = REGION_RULES

    def prior_leaf(self, problem: Problem) -> PriorLeaf:
        """The prior's setting: as given, or validated on random queries (:func:`leaf_from_options`)."""
        return leaf_from_options(
            problem,
            eta=self.eta,
            pseudo_counts=self.pseudo_counts,
            seed=self.seed,
            region_rules=self.region_rules,
            progress=None,
        )

    def tree_leaf(self, problem: Problem, tree: TreeSettings) -> TreeLeaf:
        """A precomputed tree's own setting, validated on its query (:func:`tree_leaf_from_options`)."""
        return tree_leaf_from_options(
            problem,
            eta=self.eta,
            pseudo_counts=self.pseudo_counts,
            seed=self.seed,
            tree_options=tree.kwargs(),
            region_rules=self.region_rules,
            progress=None,
        )
