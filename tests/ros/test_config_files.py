"""The shipped parameter files (config/*.yaml) with the real node: every parameter, and nothing else.

Each file is given to rclpy exactly as ``ros2 run ... --ros-args --params-file FILE`` and the launch
file give it (the context's global arguments), then the node's declared parameters are compared with
the file's, the values are read back, and ``configure`` loads the priors the file names.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from rclpy.lifecycle import TransitionCallbackReturn  # noqa: E402

from drd_planner.domains.arm import default_panda_dir  # noqa: E402
from drd_planner.exceptions import ProblemError  # noqa: E402
from drd_planner.ros.node import PlannerNode  # noqa: E402
from drd_planner.ros.parameters import PARAMETERS, plan_budgets_of  # noqa: E402

CONFIG = Path(__file__).resolve().parents[2] / "ros2_ws" / "src" / "drd_planner" / "config"
SHIPPED = ("heli_wires.yaml", "arm_table_clutter.yaml")
# Parameters every rclpy node declares itself.
BUILTIN = {"use_sim_time", "start_type_description_service"}
# Deprecated aliases the node still declares; the shipped files use the new names only.
DEPRECATED = {spec.name for spec in PARAMETERS if spec.deprecated_for is not None}
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
os.environ["ROS_DOMAIN_ID"] = str(140 + os.getpid() % 20)


def _parameters(path: Path) -> tuple[str, dict[str, Any]]:
    """(node key, parameters) of a parameter file holding one node's parameters."""
    data = yaml.safe_load(path.read_text())
    assert isinstance(data, dict), f"{path.name}: one node section expected"
    assert len(data) == 1, f"{path.name}: one node section expected"
    ((key, section),) = data.items()
    assert set(section) == {"ros__parameters"}, f"{path.name}: only ros__parameters expected"
    params = section["ros__parameters"]
    assert isinstance(params, dict)
    assert params
    return str(key), params


@pytest.fixture
def started(request: pytest.FixtureRequest) -> Iterator[tuple[PlannerNode, Path]]:
    """(node, file): a PlannerNode in a private context started with ``--ros-args --params-file file``."""
    path = CONFIG / request.param
    ctx = rclpy.context.Context()
    rclpy.init(context=ctx, args=["--ros-args", "--params-file", str(path)])
    node = PlannerNode(context=ctx)
    try:
        yield node, path
    finally:
        node.destroy_node()
        ctx.try_shutdown()


def test_the_shipped_configs_exist_and_every_one_is_tested() -> None:
    assert sorted(p.name for p in CONFIG.glob("*.yaml")) == sorted(SHIPPED)


@pytest.mark.parametrize("name", SHIPPED)
def test_every_parameter_has_a_comment(name: str) -> None:
    lines = (CONFIG / name).read_text().splitlines()
    _, params = _parameters(CONFIG / name)
    for key in params:
        at = next(i for i, line in enumerate(lines) if line.strip().startswith(f"{key}:"))
        assert lines[at - 1].strip().startswith("#"), f"{name}: no comment above {key}"


@pytest.mark.parametrize("name", SHIPPED)
def test_the_shipped_budgets_leave_the_anytime_improvement_off(name: str) -> None:
    _, params = _parameters(CONFIG / name)
    assert (params["improve_checks"], params["improve_time_budget"]) == (0, 0.0)
    assert plan_budgets_of(params) == {"max_checks": None, "time_budget_s": None, "improve_budget": None}


@pytest.mark.parametrize("started", SHIPPED, indirect=True)
def test_file_sets_exactly_the_declared_parameters_and_they_take_effect(
    started: tuple[PlannerNode, Path],
) -> None:
    node, path = started
    key, params = _parameters(path)
    # The section matches the node in any namespace (the launch file's `namespace` argument).
    assert key == f"/**/{node.get_name()}"
    declared = set(node.list_parameters([], 0).names) - BUILTIN - DEPRECATED
    assert DEPRECATED == {"tree_paths"}
    assert not DEPRECATED & set(params), "a shipped file sets a deprecated parameter"
    assert set(params) == declared, f"missing {declared - set(params)}, unknown {set(params) - declared}"
    for param, value in params.items():
        got = node.get_parameter(param).value
        if isinstance(value, float):
            assert math.isclose(got, value), param
        elif isinstance(value, list):
            assert list(got) == value, param
        else:
            assert got == value, param
    # The launch file drives the lifecycle; the files must not make the node start itself as well.
    assert node.get_parameter("autostart").value is False


def _configures(node: PlannerNode, path: Path) -> None:
    """``configure`` loads exactly the priors the file names; ``cleanup`` forgets them again."""
    _, params = _parameters(path)
    assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS, node.errors
    assert [s.name for s in node.sessions] == params["prior_paths"]
    assert all(s.improve_budget is None for s in node.sessions)  # the anytime improvement ships off
    assert node.trigger_cleanup() == TransitionCallbackReturn.SUCCESS
    assert not node.sessions


@pytest.mark.parametrize("started", ["heli_wires.yaml"], indirect=True)
def test_helicopter_config_configures(started: tuple[PlannerNode, Path]) -> None:
    _configures(*started)


@pytest.mark.parametrize("started", ["arm_table_clutter.yaml"], indirect=True)
def test_arm_config_configures(started: tuple[PlannerNode, Path]) -> None:
    try:
        default_panda_dir()
    except ProblemError as exc:
        pytest.skip(f"shared Panda model not present: {exc}")
    _configures(*started)
