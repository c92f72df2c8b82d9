"""ArmParams: the arm spec, normalised to JSON types and validated in one place."""

from __future__ import annotations

import pytest

from drd_planner.domains.arm_params import DEFAULT_START, SPEC_KEYS, ArmParams
from drd_planner.exceptions import ProblemError


def test_defaults_and_normalised_values() -> None:
    params = ArmParams.from_spec({"num_samples": 60.0, "urdf_path": None, "start": DEFAULT_START})
    assert params.num_samples == 60
    assert isinstance(params.num_samples, int)
    assert params.start == list(DEFAULT_START)
    spec = params.to_spec()
    assert tuple(spec) == SPEC_KEYS
    assert spec["floor_z"] == 0.0
    assert spec["resolution"] == 0.05
    assert spec["margin"] == 0.0
    assert ArmParams.from_spec(spec) == params


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ({"nodes": 3}, "unknown arm spec keys: nodes; valid keys: urdf_path,"),
        ({"resolution": 0.0}, "invalid arm spec: resolution must be finite and > 0"),
        ({"margin": -1.0}, "invalid arm spec: margin must be finite and >= 0"),
        ({"k": "many"}, "invalid arm spec"),
        ({"extra_states": [0.1, 0.2]}, r"invalid arm spec: extra_states\[0\] must be a list of joint values"),
        ({"extra_states": [[0.1], "abc"]}, r"extra_states\[1\] must be a list of joint values"),
        ({"extra_states": [[0.1], [0.2, float("nan")]]}, r"extra_states\[1\] must be finite joint values"),
        ({"extra_states": 3}, "extra_states must be a list of joint-value lists"),
        ({"collision_model": "boxes"}, "collision_model must be one of spheres, meshes"),
    ],
)
def test_bad_specs(spec: dict[str, object], message: str) -> None:
    with pytest.raises(ProblemError, match=message):
        ArmParams.from_spec(spec)


def test_extra_states_are_stored_as_lists_of_floats() -> None:
    params = ArmParams.from_spec({"extra_states": ((1, 2.5), [0.0, -1.0])})
    assert params.extra_states == [[1.0, 2.5], [0.0, -1.0]]
    assert all(isinstance(x, float) for row in params.extra_states for x in row)
    assert params.to_spec()["extra_states"] == [[1.0, 2.5], [0.0, -1.0]]
    assert ArmParams().extra_states == []
    assert ArmParams().to_spec()["extra_states"] == []
