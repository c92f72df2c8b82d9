"""How the node sends out what its planner service produces: plans, check logs, summaries, errors, logs.

:class:`NodeReporter` is the node's :class:`~drd_planner.planning.service.ServiceOutputs`: a served request
goes out as ``plan`` (and ``joint_trajectory``) first, then the check log, the markers and last the summary
on ``/diagnostics``; a plan kept after a map update gets a ``map update`` status; errors go to the node's
error report (log, ``/diagnostics``, :attr:`PlannerNode.errors`), a bug's with its traceback in the log.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.replan import RecheckResult
from drd_planner.planning.service import PlanRecord
from drd_planner.planning.session import QuerySession
from drd_planner.planning.session_plan import SessionPlan
from drd_planner.ros.guard import shorten
from drd_planner.ros.node_log import NodeLog
from drd_planner.ros.outputs import PlannerOutputs, plan_summary_values
from drd_planner.ros.status import LastPlan

__all__ = ["NodeReporter"]


class NodeReporter:
    """The node's outputs of the planner service (see the module docstring).

    Args:
        logger: the node's logger (written through :class:`~drd_planner.ros.node_log.NodeLog`: a line
            after each plan must not cost milliseconds).
        outputs: the node's publishers.
        report_error: the node's error report, ``(text, topic)``.
        report_bug: the node's report of a bug, ``(text, exception)``: logged at ERROR with its traceback.
    """

    def __init__(
        self,
        logger: Any,
        outputs: PlannerOutputs,
        report_error: Callable[[str, str], None],
        report_bug: Callable[[str, BaseException], None],
    ) -> None:
        self._logger = NodeLog(logger)
        self._out = outputs
        self._report_error = report_error
        self._report_bug = report_bug
        self.last_plan: LastPlan | None = None

    def error(self, text: str, topic: str = "plan") -> None:
        """Report an error under the status ``topic``."""
        self._report_error(text, topic)

    def bug(self, text: str, exc: BaseException) -> None:
        """Report a bug (a broken safety invariant) with ``exc``'s traceback, under the status ``plan``."""
        self._report_bug(text, exc)

    def info(self, text: str) -> None:
        """Log a line."""
        self._logger.info(text)

    def warning(self, text: str) -> None:
        """Log a warning (cut to the error length)."""
        self._logger.warning(shorten(text))

    def result(
        self, record: PlanRecord, *, wait_s: float, publish: Callable[[tuple[int, int]], Any | None]
    ) -> Any | None:
        """Publish a result: ``plan`` (and ``joint_trajectory``) first, then the rest.

        After the plan come the check log, the markers and last the summary. Its timing values
        (seconds): ``check_s``, ``selection_s``, ``policy_s``, ``prepare_s`` and ``total_s`` of the plan
        (:class:`SessionPlan`), ``wait_s`` (request taken -> served), ``plan_messaging_s`` (building and
        publishing ``plan``/``joint_trajectory``) and ``messaging_s`` (all messages before the summary).
        """
        session, result, snapshot, extra = record.session, record.result, record.snapshot, record.request
        assert snapshot is not None  # the newest record keeps its snapshot
        started = time.perf_counter()
        stamp = self._out.stamp()
        path = publish(stamp)
        plan_messaging_s = time.perf_counter() - started
        self._out.checks(result, stamp)
        self._out.markers(session, result, snapshot, stamp)
        values = plan_summary_values(
            result,
            extra,
            wait_s=wait_s,
            plan_messaging_s=plan_messaging_s,
            messaging_s=time.perf_counter() - started,
        )
        self.last_plan = LastPlan(result.outcome, str(extra.get("request", "request")), time.monotonic())
        self._out.status("plan", ok=result.ok, message=result.message, values=values, stamp=stamp)
        if "newer_map_refused" in extra:
            self._logger.warning(
                f"{result.prior}: planned on map version {snapshot.version}; a newer map was refused "
                f"({extra['newer_map_refused']})"
            )
        if result.ok:
            self._logger.info(f"{result.prior}: {result.message}")
        else:
            self._logger.warning(f"{result.prior}: {result.message}; nothing published on plan")
        return path

    def plan(
        self, session: QuerySession, result: SessionPlan, snapshot: MapSnapshot, stamp: tuple[int, int]
    ) -> tuple[Any, bool]:
        """Publish a found plan on ``plan`` (and ``joint_trajectory`` for the arm); it is out there if active."""
        return self._out.plan(session, result, snapshot, stamp), self._out.active

    def kept(self, session: QuerySession, outcome: RecheckResult, snapshot: MapSnapshot) -> None:
        """The ``map update`` status of a plan that stays free on ``snapshot``."""
        self._out.status(
            "map update",
            ok=True,
            message=outcome.reason,
            values={
                "prior": session.name,
                "tree": session.name,  # deprecated: the prior's name under its old key, for one release
                "map_version": snapshot.version,
                "affected": len(outcome.affected),
                "rechecked": len(outcome.rechecked),
                "check_s": f"{outcome.total_check_ms / 1e3:.6f}",
                "selection_s": f"{outcome.select_ms / 1e3:.6f}",
                "result": "plan_kept",
            },
        )
        self._logger.info(outcome.reason)

    def withdraw(self, session: QuerySession) -> None:
        """Publish an empty ``plan`` (and ``joint_trajectory``)."""
        self._out.withdraw(session)
