"""launch/planner.launch.py: it compiles, names what exists, and (where ROS's launch is installed) builds.

The PyPI rclpy wheels bring neither ``launch`` nor ``launch_ros`` (and neither is on PyPI), so the
description itself is only built where a ROS install provides them; the rest is checked from the
file's syntax tree against the package (setup.py, config/, the node class).
"""

from __future__ import annotations

import ast
import importlib.util
import inspect
from types import ModuleType

import pytest
from launch_syntax import PACKAGE_DIR, LaunchSyntax

LAUNCH = PACKAGE_DIR / "launch" / "planner.launch.py"
_SYNTAX = LaunchSyntax(LAUNCH)


def test_launch_file_compiles() -> None:
    compile(LAUNCH.read_text(), str(LAUNCH), "exec")
    assert any(isinstance(n, ast.FunctionDef) and n.name == "generate_launch_description" for n in _SYNTAX.tree.body)


def test_launch_file_names_the_package_executable_node_and_config_that_exist() -> None:
    consts = _SYNTAX.constants()
    assert f"<name>{consts['PACKAGE']}</name>" in (PACKAGE_DIR / "package.xml").read_text()
    setup = (PACKAGE_DIR / "setup.py").read_text()
    assert f'"{consts["EXECUTABLE"]} = drd_planner.ros.planner_node:main"' in setup
    assert (PACKAGE_DIR / "config" / consts["DEFAULT_CONFIG"]).is_file()
    (node,) = _SYNTAX.calls("LifecycleNode")
    keywords = {k.arg: k.value for k in node.keywords}
    assert {"package", "executable", "name", "namespace", "parameters"} <= set(keywords)
    declared = {c.args[0].value for c in _SYNTAX.calls("DeclareLaunchArgument") if isinstance(c.args[0], ast.Constant)}
    assert {"config", "namespace", "autostart"} <= declared
    # Both automatic transitions are emitted: configure, then activate once inactive.
    source = LAUNCH.read_text()
    assert "Transition.TRANSITION_CONFIGURE" in source
    assert "Transition.TRANSITION_ACTIVATE" in source


def test_launched_node_name_is_the_node_class_default() -> None:
    pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")
    from drd_planner.ros.node import PlannerNode

    default = inspect.signature(PlannerNode.__init__).parameters["node_name"].default
    assert _SYNTAX.constants()["NODE_NAME"] == default


def _load() -> ModuleType:
    spec = importlib.util.spec_from_file_location("planner_launch", LAUNCH)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_generate_launch_description_builds_the_lifecycle_node_and_its_transitions() -> None:
    # launch_ros first: an unrelated "launch" package exists on PyPI, launch_ros does not.
    launch_ros = pytest.importorskip("launch_ros", reason="ROS 2 launch_ros not installed (needs a ROS install)")
    launch = pytest.importorskip("launch", reason="ROS 2 launch not installed (needs a ROS install)")
    from launch.actions import DeclareLaunchArgument, EmitEvent, RegisterEventHandler

    description = _load().generate_launch_description()
    assert isinstance(description, launch.LaunchDescription)
    entities = description.entities
    arguments = {e.name: e for e in entities if isinstance(e, DeclareLaunchArgument)}
    assert {"config", "namespace", "autostart", "log_level"} <= set(arguments)
    assert arguments["autostart"].default_value is not None
    nodes = [e for e in entities if isinstance(e, launch_ros.actions.LifecycleNode)]
    assert len(nodes) == 1
    assert nodes[0].node_package == "drd_planner"
    assert nodes[0].node_executable == "planner_node"
    assert sum(isinstance(e, EmitEvent) for e in entities) == 1  # configure
    assert sum(isinstance(e, RegisterEventHandler) for e in entities) == 1  # activate when inactive
    # The handler is registered before the node starts, so the first transition cannot be missed.
    order = [type(e) for e in entities]
    assert order.index(RegisterEventHandler) < order.index(type(nodes[0])) < order.index(EmitEvent)
