"""A launch file read as a syntax tree: the checks both launch-file tests make without ROS's ``launch``.

The PyPI rclpy wheels bring neither ``launch`` nor ``launch_ros``, so the tests read a launch file's
module-level string constants and its calls from its syntax tree and compare them with the package.
"""

from __future__ import annotations

import ast
from pathlib import Path

#: The drd_planner ROS package folder (package.xml, setup.py, launch/, config/).
PACKAGE_DIR = Path(__file__).resolve().parents[1] / "ros2_ws" / "src" / "drd_planner"


class LaunchSyntax:
    """The syntax tree of one launch file (``path``)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.text = path.read_text()
        self.tree = ast.parse(self.text, filename=str(path))

    def constants(self) -> dict[str, str]:
        """Module-level ``NAME = "string"`` assignments."""
        out = {}
        for node in self.tree.body:
            if isinstance(node, ast.Assign) and isinstance(node.value, ast.Constant):
                for target in node.targets:
                    if isinstance(target, ast.Name) and isinstance(node.value.value, str):
                        out[target.id] = node.value.value
        return out

    def calls(self, name: str) -> list[ast.Call]:
        """Every call of the plain name ``name`` (e.g. ``Node``, ``DeclareLaunchArgument``)."""
        return [
            n
            for n in ast.walk(self.tree)
            if isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == name
        ]
