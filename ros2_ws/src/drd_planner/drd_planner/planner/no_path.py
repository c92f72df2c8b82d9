"""Why a plan found no path, in words a user can act on: the states (configurations), what was tried, what blocks.

:func:`no_path_reason` writes the reason of a NO_PATH result:

- the start and goal by their states (and vertex ids), not by internal ids alone;
- what was tried: the checks and blocked edges, and what roadmap growth added
  (:class:`~drd_planner.planner.result.GrowthReport`);
- **the endpoint rule** (any domain): when every edge joining the start (or goal) was checked blocked, the
  state itself is checked (a one-state ``check_motion``, or ``explain_motion`` of it when the oracle
  implements the optional :class:`~drd_planner.planner.connect.MotionExplainer` protocol: "" means free); the
  reason then says whether the state itself is blocked or only every motion leaving it, and, with an
  explainer, what blocks them;
- **the cut**: with an explainer, what blocks the blocked edges around the smaller of the start's and the
  goal's known-reachable parts (vertices reached over edges checked free), counted per cause (e.g. ``scene
  object 'Can1' (panda_hand) x 5``).

Explanations run only here, after the plan failed; they never change an outcome.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable

import numpy as np

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.core.episode import CheckRecord, EdgeOracle
from drd_planner.core.status import PlanCause
from drd_planner.planner.connect import MotionExplainer, MotionOracle
from drd_planner.planner.growth_samples import known_reachable
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.query_graph import QueryGraph
from drd_planner.planner.result import GrowthReport

__all__ = ["EdgeStates", "blocked_end", "edge_states_of", "no_path_reason"]

#: (K, D) states along an edge of the query's graph, or None when unknown.
EdgeStates = Callable[[int], FloatArray | None]
#: Blocked edges (around the cut, or joining an endpoint) whose causes are looked up, at most: each explanation
#: is a collision query of its own, and an endpoint joined by thousands of motions must not take minutes.
MAX_EXPLAINED = 8


def edge_states_of(prior: WorldPrior, query: QueryGraph, segment: Callable[..., FloatArray] | None) -> EdgeStates:
    """The states along an edge: a motion's own, a stored trajectory, or ``segment(tail, head)`` (straight)."""
    trajectories = prior.edge_trajectories
    states = query.graph.vertex_states

    def along(edge: int) -> FloatArray | None:
        if edge in query.motions:
            return np.asarray(query.motions[edge], dtype=np.float64)
        if trajectories is not None and edge < len(trajectories):
            return np.asarray(trajectories[edge], dtype=np.float64)
        if segment is None or states is None:
            return None
        u, v = query.graph.edges[edge]
        return segment(states[u], states[v])

    return along


def _state_text(query: QueryGraph, vertex: int, label: str) -> str:
    """``the goal [0.1, ...]`` (an off-graph state) or ``the goal (vertex 38: [0.1, ...])``."""
    states = query.graph.vertex_states
    if states is None:
        return f"the {label} (vertex {vertex})"
    values = [round(float(x), 3) for x in states[vertex]]
    return f"the {label} {values}" if vertex in query.new_states else f"the {label} (vertex {vertex}: {values})"


def _causes(explainer: MotionExplainer, motions: list[FloatArray]) -> str:
    """``A x 3, B x 1`` over the explanations of ``motions`` (their "at sample" part dropped)."""
    tally: Counter[str] = Counter()
    for states in motions:
        why = explainer.explain_motion(states).rsplit(" at sample ", 1)[0]
        tally[why or "not blocked when explained"] += 1
    return ", ".join(f"{cause} x {count}" if count > 1 else cause for cause, count in tally.most_common(4))


def _end_edges(query: QueryGraph, vertex: int) -> tuple[IntArray, IntArray]:
    """The vertex edges of an end (its state itself, checked by growth) and the edges joining it to the graph."""
    edges = query.graph.edges
    touching = (edges == vertex).any(axis=1)
    loops = touching & (edges[:, 0] == edges[:, 1])
    return np.flatnonzero(loops), np.flatnonzero(touching & ~loops)


def _end_blocked(query: QueryGraph, vertex: int, outcome: dict[int, bool]) -> bool:
    """The endpoint rule: the end's state itself, or every edge joining it to the graph, was checked blocked."""
    loops, incident = _end_edges(query, vertex)
    if any(outcome.get(int(e)) is False for e in loops.tolist()):
        return True
    return incident.size > 0 and all(outcome.get(int(e)) is False for e in incident.tolist())


def blocked_end(query: QueryGraph, checks: list[CheckRecord]) -> PlanCause | None:
    """The cause of a NO_PATH result by the endpoint rule: the start's when both ends are walled in, else None."""
    outcome = {c.edge: c.free for c in checks}
    for vertex, label in ((query.start, "start"), (query.goal, "goal")):
        if _end_blocked(query, vertex, outcome):
            return PlanCause.blocked(label)
    return None


def _endpoint_text(
    query: QueryGraph,
    vertex: int,
    label: str,
    outcome: dict[int, bool],
    oracle: EdgeOracle,
    along: EdgeStates,
) -> str:
    """The endpoint rule for one end (see the module docstring); "" when some edge at it was free or unchecked."""
    loops, incident = _end_edges(query, vertex)
    states = query.graph.vertex_states
    explainer = oracle if isinstance(oracle, MotionExplainer) else None
    if any(outcome.get(int(e)) is False for e in loops.tolist()):
        why = "" if explainer is None or states is None else f": {explainer.explain_motion(states[vertex][None])}"
        return f"the {label} state itself is blocked (checked){why}"
    if incident.size == 0 or not all(outcome.get(int(e)) is False for e in incident.tolist()):
        return ""
    lengths = query.graph.lengths[incident]
    what = (
        f"all {incident.size} edges joining {_state_text(query, vertex, label)} to the graph "
        f"({lengths.min():.3g}-{lengths.max():.3g} long) were checked blocked"
    )
    if states is not None:
        alone = states[vertex][None]
        if explainer is not None:  # an explanation checks without side effects on the plan's oracle
            why = explainer.explain_motion(alone)
            if why:
                return f"{what}, and the {label} state itself is blocked: {why}"
        elif isinstance(oracle, MotionOracle) and not oracle.check_motion(alone):
            return f"{what}, and the {label} state itself is blocked"
    if explainer is None:
        return f"{what}; the {label} state itself is free"
    shortest = incident[np.argsort(lengths, kind="stable")][:MAX_EXPLAINED]
    motions = [m for m in (along(int(e)) for e in shortest.tolist()) if m is not None]
    which = "the motions" if len(motions) == incident.size else f"the {len(motions)} shortest motions"
    return f"{what}; the {label} state itself is free, {which} are blocked by {_causes(explainer, motions)}"


def _cut_text(query: QueryGraph, outcome: dict[int, bool], oracle: EdgeOracle, along: EdgeStates) -> str:
    """What blocks the blocked edges around the smaller known-reachable side ("" without an explainer)."""
    if not isinstance(oracle, MotionExplainer):
        return ""
    graph = query.graph
    known = np.zeros(graph.num_edges, dtype=np.int8)
    for edge, free in outcome.items():
        known[edge] = 1 if free else -1
    sides = [
        (known_reachable(graph.num_vertices, graph.edges, known > 0, v), label)
        for v, label in ((query.start, "start"), (query.goal, "goal"))
    ]
    side, label = min(sides, key=lambda item: item[0].size)
    inside = np.zeros(graph.num_vertices, dtype=bool)
    inside[side] = True
    crossing = inside[graph.edges].sum(axis=1) == 1
    cut = np.flatnonzero(crossing & (known < 0))
    if cut.size == 0:
        return ""
    cut = cut[np.argsort(graph.lengths[cut], kind="stable")][:MAX_EXPLAINED]
    motions = [m for m in (along(int(e)) for e in cut.tolist()) if m is not None]
    if not motions:
        return ""
    return (
        f"the {label}'s reachable part ({side.size} vertices over edges checked free) is walled in by blocked "
        f"edges; the {len(motions)} shortest are blocked by {_causes(oracle, motions)}"
    )


def no_path_reason(
    query: QueryGraph,
    checks: list[CheckRecord],
    oracle: EdgeOracle,
    along: EdgeStates,
    growth: GrowthReport | None = None,
) -> str:
    """The reason of a NO_PATH result (see the module docstring).

    Args:
        query: the query's graph the search ended on (the grown one after growth).
        checks: the plan's check log.
        oracle: the plan's oracle, unwrapped (``check_motion`` and ``explain_motion`` when it has them).
        along: the states of an edge, for explanations.
        growth: what roadmap growth did (None: the graph did not grow).
    """
    outcome = {c.edge: c.free for c in checks}
    blocked = sum(not free for free in outcome.values())
    ends = f"{_state_text(query, query.start, 'start')} to {_state_text(query, query.goal, 'goal')}"
    if growth is not None and growth.stop.endswith("_blocked"):
        head = f"no path from {ends} can exist ({blocked} of the plan's {len(checks)} checks blocked)"
    elif growth is not None:
        head = (
            f"no free path found from {ends} within the growth budget ({growth.summary()}; {blocked} of the "
            f"plan's {len(checks)} checks blocked)"
        )
    elif blocked:
        head = f"no free path from {ends} in the graph: {blocked} blocked edges disconnect them ({len(checks)} checks)"
    else:
        directed = " (its edges are directed)" if query.graph.directed else ""
        return f"the graph has no path from {ends} even with every edge free{directed}"
    parts = [head]
    for vertex, label in ((query.start, "start"), (query.goal, "goal")):
        parts.append(_endpoint_text(query, vertex, label, outcome, oracle, along))
    if not any(parts[1:]):
        parts.append(_cut_text(query, outcome, oracle, along))
    return "; ".join(p for p in parts if p)
