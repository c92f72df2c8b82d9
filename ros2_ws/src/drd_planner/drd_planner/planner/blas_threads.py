"""One BLAS thread while a plan runs: small products gain nothing from more, and idle BLAS threads spin.

A plan multiplies small matrices (a library's incidence by a few hundred training worlds, a bias by the
weights). OpenBLAS, as `numpy` and `scipy` wheels ship it, hands such a product to its worker threads,
which then busy-wait for more work for a while after it. That spinning is CPU the planning process is
charged for and takes from everything else on the robot: measured on ``heli_wires`` new queries, a plan
with two BLAS threads cost 8.0 ms of process CPU (median), the same plan with one 3.7 ms, with the same
checks. :func:`one_blas_thread` runs a function with the BLAS libraries loaded in the process limited to
one thread (through `threadpoolctl`), and restores their limits when it ends.

A BLAS library's thread count is one setting for the whole process, and `threadpoolctl` lets only one
Python thread at a time change it. So one call at a time owns the limit: the first to start sets it and
restores it when it ends, in its own thread; calls that start while it runs (nested in it, or in other
threads) run under its limit and change nothing. Overlapping plans therefore never leave the process at one
thread, and code outside a plan keeps its threads.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable
from typing import ParamSpec, TypeVar

from threadpoolctl import ThreadpoolController

P = ParamSpec("P")
R = TypeVar("R")

_lock = threading.Lock()
_owner: list[threading.Thread] = []  # the thread whose call holds the limit now (none or one)


@functools.lru_cache(maxsize=1)
def _controller() -> ThreadpoolController:
    """The process's BLAS libraries, found on first use (they are loaded by then)."""
    return ThreadpoolController()


def _take() -> bool:
    """Whether this call owns the limit (no other call holds it)."""
    with _lock:
        if _owner:
            return False
        _owner.append(threading.current_thread())
        return True


def _release() -> None:
    with _lock:
        _owner.clear()


def one_blas_thread(func: Callable[P, R]) -> Callable[P, R]:
    """``func`` run with one BLAS thread (the former limits restored when the call that set them ends)."""

    @functools.wraps(func)
    def limited(*args: P.args, **kwargs: P.kwargs) -> R:
        if not _take():
            return func(*args, **kwargs)
        try:
            with _controller().limit(limits=1, user_api="blas"):
                return func(*args, **kwargs)
        finally:
            _release()

    return limited


def blas_threads() -> dict[str, int]:
    """The thread limit of each BLAS library loaded in the process now (``filepath`` -> threads)."""
    controller = ThreadpoolController()
    return {str(lib.filepath): int(lib.num_threads) for lib in controller.lib_controllers if lib.user_api == "blas"}
