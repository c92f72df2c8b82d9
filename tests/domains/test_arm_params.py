"""ArmParams: the arm spec, normalised to JSON types and validated in one place."""

from __future__ import annotations

import pytest

from drd_planner.domains.arm_params import DEFAULT_START, SPEC_KEYS, ArmParams
from drd_planner.exceptions import ProblemError


def test_defaults_and_normalised_values() -> None:
    params = ArmParams.from_spec({"num_samples": 60.0, "urdf_path": None, "start": DEFAULT_START})
    assert params.num_samples == 60 and isinstance(params.num_samples, int)
    assert params.start == list(DEFAULT_START)
    spec = params.to_spec()
    assert tuple(spec) == SPEC_KEYS
    assert spec["floor_z"] == 0.0 and spec["resolution"] == 0.05 and spec["margin"] == 0.0
    assert ArmParams.from_spec(spec) == params


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ({"nodes": 3}, "unknown arm spec keys: nodes; valid keys: urdf_path,"),
        ({"resolution": 0.0}, "invalid arm spec: resolution must be finite and > 0"),
        ({"margin": -1.0}, "invalid arm spec: margin must be finite and >= 0"),
        ({"k": "many"}, "invalid arm spec"),
    ],
)
def test_bad_specs(spec: dict[str, object], message: str) -> None:
    with pytest.raises(ProblemError, match=message):
        ArmParams.from_spec(spec)
