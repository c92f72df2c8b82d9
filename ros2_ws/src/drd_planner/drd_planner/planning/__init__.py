"""Online planning without ROS: the map snapshot, the lazy cached checker and one planning session.

The rclpy node (:mod:`drd_planner.ros`) is a thin shell around these classes, so that everything it
decides (which edges to check, which path to publish) is tested and benchmarked without a ROS graph.
"""
