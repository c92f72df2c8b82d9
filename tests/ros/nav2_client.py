"""A Nav2-style client of the planner, run as its own process: it imports only rclpy and standard packages.

It talks to ``compute_path_to_pose`` and ``is_path_valid`` as a Nav2 stack would, with ``nav2_msgs``
(a ROS install's, or the one ``scripts/tools/build_nav2_msgs.sh`` built into the venv) and prints one JSON line
per step for tests/ros/test_nav2_interface.py. Between steps it waits for a line on stdin where the test
changes the maps. Usage: ``python nav2_client.py '{"goal": [x, y, z], "far": [x, y, z]}'``.
"""

from __future__ import annotations

import json
import sys
import time
from typing import Any

import rclpy
from action_msgs.msg import GoalStatus
from geometry_msgs.msg import PoseStamped
from nav2_msgs.action import ComputePathToPose
from nav2_msgs.srv import IsPathValid
from rclpy.action import ActionClient


def say(**values: Any) -> None:
    print(json.dumps(values), flush=True)


def pose(xyz: list[float]) -> PoseStamped:
    msg = PoseStamped()
    msg.header.frame_id = "map"
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = (float(v) for v in xyz)
    msg.pose.orientation.w = 1.0
    return msg


def wait(node: Any, future: Any, timeout: float = 60.0) -> Any:
    rclpy.spin_until_future_complete(node, future, timeout_sec=timeout)
    assert future.done(), "timed out"
    return future.result()


def send(node: Any, client: ActionClient, xyz: list[float], planner_id: str = "") -> Any:
    goal = ComputePathToPose.Goal(goal=pose(xyz), planner_id=planner_id, use_start=False)
    handle = wait(node, client.send_goal_async(goal))
    assert handle.accepted
    return handle


def result(node: Any, handle: Any) -> tuple[int, Any]:
    done = wait(node, handle.get_result_async())
    return done.status, done.result


def main() -> None:
    scenario = json.loads(sys.argv[1])
    rclpy.init()
    node = rclpy.create_node("nav2_style_client")
    client = ActionClient(node, ComputePathToPose, "compute_path_to_pose")
    validity = node.create_client(IsPathValid, "is_path_valid")
    assert client.wait_for_server(timeout_sec=30.0)
    assert validity.wait_for_service(timeout_sec=30.0)

    status, plan = result(node, send(node, client, scenario["goal"]))
    poses = [[p.pose.position.x, p.pose.position.y, p.pose.position.z] for p in plan.path.poses]
    time_s = plan.planning_time.sec + plan.planning_time.nanosec * 1e-9
    say(
        step="plan",
        status=status,
        error_code=plan.error_code,
        poses=len(poses),
        planning_time=time_s,
        frame=plan.path.header.frame_id,
        last=poses[-1] if poses else None,
    )

    status, failed = result(node, send(node, client, scenario["far"]))
    say(step="outside", status=status, error_code=failed.error_code, error_msg=failed.error_msg)
    status, wrong = result(node, send(node, client, scenario["goal"], planner_id="nav2_navfn"))
    say(step="planner_id", status=status, error_code=wrong.error_code)

    answer = wait(node, validity.call_async(IsPathValid.Request(path=plan.path)))
    say(step="valid_before", is_valid=answer.is_valid, invalid=list(answer.invalid_pose_indices))
    say(step="block", at=poses[len(poses) // 2])
    assert sys.stdin.readline().strip() == "blocked"
    answer = wait(node, validity.call_async(IsPathValid.Request(path=plan.path)))
    say(step="valid_after", is_valid=answer.is_valid, invalid=list(answer.invalid_pose_indices))

    handle = send(node, client, scenario["goal"])  # the maps changed and checks are slow now: a long plan
    end = time.monotonic() + scenario["cancel_after_s"]
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    asked = time.monotonic()
    wait(node, handle.cancel_goal_async())
    status, cancelled = result(node, handle)
    say(
        step="cancel",
        status=status,
        seconds=time.monotonic() - asked,
        poses=len(cancelled.path.poses),
        error_code=cancelled.error_code,
        error_msg=cancelled.error_msg,
    )
    say(step="imports", drd=sorted(m for m in sys.modules if m.startswith("drd")))
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
    assert GoalStatus.STATUS_SUCCEEDED == 4  # what the test compares statuses with
