"""What the planner service sends out: a served request's record, the plan out there, and where they go.

:class:`ServiceOutputs` is the seam between :class:`~drd_planner.planning.service.PlannerService` (ROS-free) and
whatever publishes (the node: its publishers, log and ``/diagnostics``; a test: a recorder).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.replan import RecheckResult
from drd_planner.planning.requests import Goal
from drd_planner.planning.session import QuerySession
from drd_planner.planning.session_plan import SessionPlan

__all__ = ["PlanRecord", "Published", "ServiceOutputs"]


@dataclass(frozen=True)
class PlanRecord:
    """One served request, as kept in :attr:`~drd_planner.planning.service.PlannerService.history`.

    Attributes:
        session: the prior that planned it.
        result: the plan (or why there is none) with its check log.
        snapshot: the maps it was planned on (None once :data:`~drd_planner.planning.service.SNAPSHOTS_KEPT` newer
            records exist).
        request: where it came from (``goal_pose``, ``goal_joints``, ``get_plan``, ``replan``,
            ``map_update``) and the other summary values of the request.
    """

    session: QuerySession
    result: SessionPlan
    snapshot: MapSnapshot | None
    request: dict[str, Any]


@dataclass(frozen=True)
class Published:
    """The plan out there now: what a map update must re-check, and its goal for a replan."""

    session: QuerySession
    result: SessionPlan
    snapshot: MapSnapshot
    goal: Goal


class ServiceOutputs(Protocol):
    """Where the service's results and reports go (the node: its publishers, log and ``/diagnostics``)."""

    def error(self, text: str, topic: str = "plan") -> None:
        """Report a refused input or a failure (``topic``: ``plan``, ``maps`` or ``node``)."""

    def bug(self, text: str, exc: BaseException) -> None:
        """Report a bug (a broken safety invariant) with ``exc``'s traceback; never a refused input."""

    def info(self, text: str) -> None:
        """Log a line."""

    def warning(self, text: str) -> None:
        """Log a warning."""

    def result(
        self, record: PlanRecord, *, wait_s: float, publish: Callable[[tuple[int, int]], Any | None]
    ) -> Any | None:
        """Send a served request out, stamped (sec, nanosec): ``publish(stamp)`` first, then the rest.

        ``publish`` publishes a found plan (through :meth:`plan`); returns what it returned: the
        published plan as :meth:`plan` returned it, or None.
        """

    def plan(
        self, session: QuerySession, result: SessionPlan, snapshot: MapSnapshot, stamp: tuple[int, int]
    ) -> tuple[Any, bool]:
        """Publish a found plan: what was sent (the node: its Path on demand), whether it is out (False: inactive)."""

    def kept(self, session: QuerySession, outcome: RecheckResult, snapshot: MapSnapshot) -> None:
        """Report that the published plan stays free on ``snapshot`` after a map update."""

    def withdraw(self, session: QuerySession) -> None:
        """Take the published plan back (an empty plan)."""
