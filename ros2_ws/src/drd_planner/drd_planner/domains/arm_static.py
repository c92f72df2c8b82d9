"""Why an arm configuration fails the static test, in words (for errors about a start or goal).

:func:`drd_planner.domains.arm_roadmap.statically_valid` answers yes or no for many configurations at once;
:func:`static_problems` says, for one configuration, which of its three checks failed and what to
change: the joint limits (which joint, its value and range), self-collision (which two links touch) or
the floor (which link reaches how low, and the ``floor_z`` parameter that sets the floor).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.geometry.robot import RobotModel

__all__ = [
    "WHERE",
    "floor_accepting",
    "limits_text",
    "lowest_bottoms",
    "lowest_link",
    "static_problems",
    "touching_links",
]


#: Where the user changes a parameter named in a message.
WHERE = "in the arm spec (--domain-spec)"


def static_problems(robot: RobotModel, q: npt.ArrayLike, *, floor_z: float | None, name: str) -> list[str]:
    """The checks the (D,) configuration ``q`` fails, one sentence each; empty when it is statically valid.

    Each sentence names the check (joint limits: joint, value and range; self-collision: the two links;
    floor: the link whose sphere reaches lowest, how low, and ``floor_z``) and the spec parameters that
    change the outcome (``name`` itself, ``floor_z`` with the value that would accept ``q``, ``srdf_path``).

    Args:
        robot: the robot (limits, spheres, self-collision pairs).
        q: the configuration (rad).
        floor_z: the floor height of the static test (m); None: no floor.
        name: what ``q`` is in the spec (``"start"``, ``"goal"``, ``"extra_states[3]"``).
    """
    qa = robot.fk.as_configurations(np.asarray(q, dtype=np.float64).reshape(1, -1))
    config = qa[0]
    problems: list[str] = []
    joints = limits_text(robot, config)
    if joints:
        problems.append(f"outside the joint limits ({joints} rad): change {name} {WHERE}")
    if bool(robot.self_collision(qa)[0]):
        problems.append(
            f"self-colliding ({touching_links(robot, qa)}): change {name} {WHERE}, or exclude the pair in the "
            "SRDF (srdf_path)"
        )
    if floor_z is not None:
        problems.extend(_floor_problem(robot, qa, floor_z, name))
    return problems


def limits_text(robot: RobotModel, q: npt.ArrayLike) -> str:
    """The joints of the (D,) configuration ``q`` (rad) outside their limits, ``"; "``-joined; "" when none.

    Each as ``<joint> = <value> not in [<lower>, <upper>]`` (rad, three decimals).
    """
    config = np.asarray(q, dtype=np.float64).reshape(-1)
    outside = np.flatnonzero((config < robot.lower) | (config > robot.upper))
    return "; ".join(
        f"{robot.chain.joint_names[j]} = {config[j]:.3f} not in [{robot.lower[j]:.3f}, {robot.upper[j]:.3f}]"
        for j in outside.tolist()
    )


def lowest_bottoms(robot: RobotModel, q: npt.ArrayLike) -> FloatArray:
    """(N,) height (m) of the lowest point of any moving link's sphere, for (N, D) configurations (rad)."""
    qa = robot.fk.as_configurations(q)
    moving = robot.spheres.frame_index > 0
    bottoms = robot.sphere_centres(qa)[:, moving, 2] - robot.spheres.radii[moving]
    out: FloatArray = bottoms.min(axis=1) if bottoms.shape[1] else np.full(qa.shape[0], np.inf)
    return out


def floor_accepting(lowest: float) -> float:
    """The highest floor height (m) on a centimetre grid that accepts a lowest sphere bottom ``lowest`` (m)."""
    return math.floor(lowest * 100.0 - 1e-9) / 100.0


def _floor_problem(robot: RobotModel, qa: npt.NDArray[np.float64], floor_z: float, name: str) -> list[str]:
    """The floor sentence for the (1, D) configuration ``qa``, or none when every moving sphere is above."""
    link, bottom = lowest_link(robot, qa)
    if bottom >= floor_z:
        return []
    return [
        f"below the floor (a sphere of {link} reaches down to z = {bottom:.3f} m, the floor is at "
        f"floor_z = {floor_z:g} m): set floor_z to {floor_accepting(bottom):g} or lower, or "
        f"null (no floor test), {WHERE}, or change {name}"
    ]


def lowest_link(robot: RobotModel, qa: npt.NDArray[np.float64]) -> tuple[str, float]:
    """``(link, z)``: the moving link reaching lowest in the (1, D) configuration ``qa`` (rad), and how low.

    ``z`` is the height (m) of the bottom of that link's lowest sphere; ``("", inf)`` without moving spheres.
    """
    moving = np.flatnonzero(robot.spheres.frame_index > 0)
    if moving.size == 0:
        return "", float("inf")
    bottoms = robot.sphere_centres(qa)[0, moving, 2] - robot.spheres.radii[moving]
    lowest = int(np.argmin(bottoms))
    return robot.chain.link_names[int(robot.spheres.link_index[moving[lowest]])], float(bottoms[lowest])


def touching_links(robot: RobotModel, qa: npt.NDArray[np.float64]) -> str:
    """The first checked link pair whose spheres overlap in the (1, D) configuration ``qa`` (rad).

    ``"<link> touches <link>"``, or ``"two links touch"`` when no sphere pair overlaps (a pair excluded by
    the SRDF never counts).
    """
    centres = robot.sphere_centres(qa)[0]
    a, b = robot.self_pairs[:, 0], robot.self_pairs[:, 1]
    gap = np.einsum("ki,ki->k", centres[a] - centres[b], centres[a] - centres[b])
    hits = np.flatnonzero(gap < (robot.spheres.radii[a] + robot.spheres.radii[b]) ** 2)
    if hits.size == 0:
        return "two links touch"
    names = robot.chain.link_names
    link_a = names[int(robot.spheres.link_index[a[hits[0]]])]
    link_b = names[int(robot.spheres.link_index[b[hits[0]]])]
    return f"{link_a} touches {link_b}"
