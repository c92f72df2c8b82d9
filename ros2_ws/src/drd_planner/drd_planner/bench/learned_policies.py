"""The learned LazySP selectors in the policy registry: registered when the benchmark package is imported.

The planner's registry (:mod:`drd_planner.core.policies`) holds the planner's own policies; the research
selectors of :mod:`drd_planner.bench.lazysp_learned` (``lazysp_posterior``, ``lazysp_posterior_delta``)
and :mod:`drd_planner.bench.lazysp_imitation` (``lazysp_imitation``) join it through
:func:`~drd_planner.core.policies.register_policy` when ``drd_planner.bench`` is imported (its
``__init__`` imports this module), so ``drd bench --policies`` and ``run_world`` know them by name.
"""

from __future__ import annotations

from drd_planner.bench.lazysp_imitation import IMITATION_POLICY, ImitationLazySP, ImitationModel
from drd_planner.bench.lazysp_learned import (
    LEARNED_LAZYSP_POLICIES,
    PosteriorLazySP,
    PosteriorSettings,
    all_edge_outcomes,
)
from drd_planner.core.episode import Policy
from drd_planner.core.policies import (
    DEFAULT_PSEUDO_COUNT,
    POLICIES,
    PolicyContext,
    PolicyFactory,
    need_graph,
    register_policy,
)
from drd_planner.exceptions import ProblemError

__all__ = ["TRAIN_WORLD_POLICIES", "register_learned_policies"]

#: Policies that need ``PolicyContext.train_worlds`` (the learned LazySP selectors; ``lazysp_imitation``
#: also ``imitation_model``). Their kappa is ``DEFAULT_PSEUDO_COUNT`` whatever ``pseudo_count`` says,
#: which is tuned for ``direct_bisect``'s leaf.
TRAIN_WORLD_POLICIES = frozenset({*LEARNED_LAZYSP_POLICIES, IMITATION_POLICY})


def _lazysp_learned(name: str) -> PolicyFactory:
    def make(ctx: PolicyContext) -> Policy:
        graph = need_graph(ctx)
        if name == IMITATION_POLICY and not isinstance(ctx.imitation_model, ImitationModel):
            raise ProblemError(
                f"{name} needs a trained selector (PolicyContext.imitation_model, from "
                "PolicySettings.imitation_model in drd_planner.bench.runner; train it once per dataset with "
                "drd_planner.bench.lazysp_imitation.train_for_problem, as run_benchmark does)"
            )
        if ctx.start is None or ctx.goal is None:
            raise ProblemError(f"{name} needs the start and goal vertices (PolicyContext.start/goal)")
        if ctx.train_worlds is None:
            raise ProblemError(
                f"{name} needs the training worlds over every graph edge (PolicyContext.train_worlds, "
                "(n_train, E) bool; drd bench fills it from the dataset)"
            )
        if ctx.train_worlds.ndim != 2 or ctx.train_worlds.shape[1] != graph.num_edges:
            raise ProblemError(
                f"{name}: train_worlds has shape {ctx.train_worlds.shape}, the graph {graph.num_edges} edges"
            )
        # A fixed kappa: ctx.pseudo_count is tuned for direct_bisect's leaf, not for LazySP.
        outcomes = all_edge_outcomes(ctx.train_worlds, ctx.train_weights)
        if isinstance(ctx.imitation_model, ImitationModel) and name == IMITATION_POLICY:
            return ImitationLazySP(graph, ctx.start, ctx.goal, outcomes, ctx.imitation_model)
        delta = name == LEARNED_LAZYSP_POLICIES[1]
        settings = PosteriorSettings(pseudo_count=DEFAULT_PSEUDO_COUNT, delta=delta)
        return PosteriorLazySP(graph, ctx.start, ctx.goal, outcomes, settings)

    return make


def register_learned_policies() -> None:
    """Register the learned selectors (as graph policies) unless they already are; idempotent."""
    for name in (*LEARNED_LAZYSP_POLICIES, IMITATION_POLICY):
        if name not in POLICIES:
            register_policy(name, _lazysp_learned(name), needs_graph=True)


register_learned_policies()
