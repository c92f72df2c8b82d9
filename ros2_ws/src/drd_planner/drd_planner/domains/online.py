"""The online side of a domain: what a planning session, the re-checker and the node need of it.

:class:`OnlineDomain` extends the offline :class:`~drd_planner.domains.base.Domain` (graph, worlds, checker of
a world) with what planning on map snapshots needs: the collision margin and check resolution, what a state
is (joint vector or pose, periodic coordinates), positions of states, the checker of a ready scene (with an
arm model from ``robot_description``), position goals, and the *sweep model* that bounds the space an edge's
check can touch (for re-checking only the plan edges a map update can reach,
:mod:`drd_planner.planning.replan`).

Its *capabilities* say what the node does with the domain's plans and inputs, so that ``planning/`` and
``ros/`` never ask which domain they hold: :attr:`~OnlineDomain.plans_joint_goals` (goals and starts are
joint vectors), :attr:`~OnlineDomain.robot_state_topic` (where the robot's state comes from),
:attr:`~OnlineDomain.publishes_joint_trajectory` (a plan goes out as a JointTrajectory, its Path the tool
point's), :attr:`~OnlineDomain.needs_robot_description` (positions and checks use the ``robot_description``
model) and :attr:`~OnlineDomain.state_columns` (what a state's numbers are, for people).

:class:`OnlineDefaults` implements the members for a domain whose states start with positions and that has
no sweep model and no arm (the planar and SE(2) domains); the helicopter and the arm override what they add.
No code outside ``domains/`` asks which concrete domain it holds: it asks this interface.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Literal, Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.domains.base import Domain, EdgeChecker
from drd_planner.exceptions import PlanningError
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.terrain import Heightfield

__all__ = [
    "BOX_SLACK",
    "EdgeSource",
    "OnlineDefaults",
    "OnlineDomain",
    "PositionGoals",
    "RobotStateTopic",
    "SweepSpheres",
]

if TYPE_CHECKING:
    from typing_extensions import TypeVar

    W = TypeVar("W", default=Any)
else:
    from typing import TypeVar

    W = TypeVar("W")

#: Metres added to every sweep sphere on top of the geometric bound (floating-point slack of FCL's tests).
BOX_SLACK = 1e-6

#: Per edge: ``(centres (M, 3), reach (M,))`` in metres, without the scene margin.
SweepSpheres = list[tuple[FloatArray, FloatArray]]

#: How a goal given as a position becomes a state: ``"pose"`` (the state is the position and a heading),
#: ``"vertex"`` (the vertex whose position is nearest), ``"none"`` (the domain has no position goals).
PositionGoals = Literal["pose", "vertex", "none"]

#: Where the robot's current state (a plan's start when the request gives none) comes from: ``"odom"``
#: (``nav_msgs/Odometry``: a pose) or ``"joint_states"`` (``sensor_msgs/JointState``: joint angles).
RobotStateTopic = Literal["odom", "joint_states"]


class EdgeSource(Protocol):
    """Where a sweep model reads an edge's states: a planning session (graph edges and its motions)."""

    def edge_states(self, edge: int) -> FloatArray:
        """(K, D) states along a graph edge or a motion the session knows, tail first."""
        ...

    def motion_states(self, edge: int) -> FloatArray | None:
        """(K, D) states of a motion edge id (>= E) the session knows; None for graph edges and unknown ids."""
        ...


@runtime_checkable
class OnlineDomain(Domain[W], Protocol[W]):
    """A domain a planning session serves on map snapshots (see the module docstring)."""

    @classmethod
    def from_spec(cls, spec: Mapping[str, Any], /) -> OnlineDomain[Any]:
        """The domain of ``spec``; ProblemError on unknown keys (naming the valid ones) or bad values."""
        ...

    @property
    def margin(self) -> float:
        """Collision margin in metres (the scenes of snapshots for this domain use it)."""
        ...

    @property
    def resolution(self) -> float:
        """Largest coordinate step between the checked samples of a straight edge (0: edges are stored)."""
        ...

    @property
    def robot(self) -> RobotModel | None:
        """The arm model the roadmap was built for (None: no arm)."""
        ...

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The arm's chain joint names, root to tip, when states are joint vectors (else empty)."""
        ...

    @property
    def vehicle_radius(self) -> float:
        """Radius (m) of the vehicle sphere checked at each state's position, without the margin (0: none)."""
        ...

    @property
    def periodic_dims(self) -> tuple[int, ...]:
        """State dimensions that are angles (rad), compared modulo 2 pi (the helicopter's heading: (3,))."""
        ...

    @property
    def position_goals(self) -> PositionGoals:
        """How a goal position becomes a state (see :data:`PositionGoals`)."""
        ...

    @property
    def has_sweep_model(self) -> bool:
        """Whether :meth:`sweep_spheres` bounds what an edge's check touches (else every edge is affected)."""
        ...

    @property
    def plans_joint_goals(self) -> bool:
        """Whether goals and starts are joint vectors (``goal_joints``, a MoveIt request); a start pose is refused."""
        ...

    @property
    def robot_state_topic(self) -> RobotStateTopic:
        """Where the robot's current state comes from (see :data:`RobotStateTopic`)."""
        ...

    @property
    def publishes_joint_trajectory(self) -> bool:
        """Whether a plan also goes out as a JointTrajectory; its Path is then the positions of its states."""
        ...

    @property
    def needs_robot_description(self) -> bool:
        """Whether positions and checks use the robot model of a ``robot_description`` (the snapshot's robot)."""
        ...

    @property
    def state_columns(self) -> str:
        """What the numbers of a state are, with their units (for people: tables, logs)."""
        ...

    def positions(self, states: npt.ArrayLike, robot: RobotModel | None = None) -> FloatArray:
        """(K, 3) positions (m, planning frame) of (K, D) states (the arm: its tool point with ``robot``)."""
        ...

    def scene_checker(self, scene: Scene, robot: RobotModel | None = None) -> EdgeChecker:
        """The edge checker of a ready scene (its own margin), with another arm model when given."""
        ...

    def state_from_position(self, xyz: npt.ArrayLike, yaw: float) -> FloatArray:
        """(D,) the state of a goal position (m) and yaw (rad) when :attr:`position_goals` is ``"pose"``."""
        ...

    def world_model_params(self, model: str) -> dict[str, Any]:
        """The JSON-able parameters of world model ``model`` (``{}`` when the spec holds none)."""
        ...

    def robot_loader(self) -> Callable[[str], RobotModel] | None:
        """Turns a ``robot_description`` URDF into an arm model for snapshots (None: no arm)."""
        ...

    def terrain_mismatch(self, terrain: Heightfield) -> str | None:
        """Why a terrain map cannot be this prior's ground (wrong place or datum), or None when it can be."""
        ...

    def sweep_robot(self, robot: RobotModel | None) -> RobotModel | None:
        """The arm model a sweep must use for a snapshot's ``robot`` (None: the domain's own)."""
        ...

    def sweep_spheres(self, source: EdgeSource, edges: Sequence[int], robot: RobotModel | None) -> SweepSpheres:
        """Per edge the spheres its check places, each grown by half a sample step (no margin).

        Raises:
            PlanningError: the domain has no sweep model.
        """
        ...


class OnlineDefaults(ABC):
    """Online members of a domain whose states start with positions, with no arm and no sweep model.

    The planar and SE(2) domains use these as they are; the helicopter and the arm override some.
    """

    @property
    @abstractmethod
    def name(self) -> str:
        """The registry name (each domain defines it)."""

    @property
    def margin(self) -> float:
        """No margin (0.0)."""
        return 0.0

    @property
    def resolution(self) -> float:
        """0.0: no straight-edge sampling."""
        return 0.0

    @property
    def robot(self) -> RobotModel | None:
        """None: no arm."""
        return None

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Empty: states are not joint vectors."""
        return ()

    @property
    def vehicle_radius(self) -> float:
        """0.0: a point robot."""
        return 0.0

    @property
    def periodic_dims(self) -> tuple[int, ...]:
        """None."""
        return ()

    @property
    def position_goals(self) -> PositionGoals:
        """``"none"``."""
        return "none"

    @property
    def has_sweep_model(self) -> bool:
        """False."""
        return False

    @property
    def plans_joint_goals(self) -> bool:
        """False: goals are positions (poses), not joint vectors."""
        return False

    @property
    def robot_state_topic(self) -> RobotStateTopic:
        """``"odom"``: the robot's state is a pose."""
        return "odom"

    @property
    def publishes_joint_trajectory(self) -> bool:
        """False: a plan goes out as a Path of its states."""
        return False

    @property
    def needs_robot_description(self) -> bool:
        """False: no robot model from ``robot_description``."""
        return False

    @property
    def state_columns(self) -> str:
        """The generic text (a domain says better)."""
        return "the domain's state coordinates"

    def positions(self, states: npt.ArrayLike, robot: RobotModel | None = None) -> FloatArray:
        """The first three columns of (K, D) states (fewer when D < 3)."""
        q = np.asarray(states, dtype=np.float64)
        return np.array(q[:, :3], dtype=np.float64)

    def scene_checker(self, scene: Scene, robot: RobotModel | None = None) -> EdgeChecker:
        """``self.checker(scene)``."""
        checker: EdgeChecker = self.checker(scene)  # type: ignore[attr-defined]
        return checker

    def robot_loader(self) -> Callable[[str], RobotModel] | None:
        """None: no arm."""
        return None

    def terrain_mismatch(self, terrain: Heightfield) -> str | None:
        """None: a domain without a terrain model can use any terrain (it does not check against it)."""
        return None

    def state_from_position(self, xyz: npt.ArrayLike, yaw: float) -> FloatArray:
        """Refused: states are not poses.

        Raises:
            PlanningError: always.
        """
        raise PlanningError(f"the {self.name} domain has no position goals")

    def world_model_params(self, model: str) -> dict[str, Any]:
        """No world model parameters beyond the spec: ``{}``."""
        return {}

    def sweep_robot(self, robot: RobotModel | None) -> RobotModel | None:
        """None: no arm."""
        return None

    def sweep_spheres(self, source: EdgeSource, edges: Sequence[int], robot: RobotModel | None) -> SweepSpheres:
        """Refused: no sweep model.

        Raises:
            PlanningError: always.
        """
        raise PlanningError(f"no sweep model for the {self.name} domain")
