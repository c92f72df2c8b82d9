"""The node's log lines: the rcutils call with the logger's name, its level check, the caller's place."""

from __future__ import annotations

import inspect
from typing import Any

import pytest

from drd_planner.ros.node_log import INFO, WARN, NodeLog, rcutils_log_function


class _Logger:
    """An rclpy-like logger enabled from ``level`` on; records what its own methods were asked."""

    name = "drd_planner"

    def __init__(self, level: int) -> None:
        self.level = level
        self.own: list[str] = []

    def is_enabled_for(self, severity: int) -> bool:
        return severity >= self.level

    def info(self, text: str) -> None:
        self.own.append(text)


def test_lines_go_to_rcutils_named_after_the_caller_and_filtered_by_level() -> None:
    written: list[tuple[Any, ...]] = []
    logger = _Logger(level=INFO)
    log = NodeLog(logger, write=lambda *args: written.append(args))
    here = inspect.currentframe()
    assert here is not None
    log.info("planned")
    line = here.f_lineno - 1
    log.warning("kept")
    assert written[0] == (INFO, "drd_planner", "planned", here.f_code.co_name, __file__, line)
    assert written[1][:3] == (WARN, "drd_planner", "kept")
    assert written[1][5] == line + 2
    quiet = NodeLog(_Logger(level=WARN), write=lambda *args: written.append(args))
    quiet.info("hidden")
    quiet.warning("shown")
    assert [w[2] for w in written] == ["planned", "kept", "shown"]
    assert not logger.own


def test_a_logger_without_rclpy_interface_is_called_as_it_is() -> None:
    class Recorder:
        def __init__(self) -> None:
            self.lines: list[str] = []

        def info(self, text: str) -> None:
            self.lines.append(f"info {text}")

        def warning(self, text: str) -> None:
            self.lines.append(f"warning {text}")

    recorder = Recorder()
    log = NodeLog(recorder, write=lambda *args: pytest.fail("not an rclpy logger"))
    log.info("a")
    log.warning("b")
    assert recorder.lines == ["info a", "warning b"]


def test_rclpy_has_the_rcutils_call_and_a_real_logger_takes_lines(capfd: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")
    import rclpy.logging

    assert rcutils_log_function() is not None
    NodeLog(rclpy.logging.get_logger("node_log_test")).warning("a line from the test")
    assert "[node_log_test]: a line from the test" in capfd.readouterr().err
