"""Plan any query of a graph from one world prior (ROS-free): :class:`Planner` and its file format."""

from drd_planner.planner.anytime import ImproveBudget
from drd_planner.planner.endpoints import QueryError
from drd_planner.planner.planner import PLAN_POLICIES, Planner
from drd_planner.planner.prior import LeafSetting, QueryTree, WorldPrior, prior_from_problem
from drd_planner.planner.prior_file import load_prior, load_tree_bundle, save_prior
from drd_planner.planner.query_model import QueryModel
from drd_planner.planner.result import Improvement, PlanResult, PlanStage, PlanStatus, PlanTimings

__all__ = [
    "PLAN_POLICIES",
    "ImproveBudget",
    "Improvement",
    "LeafSetting",
    "PlanResult",
    "PlanStage",
    "PlanStatus",
    "PlanTimings",
    "Planner",
    "QueryError",
    "QueryModel",
    "QueryTree",
    "WorldPrior",
    "load_prior",
    "load_tree_bundle",
    "prior_from_problem",
    "save_prior",
]
