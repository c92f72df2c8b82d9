"""Progress reports on stderr for long command-line steps: a bar on a terminal, plain lines otherwise.

A tqdm bar is useless in a log file or a pipe (it is either hidden, or one line of carriage returns), so
when stderr is not a terminal :class:`Progress` writes one plain line every :data:`PLAIN_INTERVAL_S`
seconds instead, for example::

    validating eta x kappa: 640/1536 episodes (42%), 4 s elapsed, about 6 s left

and, when it wrote any such line, a last one when the step ends. Steps shorter than the interval stay
silent unless they ``announce`` themselves with a first line.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterable, Iterator, Sized
from types import TracebackType
from typing import Any, TextIO, TypeVar

from tqdm import tqdm

__all__ = ["PLAIN_INTERVAL_S", "Progress", "progress_iter"]

#: Seconds between two plain progress lines (stderr not a terminal).
PLAIN_INTERVAL_S = 5.0

T = TypeVar("T")


class Progress:
    """Counts the work of one step and reports it on ``stream`` (default: stderr).

    Args:
        total: units of work in the step (None: unknown).
        desc: what the step does (the line's prefix).
        unit: the name of one unit of work (plural with an "s").
        enabled: False is silent; None or True report: a tqdm bar when ``stream`` is a terminal, else
            a plain line every :data:`PLAIN_INTERVAL_S` seconds.
        announce: in plain mode, also write one line when the step starts.
        stream: where to write (None: ``sys.stderr`` at the time of the call).
        initial: units already done (a resumed step).
    """

    def __init__(
        self,
        total: int | None,
        desc: str,
        *,
        unit: str = "it",
        enabled: bool | None = None,
        announce: bool = False,
        stream: TextIO | None = None,
        initial: int = 0,
    ) -> None:
        self.total = total
        self.desc = desc
        self.unit = unit
        self.count = initial
        self._initial = initial
        self._stream = sys.stderr if stream is None else stream
        self._t0 = time.monotonic()
        self._last = self._t0
        self._lines = 0
        self._postfix = ""
        self._bar: Any = None
        self._plain = False
        if enabled is False:
            return
        if _is_terminal(self._stream):
            self._bar = tqdm(total=total, initial=initial, desc=desc, unit=unit, file=self._stream)
            return
        self._plain = True
        if announce:
            what = f"{total} {unit}s" if total is not None else "started"
            self._write(f"{desc}: {what}")

    def update(self, n: int = 1) -> None:
        """Record ``n`` more units done (and report, when it is time to)."""
        self.count += n
        if self._bar is not None:
            self._bar.update(n)
        elif self._plain:
            now = time.monotonic()
            if now - self._last >= PLAIN_INTERVAL_S:
                self._write(self._status(now))

    def set_postfix_str(self, text: str) -> None:
        """Show ``text`` after the count (for example the item being worked on)."""
        self._postfix = text
        if self._bar is not None:
            self._bar.set_postfix_str(text)

    def close(self) -> None:
        """End the step: close the bar, or write the last plain line if any line was written."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        elif self._plain and self._lines:
            self._write(f"{self.desc}: {self._count_text()} done in {time.monotonic() - self._t0:.1f} s")
        self._plain = False

    def __enter__(self) -> Progress:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def _count_text(self) -> str:
        if self.total is None:
            return f"{self.count} {self.unit}s"
        return f"{self.count}/{self.total} {self.unit}s"

    def _status(self, now: float) -> str:
        elapsed = now - self._t0
        text = f"{self.desc}: {self._count_text()}"
        if self.total:
            text += f" ({100.0 * self.count / self.total:.0f}%)"
        text += f", {elapsed:.0f} s elapsed"
        done_here = self.count - self._initial
        if self.total and done_here > 0 and self.count < self.total:
            text += f", about {elapsed * (self.total - self.count) / done_here:.0f} s left"
        return text + (f" [{self._postfix}]" if self._postfix else "")

    def _write(self, line: str) -> None:
        print(line, file=self._stream, flush=True)
        self._lines += 1
        self._last = time.monotonic()


def progress_iter(
    items: Iterable[T],
    desc: str,
    *,
    unit: str = "it",
    total: int | None = None,
    enabled: bool | None = None,
    announce: bool = False,
) -> Iterator[T]:
    """Yield ``items`` while reporting them as a :class:`Progress` (``total`` defaults to ``len(items)``)."""
    if total is None and isinstance(items, Sized):
        total = len(items)
    with Progress(total, desc, unit=unit, enabled=enabled, announce=announce) as bar:
        for item in items:
            yield item
            bar.update(1)


def _is_terminal(stream: TextIO) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # closed or unusual streams
        return False
