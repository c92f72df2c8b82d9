"""Nav2's planner error codes for what a request came to: one code per failure, as Nav2's planner server.

Nav2's ``ComputePathToPose`` result (Jazzy) carries one ``error_code`` and an ``error_msg``. The planner
says why a plan failed in its own vocabulary (:class:`~drd_planner.planning.plan_outcome.PlanOutcome`: a
refusal before planning and what it was about, or the plan's ``status`` and ``message``);
:func:`nav2_error` maps it:

==================================================  ======================
what happened                                       Nav2 code
==================================================  ======================
a verified path                                     ``NONE``
``planner_id`` names no loaded prior (the action)   ``INVALID_PLANNER``
no loaded prior plans for the goal                  ``INVALID_PLANNER``
no start: no robot state yet, a start pose the      ``TF_ERROR`` (Nav2: "unable to get start pose")
prior cannot take, or a pose in another frame
start outside the graph's extent (refused)          ``START_OUTSIDE_MAP``
goal outside the graph's extent, or no roadmap      ``GOAL_OUTSIDE_MAP``
vertex within the goal tolerance
no free path, every motion at the start blocked     ``START_OCCUPIED``
no free path, every motion at the goal blocked      ``GOAL_OCCUPIED``
``max_checks`` or ``time_budget_s`` ran out         ``TIMEOUT``
no free path otherwise                              ``NO_VALID_PATH``
no maps yet, a malformed request, a bug, the rest   ``UNKNOWN``
==================================================  ======================

The codes come from the plan's status and cause (:class:`~drd_planner.core.status.PlanStatus`,
:class:`~drd_planner.core.status.PlanCause`), never from its reason text. When both ends are walled in, the
start's code wins (Nav2's result lists its codes in priority order, start before goal). A cancelled
plan has no code: the goal ends CANCELED, as in Nav2.
"""

from __future__ import annotations

from dataclasses import dataclass

from drd_planner.core.status import PlanCause, PlanStatus
from drd_planner.planning.plan_outcome import PlanOutcome

__all__ = ["NAV2_CODES", "Nav2Error", "nav2_error"]

#: Nav2 Jazzy's ``ComputePathToPose.Result`` error codes (nav2_msgs/action/ComputePathToPose.action).
NAV2_CODES = {
    "NONE": 0,
    "UNKNOWN": 200,
    "INVALID_PLANNER": 201,
    "TF_ERROR": 202,
    "START_OUTSIDE_MAP": 203,
    "GOAL_OUTSIDE_MAP": 204,
    "START_OCCUPIED": 205,
    "GOAL_OCCUPIED": 206,
    "TIMEOUT": 207,
    "NO_VALID_PATH": 208,
}

_REFUSED_PART = {
    "prior": "INVALID_PLANNER",
    "start": "TF_ERROR",
    "goal": "GOAL_OUTSIDE_MAP",
    "maps": "UNKNOWN",
}


@dataclass(frozen=True)
class Nav2Error:
    """One Nav2 error: the code's name (a key of :data:`NAV2_CODES`) and the text for ``error_msg``."""

    name: str
    text: str

    @property
    def code(self) -> int:
        """The code's number (uint16)."""
        return NAV2_CODES[self.name]


#: The code of each failure cause of an end the planner names.
_CAUSE_CODE = {
    PlanCause.START_OUTSIDE: "START_OUTSIDE_MAP",
    PlanCause.GOAL_OUTSIDE: "GOAL_OUTSIDE_MAP",
    PlanCause.START_BLOCKED: "START_OCCUPIED",
    PlanCause.GOAL_BLOCKED: "GOAL_OCCUPIED",
}


def nav2_error(outcome: PlanOutcome) -> Nav2Error:
    """The Nav2 error of a served request (``NONE`` with a verified path); see the module docstring."""
    result = outcome.result
    if outcome.internal_error:
        return Nav2Error("UNKNOWN", outcome.internal_error)
    if result is None:
        return Nav2Error(_REFUSED_PART.get(outcome.refused, "UNKNOWN"), outcome.refusal)
    if result.ok:
        return Nav2Error("NONE", "")
    message = result.message
    if result.status is PlanStatus.BUDGET_EXHAUSTED:  # the message says which budget ran out
        return Nav2Error("TIMEOUT", message)
    fallback = "UNKNOWN" if result.status is PlanStatus.REFUSED else "NO_VALID_PATH"
    code = _CAUSE_CODE.get(result.cause, fallback) if result.cause is not None else fallback
    return Nav2Error(code, message)
