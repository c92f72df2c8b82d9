"""The arm domain's parameters (its spec): robot files, start and goal, roadmap size, check resolution."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from drd_planner.domains.params import SpecParams
from drd_planner.exceptions import ProblemError

__all__ = ["DEFAULT_GOAL", "DEFAULT_START", "SPEC_KEYS", "ArmParams"]

#: Default start: the gripper low (about 0.13 m above the base) over the front left of the table (rad).
DEFAULT_START: tuple[float, ...] = (0.5, 0.7, 0.0, -1.6, 0.0, 2.4, 0.785)
#: Default goal: the mirror image, low over the front right of the table (rad).
DEFAULT_GOAL: tuple[float, ...] = (-0.5, 0.7, 0.0, -1.6, 0.0, 2.4, 0.785)


def _path(value: Any) -> str | None:
    return None if value is None else str(value)


@dataclass(frozen=True)
class ArmParams(SpecParams):
    """The arm domain's spec, validated (values converted to plain JSON types).

    Attributes:
        urdf_path: kinematic URDF file; None: the shared Panda (``panda.urdf`` + ``panda_spherized.urdf``
            spheres + ``panda.srdf``), see :func:`~drd_planner.domains.arm_robot.robot_texts`.
        sphere_urdf_path: spherized URDF file (spheres; the kinematic URDF itself when None).
        srdf_path: SRDF file (self-collision exclusions; adjacent links when None).
        start: (D,) start configuration (rad), stored as a list.
        goal: (D,) goal configuration (rad), stored as a list.
        num_samples: Halton samples drawn for the roadmap.
        k: nearest neighbours per vertex.
        seed: Halton scrambling seed.
        resolution: max joint step between edge samples (rad), finite and > 0.
        margin: safety distance added to every robot sphere in world checks (m), finite and >= 0.
        floor_z: no moving sphere below this height in the roadmap (m); None disables the floor.

    Raises:
        ProblemError: a value of the wrong type, or out of range.
    """

    SPEC_LABEL: ClassVar[str] = "arm"

    urdf_path: str | None = None
    sphere_urdf_path: str | None = None
    srdf_path: str | None = None
    start: Sequence[float] = DEFAULT_START
    goal: Sequence[float] = DEFAULT_GOAL
    num_samples: int = 600
    k: int = 8
    seed: int = 0
    resolution: float = 0.05
    margin: float = 0.0
    floor_z: float | None = 0.0

    def __post_init__(self) -> None:
        try:
            values = self._normalised()
        except (TypeError, ValueError) as exc:
            raise ProblemError(f"invalid arm spec: {exc}") from exc
        for name, value in values.items():
            object.__setattr__(self, name, value)

    def _normalised(self) -> dict[str, Any]:
        """The fields as plain JSON types (TypeError/ValueError on bad values)."""
        resolution = float(self.resolution)
        margin = float(self.margin)
        if not (math.isfinite(resolution) and resolution > 0):
            raise ValueError(f"resolution must be finite and > 0 rad, got {resolution}")
        if not (math.isfinite(margin) and margin >= 0):
            raise ValueError(f"margin must be finite and >= 0 m, got {margin}")
        return {
            "urdf_path": _path(self.urdf_path),
            "sphere_urdf_path": _path(self.sphere_urdf_path),
            "srdf_path": _path(self.srdf_path),
            "start": [float(x) for x in self.start],
            "goal": [float(x) for x in self.goal],
            "num_samples": int(self.num_samples),
            "k": int(self.k),
            "seed": int(self.seed),
            "resolution": resolution,
            "margin": margin,
            "floor_z": None if self.floor_z is None else float(self.floor_z),
        }


#: Keys of the arm spec (the fields of :class:`ArmParams`).
SPEC_KEYS: tuple[str, ...] = (
    "urdf_path",
    "sphere_urdf_path",
    "srdf_path",
    "start",
    "goal",
    "num_samples",
    "k",
    "seed",
    "resolution",
    "margin",
    "floor_z",
)
