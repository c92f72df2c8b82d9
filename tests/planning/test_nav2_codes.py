"""Nav2's error codes for what a request came to (planning/nav2_codes.py), on real plans of heli_wires.

Each failure the planner can meet is made for real through the service (``serve_request``) and mapped:
one code per failure, as Nav2's planner server; plus the priority of the start over the goal.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from test_service import TREE, Recorder, _feed

from drd_msgs_py.bags import BagMessage, bag_requests, jazzy_typestore, read_bag, topic_base
from drd_msgs_py.factory import RosbagsMessages
from drd_planner.core.status import PlanCause, PlanStatus
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box
from drd_planner.planner import load_prior
from drd_planner.planning.nav2_codes import NAV2_CODES, Nav2Error, nav2_error
from drd_planner.planning.plan_outcome import PlanOutcome
from drd_planner.planning.requests import Goal, read_goal
from drd_planner.planning.service import LiveSettings, PlannerService
from drd_planner.planning.session import QuerySession
from drd_planner.planning.session_plan import SessionPlan
from drd_planner.planning.world_messages import obstacle_markers

BAG = TREE.parents[1] / "bags" / "heli_wires.mcap"


@pytest.fixture(scope="module")
def messages() -> list[BagMessage]:
    return read_bag(BAG)


@pytest.fixture(scope="module")
def prior() -> Any:
    return load_prior(TREE)


def _ready(prior: Any, messages: list[BagMessage], **budgets: Any) -> tuple[PlannerService, Goal]:
    """A service fed the bag up to its first request (maps and odometry), and that request's goal."""
    session = QuerySession(prior, name="heli_wires", **budgets)
    service = PlannerService([session], Recorder(), frame_id="map", live=LiveSettings)
    first = bag_requests(messages)[0].position
    for m in messages[:first]:
        _feed(service, m)
    return service, read_goal("goal_pose", messages[first].message, service.sessions, "map")


def test_the_codes_are_nav2_jazzys() -> None:
    assert NAV2_CODES == {
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
    assert Nav2Error("GOAL_OCCUPIED", "").code == 206


def test_a_plan_and_each_failure_get_their_one_code(prior: Any, messages: list[BagMessage]) -> None:
    service, goal = _ready(prior, messages)
    found = service.serve_request(goal, None, "compute_path_to_pose")
    assert found.ok
    assert found.sent is not None
    assert nav2_error(found) == Nav2Error("NONE", "")
    far = Goal(position=np.array([1e5, 0.0, 65.0]), yaw=0.0)
    outside = nav2_error(service.serve_request(far, None))
    assert outside.name == "GOAL_OUTSIDE_MAP"
    assert "outside the lattice" in outside.text
    start_far = nav2_error(service.serve_request(goal, far))
    assert start_far.name == "START_OUTSIDE_MAP"
    assert nav2_error(service.serve_request(Goal(joints=np.zeros(7)), None)).name == "INVALID_PLANNER"
    no_yaw = Goal(position=goal.position, yaw=None)
    assert nav2_error(service.serve_request(goal, no_yaw)).name == "TF_ERROR"
    timed_out, _ = _ready(prior, messages, max_checks=1)
    timeout = nav2_error(timed_out.serve_request(goal, None))
    assert timeout.name == "TIMEOUT"
    assert timeout.text.startswith("the check budget ran out")


def test_no_robot_state_and_no_maps_are_tf_error_and_unknown(prior: Any, messages: list[BagMessage]) -> None:
    session = QuerySession(prior, name="heli_wires")
    service = PlannerService([session], Recorder(), frame_id="map", live=LiveSettings)
    goal = Goal(position=np.array([0.0, 0.0, 65.0]))
    outcome = service.serve_request(goal, None)
    assert outcome.refused == "start"
    assert nav2_error(outcome).name == "TF_ERROR"
    assert "no robot state known yet" in nav2_error(outcome).text
    odom = next(m for m in messages if topic_base(m.topic) == "odom")
    service.take_robot_state("odom", odom.message)
    no_maps = service.serve_request(goal, None)
    assert no_maps.refused == "maps"
    assert nav2_error(no_maps).name == "UNKNOWN"


def test_a_goal_inside_an_obstacle_is_goal_occupied(prior: Any, messages: list[BagMessage]) -> None:
    service, goal = _ready(prior, messages)
    assert goal.position is not None
    box = [("walls/7", Box((120.0, 120.0, 120.0)), Pose(position=tuple(float(v) for v in goal.position)))]
    service.take_map(
        "obstacles",
        obstacle_markers(box, frame_id="map", msgs=RosbagsMessages(jazzy_typestore()), delete_all_first=False),
    )
    error = nav2_error(service.serve_request(goal, None))
    assert error.name == "GOAL_OCCUPIED", error.text


def _failed(message: str, status: PlanStatus = PlanStatus.NO_PATH, cause: PlanCause | None = None) -> PlanOutcome:
    result = SessionPlan(status=status, message=message, map_version=1, prior="t", cause=cause)
    return PlanOutcome(result=result)


def test_the_codes_come_from_the_cause_not_from_the_text() -> None:
    walled = "no free path; all 12 edges joining the start [1.0, 2.0] to the graph (3-5 long) were checked blocked"
    assert nav2_error(_failed(walled, cause=PlanCause.START_BLOCKED)).name == "START_OCCUPIED"
    assert nav2_error(_failed(walled)).name == "NO_VALID_PATH"  # words alone name no cause
    assert nav2_error(_failed("x", cause=PlanCause.GOAL_BLOCKED)).name == "GOAL_OCCUPIED"
    assert (
        nav2_error(_failed("x", status=PlanStatus.REFUSED, cause=PlanCause.START_OUTSIDE)).name == "START_OUTSIDE_MAP"
    )
    assert nav2_error(_failed("x", status=PlanStatus.REFUSED, cause=PlanCause.GOAL_OUTSIDE)).name == "GOAL_OUTSIDE_MAP"
    cut = "no free path from the start to the goal in the graph: 9 blocked edges disconnect them (40 checks)"
    assert nav2_error(_failed(cut)).name == "NO_VALID_PATH"
    assert nav2_error(_failed("x", status=PlanStatus.BUDGET_EXHAUSTED, cause=PlanCause.TIME_BUDGET)).name == "TIMEOUT"
    capped = nav2_error(_failed("x", status=PlanStatus.BUDGET_EXHAUSTED, cause=PlanCause.CHECK_BUDGET))
    assert (capped.name, capped.text) == ("TIMEOUT", "x")
    assert nav2_error(_failed("start must be a vertex id", status=PlanStatus.REFUSED)).name == "UNKNOWN"
    assert nav2_error(PlanOutcome(refusal="x", refused="goal")).name == "GOAL_OUTSIDE_MAP"
