"""drd_msgs_py: conversions between standard ROS 2 messages and plain data (numpy arrays, small dataclasses).

The wire uses standard messages only (visualization_msgs, sensor_msgs, nav_msgs, diagnostic_msgs,
trajectory_msgs), so this is a plain Python package rather than an interface package. Reading
accepts rclpy and rosbags messages alike; building goes through a :class:`~drd_msgs_py.factory.MessageFactory`
(``RclpyMessages()`` or ``RosbagsMessages(typestore)``).

Modules: :mod:`~drd_msgs_py.obstacles` (MarkerArray <-> marker shapes and poses), :mod:`~drd_msgs_py.terrain`
(organized PointCloud2 <-> height grid), :mod:`~drd_msgs_py.shapes` (those plain types),
:mod:`~drd_msgs_py.limits` (size limits of map messages), :mod:`~drd_msgs_py.plans` (path, check log,
diagnostics, RViz markers), :mod:`~drd_msgs_py.cdr` (the path and joint trajectory serialized in bulk from
arrays), :mod:`~drd_msgs_py.bags` (rosbag2 MCAP reading and writing). Malformed input
raises :class:`~drd_msgs_py.exceptions.MessageError`. It imports nothing from drd_planner (which depends on it).
"""

__version__ = "0.1.0"
