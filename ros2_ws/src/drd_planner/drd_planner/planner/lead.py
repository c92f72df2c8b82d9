"""Before a new query's library: the probe, then the lead (a lazy search worth the library's cost in checks).

A new query's library (one shortest free path per training world, BiSECt's set-up, an online tree) saves checks
but costs CPU: a few milliseconds at real scale, more on a prior of many small worlds. When checks are cheap, a
lazy search over the graph often verifies a path for less than the library costs. The planner cannot know in
advance which query is which, so when it is told what one check costs (``check_cost_ms``, C ms) it runs a
*lead* before building the library:

1. the probe, when the query has one (:mod:`~drd_planner.planner.probe`);
2. the **lead**: the graph stage's lazy search (LazySP with the prior's edge probabilities,
   :func:`~drd_planner.planner.roadmap_growth.lazy_search`) for at most ``floor(L / (C + o))`` checks. L is
   what *buying* costs: a new query's library and tree built, and the library stage's own CPU (BiSECt's
   selections) to its plan; o is the lead's own CPU per check (its searches). Both are measured once per prior
   on seeded random queries of the same kind, each planned in one training world's outcomes: between vertices,
   or between states off the graph, whose library costs more
   (:meth:`~drd_planner.planner.query_models.QueryModels.library_cost_ms`,
   :meth:`~drd_planner.planner.query_models.QueryModels.lead_check_ms`);
3. the library, only when the lead did not verify a path: built then, its policy told every outcome so far.

This is the rent-or-buy rule: the lead spends (in checks and its own searches) at most what buying would, so a
plan costs at most about twice what the cheaper of "lazy search only" and "library at once" would have cost, and
far less than the library where a short lazy search suffices (a robot's easy queries). The lead's checks are not
lost: the library stage and the graph stage after it reuse every outcome. A lead that proves the graph has no free
path ends the plan there (the library could not find one either). With C = 0 the lead's own time alone limits it
(``floor(L / o)``; no limit when that is 0 too, as with a price fixed by
:meth:`~drd_planner.planner.Planner.set_library_cost_ms`); with C unknown (the default) there is no lead: every
new query builds its library at once, as the method alone does.

The lead searches as the graph stage does (the most probable path under the prior, not the shortest): chosen on
held-out data (the authors' Baffle set, 30 random queries of seed 2) where it took 0.37 / 0.52 of plain LazySP's
median CPU time at C = 0.2 / 1 ms against 1.06 / 0.85 with plain lengths as the lead's weights; on the shipped
priors' held-out worlds the two were within the machine's run-to-run spread.

Only the method's policy (``direct_bisect``) gets a lead; queries with a precomputed tree never do (their
library and tree cost nothing per query), nor a query whose library is already built (cached).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from drd_planner.arrays import IntArray
from drd_planner.core.episode import CheckRecord, EdgeOracle, EpisodeResult, append_episode
from drd_planner.core.status import PlanCause
from drd_planner.exceptions import ProblemError
from drd_planner.planner.anytime import PlanLimits
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.probe import PROBE_POLICIES, probe_episode
from drd_planner.planner.query_model import QueryModel
from drd_planner.planner.result import PlanStage
from drd_planner.planner.roadmap_growth import lazy_search

__all__ = ["BeforeLibrary", "before_library", "check_cost", "lead_checks"]


def check_cost(value: float | None, name: str) -> float | None:
    """``value`` as a float when None or a finite number >= 0 (ProblemError naming ``name`` otherwise)."""
    if value is None:
        return None
    number = float(value)
    if not math.isfinite(number) or number < 0.0:
        raise ProblemError(f"{name} must be a finite number of milliseconds >= 0 or None, got {value!r}")
    return number


def lead_checks(check_cost_ms: float | None, library_cost_ms: float, own_ms: float = 0.0) -> int | None:
    """The lead's check budget: ``floor(L / (C + o))``; 0 (no lead) when C is None, None (no limit) when C + o is 0.

    Args:
        check_cost_ms: C, what one check costs in CPU milliseconds (None: unknown).
        library_cost_ms: L, what buying a new query's library costs in CPU milliseconds.
        own_ms: o, the lead's own CPU per check in milliseconds (its searches), spent beside the check's C.
    """
    if check_cost_ms is None:
        return 0
    per_check = check_cost_ms + own_ms
    if per_check == 0.0:
        return None
    return math.floor(round(library_cost_ms / per_check, 9))  # 10 / 0.2 is 50 checks, not 49.99...


@dataclass
class BeforeLibrary:
    """What the probe and the lead did.

    Attributes:
        checks: their checks, in order (steps numbered from 0).
        known: every outcome of them (edge id -> free).
        path_edges: (L,) the verified path's edge ids when one of them found it, else None.
        stage: the stage that verified ``path_edges`` (PROBE or LEAD), else None.
        ran_out: the plan's budget that ran out during them (``CHECK_BUDGET``, ``TIME_BUDGET``), else None.
        no_path: the lead proved that the query's graph has no free path.
    """

    checks: list[CheckRecord] = field(default_factory=list)
    known: dict[int, bool] = field(default_factory=dict)
    path_edges: IntArray | None = None
    stage: PlanStage | None = None
    ran_out: PlanCause | None = None
    no_path: bool = False

    def add(self, episode: EpisodeResult) -> None:
        """Append an episode's checks (renumbered after those before) and outcomes."""
        append_episode(self.checks, self.known, episode)


def before_library(
    prior: WorldPrior,
    model: QueryModel,
    oracle: EdgeOracle,
    policy: str,
    limits: PlanLimits,
    lead: int | None,
) -> BeforeLibrary:
    """Run a query's probe and lead (each only when it applies; see the module docstring).

    Args:
        prior: the prior (the lead's edge probabilities).
        model: the query's model; a lead runs only when its library is not built yet and it has no
            precomputed tree.
        oracle: the plan's oracle.
        policy: the plan's library policy (only :data:`~drd_planner.planner.probe.PROBE_POLICIES` get either).
        limits: the plan's check budget and deadline.
        lead: the lead's check budget (:func:`lead_checks`; 0: no lead, None: no limit but the plan's).
    """
    done = BeforeLibrary()
    if policy not in PROBE_POLICIES:
        return done
    if model.probe is not None:
        probed = probe_episode(
            model.probe, model.query.edge_costs, oracle, max_checks=limits.max_checks, deadline=limits.deadline
        )
        done.add(probed)
        if probed.success and probed.path_edges is not None:
            done.path_edges, done.stage = probed.path_edges, PlanStage.PROBE
            return done
        if probed.ran_out is not None:
            done.ran_out = probed.ran_out
            return done
    if lead == 0 or model.library is not None or model.precomputed is not None:
        return done
    plan_left = None if limits.max_checks is None else limits.max_checks - len(done.checks)
    budget = plan_left if lead is None else (lead if plan_left is None else min(lead, plan_left))
    if budget is not None and budget <= 0:
        done.ran_out = PlanCause.CHECK_BUDGET if plan_left is not None and plan_left <= 0 else None
        return done
    episode = lazy_search(
        prior, model.query, oracle, dict(done.known), budget=budget, deadline=limits.deadline, stage="lead"
    )
    done.add(episode)
    if episode.success and episode.path_edges is not None:
        done.path_edges, done.stage = episode.path_edges, PlanStage.LEAD
    elif episode.ran_out is None:
        done.no_path = True
    elif episode.ran_out is not PlanCause.CHECK_BUDGET or budget == plan_left:
        done.ran_out = episode.ran_out
    return done
