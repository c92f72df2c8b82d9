"""drd_msgs_py: conversions between standard ROS 2 messages and drd_planner library types.

The wire uses standard messages only (visualization_msgs, sensor_msgs, nav_msgs, diagnostic_msgs,
trajectory_msgs), so this is a plain Python package rather than an interface package. Reading
accepts rclpy and rosbags messages alike; building goes through a :class:`~drd_msgs_py.factory.MessageFactory`
(``RclpyMessages()`` or ``RosbagsMessages(typestore)``).

Modules: :mod:`~drd_msgs_py.obstacles` (MarkerArray <-> collision parts), :mod:`~drd_msgs_py.terrain`
(organized PointCloud2 <-> heightfield), :mod:`~drd_msgs_py.plans` (path, check log, diagnostics, RViz
markers). Malformed input raises :class:`~drd_msgs_py.exceptions.MessageError`.
"""

__version__ = "0.1.0"
