"""launch/site.launch.py: map server + planner on one site prior; names what exists, builds where ROS's launch is.

As for ``planner.launch.py`` (``tests/ros/test_launch_file.py``): the PyPI rclpy wheels bring neither
``launch`` nor ``launch_ros``, so the description is only built where a ROS install provides them; the rest
is checked from the file's syntax tree against the package (setup.py, config/, the node classes).
"""

from __future__ import annotations

import ast
import importlib.util
import inspect
from types import ModuleType

import pytest
from launch_syntax import PACKAGE_DIR, LaunchSyntax

LAUNCH = PACKAGE_DIR / "launch" / "site.launch.py"
_SYNTAX = LaunchSyntax(LAUNCH)


def test_the_site_launch_file_names_both_executables_the_prior_and_the_config_that_exist() -> None:
    compile(LAUNCH.read_text(), str(LAUNCH), "exec")
    consts = _SYNTAX.constants()
    setup = (PACKAGE_DIR / "setup.py").read_text()
    assert f'"{consts["EXECUTABLE"]} = drd_planner.ros.planner_node:main"' in setup
    assert f'"{consts["MAP_SERVER_EXECUTABLE"]} = drd_planner.cli.map_server:main"' in setup
    assert (PACKAGE_DIR / "config" / consts["DEFAULT_CONFIG"]).is_file()
    assert (PACKAGE_DIR.parents[2] / "trees" / f"{consts['DEFAULT_PRIOR']}.npz").is_file()
    declared = {c.args[0].value for c in _SYNTAX.calls("DeclareLaunchArgument") if isinstance(c.args[0], ast.Constant)}
    assert declared == {"prior", "config", "frame_id", "namespace", "autostart", "log_level"}
    (planner,) = _SYNTAX.calls("LifecycleNode")
    (server,) = _SYNTAX.calls("Node")
    for call in (planner, server):
        assert {"package", "executable", "name", "namespace", "parameters"} <= {k.arg for k in call.keywords}
    source = LAUNCH.read_text()
    assert "Transition.TRANSITION_CONFIGURE" in source
    assert "Transition.TRANSITION_ACTIVATE" in source


def test_the_node_names_are_the_node_classes_defaults() -> None:
    pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")
    from drd_planner.ros.map_server import MapServer
    from drd_planner.ros.node import PlannerNode

    consts = _SYNTAX.constants()
    assert consts["NODE_NAME"] == inspect.signature(PlannerNode.__init__).parameters["node_name"].default
    assert consts["MAP_SERVER_NAME"] == inspect.signature(MapServer.__init__).parameters["node_name"].default


def _load() -> ModuleType:
    spec = importlib.util.spec_from_file_location("site_launch", LAUNCH)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_generate_launch_description_builds_both_nodes_and_the_planners_transitions() -> None:
    launch_ros = pytest.importorskip("launch_ros", reason="ROS 2 launch_ros not installed (needs a ROS install)")
    launch = pytest.importorskip("launch", reason="ROS 2 launch not installed (needs a ROS install)")
    from launch.actions import DeclareLaunchArgument, EmitEvent, RegisterEventHandler

    description = _load().generate_launch_description()
    entities = description.entities
    assert isinstance(description, launch.LaunchDescription)
    arguments = {e.name: e for e in entities if isinstance(e, DeclareLaunchArgument)}
    assert set(arguments) == {"prior", "config", "frame_id", "namespace", "autostart", "log_level"}
    lifecycle = [e for e in entities if isinstance(e, launch_ros.actions.LifecycleNode)]
    plain = [e for e in entities if type(e) is launch_ros.actions.Node]
    assert [n.node_executable for n in lifecycle] == ["planner_node"]
    assert [n.node_executable for n in plain] == ["drd_map_server"]
    assert sum(isinstance(e, EmitEvent) for e in entities) == 1  # configure
    assert sum(isinstance(e, RegisterEventHandler) for e in entities) == 1  # activate when inactive
    order = [type(e) for e in entities]
    assert order.index(RegisterEventHandler) < order.index(type(lifecycle[0])) < order.index(EmitEvent)
