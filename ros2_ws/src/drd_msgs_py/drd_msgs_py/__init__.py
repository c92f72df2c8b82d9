"""drd_msgs_py: conversions between standard ROS 2 messages and drd_planner library types.

The wire uses standard messages only (visualization_msgs, sensor_msgs, nav_msgs, diagnostic_msgs,
trajectory_msgs), so this is a plain Python package rather than an interface package. The
conversions arrive with the ROS node work; they accept rclpy and rosbags message classes alike.
"""

__version__ = "0.1.0"
