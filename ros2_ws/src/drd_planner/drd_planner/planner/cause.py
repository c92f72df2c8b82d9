"""Why a plan failed, as a value: what a caller maps to its own error codes without reading the reason text.

The planner's reason (:attr:`PlanResult.reason <drd_planner.planner.result.PlanResult.reason>`) says in words
why a plan has no path; :class:`PlanCause` names the causes an interface needs to tell apart (Nav2's planner
server has one error code for each: ``START_OUTSIDE_MAP``, ``GOAL_OCCUPIED``, ...). A failure with none of these
causes has no cause (None): malformed input, a budget that ran out (its own status), or no free path for
another reason.
"""

from __future__ import annotations

from enum import Enum

__all__ = ["PlanCause"]


class PlanCause(str, Enum):
    """What made a plan fail, where the planner can tell (see the module docstring)."""

    #: The start lies outside the graph's extent, or no motion can join it to a vertex within reach (refused).
    START_OUTSIDE = "start_outside"
    #: The goal lies outside the graph's extent, or no motion can join a vertex within reach to it (refused).
    GOAL_OUTSIDE = "goal_outside"
    #: No path: the start state itself, or every edge joining it to the graph, was checked blocked.
    START_BLOCKED = "start_blocked"
    #: No path: the goal state itself, or every edge joining it to the graph, was checked blocked.
    GOAL_BLOCKED = "goal_blocked"

    @classmethod
    def outside(cls, end: str) -> PlanCause:
        """``START_OUTSIDE`` or ``GOAL_OUTSIDE`` for ``end`` (``"start"`` or ``"goal"``)."""
        return cls.START_OUTSIDE if end == "start" else cls.GOAL_OUTSIDE

    @classmethod
    def blocked(cls, end: str) -> PlanCause:
        """``START_BLOCKED`` or ``GOAL_BLOCKED`` for ``end`` (``"start"`` or ``"goal"``)."""
        return cls.START_BLOCKED if end == "start" else cls.GOAL_BLOCKED
