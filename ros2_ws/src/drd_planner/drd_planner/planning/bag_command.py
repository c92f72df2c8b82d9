"""``drd plan --bag``: plan a bag's request offline as the node would, and print its check log.

:func:`plan_bag` takes a :class:`BagPlanOptions` (made by :mod:`drd_planner.cli.plan`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drd_planner.core.status import PlanStatus
from drd_planner.exceptions import DrdError

__all__ = ["BagPlanOptions", "plan_bag", "print_check"]


@dataclass(frozen=True)
class BagPlanOptions:
    """One ``drd plan --bag``.

    Attributes:
        prior: the prior file, or a shipped tree's name (:func:`~drd_planner.planning.shipped.resolve_tree_path`).
        bag: the rosbag2 MCAP bag, or a shipped bag's name.
        request: the 0-based index of the bag's request to plan.
        frame: the planning frame (None: the bag's map frame, else "map").
        prior_start: plan from the prior's start when the bag has no robot state before the request.
        skip_refused_maps: plan on the maps before a map message the node would refuse (False: stop with
            its reason).
        max_checks: end the plan after this many checks (None: no cap).
        seed: the policy's seed.
    """

    prior: str
    bag: str
    request: int = 0
    frame: str | None = None
    prior_start: bool = False
    skip_refused_maps: bool = False
    max_checks: int | None = None
    seed: int = 0


def print_check(number: int, edge: int, ends: tuple[int, int] | None, free: bool, stage: str) -> None:
    """One line of the check log (``number`` 1-based; ``ends``: the edge's vertex ids, None for a motion)."""
    where = f" ({ends[0]}->{ends[1]})" if ends is not None else ""
    state = "free   " if free else "BLOCKED"
    print(f"  check {number:3d}: edge {edge:5d}{where:14s} {state} [{stage}]")


def _where(value: object) -> str:
    if isinstance(value, int):
        return f"vertex {value}"
    return "state " + str(np.round(np.asarray(value, dtype=np.float64), 3).tolist())


def plan_bag(options: BagPlanOptions) -> int:
    """Plan the ``request``-th request of ``bag`` with the prior ``prior``; 0 when a path was found.

    The plan starts at the robot's state in the bag before the request (``odom`` / ``joint_states``;
    ``--prior-start`` uses the prior's start when there is none) and goes to the request's goal as the
    node reads it (:func:`drd_planner.planning.bag_plan.plan_bag_request`). A map message before the request
    that the node would refuse (corrupt, another frame, over a limit) stops it with the reason, unless
    ``--skip-refused-maps`` plans on the maps before it as the node does (the refusals are then listed).
    """
    from drd_msgs_py.bags import bag_frame, read_bag
    from drd_msgs_py.exceptions import MessageError
    from drd_planner.planner.prior_file import load_prior
    from drd_planner.planning.bag_plan import plan_bag_request
    from drd_planner.planning.session import QuerySession
    from drd_planner.planning.shipped import resolve_bag_path, resolve_tree_path

    tree_path = resolve_tree_path(options.prior)
    session = QuerySession(load_prior(tree_path), name=tree_path.stem, max_checks=options.max_checks)
    try:
        messages = read_bag(resolve_bag_path(options.bag))
        frame = options.frame or bag_frame(messages) or "map"
        plan = plan_bag_request(
            session,
            messages,
            options.request,
            frame=frame,
            seed=options.seed,
            prior_start=options.prior_start,
        )
    except MessageError as exc:
        raise DrdError(str(exc)) from exc
    if plan.maps.refused and not options.skip_refused_maps:  # a corrupt or foreign map: say so, plan nothing
        raise DrdError(
            f"bag {options.bag}: {plan.maps.refused[0]} ({len(plan.maps.refused)} map message(s) before request "
            f"{options.request} refused; the node would plan on the maps before them, map version "
            f"{plan.maps.snapshot.version}: --skip-refused-maps plans that way)"
        )
    if plan.result.status is PlanStatus.REFUSED:  # a start or goal the prior cannot serve
        raise DrdError(f"request {options.request} refused: {plan.result.message}")
    snapshot, request, result = plan.maps.snapshot, plan.request, plan.result
    terrain = "none" if snapshot.terrain is None else "x".join(str(n) for n in snapshot.terrain.shape)
    robot = "" if plan.maps.robot_description is None else ", robot_description"
    print(
        f"bag {options.bag}: request {request.index} ({request.kind} at "
        f"+{(request.time_ns - messages[0].time_ns) / 1e9:.2f} s); "
        f"maps in {frame!r}: version {snapshot.version}, {len(snapshot.obstacles)} obstacles, terrain {terrain}{robot}"
    )
    for line in (*plan.maps.refused, *plan.notes):
        print(f"  refused: {line}")
    print(f"  from {_where(plan.start)} to {_where(plan.goal)}")
    for k, check in enumerate(result.checks):
        print_check(k + 1, check.edge, check.endpoints, check.free, check.stage)
    if not result.ok:
        print(f"  -> {result.outcome} after {len(result.checks)} checks: {result.message}")
        return 1
    print(
        f"  -> path ({len(result.path_edges)} edges) verified free after {len(result.checks)} checks "
        f"[query {result.query}, stage {result.stage}]"
    )
    print(f"  path edges: {list(result.path_edges)}")
    columns = session.domain.state_columns
    print(
        f"  path vertices ({columns}; 'state' is a state off the graph: the request's own start or goal, or a "
        "vertex roadmap growth added):"
    )
    num_vertices = session.prior.graph.num_vertices
    edges = list(result.path_edges)
    for k, vertex in enumerate(result.path_vertices):
        if vertex < num_vertices:
            state = session.vertex_state(vertex)
        else:  # where the path's motions meet it (a goal's heading is the one it arrives with)
            state = session.edge_states(edges[k])[0] if k < len(edges) else session.edge_states(edges[k - 1])[-1]
        label = f"{vertex:5d}" if vertex < num_vertices else "state"
        print(f"    {label}: " + " ".join(f"{v:9.3f}" for v in state))
    return 0
