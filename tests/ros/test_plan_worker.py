"""PlanWorker: the node's planning thread (runs on wake, coalesces wakes, survives errors, stops)."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

from drd_planner.ros.plan_worker import PlanWorker


def _wait(done: Callable[[], bool], timeout: float = 5.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if done():
            return True
        time.sleep(0.002)
    return done()


def test_work_runs_in_its_own_thread_after_each_wake() -> None:
    threads: list[int] = []
    worker = PlanWorker(lambda: threads.append(threading.get_ident()), on_error=lambda exc: None)
    worker.start()
    try:
        worker.wake()
        assert _wait(lambda: len(threads) == 1)
        worker.wake()
        assert _wait(lambda: len(threads) == 2)
        assert threading.get_ident() not in threads
    finally:
        assert worker.stop()
    assert not worker.running


def test_wakes_during_a_run_coalesce_into_one_more_run() -> None:
    started, release = threading.Event(), threading.Event()
    runs: list[int] = []

    def work() -> None:
        runs.append(len(runs))
        if len(runs) == 1:
            started.set()
            release.wait(5.0)

    worker = PlanWorker(work, on_error=lambda exc: None)
    worker.start()
    try:
        worker.wake()
        assert started.wait(5.0)
        for _ in range(50):  # all while the first run is busy
            worker.wake()
        release.set()
        assert _wait(lambda: len(runs) == 2)
        time.sleep(0.05)
        assert len(runs) == 2  # not 51
    finally:
        assert worker.stop()


def test_an_error_is_reported_and_the_thread_goes_on() -> None:
    errors: list[Exception] = []
    runs: list[int] = []

    def work() -> None:
        runs.append(1)
        if len(runs) == 1:
            raise RuntimeError("bug in a plan")

    worker = PlanWorker(work, on_error=errors.append)
    worker.start()
    try:
        worker.wake()
        assert _wait(lambda: len(errors) == 1)
        assert "bug in a plan" in str(errors[0])
        worker.wake()
        assert _wait(lambda: len(runs) == 2)
        assert worker.running
    finally:
        assert worker.stop()


def test_a_wake_before_start_is_served_at_start_and_start_is_idempotent() -> None:
    runs: list[int] = []
    worker = PlanWorker(lambda: runs.append(1), on_error=lambda exc: None, name="test-worker-idempotent")
    worker.wake()
    time.sleep(0.05)
    assert runs == []  # no thread yet
    worker.start()
    worker.start()
    try:
        assert _wait(lambda: len(runs) == 1)
        assert sum(t.name == "test-worker-idempotent" for t in threading.enumerate()) == 1
    finally:
        assert worker.stop()


def test_stop_lets_the_running_work_finish_and_can_restart() -> None:
    started, finished = threading.Event(), threading.Event()

    def work() -> None:
        started.set()
        time.sleep(0.1)
        finished.set()

    worker = PlanWorker(work, on_error=lambda exc: None)
    worker.start()
    worker.wake()
    assert started.wait(5.0)
    assert worker.stop()
    assert finished.is_set()
    assert not worker.running
    finished.clear()
    worker.start()
    try:
        worker.wake()
        assert finished.wait(5.0)
    finally:
        assert worker.stop()
    assert worker.stop()  # stopping a stopped worker is fine


def test_a_start_after_a_stop_that_timed_out_keeps_the_thread_serving() -> None:
    """Deactivate while a plan runs past the stop timeout, then activate: later wakes are still served."""
    started, release = threading.Event(), threading.Event()
    runs: list[int] = []

    def work() -> None:
        runs.append(len(runs))
        if len(runs) == 1:
            started.set()
            release.wait(5.0)

    worker = PlanWorker(work, on_error=lambda exc: None)
    worker.start()
    try:
        worker.wake()
        assert started.wait(5.0)
        assert not worker.stop(timeout=0.05)  # the long plan outlives the stop
        worker.start()  # re-activation while that plan still runs
        release.set()
        time.sleep(0.05)
        worker.wake()
        assert _wait(lambda: len(runs) == 2), "the planning thread ended: the wake was never served"
        assert worker.running
    finally:
        release.set()
        assert worker.stop()


def test_an_error_in_the_error_reporter_does_not_end_the_thread() -> None:
    runs: list[int] = []

    def work() -> None:
        runs.append(1)
        raise RuntimeError("a bug in a plan")

    def report(exc: Exception) -> None:
        raise MemoryError("no memory left to report it")

    worker = PlanWorker(work, on_error=report)
    worker.start()
    try:
        worker.wake()
        assert _wait(lambda: len(runs) == 1)
        worker.wake()
        assert _wait(lambda: len(runs) == 2)
    finally:
        assert worker.stop()
