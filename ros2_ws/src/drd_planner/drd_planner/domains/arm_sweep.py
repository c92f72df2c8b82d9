"""The arm's sweep model: the spheres an edge's check places, grown by how far they move between samples.

For re-checking only the plan edges a map update can reach (:mod:`drd_planner.planning.replan`): an edge's
checked configurations are both end vertices and the interior samples of the roadmap's
:class:`~drd_planner.domains.arm_roadmap.EdgeSamples` (the fixed base spheres are in every one); a motion
edge's are its own samples, exactly what :meth:`~drd_planner.domains.arm_checker.ArmEdgeChecker.check_motion`
tests. Each sphere's reach is its radius plus half the distance it can move in one sample step: the joint
step times :meth:`ArmSweep.rates` (a bound on each centre's speed per unit of each joint).
"""

from __future__ import annotations

import weakref
from collections.abc import Sequence

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.arm_roadmap import EdgeSamples
from drd_planner.domains.online import BOX_SLACK, EdgeSource, SweepSpheres
from drd_planner.exceptions import PlanningError
from drd_planner.geometry.robot import RobotModel

__all__ = ["ArmSweep", "sphere_rates"]


def sphere_rates(robot: RobotModel) -> FloatArray:
    """(D, S) upper bounds (m per rad, or m per m for prismatic joints) on each sphere centre's speed.

    Joint k turns everything on moving frames k + 1 .. D about an axis through frame k + 1's origin, so a
    centre moves at most its distance from that origin per radian; that distance is bounded, whatever the
    other joints do, by the joint-origin offsets along the chain (plus the prismatic travel within the
    limits) and the sphere's offset in its own frame. A prismatic joint moves a centre 1 m per m.
    """
    chain, spheres = robot.chain, robot.spheres
    prismatic = np.array([t == "prismatic" for t in chain.joint_types])
    travel = np.where(prismatic, np.maximum(np.abs(chain.lower), np.abs(chain.upper)), 0.0)
    link = np.linalg.norm(chain.joint_origins[:, :3, 3], axis=1) + travel  # frame j -> j + 1 offset bound
    own = np.linalg.norm(spheres.centres, axis=1)
    rates = np.zeros((chain.dof, spheres.count))
    for s, frame in enumerate(spheres.frame_index.tolist()):
        for k in range(frame):  # joints 0 .. frame - 1 move frame `frame`
            rates[k, s] = 1.0 if prismatic[k] else float(link[k + 1 : frame].sum() + own[s])
    return rates


class ArmSweep:
    """The sweep spheres of a roadmap's edges and of motions off it (see the module docstring).

    Args:
        graph: the roadmap; ``vertex_states`` (V, D) in radians.
        samples: its edges' interior samples (the checker's).
    """

    def __init__(self, graph: ExplicitGraph, samples: EdgeSamples) -> None:
        self._graph = graph
        self._samples = samples
        self._rates: weakref.WeakKeyDictionary[RobotModel, FloatArray] = weakref.WeakKeyDictionary()

    def rates(self, robot: RobotModel) -> FloatArray:
        """(D, S) :func:`sphere_rates` of ``robot`` (computed once per model)."""
        cached = self._rates.get(robot)
        if cached is None:
            cached = sphere_rates(robot)
            self._rates[robot] = cached
        return cached

    def _configurations(
        self, source: EdgeSource, edge: int, radii: FloatArray, rates: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """(M, D) checked configurations of one edge and (M * S,) reach of every sphere in them."""
        motion = source.motion_states(edge) if edge >= self._graph.num_edges else None
        if motion is not None:
            q = np.asarray(motion, dtype=np.float64)
            step = np.abs(np.diff(q, axis=0)).max(axis=0) if q.shape[0] > 1 else np.zeros(q.shape[1])
            return q, np.tile(radii + 0.5 * (step @ rates) + BOX_SLACK, q.shape[0])
        states = self._graph.vertex_states
        if states is None:
            raise PlanningError("the arm graph has no vertex states")
        u, v = (int(x) for x in self._graph.edges[edge])
        interior = self._samples.configurations(self._graph, edge)
        step = np.abs(states[v] - states[u]) / (interior.shape[0] + 1)  # fractions are k / n, n = interior + 1
        reach = np.tile(radii + 0.5 * (step @ rates) + BOX_SLACK, interior.shape[0] + 2)
        return np.concatenate([states[[u, v]], interior]), reach

    def spheres(
        self,
        source: EdgeSource,
        edges: Sequence[int],
        robot: RobotModel,
        growth: FloatArray | None = None,
    ) -> SweepSpheres:
        """Per edge (M, 3) centres and (M,) reach (m) of every robot sphere at every checked configuration.

        Args:
            source: the planning session whose graph edges and motions are swept.
            edges: edge ids (into ``source``'s graph).
            robot: the arm model whose spheres sweep.
            growth: (S,) metres added to every sphere radius first (None: none): under the mesh collision
                model, the growth that makes the spheres contain the link meshes.
        """
        rates = self.rates(robot)
        radii = robot.spheres.radii if growth is None else robot.spheres.radii + growth
        blocks: list[FloatArray] = []
        reaches: list[FloatArray] = []
        for e in edges:
            block, reach = self._configurations(source, int(e), radii, rates)
            blocks.append(block)
            reaches.append(reach)
        centres = robot.sphere_centres(np.concatenate(blocks))  # (sum of counts, S, 3): one batched FK
        out = []
        start = 0
        for block, reach in zip(blocks, reaches, strict=True):
            count = block.shape[0]
            out.append((centres[start : start + count].reshape(-1, 3), reach))
            start += count
        return out
