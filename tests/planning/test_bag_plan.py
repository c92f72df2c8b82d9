"""A bag's requests planned offline as the node plans them: goals, the robot's state, refusals."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import REPO_ROOT

from drd_msgs_py.bags import BagMessage, bag_requests, read_bag
from drd_msgs_py.exceptions import MessageError
from drd_planner.exceptions import PlanningError
from drd_planner.planner import load_prior
from drd_planner.planning.bag_plan import plan_bag_request, request_goal, robot_state_at
from drd_planner.planning.session import QuerySession

BAG = REPO_ROOT / "bags" / "heli_wires.mcap"
PRIOR = REPO_ROOT / "trees" / "heli_wires.npz"


@pytest.fixture(scope="module")
def session() -> QuerySession:
    return QuerySession(load_prior(PRIOR), name="heli_wires")


@pytest.fixture(scope="module")
def messages() -> list[BagMessage]:
    if not BAG.is_file():
        pytest.skip(f"{BAG} not generated (python scripts/tools/make_bags.py)")
    return read_bag(BAG)


def _odometry(messages: list[BagMessage]) -> list[BagMessage]:
    return [m for m in messages if m.topic == "/odom"]


def test_the_robot_state_is_the_last_accepted_odometry_before_the_request(
    session: QuerySession, messages: list[BagMessage]
) -> None:
    odometry = _odometry(messages)
    assert len(odometry) == 3  # at the start, at a vertex, between two vertices
    first, second = odometry[0], odometry[1]
    state, notes = robot_state_at(session, messages, first.time_ns, "map")
    assert state is not None
    assert not notes
    np.testing.assert_allclose(state, session.vertex_state(int(session.domain.start)), atol=1e-9)
    later, _ = robot_state_at(session, messages, second.time_ns, "map")
    assert later is not None
    assert not np.allclose(later, state)
    # Odometry in another frame is dropped with a note, and the last good state stays.
    second.message.header.frame_id = "odom"
    try:
        kept, notes = robot_state_at(session, messages, second.time_ns, "map")
    finally:
        second.message.header.frame_id = "map"
    np.testing.assert_allclose(kept, state)  # type: ignore[arg-type]
    assert len(notes) == 1
    assert "frame 'odom'" in notes[0]
    # Nothing before the first message: no state.
    assert robot_state_at(session, messages, first.time_ns - 1, "map") == (None, ())


def test_goals_are_read_as_the_node_reads_them(session: QuerySession, messages: list[BagMessage]) -> None:
    requests = bag_requests(messages)
    goal = request_goal(session, requests[0], "map")
    assert goal.position is not None
    assert goal.joints is None
    np.testing.assert_allclose(goal.position, session.goal_position, atol=1e-9)
    with pytest.raises(MessageError, match="frame 'map'"):
        request_goal(session, requests[0], "odom")


def test_requests_plan_from_where_the_robot_is(session: QuerySession, messages: list[BagMessage]) -> None:
    plans = [plan_bag_request(session, messages, k, frame="map") for k in range(4)]
    assert all(p.result.ok for p in plans)
    assert [p.result.query for p in plans] == ["tree:heli_wires", "tree:heli_wires", "online", "connected"]
    stored_goal = int(session.domain.goal)
    assert plans[0].goal == plans[1].goal == stored_goal  # the goal_pose at the stored goal snaps to it
    for plan in plans:
        assert plan.result.map_version == plan.maps.snapshot.version
        np.testing.assert_allclose(plan.result.states[0][:3], np.asarray(plan.start)[:3], atol=1e-6)
    # Same bag, same seed: the same checks.
    again = plan_bag_request(QuerySession(load_prior(PRIOR), name="again"), messages, 2, frame="map")
    assert [(c.edge, c.free) for c in again.result.checks] == [(c.edge, c.free) for c in plans[2].result.checks]


def test_no_robot_state_is_an_error_unless_the_prior_start_is_asked_for(
    session: QuerySession, messages: list[BagMessage]
) -> None:
    stateless = [m for m in messages if m.topic != "/odom"]
    with pytest.raises(PlanningError, match="no accepted odom message before it"):
        plan_bag_request(session, stateless, 0, frame="map")
    plan = plan_bag_request(session, stateless, 0, frame="map", prior_start=True)
    assert plan.start == int(session.domain.start)
    assert plan.result.ok
