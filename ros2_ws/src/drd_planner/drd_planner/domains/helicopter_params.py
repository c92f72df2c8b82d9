"""Parameter records of the helicopter domain as JSON-able dicts: conversion and validation helpers.

Parameter classes are frozen dataclasses whose fields are numbers, strings, tuples of numbers, ranges
``(lo, hi)`` or tuples of tuples. :func:`params_to_dict` turns one into plain lists/numbers (JSON), and
:func:`params_from_dict` back (unknown keys and malformed values raise :class:`ProblemError`).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, TypeVar

from drd_planner.exceptions import ProblemError

__all__ = ["check_range", "params_from_dict", "params_to_dict", "to_jsonable"]

T = TypeVar("T")


def to_jsonable(value: Any) -> Any:
    """Tuples (nested) as lists; dataclass parameter records as dicts; everything else unchanged."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return params_to_dict(value)
    if isinstance(value, (tuple, list)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    return value


def _to_tuples(value: Any) -> Any:
    """Lists (nested) as tuples."""
    if isinstance(value, (list, tuple)):
        return tuple(_to_tuples(v) for v in value)
    return value


def params_to_dict(params: Any) -> dict[str, Any]:
    """The fields of a parameter dataclass as a JSON-able dict (tuples become lists)."""
    return {f.name: to_jsonable(getattr(params, f.name)) for f in dataclasses.fields(params)}


def params_from_dict(cls: type[T], values: Any, *, what: str) -> T:
    """Build ``cls`` from a (partial) dict; missing keys take the defaults, lists become tuples.

    Raises:
        ProblemError: ``values`` is not a dict, has unknown keys, or the class rejects a value.
    """
    if values is None:
        values = {}
    if not isinstance(values, dict):
        raise ProblemError(f"{what} parameters must be a dict, got {type(values).__name__}")
    known = {f.name for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    unknown = sorted(set(values) - known)
    if unknown:
        raise ProblemError(f"unknown {what} parameters {unknown}; known: {sorted(known)}")
    try:
        return cls(**{k: _to_tuples(v) for k, v in values.items()})
    except (TypeError, ValueError) as exc:
        raise ProblemError(f"invalid {what} parameters: {exc}") from None


def check_range(
    value: Any, what: str, *, low: float = -math.inf, integer: bool = False
) -> tuple[float, float] | tuple[int, int]:
    """A validated range ``(lo, hi)`` with ``low <= lo <= hi``, finite (integers when ``integer``).

    Raises:
        ProblemError: not a pair of finite numbers in order, or below ``low``.
    """
    try:
        lo, hi = value
        pair = (float(lo), float(hi))
    except (TypeError, ValueError):
        raise ProblemError(f"{what} must be a range [lo, hi], got {value!r}") from None
    if not all(math.isfinite(v) for v in pair) or pair[0] > pair[1] or pair[0] < low:
        raise ProblemError(f"{what} must be finite with {low} <= lo <= hi, got {value!r}")
    if integer:
        if any(v != int(v) for v in pair):
            raise ProblemError(f"{what} must be a range of integers, got {value!r}")
        return int(pair[0]), int(pair[1])
    return pair
