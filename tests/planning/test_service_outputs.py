"""What the service sends out: records are frozen, and the service module still offers them."""

from __future__ import annotations

import dataclasses

import pytest

from drd_planner.planning import service
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.service_outputs import PlanRecord, Published, ServiceOutputs


def test_records_are_frozen_and_re_exported_by_the_service() -> None:
    record = PlanRecord(session=None, result=None, snapshot=MapSnapshot(3), request={"request": "goal_pose"})  # type: ignore[arg-type]
    with pytest.raises(dataclasses.FrozenInstanceError):
        record.snapshot = None  # type: ignore[misc]
    assert service.PlanRecord is PlanRecord
    assert service.Published is Published
    assert service.ServiceOutputs is ServiceOutputs
    assert {f.name for f in dataclasses.fields(Published)} == {"session", "result", "snapshot", "goal"}
