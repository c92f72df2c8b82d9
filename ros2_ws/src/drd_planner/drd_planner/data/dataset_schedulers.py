"""Where a dataset build's chunk tasks run: in this process, a local process pool, or a Dask cluster.

All three run :func:`~drd_planner.data.dataset_worker.evaluate_chunk` on the same tasks, so the dataset
file is byte-identical whichever is used. A process pool is the local default because it starts in
milliseconds (fork) to half a second (spawn), opens no network ports and needs no scheduler or nanny
processes; a ``distributed.LocalCluster`` costs a second or more of start-up, which matters when the
build itself takes seconds. A Dask scheduler address sends the tasks to that cluster
(``distributed.Client(address)``), whose workers must have drd_planner (and the domain's module)
installed.
"""

from __future__ import annotations

import multiprocessing
import threading
import uuid
from collections.abc import Generator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool

from drd_planner.data.dataset_chunks import ChunkResult, ChunkTask
from drd_planner.data.dataset_worker import evaluate_chunk
from drd_planner.exceptions import DatasetError, DrdError

__all__ = ["DASK_CONNECT_TIMEOUT_S", "choose_start_method", "run_tasks"]

DASK_CONNECT_TIMEOUT_S = 10.0

#: Results of chunk tasks, in the order they finish.
ResultStream = Generator[ChunkResult, None, None]


def run_tasks(tasks: Sequence[ChunkTask], *, workers: int, scheduler: str | None, method: str | None) -> ResultStream:
    """Run ``tasks`` on the Dask ``scheduler`` when given, else on ``workers`` local processes.

    One local worker (or a single task) runs in this process; ``method`` is the start method of a
    process pool (None: :func:`choose_start_method`).
    """
    if scheduler is not None:
        return _run_dask(tasks, scheduler)
    if workers > 1 and len(tasks) > 1:
        return _run_pool(tasks, workers, method)
    return _run_inline(tasks)


def _run_inline(tasks: Sequence[ChunkTask]) -> ResultStream:
    for task in tasks:
        yield evaluate_chunk(task)


def choose_start_method(requested: str | None = None) -> str:
    """The multiprocessing start method for local workers.

    ``fork`` when the platform has it and this process runs a single thread (then forking is safe, and
    workers start in milliseconds with the modules and the domain already loaded); otherwise ``spawn``
    (fresh interpreters that import drd_planner and rebuild the domain from its spec, about half a
    second each). ``requested`` forces one of ``multiprocessing.get_all_start_methods()``.

    Raises:
        DatasetError: ``requested`` is not available on this platform.
    """
    methods = multiprocessing.get_all_start_methods()
    if requested is not None:
        if requested not in methods:
            raise DatasetError(f"start method {requested!r} is not available here; choose one of: {', '.join(methods)}")
        return requested
    return "fork" if "fork" in methods and threading.active_count() == 1 else "spawn"


def _run_pool(tasks: Sequence[ChunkTask], workers: int, method: str | None) -> ResultStream:
    """Start the pool and submit every task now (before any other thread exists), then drain it."""
    context = multiprocessing.get_context(choose_start_method(method))
    executor = ProcessPoolExecutor(max_workers=min(workers, len(tasks)), mp_context=context)
    try:
        futures = [executor.submit(evaluate_chunk, task) for task in tasks]
    except BaseException:
        executor.shutdown(wait=True, cancel_futures=True)
        raise
    return _drain(executor, futures)


def _drain(executor: ProcessPoolExecutor, futures: list[Future[ChunkResult]]) -> ResultStream:
    try:
        for future in as_completed(futures):
            try:
                result = future.result()
            except BrokenProcessPool as exc:
                raise DatasetError(
                    f"a worker process died ({exc}); finished chunks are kept: run the same build again to resume"
                ) from exc
            yield result
    finally:
        executor.shutdown(wait=True, cancel_futures=True)


def _run_dask(tasks: Sequence[ChunkTask], address: str) -> ResultStream:
    try:
        from distributed import Client
        from distributed import as_completed as dask_as_completed
    except ImportError as exc:  # pragma: no cover - dask[distributed] is a declared dependency
        raise DatasetError(f"--scheduler needs dask[distributed]: {exc}") from exc
    try:
        client = Client(address, timeout=DASK_CONNECT_TIMEOUT_S, set_as_default=False)  # type: ignore[no-untyped-call]
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        raise DatasetError(f"cannot connect to the Dask scheduler at {address!r}: {exc}") from exc
    try:
        run = uuid.uuid4().hex[:12]
        futures = [
            client.submit(evaluate_chunk, task, key=f"drd-chunk-{run}-{task.index}", pure=False) for task in tasks
        ]
        for future in dask_as_completed(futures, loop=client.loop):  # type: ignore[no-untyped-call]
            try:
                result: ChunkResult = future.result()
            except DrdError:
                raise
            except Exception as exc:  # a worker without drd_planner or the domain's module, a lost worker
                raise DatasetError(
                    f"a task failed on the Dask cluster at {address}: {type(exc).__name__}: {exc} "
                    "(its workers need drd_planner and the domain's module; finished chunks are kept)"
                ) from exc
            future.release()
            yield result
    finally:
        client.close()  # type: ignore[no-untyped-call]
