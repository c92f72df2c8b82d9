"""The arm domain's parameters (its spec): robot files, start and goal, roadmap size, check resolution."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, ClassVar

from drd_planner.domains.params import SpecParams
from drd_planner.exceptions import ProblemError

__all__ = [
    "COLLISION_MODELS",
    "DEFAULT_GOAL",
    "DEFAULT_START",
    "SCENE_SPEC_DEFAULTS",
    "SPEC_KEYS",
    "ArmParams",
]

#: The arm's collision models (``collision_model`` spec key).
COLLISION_MODELS: tuple[str, ...] = ("spheres", "meshes")

#: Spec values for worlds read from MoveIt PlanningScenes (a scene set, ``--scenes``) where the user's spec
#: does not set them: MoveIt has no implicit floor, a scene models its own support surfaces (tables, boxes
#: below the robot base), so the floor test is off. The built-in world models (``clutter``,
#: ``table_clutter``) stand the robot on unmodelled ground at z = 0 and keep the ``floor_z`` default 0.0.
SCENE_SPEC_DEFAULTS: Mapping[str, Any] = MappingProxyType({"floor_z": None})

#: Default start: the gripper low (about 0.13 m above the base) over the front left of the table (rad).
DEFAULT_START: tuple[float, ...] = (0.5, 0.7, 0.0, -1.6, 0.0, 2.4, 0.785)
#: Default goal: the mirror image, low over the front right of the table (rad).
DEFAULT_GOAL: tuple[float, ...] = (-0.5, 0.7, 0.0, -1.6, 0.0, 2.4, 0.785)


def _path(value: Any) -> str | None:
    return None if value is None else str(value)


def _extra_states(value: Any) -> list[list[float]]:
    """``extra_states`` as a list of lists of finite floats (ValueError naming the bad index)."""
    if isinstance(value, str | bytes) or not isinstance(value, Sequence):
        raise ValueError(f"extra_states must be a list of joint-value lists (rad), got {type(value).__name__}")
    out: list[list[float]] = []
    for i, state in enumerate(value):
        try:
            if isinstance(state, str | bytes) or not isinstance(state, Sequence):
                raise TypeError(type(state).__name__)
            row = [float(x) for x in state]
        except (TypeError, ValueError) as exc:
            raise ValueError(f"extra_states[{i}] must be a list of joint values (rad), got {state!r}") from exc
        if not all(math.isfinite(x) for x in row):
            raise ValueError(f"extra_states[{i}] must be finite joint values (rad), got {row}")
        out.append(row)
    return out


@dataclass(frozen=True)
class ArmParams(SpecParams):
    """The arm domain's spec, validated (values converted to plain JSON types).

    Attributes:
        urdf_path: kinematic URDF file (file); None: the shared Panda (``panda.urdf`` + ``panda_spherized.urdf``
            spheres + ``panda.srdf``), see :func:`~drd_planner.domains.arm_robot.robot_texts`.
        sphere_urdf_path: spherized URDF file (file) whose collision geometry is spheres; None: the kinematic
            URDF itself.
        srdf_path: SRDF file (file) of self-collision exclusions (adjacent links when None).
        start: (D,) start configuration (rad), stored as a list.
        goal: (D,) goal configuration (rad), stored as a list.
        num_samples: Halton samples drawn for the roadmap (count); more samples connect more states.
        k: nearest neighbours per vertex (count).
        seed: Halton scrambling seed (seed).
        resolution: max joint step between edge samples (rad), finite and > 0.
        margin: safety distance added to every robot sphere in world checks (m), finite and >= 0.
        floor_z: no sphere of a moving link below this height in the roadmap (m); None (JSON null) disables
            the floor test. The default 0.0 is the ground of the built-in world models; scene sets use None
            (:data:`SCENE_SPEC_DEFAULTS`).
        extra_states: (M, D) further configurations (rad) made roadmap vertices 2..M+1 after start and goal,
            joined to their k nearest neighbours like every sample (e.g. the start and goal states of the
            MoveIt requests of a scene set); stored as a list of lists.
        collision_model: how world checks see the arm (name): ``"spheres"`` (the spherized model; fast, but
            an approximation: the Panda's collision meshes reach up to 8 cm outside it) or ``"meshes"`` (FCL BVH
            meshes of the URDF's collision geometry, as MoveIt).

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
    extra_states: Sequence[Sequence[float]] = ()
    collision_model: str = "spheres"

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
        if self.collision_model not in COLLISION_MODELS:
            raise ValueError(
                f"collision_model must be one of {', '.join(COLLISION_MODELS)}, got {self.collision_model!r}"
            )
        extra = _extra_states(self.extra_states)
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
            "extra_states": extra,
            "collision_model": str(self.collision_model),
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
    "extra_states",
    "collision_model",
)
