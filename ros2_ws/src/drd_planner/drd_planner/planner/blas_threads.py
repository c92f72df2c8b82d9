"""One BLAS thread while a plan runs: small products gain nothing from more, and idle BLAS threads spin.

A plan multiplies small matrices (a library's incidence by a few hundred training worlds, a bias by the
weights). OpenBLAS, as `numpy` and `scipy` wheels ship it, hands such a product to its worker threads,
which then busy-wait for more work for a while after it. That spinning is CPU the planning process is
charged for and takes from everything else on the robot: measured on ``heli_wires`` new queries, a plan
with two BLAS threads cost 8.0 ms of process CPU (median), the same plan with one 3.7 ms, with the same
checks. :func:`one_blas_thread` runs a function with the BLAS libraries loaded in the process limited to
one thread (through `threadpoolctl`), and restores their limits when the last such call running ends, so
nested and concurrent plans are safe and code outside a plan keeps its threads.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable
from typing import Any, ParamSpec, TypeVar

from threadpoolctl import ThreadpoolController

P = ParamSpec("P")
R = TypeVar("R")

_lock = threading.Lock()
_controller: ThreadpoolController | None = None
_limiter: Any = None  # threadpoolctl's limiter of the outermost call (restores the former limits)
_depth = 0


def _enter() -> None:
    global _controller, _limiter, _depth
    with _lock:
        if _depth == 0:
            if _controller is None:  # made on first use: the BLAS libraries are loaded by then
                _controller = ThreadpoolController()
            _limiter = _controller.limit(limits=1, user_api="blas")
        _depth += 1


def _leave() -> None:
    global _limiter, _depth
    with _lock:
        _depth -= 1
        if _depth == 0 and _limiter is not None:
            _limiter.restore_original_limits()
            _limiter = None


def one_blas_thread(func: Callable[P, R]) -> Callable[P, R]:
    """``func`` run with one BLAS thread (the former limits restored after the last such call ends)."""

    @functools.wraps(func)
    def limited(*args: P.args, **kwargs: P.kwargs) -> R:
        _enter()
        try:
            return func(*args, **kwargs)
        finally:
            _leave()

    return limited


def blas_threads() -> dict[str, int]:
    """The thread limit of each BLAS library loaded in the process now (``filepath`` -> threads)."""
    controller = ThreadpoolController()
    return {str(lib.filepath): int(lib.num_threads) for lib in controller.lib_controllers if lib.user_api == "blas"}
