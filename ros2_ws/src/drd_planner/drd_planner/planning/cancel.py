"""Cancelling a plan between two checks: a token the requester sets, the plan's oracle reads.

A plan cannot be interrupted inside a collision check (an FCL query), but it can be stopped before the next
one: :class:`~drd_planner.planning.snapshot_oracle.SnapshotOracle` reads the token before every check it is
asked for (graph edges and motions alike) and raises :class:`PlanCancelled` once it is set. The plan then
ends at once: nothing is published, the snapshot's outcome cache keeps only completed checks (each one a
true outcome, so a later plan may use them), and the planning lock is released on the way out.
"""

from __future__ import annotations

import threading

__all__ = ["Cancel", "CancelToken", "PlanCancelled"]


class PlanCancelled(Exception):  # noqa: N818 (not an error: what the requester asked for)
    """A plan stopped because its :class:`CancelToken` was set (``checks``: the checks made before).

    Deliberately not a :class:`~drd_planner.exceptions.DrdError`: the service's refusal handling must not
    turn a cancellation into a refused request.
    """

    def __init__(self, checks: int) -> None:
        super().__init__(f"cancelled after {checks} checks")
        self.checks = checks


class CancelToken:
    """Set once (from any thread) to stop the plan that reads it before its next check."""

    def __init__(self) -> None:
        self._event = threading.Event()

    def cancel(self) -> None:
        """Ask the plan to stop before its next check."""
        self._event.set()

    @property
    def cancelled(self) -> bool:
        """Whether :meth:`cancel` was called."""
        return self._event.is_set()

    def check(self, checks: int) -> None:
        """Raise :class:`PlanCancelled` if cancelled (``checks``: the checks the plan made so far).

        Raises:
            PlanCancelled: the token was set.
        """
        if self._event.is_set():
            raise PlanCancelled(checks)


#: What a plan takes as its ``cancel`` argument: a token, or None (it runs to its end).
Cancel = CancelToken | None
