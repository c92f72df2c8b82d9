"""The arm's plan picture: the end effector's paths in a top view (x, y) and a side view.

The side view is the vertical plane through the start-goal direction of the end effector. Both show
the obstacles' outlines projected on the plane, the edge layers (the positions of each edge's joint
samples, as the node publishes them) and the arm (its joint frames) at its start and goal; both views
carry the check numbers (placed off the obstacles once the figure's layout is fixed).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.pictures.geometry import (
    TOP,
    PictureError,
    PlanGeometry,
    domain_robot,
    end_states,
    shape_points,
    split_obstacles,
)
from drd_planner.pictures.style import EXTRA_COLOURS
from drd_planner.pictures.view import PanelView, PlanDrawing
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.session import QuerySession
from drd_planner.planning.session_plan import SessionPlan

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["arm_skeleton", "arm_views"]


def arm_skeleton(session: QuerySession, snapshot: MapSnapshot, q: FloatArray) -> FloatArray:
    """(D + 2, 3) joint-frame origins and the end effector (metres) of one (D,) arm configuration."""
    from drd_planner.geometry.robot import RobotModel

    robot = snapshot.robot if snapshot.robot is not None else domain_robot(session)
    if not isinstance(robot, RobotModel):
        raise PictureError(f"{session.name}: the arm domain has no robot model to draw")
    origins = robot.fk.frames(q)[0, :, :3, 3]
    return np.vstack([origins, session.positions(q, snapshot)])


def arm_views(
    top: Axes,
    side: Axes,
    session: QuerySession,
    snapshot: MapSnapshot,
    result: SessionPlan,
    geometry: PlanGeometry,
    drawing: PlanDrawing,
) -> None:
    """The arm's top (x, y) and side (vertical plane through start -> goal) views of the end effector."""
    start, goal = end_states(session, result)
    skeletons = {
        "start": arm_skeleton(session, snapshot, start),
        "goal": arm_skeleton(session, snapshot, goal),
    }
    heading = skeletons["goal"][-1, :2] - skeletons["start"][-1, :2]
    norm = float(np.linalg.norm(heading))
    across = np.array([heading[0] / norm, heading[1] / norm, 0.0]) if norm > 1e-6 else np.eye(3)[0]
    side_plane = np.stack([across, np.eye(3)[2]], axis=1)
    points = np.concatenate([geometry.points(), *skeletons.values()])
    _, solids = split_obstacles(snapshot)
    for ax, plane in ((top, TOP), (side, side_plane)):
        view = PanelView(ax, plane, drawing if ax is top else None)
        drawing.panels.append(view)
        view.draw_obstacles(snapshot, solid_label="obstacle")
        view.edges(geometry, result)
        for key, bones in skeletons.items():
            x, y = view.project(bones).T
            style = "-o" if key == "start" else "--o"
            ax.plot(
                x,
                y,
                style,
                color=EXTRA_COLOURS["arm"],
                lw=1.2,
                ms=3,
                alpha=0.8,
                zorder=7,
                label=f"arm at {key}",
            )
        view.endpoints(skeletons["start"][-1], skeletons["goal"][-1])
        outlines = [shape_points(s, p, plane) for s, p in solids]
        view.fit(np.concatenate([points, *outlines]), pad=0.05)
        ax.grid(True, linewidth=0.3, alpha=0.5)
    top.set_xlabel("x (m)")
    top.set_ylabel("y (m)")
    top.set_title("end effector, top view", fontsize=10)
    side.axhline(0.0, color="black", linewidth=0.8, zorder=1)
    side.set_xlabel("horizontal position along the start -> goal direction (m)")
    side.set_ylabel("z (m)")
    side.set_title("end effector, side view", fontsize=10)
    side.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), framealpha=0.9)
