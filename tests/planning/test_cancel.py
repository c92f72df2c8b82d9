"""Cancelling a plan between two checks (planning/cancel.py): the oracle stops before the next check."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from test_nav2_codes import _ready, messages, prior  # noqa: F401 (fixtures)

from drd_msgs_py.bags import BagMessage
from drd_planner.planning.cancel import CancelToken, PlanCancelled
from drd_planner.planning.requests import Goal


class CancelAfter(CancelToken):
    """A token its plan cancels itself on the ``n``-th check asked for (as a client would, mid-plan)."""

    def __init__(self, n: int) -> None:
        super().__init__()
        self.n = n
        self.asked = 0

    def check(self, checks: int) -> None:
        self.asked += 1
        if self.asked == self.n:
            self.cancel()
        super().check(checks)


def test_a_token_raises_once_cancelled() -> None:
    token = CancelToken()
    token.check(3)
    assert not token.cancelled
    token.cancel()
    with pytest.raises(PlanCancelled, match="after 3 checks") as caught:
        token.check(3)
    assert caught.value.checks == 3
    assert token.cancelled


def test_a_cancelled_plan_stops_between_checks_publishes_nothing_and_the_next_plan_runs(
    prior: Any,  # noqa: F811
    messages: list[BagMessage],  # noqa: F811
) -> None:
    service, goal = _ready(prior, messages)
    far_goal = Goal(position=np.array([650.0, 20.0, 65.0]), yaw=0.0)  # a long new query: many checks
    with pytest.raises(PlanCancelled) as caught:
        service.serve_request(far_goal, None, cancel=CancelAfter(4))
    assert caught.value.checks == 3  # three checks answered, the fourth never asked of the checker
    assert service.published is None
    assert not service.history
    outcome = service.serve_request(goal, None, cancel=CancelToken())  # the planning lock was released
    assert outcome.ok
    assert service.published is not None
