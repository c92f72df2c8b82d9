"""argparse ``type=`` converters for bounded numbers, shared by the command-line tools."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

__all__ = ["bounded_float", "bounded_int"]


def _check(value: float, at_least: float | None, above: float | None, at_most: float | None) -> None:
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be finite, got {value}")
    if at_least is not None and at_most is not None and not at_least <= value <= at_most:
        raise argparse.ArgumentTypeError(f"must lie in [{at_least:g}, {at_most:g}], got {value}")
    if at_least is not None and value < at_least:
        bound = "non-negative" if at_least == 0 else f"at least {at_least:g}"
        raise argparse.ArgumentTypeError(f"must be {bound}, got {value}")
    if above is not None and value <= above:
        raise argparse.ArgumentTypeError(f"must be > {above:g}, got {value}")
    if at_most is not None and value > at_most:
        raise argparse.ArgumentTypeError(f"must be at most {at_most:g}, got {value}")


def bounded_int(*, at_least: int | None = None, at_most: int | None = None) -> Callable[[str], int]:
    """A converter of text to an int within the given bounds (inclusive)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
        _check(value, at_least, None, at_most)
        return value

    return parse


def bounded_float(
    *, at_least: float | None = None, above: float | None = None, at_most: float | None = None
) -> Callable[[str], float]:
    """A converter of text to a finite float within the given bounds (``above`` is exclusive)."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        _check(value, at_least, above, at_most)
        return value

    return parse
