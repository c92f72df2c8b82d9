"""The node's log lines, written without rclpy's per-call search for the calling source line.

rclpy's ``RcutilsLogger.log`` (7.1.6, the Jazzy and PyPI version) names the caller of every line with
``inspect.getframeinfo``, which reads the caller's source file each time (``linecache`` stats it, the
path is resolved component by component): one line after each plan took 6 ms at the median and 20 ms
at p95 in the planning thread on the 2-core development machine, more than the rest of the node's
work on a request. :class:`NodeLog` writes the same line through the same rcutils call (the console and
``/rosout`` alike, same logger name, severity and level check), naming the caller from its frame
directly: microseconds.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

__all__ = ["NodeLog", "rcutils_log_function"]

#: rclpy's severities (``rclpy.logging.LoggingSeverity``): INFO and WARN.
INFO, WARN = 20, 30

#: rcutils' log call: (severity, logger name, message, function, file, line).
LogFunction = Callable[[int, str, str, str, str, int], None]


def rcutils_log_function() -> LogFunction | None:
    """The rcutils log call as rclpy binds it, or None when this rclpy has none by that name."""
    try:
        from rclpy.impl.implementation_singleton import rclpy_implementation
    except ImportError:
        return None
    function: LogFunction | None = getattr(rclpy_implementation, "rclpy_logging_rcutils_log", None)
    return function


class NodeLog:
    """``info`` and ``warning`` lines of a node's logger, caller named from its frame.

    Args:
        logger: the node's logger (``node.get_logger()``). A logger without ``name`` and
            ``is_enabled_for`` (a test's recorder) is called as it is.
        write: the rcutils log call (default: rclpy's, :func:`rcutils_log_function`; without one
            the logger's own methods are used).
    """

    def __init__(self, logger: Any, write: LogFunction | None = None) -> None:
        self._logger = logger
        direct = hasattr(logger, "name") and hasattr(logger, "is_enabled_for")
        self._write = (write or rcutils_log_function()) if direct else None

    def info(self, text: str) -> None:
        """Log ``text`` at INFO."""
        if self._write is None:
            self._logger.info(text)
        else:
            self._emit(INFO, text)

    def warning(self, text: str) -> None:
        """Log ``text`` at WARN."""
        if self._write is None:
            self._logger.warning(text)
        else:
            self._emit(WARN, text)

    def _emit(self, severity: int, text: str) -> None:
        """Write one line when the logger is enabled for ``severity``, named after the caller of info/warning."""
        assert self._write is not None
        if not self._logger.is_enabled_for(severity):
            return
        caller = sys._getframe(2)  # _emit <- info/warning <- the caller
        code = caller.f_code
        self._write(severity, str(self._logger.name), text, code.co_name, code.co_filename, caller.f_lineno)
