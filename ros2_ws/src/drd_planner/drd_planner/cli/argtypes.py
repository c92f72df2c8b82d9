"""argparse ``type=`` converters and option helpers shared by the command-line tools.

The converters turn one argument's text into a typed value or raise :class:`argparse.ArgumentTypeError`
(argparse then prints a usage line and exits 2); :func:`add_prior_option` adds ``--prior FILE`` with its
deprecated spelling ``--tree`` (hidden from help, one warning line on stderr when used).
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

__all__ = [
    "DeprecatedAlias",
    "add_prior_option",
    "bounded_float",
    "bounded_int",
    "eta_arg",
    "int_list",
    "kappa_arg",
    "name_list",
    "query_arg",
]

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


def name_list(text: str) -> list[str]:
    """Comma-separated names (``--policies a,b``), blanks dropped."""
    return [p.strip() for p in text.split(",") if p.strip()]


def int_list(text: str) -> tuple[int, ...]:
    """Comma-separated integers (``--training-sizes 50,100``; empty text: none)."""
    try:
        return tuple(int(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {text!r}") from None


def eta_arg(text: str) -> float | None:
    """``--eta``: 'auto' (None: validate per dataset) or a number in (0, 1]."""
    if text.strip().lower() == "auto":
        return None
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'auto' or a number in (0, 1], got {text!r}") from None
    if not 0.0 < value <= 1.0:
        raise argparse.ArgumentTypeError(f"eta must lie in (0, 1], got {value}")
    return value


def kappa_arg(text: str) -> tuple[float | None, ...]:
    """``--kappa``: 'auto' (validate among the defaults), 'none' (fixed leaf bias) or a number > 0."""
    from drd_planner.core.switch_threshold import DEFAULT_PSEUDO_COUNTS

    word = text.strip().lower()
    if word == "auto":
        return DEFAULT_PSEUDO_COUNTS
    if word == "none":
        return (None,)
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'auto', 'none' or a number > 0, got {text!r}") from None
    if not (value > 0 and math.isfinite(value)):
        raise argparse.ArgumentTypeError(f"kappa must be a positive number of worlds, got {value}")
    return (value,)


def query_arg(text: str) -> tuple[str, str]:
    """``--query START,GOAL``: each a vertex id, or a state as numbers separated by spaces or ';'.

    Examples: ``0,730`` (vertex ids), ``"0 0 65 0,700 0 65 0"`` (helicopter states).
    """
    parts = text.split(",")
    if len(parts) != 2 or not all(p.strip() for p in parts):
        raise argparse.ArgumentTypeError(
            f"expected START,GOAL (vertex ids, or states as space-separated numbers), got {text!r}"
        )
    return parts[0].strip(), parts[1].strip()


class DeprecatedAlias(argparse.Action):
    """Stores its value like ``store`` and prints one line on stderr: the flag is deprecated for ``replacement``."""

    def __init__(self, option_strings: Sequence[str], dest: str, *, replacement: str, **kwargs: Any) -> None:
        super().__init__(option_strings, dest, **kwargs)
        self.replacement = replacement

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: str | Sequence[Any] | None,
        option_string: str | None = None,
    ) -> None:
        """Warn that ``option_string`` is deprecated, then store ``values``."""
        print(f"{parser.prog}: warning: {option_string} is deprecated; use {self.replacement}", file=sys.stderr)
        setattr(namespace, self.dest, values)


def add_prior_option(
    parser: argparse.ArgumentParser | argparse._ArgumentGroup,
    *,
    help: str,
    default: str | None = None,
) -> None:
    """Add ``--prior FILE`` (dest ``prior``) and its deprecated spelling ``--tree`` (hidden from help)."""
    parser.add_argument("--prior", metavar="FILE", default=default, help=help)
    parser.add_argument(
        "--tree",
        dest="prior",
        action=DeprecatedAlias,
        replacement="--prior",
        default=default,
        help=argparse.SUPPRESS,
    )
