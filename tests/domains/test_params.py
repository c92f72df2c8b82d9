"""SpecParams: one from_spec / to_spec for every domain's parameter dataclass."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import pytest

from drd_planner.domains.params import SpecParams, spec_keys
from drd_planner.domains.se2 import Se2Domain
from drd_planner.exceptions import ProblemError


@dataclass(frozen=True)
class Toy(SpecParams):
    SPEC_LABEL: ClassVar[str] = "toy"

    size: float = 1.0
    corner: tuple[float, float] = (0.0, 0.0)


def test_from_spec_fills_defaults_and_to_spec_writes_lists() -> None:
    toy = Toy.from_spec({"corner": (1.0, 2.0)})
    assert toy == Toy(size=1.0, corner=(1.0, 2.0))
    assert toy.to_spec() == {"size": 1.0, "corner": [1.0, 2.0]}
    assert spec_keys(Toy) == ("size", "corner")


def test_unknown_keys_name_the_valid_ones() -> None:
    with pytest.raises(ProblemError, match=r"^unknown toy spec keys: colour, weight; valid keys: size, corner$"):
        Toy.from_spec({"weight": 1, "colour": 2})
    with pytest.raises(ProblemError, match="toy spec must be a dict"):
        Toy.from_spec([1, 2])  # type: ignore[arg-type]


def test_a_domain_spec_round_trips() -> None:
    domain = Se2Domain()
    assert Se2Domain.from_spec(domain.spec()) == domain
    assert domain.spec()["bounds"] == [0.0, 0.0, 1.0, 1.0]
