"""The rclpy lifecycle node (the only subpackage that imports rclpy)."""
