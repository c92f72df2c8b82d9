"""drd_planner: Bayesian active edge evaluation on expensive graphs.

DiRECt (a decision tree over a database of sampled worlds) chooses which graph edge to collision-check
next; BiSECt (an independent-edge Bernoulli model) finishes online, and a lazy search over the whole
graph takes over when every library path is blocked. The entry point is :class:`Planner`::

    from drd_planner import Planner, TableOracle
    planner = Planner.from_file("prior.npz")
    result = planner.plan(start, goal, oracle)        # PlanResult: status, path, check log, timings

See ``core`` for the ROS-free algorithms, ``data`` for file formats and ``bench`` for the benchmark.
"""

__version__ = "0.1.0"

from drd_planner.core.episode import CheckRecord, EdgeOracle, TableOracle
from drd_planner.exceptions import DrdError, PlanningError, PriorFileError
from drd_planner.planner import (
    PLAN_POLICIES,
    Planner,
    PlanResult,
    PlanStage,
    PlanStatus,
    PlanTimings,
    QueryError,
    QueryTree,
    WorldPrior,
    load_prior,
    prior_from_problem,
    save_prior,
)

__all__ = [
    "PLAN_POLICIES",
    "CheckRecord",
    "DrdError",
    "EdgeOracle",
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
