"""Keep the node up whatever arrives: guarded executor callbacks, bounded error texts, checked lifecycle ids.

An exception that escapes an rclpy callback ends ``executor.spin()`` and with it the node. Every
subscription, service and timer callback of :class:`~drd_planner.ros.node.PlannerNode` is therefore
wrapped here: a :class:`~drd_planner.exceptions.DrdError` or a message error is the callback's own
business (it reports a clear refusal), anything else (``MemoryError`` included) is reported as an
internal error and the input is dropped. Reports quote hostile input (an 8 MB ``frame_id``), so every
text is cut to :data:`MAX_ERROR_CHARS` before it is logged, published or kept.

rclpy 7.1.6 (the Jazzy wheels) dies on a ``change_state`` request whose transition *id* is not
available in the current state (ros2/rclpy#1209, fixed upstream by #1319):
:func:`guard_change_state` answers such requests ``success = False`` instead.
"""

from __future__ import annotations

import sys
import traceback
from collections import Counter
from collections.abc import Callable
from typing import Any

__all__ = [
    "MAX_ERROR_CHARS",
    "MAX_TRACEBACK_CHARS",
    "guard_callback",
    "guard_change_state",
    "guard_service",
    "shorten",
    "traceback_of",
]

#: Longest error text the node logs, publishes on ``/diagnostics`` or keeps in its history (characters).
MAX_ERROR_CHARS = 400
#: Longest traceback the node logs after a bug's error line (characters; its last ones are kept).
MAX_TRACEBACK_CHARS = 8000

Report = Callable[[str], None]


def shorten(text: str, limit: int = MAX_ERROR_CHARS) -> str:
    """``text`` cut to at most ``limit`` characters, saying how long it was when it is cut."""
    if len(text) <= limit:
        return text
    tail = f"... [{len(text)} characters]"
    return text[: max(0, limit - len(tail))] + tail


def traceback_of(exc: BaseException, limit: int = MAX_TRACEBACK_CHARS) -> str:
    """``exc``'s traceback as Python prints it, its last ``limit`` characters (the frames nearest the raise)."""
    text = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__)).rstrip("\n")
    if len(text) <= limit:
        return text
    return f"[{len(text) - limit} characters before]..." + text[len(text) - limit :]


def _describe(exc: BaseException) -> str:
    return shorten(f"{type(exc).__name__}: {exc}")


def _report_safely(report: Report, text: str) -> None:
    """Report ``text``; if reporting fails too (memory exhausted), fall back to one line on stderr."""
    try:
        report(shorten(text))
    except Exception as exc:  # the last line of defence: never let the report end the node
        try:
            print(f"drd_planner: could not report an error ({type(exc).__name__})", file=sys.stderr)
        except Exception:  # stderr closed: nothing left to tell
            pass


def guard_callback(
    callback: Callable[..., None], *, name: str, report: Report, taken: Counter[str] | None = None
) -> Callable[..., None]:
    """``callback`` (a subscription or timer callback) that reports any exception instead of raising it.

    Args:
        callback: takes the message (a timer's: nothing); its arguments are passed through.
        name: the topic or timer, quoted in the report.
        report: the node's error reporter (log, ``/diagnostics``, history).
        taken: counts ``name`` once per call when the callback has returned (or failed): the messages a node
            has taken, for a replay that waits for them.
    """

    def guarded(*args: Any) -> None:
        try:
            callback(*args)
        except Exception as exc:
            _report_safely(report, f"{name}: internal error, input dropped (the node goes on): {_describe(exc)}")
        finally:
            if taken is not None:
                taken[name] += 1

    return guarded


def guard_service(callback: Callable[[Any, Any], Any], *, name: str, report: Report) -> Callable[[Any, Any], Any]:
    """``callback`` (a service callback) that answers the untouched response instead of raising."""

    def guarded(request: Any, response: Any) -> Any:
        try:
            return callback(request, response)
        except Exception as exc:
            _report_safely(report, f"{name}: internal error, request answered empty: {_describe(exc)}")
            return response

    return guarded


def guard_change_state(node: Any, *, report: Report) -> bool:
    """Make ``node``'s ``change_state`` service refuse transition ids the current state does not offer.

    Args:
        node: an rclpy ``LifecycleNode`` (with its lifecycle services enabled).
        report: the node's error reporter.

    Returns:
        Whether the service was found and guarded (False: the node has no lifecycle services).
    """
    service = getattr(node, "_service_change_state", None)
    machine = getattr(node, "_state_machine", None)
    if service is None or machine is None:
        return False
    original = service.callback

    def change_state(request: Any, response: Any) -> Any:
        transition = request.transition
        if not str(transition.label):  # by label rclpy refuses unknown transitions itself
            available = {int(t[0]): str(t[1]) for t in machine.available_transitions}
            if int(transition.id) not in available:
                state = str(machine.current_state[1])
                offered = ", ".join(f"{label} ({tid})" for tid, label in sorted(available.items()))
                _report_safely(
                    report,
                    f"change_state refused: transition id {int(transition.id)} is not available in state "
                    f"{state!r} (available: {offered or 'none'})",
                )
                response.success = False
                return response
        try:
            return original(request, response)
        except Exception as exc:
            _report_safely(report, f"change_state failed: {_describe(exc)}")
            response.success = False
            return response

    service.callback = change_state
    return True
