"""drd_planner: Bayesian active edge evaluation on expensive graphs.

DiRECt (a decision tree over a database of sampled worlds) chooses which graph edge to collision-check
next; BiSECt (an independent-edge Bernoulli model) finishes online, and a lazy search over the whole
graph takes over when every library path is blocked. The entry point is :class:`Planner`::

    from drd_planner import Planner, TableOracle
    planner = Planner.from_file("prior.npz")
    result = planner.plan(start, goal, oracle)        # PlanResult: status, path, check log, timings

See ``core`` for the ROS-free algorithms, ``data`` for file formats and ``bench`` for the benchmark.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

if TYPE_CHECKING:  # the names below load on first use (``planner_node`` installs its signal handlers first)
    from drd_planner.core.episode import CheckRecord, EdgeOracle, TableOracle
    from drd_planner.core.status import PlanCause, PlanStatus
    from drd_planner.exceptions import DrdError, PlanningError, PriorFileError
    from drd_planner.planner import (
        PLAN_POLICIES,
        ImproveBudget,
        Improvement,
        LeafSetting,
        Planner,
        PlanResult,
        PlanStage,
        PlanTimings,
        QueryError,
        QueryTree,
        WorldPrior,
        load_prior,
        prior_from_problem,
        save_prior,
    )

#: Exported name -> the module that defines it (imported on first access, PEP 562).
_EXPORTS: dict[str, str] = {
    **dict.fromkeys(("CheckRecord", "EdgeOracle", "TableOracle"), "drd_planner.core.episode"),
    **dict.fromkeys(("PlanCause", "PlanStatus"), "drd_planner.core.status"),
    **dict.fromkeys(("DrdError", "PlanningError", "PriorFileError"), "drd_planner.exceptions"),
    **dict.fromkeys(
        (
            "PLAN_POLICIES",
            "ImproveBudget",
            "Improvement",
            "LeafSetting",
            "Planner",
            "PlanResult",
            "PlanStage",
            "PlanTimings",
            "QueryError",
            "QueryTree",
            "WorldPrior",
            "load_prior",
            "prior_from_problem",
            "save_prior",
        ),
        "drd_planner.planner",
    ),
}

__all__ = [
    "PLAN_POLICIES",
    "CheckRecord",
    "DrdError",
    "EdgeOracle",
    "ImproveBudget",
    "Improvement",
    "LeafSetting",
    "PlanCause",
    "PlanResult",
    "PlanStage",
    "PlanStatus",
    "PlanTimings",
    "Planner",
    "PlanningError",
    "PriorFileError",
    "QueryError",
    "QueryTree",
    "TableOracle",
    "WorldPrior",
    "__version__",
    "load_prior",
    "prior_from_problem",
    "save_prior",
]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'drd_planner' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
