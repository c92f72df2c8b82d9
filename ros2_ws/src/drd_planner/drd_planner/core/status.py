"""How a plan or an episode ended, and why it failed: the one status vocabulary of the whole package.

:class:`PlanStatus` says how it ended; :class:`PlanCause` says why it did not find a path, where that can be told
apart (Nav2's planner server has one error code for each of the first four; the budget causes say which budget
ran out). The episode runner (:func:`~drd_planner.core.episode.run_episode`), the planner
(:class:`~drd_planner.planner.result.PlanResult`) and the online session
(:class:`~drd_planner.planning.session_plan.SessionPlan`) all speak it; what goes on the wire (``/diagnostics``
values, ``drd plan`` output, benchmark JSON) is the members' values.
"""

from __future__ import annotations

from enum import Enum

__all__ = ["PlanCause", "PlanStatus"]


class PlanStatus(str, Enum):
    """How a plan ended."""

    #: A path was found and every edge of it was checked free in this plan.
    FOUND = "found"
    #: No free start-goal path was found: the graph has none given the checks made and, for a domain that
    #: grows its roadmap, none was found within the growth budget (the reason says what was tried). An
    #: episode on a path library ends so when every library path has a checked blocked edge.
    NO_PATH = "no_path"
    #: The search stopped before it settled anything: ``max_checks`` or ``time_budget_s`` ran out, or (an
    #: episode) the policy had nothing left to ask of a library not yet settled; the cause says which.
    #: Nothing is known to be free yet, and no absence of a path was shown.
    BUDGET_EXHAUSTED = "budget_exhausted"
    #: The query cannot be served (a malformed or unreachable start or goal); no check was made.
    REFUSED = "refused"


class PlanCause(str, Enum):
    """Why a plan or an episode did not find a path, where it can tell (None otherwise, and when FOUND)."""

    #: The start lies outside the graph's extent, or no motion can join it to a vertex within reach (refused).
    START_OUTSIDE = "start_outside"
    #: The goal lies outside the graph's extent, or no motion can join a vertex within reach to it (refused).
    GOAL_OUTSIDE = "goal_outside"
    #: No path: the start state itself, or every edge joining it to the graph, was checked blocked.
    START_BLOCKED = "start_blocked"
    #: No path: the goal state itself, or every edge joining it to the graph, was checked blocked.
    GOAL_BLOCKED = "goal_blocked"
    #: BUDGET_EXHAUSTED: the cap on checks (``max_checks``) was reached.
    CHECK_BUDGET = "check_budget"
    #: BUDGET_EXHAUSTED: the time budget (``time_budget_s``, a deadline) passed.
    TIME_BUDGET = "time_budget"
    #: BUDGET_EXHAUSTED (an episode): the policy had nothing left to ask while the library was not settled;
    #: that proves no absence of a path (the planner goes on to the graph search then).
    POLICY_GAVE_UP = "policy_gave_up"

    @classmethod
    def outside(cls, end: str) -> PlanCause:
        """``START_OUTSIDE`` or ``GOAL_OUTSIDE`` for ``end`` (``"start"`` or ``"goal"``)."""
        return cls.START_OUTSIDE if end == "start" else cls.GOAL_OUTSIDE

    @classmethod
    def blocked(cls, end: str) -> PlanCause:
        """``START_BLOCKED`` or ``GOAL_BLOCKED`` for ``end`` (``"start"`` or ``"goal"``)."""
        return cls.START_BLOCKED if end == "start" else cls.GOAL_BLOCKED

    @property
    def is_budget(self) -> bool:
        """A check or time budget ran out (``CHECK_BUDGET`` or ``TIME_BUDGET``)."""
        return self in (PlanCause.CHECK_BUDGET, PlanCause.TIME_BUDGET)
