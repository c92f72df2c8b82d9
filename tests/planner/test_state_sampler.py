"""The optional sampler capability of a connector: found only when it implements the protocol."""

from __future__ import annotations

import numpy as np

from drd_planner.planner.state_sampler import StateSampler, sampler_of
from drd_planner.planner.straight_connector import StraightConnector


class Box:
    lower = np.zeros(2)
    upper = np.ones(2)

    def valid(self, states: object) -> np.ndarray:
        return np.ones(np.asarray(states).reshape(-1, 2).shape[0], dtype=bool)

    def refusal(self, state: object, label: str) -> str | None:
        return None


def test_sampler_of_finds_a_connectors_sampler() -> None:
    assert isinstance(Box(), StateSampler)
    with_one = StraightConnector(reach=1.0, resolution=0.1, sampler=Box())
    without = StraightConnector(reach=1.0, resolution=0.1)
    assert isinstance(sampler_of(with_one), Box)
    assert sampler_of(without) is None
    assert sampler_of(None) is None
    assert sampler_of(object()) is None
