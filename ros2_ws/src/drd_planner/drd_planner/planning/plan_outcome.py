"""What one request served at once came to: the plan sent out, the plan's result, or why it was refused.

:meth:`~drd_planner.planning.service.PlannerService.serve_request` returns a :class:`PlanOutcome`, so a
caller that must say *why* there is no plan (Nav2's ``compute_path_to_pose`` with its error codes,
:mod:`drd_planner.planning.nav2_codes`) gets it without parsing reports. The reasons are also reported
on ``/diagnostics`` and in the log as for every request.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.session import QuerySession
from drd_planner.planning.session_plan import SessionPlan

__all__ = ["PlanOutcome", "RefusedPart"]

#: What a refusal before planning is about: no loaded prior serves the goal (``prior``), the start could not
#: be had (``start``: no robot state yet, or a start pose the prior cannot take), the goal could not be made
#: an endpoint (``goal``), or the planner could not run on the maps (``maps``: none received yet).
RefusedPart = Literal["prior", "start", "goal", "maps", ""]


@dataclass(frozen=True)
class PlanOutcome:
    """One served request.

    Attributes:
        sent: the published plan as :meth:`ServiceOutputs.plan` returned it (the node: its Path on
            demand); None when no plan was found or the node is inactive.
        result: the plan's result (None: refused before planning); ``result.ok`` with a verified path.
        refusal: why the request was refused before the planner ran ("" otherwise).
        refused: what that refusal is about (:data:`RefusedPart`).
        internal_error: why the request ended without a plan because of a bug ("" otherwise): a broken
            safety invariant (:class:`~drd_planner.exceptions.InvariantError`), reported with its
            traceback; never a refusal.
        session: the prior that planned it (None: refused before planning).
        snapshot: the maps it was planned on (None: refused before planning).
    """

    sent: Any | None = None
    result: SessionPlan | None = None
    refusal: str = ""
    refused: RefusedPart = ""
    internal_error: str = ""
    session: QuerySession | None = None
    snapshot: MapSnapshot | None = None

    @property
    def ok(self) -> bool:
        """A verified path was found."""
        return self.result is not None and self.result.ok
