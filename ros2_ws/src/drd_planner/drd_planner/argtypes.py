"""argparse ``type=`` converters for bounded numbers, shared by the command-line tools."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from typing import TypeVar

__all__ = ["bounded_float", "bounded_int"]

_N = TypeVar("_N", int, float)


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


def _converter(
    convert: Callable[[str], _N], noun: str, bounds: tuple[float | None, float | None, float | None]
) -> Callable[[str], _N]:
    """A converter of text with ``convert``, then checked against ``(at_least, above, at_most)``.

    Text that ``convert`` rejects is "not ``noun``".
    """

    def parse(text: str) -> _N:
        try:
            value = convert(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not {noun}") from None
        _check(value, *bounds)
        return value

    return parse


def bounded_int(*, at_least: int | None = None, at_most: int | None = None) -> Callable[[str], int]:
    """A converter of text to an int within the given bounds (inclusive)."""
    return _converter(int, "an integer", (at_least, None, at_most))


def bounded_float(
    *, at_least: float | None = None, above: float | None = None, at_most: float | None = None
) -> Callable[[str], float]:
    """A converter of text to a finite float within the given bounds (``above`` is exclusive)."""
    return _converter(float, "a number", (at_least, above, at_most))
