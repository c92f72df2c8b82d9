"""A MoveIt-style client of the planner, run as its own process: it imports only rclpy and standard packages.

It publishes planning scenes on ``monitored_planning_scene`` and calls ``plan_kinematic_path`` as a MoveIt
stack would, with ``moveit_msgs`` (a ROS install's, or the subset ``scripts/tools/build_moveit_msgs.sh`` built
into the venv), and prints one JSON line per step for tests/ros/test_moveit_host.py. After each scene it
waits for a line on stdin (the test says when the node has applied it). Usage:
``python moveit_client.py '{"frame": ..., "joints": [...], "start": [...], "goal": [...], "box": {...}}'``.
"""

from __future__ import annotations

import json
import sys
import time
from typing import Any

import rclpy
from geometry_msgs.msg import Pose
from moveit_msgs.msg import CollisionObject, Constraints, JointConstraint, PlanningScene, PositionConstraint
from moveit_msgs.srv import GetMotionPlan
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from shape_msgs.msg import SolidPrimitive


def say(**values: Any) -> None:
    print(json.dumps(values), flush=True)


def wait(node: Any, future: Any, timeout: float = 120.0) -> Any:
    rclpy.spin_until_future_complete(node, future, timeout_sec=timeout)
    assert future.done(), "timed out"
    return future.result()


def box_scene(frame: str, box: dict[str, Any]) -> PlanningScene:
    """A full scene with one box (MoveIt's usual way of adding an obstacle)."""
    obj = CollisionObject()
    obj.header.frame_id = frame
    obj.id = "blocker"
    obj.pose.position.x, obj.pose.position.y, obj.pose.position.z = (float(v) for v in box["center"])
    obj.pose.orientation.w = 1.0
    obj.primitives = [SolidPrimitive(type=SolidPrimitive.BOX, dimensions=[float(v) for v in box["size"]])]
    obj.primitive_poses = [Pose()]  # the zero quaternion: no rotation, as MoveIt reads it
    obj.operation = CollisionObject.ADD
    scene = PlanningScene(is_diff=False)
    scene.world.collision_objects = [obj]
    return scene


def request(scenario: dict[str, Any], *, position_goal: bool = False) -> GetMotionPlan.Request:
    req = GetMotionPlan.Request()
    plan = req.motion_plan_request
    plan.group_name = "panda_arm"
    plan.allowed_planning_time = 30.0
    plan.start_state.joint_state.name = list(scenario["joints"])
    plan.start_state.joint_state.position = [float(v) for v in scenario["start"]]
    goal = Constraints()
    if position_goal:
        goal.position_constraints = [PositionConstraint(link_name="panda_hand")]
    else:
        goal.joint_constraints = [
            JointConstraint(joint_name=n, position=float(q), tolerance_above=1e-3, tolerance_below=1e-3, weight=1.0)
            for n, q in zip(scenario["joints"], scenario["goal"], strict=True)
        ]
    plan.goal_constraints = [goal]
    return req


def main() -> None:
    scenario = json.loads(sys.argv[1])
    rclpy.init()
    node = rclpy.create_node("moveit_style_client")
    qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)
    scenes = node.create_publisher(PlanningScene, "monitored_planning_scene", qos)
    planner = node.create_client(GetMotionPlan, "plan_kinematic_path")
    assert planner.wait_for_service(timeout_sec=30.0)
    end = time.monotonic() + 30.0
    while scenes.get_subscription_count() == 0 and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)

    scenes.publish(box_scene(scenario["frame"], scenario["box"]))
    say(step="scene")
    assert sys.stdin.readline().strip() == "applied"
    answer = wait(node, planner.call_async(request(scenario))).motion_plan_response
    trajectory = answer.trajectory.joint_trajectory
    say(
        step="plan",
        code=answer.error_code.val,
        message=answer.error_code.message,
        joints=list(trajectory.joint_names),
        points=[list(p.positions) for p in trajectory.points],
        times=[p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 for p in trajectory.points],
        planning_time=answer.planning_time,
    )

    answer = wait(node, planner.call_async(request(scenario, position_goal=True))).motion_plan_response
    say(step="position_goal", code=answer.error_code.val, message=answer.error_code.message)

    octomap = PlanningScene(is_diff=True)
    octomap.world.octomap.header.frame_id = scenario["frame"]
    octomap.world.octomap.octomap.resolution = 0.05
    octomap.world.octomap.octomap.data = [1, 2, 3]
    scenes.publish(octomap)
    say(step="octomap")
    assert sys.stdin.readline().strip() == "refused"
    diff = PlanningScene(is_diff=True)  # a second box, at the goal, added by a diff
    at_goal = box_scene(scenario["frame"], scenario["goal_box"]).world.collision_objects[0]
    at_goal.id = "at_goal"
    diff.world.collision_objects = [at_goal]
    scenes.publish(diff)
    say(step="diff")
    assert sys.stdin.readline().strip() == "applied"
    answer = wait(node, planner.call_async(request(scenario))).motion_plan_response
    say(
        step="goal_blocked",
        code=answer.error_code.val,
        message=answer.error_code.message,
        points=len(answer.trajectory.joint_trajectory.points),
    )
    say(step="imports", drd=sorted(m for m in sys.modules if m.startswith("drd")))
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
