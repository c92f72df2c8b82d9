"""One typed parameter model per domain: a frozen dataclass whose fields are the domain's spec.

:class:`SpecParams` gives such a dataclass its two conversions: :meth:`SpecParams.from_spec` (a JSON-able
mapping, missing keys taking the defaults, unknown keys refused with an error naming the valid keys) and
:meth:`SpecParams.to_spec` (tuples as lists, nested parameter records as dicts). Each dataclass validates
its values in ``__post_init__``, the one place a domain's parameters are checked.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any, ClassVar, TypeVar

from drd_planner.domains.helicopter_params import to_jsonable
from drd_planner.exceptions import ProblemError

__all__ = ["SpecParams", "spec_keys"]

P = TypeVar("P", bound="SpecParams")


def spec_keys(cls: type[Any]) -> tuple[str, ...]:
    """The spec keys of a parameter dataclass: its init fields, in order."""
    return tuple(f.name for f in dataclasses.fields(cls) if f.init)


class SpecParams:
    """Mixin of a frozen parameter dataclass: ``from_spec`` and ``to_spec`` (see the module docstring).

    ``SPEC_LABEL`` names the domain in messages (``"arm"``, ``"helicopter"``, ...).
    """

    SPEC_LABEL: ClassVar[str] = "domain"

    @classmethod
    def check_spec_keys(cls, spec: Any) -> None:
        """Refuse a spec that is not a mapping or has keys that are not fields.

        Raises:
            ProblemError: naming the unknown and the valid keys.
        """
        if not isinstance(spec, Mapping):
            raise ProblemError(f"{cls.SPEC_LABEL} spec must be a dict, got {type(spec).__name__}")
        known = spec_keys(cls)
        unknown = sorted(set(spec) - set(known))
        if unknown:
            raise ProblemError(
                f"unknown {cls.SPEC_LABEL} spec keys: {', '.join(map(str, unknown))}; valid keys: {', '.join(known)}"
            )

    @classmethod
    def from_spec(cls: type[P], spec: Mapping[str, Any]) -> P:
        """The parameters of a (partial) spec; missing keys take the defaults.

        Raises:
            ProblemError: unknown keys (the valid ones named) or invalid values.
        """
        cls.check_spec_keys(spec)
        return cls(**dict(spec))

    def to_spec(self) -> dict[str, Any]:
        """The full JSON-able spec (tuples as lists); ``from_spec(to_spec())`` gives equal parameters."""
        return {name: to_jsonable(getattr(self, name)) for name in spec_keys(type(self))}
