#!/bin/bash
# Container entry point: source ROS and the drd_planner workspace, then run the command
# (by default `ros2 launch drd_planner planner.launch.py`).
set -e
source "/opt/ros/${ROS_DISTRO}/setup.bash" --
source /opt/drd/install/setup.bash --
exec "$@"
