"""The node's planning thread: runs one function each time it is woken, outside the ROS executor.

Plans run here rather than in an executor callback so that the node can be spun by a
``SingleThreadedExecutor`` and still take maps and requests while a plan runs. (rclpy 7.1.6's
``MultiThreadedExecutor``, the one in the PyPI wheels and Jazzy, re-submits a task that its thread
pool has not started yet and spins without waiting meanwhile, holding the GIL: measured here, it
delayed a ``goal_pose`` reaching the node by 15 to 470 ms. rclpy 10.0.4 fixed that upstream.)

Wake-ups coalesce: any number of :meth:`PlanWorker.wake` calls while the function runs cause one
more run after it, which then finds everything that arrived meanwhile.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

__all__ = ["PlanWorker"]


class PlanWorker:
    """A daemon thread that calls ``work()`` after each :meth:`wake`.

    Args:
        work: the function to run (the node's ``_serve``); it takes the pending requests itself.
        on_error: called with any exception ``work`` raises; the thread then goes on waiting.
        name: the thread's name (shows in ``py-spy`` and in thread dumps).
    """

    def __init__(
        self,
        work: Callable[[], None],
        *,
        on_error: Callable[[Exception], None],
        name: str = "drd_planner-plans",
    ) -> None:
        self._work = work
        self._on_error = on_error
        self._name = name
        self._condition = threading.Condition()
        self._woken = False
        self._stopping = False
        self._looping = False  # a thread is in its loop (set and cleared under the condition)
        self._busy = False  # ``work`` is running (set and cleared under the condition)
        self._thread: threading.Thread | None = None

    @property
    def running(self) -> bool:
        """Whether the thread is alive."""
        return self._thread is not None and self._thread.is_alive()

    @property
    def idle(self) -> bool:
        """True when no ``work`` runs and none is asked for (every wake so far has been served)."""
        with self._condition:
            return not (self._woken or self._busy)

    def start(self) -> None:
        """Start the thread; a wake before the start is served at once.

        If a thread is still in its loop (running, or finishing a long ``work`` after a :meth:`stop`
        that timed out), it is kept and goes on serving: it is not told to stop any more.
        """
        with self._condition:
            self._stopping = False
            if self._looping:
                self._condition.notify()
                return
            self._looping = True
        self._thread = threading.Thread(target=self._run, name=self._name, daemon=True)
        self._thread.start()

    def wake(self) -> None:
        """Ask for one more run of ``work`` (served when the thread runs)."""
        with self._condition:
            self._woken = True
            self._condition.notify()

    def stop(self, timeout: float | None = 30.0) -> bool:
        """Let the running ``work`` finish, end the thread; whether it ended within ``timeout`` s."""
        thread = self._thread
        with self._condition:
            self._stopping = True
            self._condition.notify()
        if thread is None or thread is threading.current_thread():
            return True
        thread.join(timeout)
        ended = not thread.is_alive()
        if ended:
            self._thread = None
        return ended

    def _run(self) -> None:
        while True:
            with self._condition:
                while not (self._woken or self._stopping):
                    self._condition.wait()
                if self._stopping:
                    self._looping = False
                    return
                self._woken = False
                self._busy = True
            try:
                self._work()
            except Exception as exc:  # a bug in one plan must not end the planning thread
                try:
                    self._on_error(exc)
                except Exception:  # the reporter failed too: keep the thread alive
                    pass
            finally:
                with self._condition:
                    self._busy = False
