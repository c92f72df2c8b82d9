"""Why a plan failed, as a value: what a caller maps to its own error codes without reading the reason text.

The planner's reason (:attr:`PlanResult.reason <drd_planner.planner.result.PlanResult.reason>`) says in words
why a plan has no path; :class:`PlanCause` names the causes an interface needs to tell apart (Nav2's planner
server has one error code for each: ``START_OUTSIDE_MAP``, ``GOAL_OCCUPIED``, ...), and which budget ran out
(``CHECK_BUDGET``, ``TIME_BUDGET``). A failure with none of these causes has no cause (None): malformed input,
or no free path for another reason.

:class:`PlanCause` is defined at the core's floor (:mod:`drd_planner.core.status`, beside
:class:`~drd_planner.core.status.PlanStatus`, so the episode runner speaks it too); this module re-exports it.
"""

from __future__ import annotations

from drd_planner.core.status import PlanCause

__all__ = ["PlanCause"]
