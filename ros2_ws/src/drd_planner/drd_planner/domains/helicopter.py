"""The helicopter domain: an (x, y, z, heading) Dubins lattice, seeded terrain/wire/canyon worlds, FCL checks.

Pieces (one concept per module):

- :mod:`~drd_planner.domains.helicopter_lattice`: the state lattice and every edge's sampled trajectory;
- :mod:`~drd_planner.domains.helicopter_worlds`: the world models (``"wires"``, ``"canyon"``, ``"terrain"``,
  ``"corridors"``, each with optional no-fly zones) and the scene of a world;
- :mod:`~drd_planner.domains.helicopter_checker`: the sphere-sweep edge checker the node also uses.

- :mod:`~drd_planner.domains.helicopter_spec`: the spec (:class:`HelicopterParams`).

The sweep model (:meth:`HelicopterDomain.sweep_spheres`, for re-checking plans after a map update): the
vehicle sphere at every trajectory sample, grown by half a sample step.

Units: metres and radians (degrees where a name says ``_deg``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.domains.base import LatticeMembers
from drd_planner.domains.helicopter_checker import HelicopterChecker, obstacle_boxes
from drd_planner.domains.helicopter_lattice import HelicopterLattice, LatticeParams, build_lattice
from drd_planner.domains.helicopter_params import params_to_dict
from drd_planner.domains.helicopter_spec import HelicopterParams
from drd_planner.domains.helicopter_worlds import (
    WORLD_MODELS,
    HelicopterWorld,
    ModelParams,
    WorldFrame,
    generate_world,
    world_parts,
    world_scene,
)
from drd_planner.domains.online import BOX_SLACK, EdgeSource, OnlineDefaults, PositionGoals, SweepSpheres
from drd_planner.domains.pose_states import state_from_pose
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.terrain import Heightfield

__all__ = ["HelicopterDomain", "HelicopterParams"]


class HelicopterDomain(LatticeMembers[HelicopterLattice], OnlineDefaults):
    """Helicopter planning domain (implements :class:`drd_planner.domains.online.OnlineDomain`).

    The graph is the directed lattice (:attr:`lattice`, its trajectories and primitives), ``vertex_states``
    (V, 4) = x, y, z (m), heading (rad); the start vertex is (start x, start y, start level, heading 0), the
    goal vertex (goal x, goal y, goal level, heading 0).

    Args:
        lattice: lattice parameters (default :class:`LatticeParams`).
        vehicle_radius: vehicle sphere radius, metres (> 0, >= the lattice's sample spacing).
        margin: collision margin added to the radius, metres (>= 0).
        terrain_cell: grid spacing of generated terrain, metres.
        world_margin: how far generated terrain extends beyond the lattice corridor, metres.
        wire_segments: capsules per wire span in the scene (None: :meth:`Wire.default_segments`); the chain
            contains the wire and reaches at most ``2 sag / wire_segments**2`` metres beyond its surface
            (8 segments: 0.8 m for a 25 m sag), so fewer capsules are faster and a little conservative.
        models: per world model, its parameter record or a (partial) dict of it.

    Raises:
        ProblemError: invalid parameters.
    """

    def __init__(
        self,
        *,
        lattice: LatticeParams | None = None,
        vehicle_radius: float = 5.0,
        margin: float = 2.0,
        terrain_cell: float = 10.0,
        world_margin: float = 100.0,
        wire_segments: int | None = 8,
        models: Mapping[str, ModelParams | Mapping[str, Any]] | None = None,
    ) -> None:
        self._init(
            HelicopterParams(
                lattice=lattice or LatticeParams(),
                vehicle_radius=vehicle_radius,
                margin=margin,
                terrain_cell=terrain_cell,
                world_margin=world_margin,
                wire_segments=wire_segments,
                models=dict(models or {}),
            )
        )

    def _init(self, params: HelicopterParams) -> None:
        self._params = params
        self._radius = params.vehicle_radius
        self._margin = params.margin
        self._wire_segments = params.wire_segments
        self._lattice = build_lattice(params.lattice)
        states = self._lattice.graph.vertex_states
        assert states is not None
        keep = tuple((float(states[i, 0]), float(states[i, 1]), float(states[i, 2])) for i in (self.start, self.goal))
        lattice = self._lattice.params
        self._frame = WorldFrame(
            x_range=lattice.x_range,
            y_range=lattice.y_range,
            margin=params.world_margin,
            cell_size=params.terrain_cell,
            keep_clear=keep,
            clearance=self._radius + self._margin,
            lowest_level=lattice.z_levels[0],
        )

    # ------------------------------------------------------------------------------------------------
    # Spec

    @classmethod
    def from_params(cls, params: HelicopterParams) -> HelicopterDomain:
        """The domain of validated parameters."""
        domain = cls.__new__(cls)
        domain._init(params)
        return domain

    @classmethod
    def from_spec(cls, spec: Mapping[str, Any]) -> HelicopterDomain:
        """The domain of a (partial) spec dict; missing keys take the defaults.

        Raises:
            ProblemError: unknown keys (the valid ones named) or invalid values.
        """
        return cls.from_params(HelicopterParams.from_spec(spec))

    def spec(self) -> dict[str, Any]:
        """The full JSON-able spec (defaults filled in); ``from_spec(spec())`` rebuilds an equal domain."""
        return self._params.to_spec()

    @property
    def params(self) -> HelicopterParams:
        """The domain's parameters."""
        return self._params

    # ------------------------------------------------------------------------------------------------
    # Domain protocol

    @property
    def name(self) -> str:
        """``"helicopter"``."""
        return "helicopter"

    @property
    def world_models(self) -> tuple[str, ...]:
        """``("wires", "canyon", "terrain", "corridors")``."""
        return WORLD_MODELS

    @property
    def vehicle_radius(self) -> float:
        """Vehicle sphere radius in metres (the scene adds :attr:`margin`)."""
        return self._radius

    @property
    def margin(self) -> float:
        """Collision margin in metres."""
        return self._margin

    @property
    def frame(self) -> WorldFrame:
        """What the world models know of the lattice (corridor, terrain grid, keep-clear points)."""
        return self._frame

    def model_params(self, model: str) -> ModelParams:
        """The parameter record of world model ``model``."""
        return self._params.model(model)

    def world_model_params(self, model: str) -> dict[str, Any]:
        """The parameters of world model ``model`` as a JSON-able dict."""
        return params_to_dict(self.model_params(model))

    def make_world(self, model: str, seed: int) -> HelicopterWorld:
        """World ``seed`` of ``model`` (same arguments, same world)."""
        return generate_world(model, seed, self.model_params(model), self._frame)

    def scene(self, world: HelicopterWorld) -> Scene:
        """The collision scene of ``world`` with this domain's margin."""
        return world_scene(world, margin=self._margin, wire_segments=self._wire_segments)

    def checker(self, world: HelicopterWorld | Scene) -> HelicopterChecker:
        """The edge checker of a world (or of a ready scene, e.g. one built from ROS messages)."""
        boxes = None
        if isinstance(world, HelicopterWorld):
            parts = world_parts(world, wire_segments=self._wire_segments)
            scene = world_scene(world, margin=self._margin, parts=parts)
            boxes = obstacle_boxes([(shape, pose) for _name, shape, pose in parts])
        elif isinstance(world, Scene):
            scene = world
        else:
            raise ProblemError(f"helicopter checker needs a HelicopterWorld or a Scene, got {type(world).__name__}")
        return HelicopterChecker(scene, self._lattice.points, self._lattice.offsets, radius=self._radius, boxes=boxes)

    def edge_trajectories(self) -> list[FloatArray]:
        """Per edge (graph order) its (K_e, 4) samples: x, y, z (m), heading (rad)."""
        return self._lattice.trajectories()

    def check_metadata(self) -> dict[str, Any]:
        """How edges are checked, with units."""
        counts = np.diff(self._lattice.offsets)
        steps = np.linalg.norm(np.diff(self._lattice.points[:, :3], axis=0), axis=1)
        inner = np.ones(steps.size, dtype=bool)
        inner[self._lattice.offsets[1:-1] - 1] = False  # steps across edge boundaries
        return {
            "method": (
                "sphere at every trajectory sample (bisection order) vs FCL scene; centre under terrain = blocked"
            ),
            "vehicle_shape": "sphere",
            "vehicle_radius_m": self._radius,
            "margin_m": self._margin,
            "effective_radius_m": self._radius + self._margin,
            "sample_spacing_m": self._lattice.params.sample_spacing,
            "max_sample_step_m": float(steps[inner].max()) if inner.any() else 0.0,
            "samples_per_edge": {
                "min": int(counts.min()),
                "mean": float(counts.mean()),
                "max": int(counts.max()),
            },
            "terrain_cell_m": self._params.terrain_cell,
            "terrain_surface": "two triangles per grid cell",
            "wire_segments": self._wire_segments,
            "wire_model": "parabolic sag, capsule chain containing the wire",
        }

    # ------------------------------------------------------------------------------------------------
    # Online domain

    @property
    def periodic_dims(self) -> tuple[int, ...]:
        """(3,): the heading (rad)."""
        return (3,)

    @property
    def position_goals(self) -> PositionGoals:
        """``"pose"``: a goal position and yaw are the state (x, y, z, heading)."""
        return "pose"

    @property
    def state_columns(self) -> str:
        """Position and heading."""
        return "x, y, z m; heading rad"

    @property
    def has_sweep_model(self) -> bool:
        """True."""
        return True

    def state_from_position(self, xyz: npt.ArrayLike, yaw: float) -> FloatArray:
        """(4,) the state at ``xyz`` (m) with heading ``yaw`` (rad, wrapped to [-pi, pi)).

        Raises:
            PlanningError: the position is not three finite numbers, or the yaw is not finite.
        """
        return state_from_pose(xyz, yaw)

    def terrain_mismatch(self, terrain: Heightfield) -> str | None:
        """Why ``terrain`` cannot be this lattice's ground, or None when it can.

        Heights are taken as they come: metres above the lattice's own z = 0 (the datum its ``z_levels``
        are given in), x and y in the planning frame whose origin is the lattice's. A terrain whose grid
        does not reach the lattice's horizontal extent, or that lies above every vertex it reaches (its
        heights in another datum, such as above sea level), is not this prior's.
        """
        states = np.asarray(self.graph.vertex_states, dtype=np.float64)
        lo, hi = states[:, :3].min(axis=0), states[:, :3].max(axis=0)
        x0, x1, y0, y1 = terrain.extent
        where = (
            f"the terrain spans x [{x0:.0f}, {x1:.0f}] m, y [{y0:.0f}, {y1:.0f}] m, the prior's lattice "
            f"x [{lo[0]:.0f}, {hi[0]:.0f}] m, y [{lo[1]:.0f}, {hi[1]:.0f}] m"
        )
        if x1 < lo[0] or x0 > hi[0] or y1 < lo[1] or y0 > hi[1]:
            return (
                f"{where}: they do not overlap (terrain x, y are metres in the planning frame, whose origin "
                "is the lattice's)"
            )
        ground = terrain.height_at(states[:, :2])
        known = np.isfinite(ground)
        if known.any() and bool(np.all(ground[known] > states[known, 2])):
            return (
                f"every lattice vertex over the terrain lies below it (terrain heights there "
                f"{float(ground[known].min()):.0f} to {float(ground[known].max()):.0f} m, the lattice's "
                f"altitudes {lo[2]:.0f} to {hi[2]:.0f} m): terrain heights are metres above the lattice's "
                "z = 0, not above sea level or another datum"
            )
        return None

    def scene_checker(self, scene: Scene, robot: RobotModel | None = None) -> HelicopterChecker:
        """The edge checker of a ready scene (``robot`` is ignored: no arm)."""
        return self.checker(scene)

    def sweep_spheres(self, source: EdgeSource, edges: Sequence[int], robot: RobotModel | None) -> SweepSpheres:
        """Per edge: the (K, 3) trajectory samples and (K,) reach = vehicle radius + half a sample step.

        The samples are spaced by at most ``lattice.params.sample_spacing`` metres of arc length (the
        longest chord between two samples is taken too, in case a trajectory was sampled otherwise), so
        every point of the flown curve lies within half a step of a sample.
        """
        spacing = float(self._lattice.params.sample_spacing)
        out = []
        for e in edges:
            xyz = np.array(source.edge_states(int(e))[:, :3], dtype=np.float64)
            chord = float(np.linalg.norm(np.diff(xyz, axis=0), axis=1).max()) if xyz.shape[0] > 1 else 0.0
            reach = self._radius + 0.5 * max(spacing, chord) + BOX_SLACK
            out.append((xyz, np.full(xyz.shape[0], reach)))
        return out
