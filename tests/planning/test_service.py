"""The ROS-free planner service: a bag's messages in, the node's plans out (equal to drd plan --bag).

A recording :class:`ServiceOutputs` stands in for the node's publishers. Feeding the bundled helicopter bag's
messages to the service in order (maps, odometry, requests, each request served before the next message)
gives, request by request, the plan :func:`~drd_planner.planning.bag_plan.plan_bag_request` makes offline; every
published plan's edges were checked free on the snapshot it was planned on.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pytest
from conftest import REPO_ROOT

from drd_msgs_py.bags import BagMessage, bag_requests, jazzy_typestore, read_bag, topic_base
from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.factory import RosbagsMessages
from drd_msgs_py.terrain import cloud_from_heightfield
from drd_planner.exceptions import DrdError, UnverifiedPathError
from drd_planner.geometry.terrain import Heightfield
from drd_planner.planner import load_prior
from drd_planner.planning.bag_plan import plan_bag_request
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.replan import RecheckResult
from drd_planner.planning.requests import Goal, read_goal
from drd_planner.planning.service import LiveSettings, PlannerService, PlanRecord
from drd_planner.planning.session import QuerySession
from drd_planner.planning.session_plan import SessionPlan

BAG = REPO_ROOT / "bags" / "heli_wires.mcap"
TREE = REPO_ROOT / "trees" / "heli_wires.npz"


@dataclass
class Recorder:
    """What the service sent out, in order."""

    errors: list[str] = field(default_factory=list)
    records: list[PlanRecord] = field(default_factory=list)
    plans: list[SessionPlan] = field(default_factory=list)
    kept_versions: list[int] = field(default_factory=list)
    bugs: list[tuple[str, BaseException]] = field(default_factory=list)
    withdrawn: int = 0
    active: bool = True

    def error(self, text: str, topic: str = "plan") -> None:
        self.errors.append(text)

    def bug(self, text: str, exc: BaseException) -> None:
        self.bugs.append((text, exc))

    def info(self, text: str) -> None:
        pass

    def warning(self, text: str) -> None:
        pass

    def result(
        self, record: PlanRecord, *, wait_s: float, publish: Callable[[tuple[int, int]], Any | None]
    ) -> Any | None:
        self.records.append(record)
        return publish((0, 0))

    def plan(
        self, session: QuerySession, result: SessionPlan, snapshot: MapSnapshot, stamp: tuple[int, int]
    ) -> tuple[Any, bool]:
        self.plans.append(result)
        return f"path of {len(result.path_edges)} edges", self.active

    def kept(self, session: QuerySession, outcome: RecheckResult, snapshot: MapSnapshot) -> None:
        self.kept_versions.append(snapshot.version)

    def withdraw(self, session: QuerySession) -> None:
        self.withdrawn += 1


@pytest.fixture(scope="module")
def messages() -> list[BagMessage]:
    if not BAG.is_file():
        pytest.skip(f"{BAG} not generated (python scripts/tools/make_bags.py)")
    return read_bag(BAG)


def _service(out: Recorder, **live: Any) -> PlannerService:
    session = QuerySession(load_prior(TREE), name="heli_wires")
    return PlannerService([session], out, frame_id="map", live=lambda: LiveSettings(**live))


def _feed(service: PlannerService, m: BagMessage) -> None:
    base = topic_base(m.topic)
    if base in ("obstacles", "terrain", "robot_description"):
        service.take_map(base, m.message)
        service.serve()  # the node's planning thread is woken: the published plan is re-checked
    elif base in ("odom", "joint_states"):
        service.take_robot_state(base, m.message)
    else:
        service.enqueue(read_goal(base, m.message, service.sessions, service.frame_id), base, "0.0")
        service.serve()


def test_the_service_plans_each_bag_request_as_drd_plan_does(messages: list[BagMessage]) -> None:
    out = Recorder()
    service = _service(out)
    for m in messages:
        _feed(service, m)
    served = [r for r in out.records if r.request["request"] == "goal_pose"]
    assert len(served) == len(bag_requests(messages)) == 4
    assert not out.errors
    session = service.sessions[0]
    for index, record in enumerate(served):
        offline = plan_bag_request(session, messages, index, frame="map").result
        assert record.result.ok
        assert offline.ok
        assert [(c.edge, c.free) for c in record.result.checks] == [(c.edge, c.free) for c in offline.checks]
        assert list(record.result.path_edges) == list(offline.path_edges)
    # The safety invariant: every published plan's edges were checked free on the maps it was planned on.
    for plan in out.plans:
        free = {c.edge for c in plan.checks if c.free}
        assert set(plan.path_edges) <= free
    assert service.published is not None
    assert service.published.result is out.plans[-1]
    # The update at 1.5 s blocked the first plan: it was replanned, never withdrawn.
    assert [r.request["request"] for r in out.records].count("map_update") == 1
    assert out.withdrawn == 0
    # The same obstacle map again: nothing near the plan changed, so it is kept without a new plan.
    plans = len(out.plans)
    _feed(service, [m for m in messages if topic_base(m.topic) == "obstacles"][-1])
    assert out.kept_versions == [service.snapshot.version]
    assert len(out.plans) == plans


def test_requests_for_one_prior_are_coalesced(messages: list[BagMessage]) -> None:
    out = Recorder()
    service = _service(out)
    first_request = bag_requests(messages)[0].position
    for m in messages[:first_request]:
        _feed(service, m)
    goal = read_goal("goal_pose", messages[first_request].message, service.sessions, "map")
    assert service.enqueue(goal, "goal_pose", "1.0")
    assert service.enqueue(goal, "goal_pose", "2.0")
    assert service.pending == 1
    service.serve()
    assert [(r.request["request_stamp"], r.request["coalesced"]) for r in out.records] == [("2.0", 1)]
    assert service.pending == 0
    assert len(service.history) == 1


def test_bad_input_is_refused_and_the_service_goes_on(messages: list[BagMessage]) -> None:
    out = Recorder()
    service = _service(out)
    goal = Goal(position=np.array([0.0, 0.0, 65.0]))
    service.enqueue(goal, "goal_pose", "0.0")
    service.serve()
    assert "no robot state known yet" in out.errors[-1]
    assert "'odom'" in out.errors[-1]
    obstacles = next(m for m in messages if topic_base(m.topic) == "obstacles")
    before = service.snapshot
    service.maps.frame_id = "elsewhere"
    with pytest.raises(MessageError, match="frame"):
        service.take_map("obstacles", obstacles.message)
    assert service.snapshot is before
    assert service.plan_now(Goal(joints=np.zeros(3)), None) is None  # no arm prior
    assert "no loaded prior plans" in out.errors[-1]
    assert service.replan() == (None, False)
    prior = _service(Recorder(), prior_start=True)
    assert prior.plan_now(goal, None) is None  # no maps: the plan is refused, not published
    assert prior.published is None


def test_an_inactive_output_publishes_no_plan_to_re_check(messages: list[BagMessage]) -> None:
    out = Recorder(active=False)
    service = _service(out)
    for m in messages[: bag_requests(messages)[0].position + 1]:
        _feed(service, m)
    assert out.plans
    assert service.published is None


def test_a_plan_after_a_refused_map_says_so(messages: list[BagMessage]) -> None:
    out = Recorder()
    service = _service(out)
    first_request = bag_requests(messages)[0].position
    for m in messages[:first_request]:
        _feed(service, m)
    goal = read_goal("goal_pose", messages[first_request].message, service.sessions, "map")
    service.plan_now(goal, None)
    assert "newer_map_refused" not in out.records[-1].request  # nothing refused yet
    obstacles = next(m for m in messages if topic_base(m.topic) == "obstacles")
    used = service.snapshot.version
    service.maps.frame_id = "elsewhere"
    with pytest.raises(MessageError, match="frame"):
        service.take_map("obstacles", obstacles.message)
    service.maps.frame_id = "map"
    service.plan_now(goal, None)  # planned on the older maps: the summary says a newer one was refused
    record = out.records[-1]
    assert record.snapshot.version == used
    assert record.result.map_version == used
    assert record.request["newer_map_refused"].startswith("obstacles refused:")
    assert "frame" in record.request["newer_map_refused"]
    service.take_map("obstacles", obstacles.message)  # a newer map accepted: the refusal is history
    service.plan_now(goal, None)
    assert "newer_map_refused" not in out.records[-1].request


def test_a_terrain_above_every_vertex_is_refused_and_the_next_plan_says_so(
    messages: list[BagMessage],
) -> None:
    """Issue 33 item 17: the bag's terrain raised to heights above sea level is not the prior's ground."""
    out = Recorder()
    service = _service(out)
    first_request = bag_requests(messages)[0].position
    for m in messages[:first_request]:
        _feed(service, m)
    goal = read_goal("goal_pose", messages[first_request].message, service.sessions, "map")
    terrain = service.snapshot.terrain
    assert terrain is not None
    raised = Heightfield(terrain.origin, terrain.cell_size, terrain.heights + 1600.0)
    cloud = cloud_from_heightfield(raised, frame_id="map", stamp=(1, 0), msgs=RosbagsMessages(jazzy_typestore()))
    used = service.snapshot.version
    with pytest.raises(DrdError, match="not the prior's terrain: every lattice vertex over the terrain lies below"):
        service.take_map("terrain", cloud)
    service.plan_now(goal, None)
    record = out.records[-1]
    assert record.result.ok
    assert record.snapshot.version == used
    assert record.request["newer_map_refused"].startswith("terrain refused: not the prior's terrain")


def test_an_unverified_path_is_a_bug_reported_as_one_and_nothing_is_published(
    messages: list[BagMessage], monkeypatch: pytest.MonkeyPatch
) -> None:
    out = Recorder()
    service = _service(out)
    first_request = bag_requests(messages)[0].position
    for m in messages[:first_request]:
        _feed(service, m)
    session = service.sessions[0]

    def broken(*args: Any, **kwargs: Any) -> Any:
        raise UnverifiedPathError("edge 3 of the returned path was not checked free")

    monkeypatch.setattr(session, "plan", broken)
    goal = read_goal("goal_pose", messages[first_request].message, service.sessions, "map")
    assert service.enqueue(goal, "goal_pose", "1.0")
    service.serve()  # the planning thread: the bug is reported, the thread goes on
    assert not out.plans
    assert not out.records
    assert service.published is None
    assert not any("refused" in e for e in out.errors)  # a bug, never a refused request
    assert len(out.bugs) == 1
    assert isinstance(out.bugs[0][1], UnverifiedPathError)
    assert out.bugs[0][0].startswith("goal_pose: internal error")
    assert "edge 3" in out.bugs[0][0]
    outcome = service.serve_request(goal, None, "get_plan")  # a service call: answered empty, not refused
    assert outcome.sent is None
    assert outcome.refusal == ""
    assert "edge 3" in outcome.internal_error
    assert len(out.bugs) == 2
    assert not out.plans
