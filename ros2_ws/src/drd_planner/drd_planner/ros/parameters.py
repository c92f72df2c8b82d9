"""The node's parameters: one table with defaults, descriptions, ranges, and the checks a value must pass.

:func:`declare_parameters` declares them with ``ParameterDescriptor`` s (description, range, read-only),
:func:`parameter_problems` checks a set of values; the node runs it at ``configure`` (over the values
it starts from, overrides included) and on every runtime change (a bad change is refused with its
reason, the old value stays). Parameters read at ``configure`` (priors, frame, tolerances, check cap,
budgets) take effect at the next ``configure``; ``seed`` and ``replan_on_map_update`` at the next plan.
:func:`plan_budgets_of` turns the budget parameters into the priors' plan budgets; :func:`prior_paths_of`
reads the prior files from ``prior_paths`` or its deprecated alias ``tree_paths``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

from drd_planner.geometry.map_limits import MapLimits

if TYPE_CHECKING:
    from drd_planner.planning.requests import GoalTolerances
    from drd_planner.planning.session import SessionBudgets

__all__ = [
    "MAP_LIMIT_PARAMETERS",
    "PARAMETERS",
    "ParameterSpec",
    "check_cost_of",
    "declare_parameters",
    "map_limits_of",
    "parameter_problems",
    "plan_budgets_of",
    "prior_paths_of",
]

#: Largest goal tolerance (metres) a goal may be off a graph vertex and be that vertex; beyond it a request
#: would match vertices far from the goal it asked for.
MAX_GOAL_TOLERANCE_M = 100.0
#: Largest joint tolerance (radians).
MAX_JOINT_TOLERANCE_RAD = math.pi
#: Largest stated check cost (ms of CPU per check).
MAX_CHECK_COST_MS = 10_000.0


def _positive_at_most(limit: float, unit: str) -> Callable[[Any], str | None]:
    def check(value: Any) -> str | None:
        v = float(value)
        if not (math.isfinite(v) and 0.0 < v <= limit):
            return f"must be finite, > 0 and <= {limit:g} {unit}, got {v}"
        return None

    return check


def _non_negative(value: Any) -> str | None:
    return None if int(value) >= 0 else f"must be >= 0, got {int(value)}"


def _frame(value: Any) -> str | None:
    text = str(value)
    if not text or len(text) > 256 or not text.isprintable() or " " in text:
        return "must be a non-empty frame name of at most 256 printable characters without spaces"
    return None


def _topic(value: Any) -> str | None:
    text = str(value)
    if not text or len(text) > 256 or not all(c.isalnum() or c in "_/~" for c in text):
        return "must be a topic name (letters, digits, _ and /, at most 256 characters)"
    return None


def _one_of(*choices: str) -> Callable[[Any], str | None]:
    def check(value: Any) -> str | None:
        return None if str(value) in choices else f"must be one of {', '.join(choices)}, got {str(value)[:40]!r}"

    return check


def _check_cost(value: Any) -> str | None:
    v = float(value)
    if math.isfinite(v) and 0.0 <= v <= MAX_CHECK_COST_MS:
        return None
    return f"must be finite, >= 0 and <= {MAX_CHECK_COST_MS:g} ms, got {v}"


def check_cost_of(values: Mapping[str, Any]) -> float | None:
    """The planners' ``check_cost_ms`` from the checked parameter value (missing or 0: not stated, None)."""
    cost = float(values.get("check_cost_ms", 0.0))
    return cost if cost > 0.0 else None


def _non_negative_seconds(value: Any) -> str | None:
    v = float(value)
    return None if math.isfinite(v) and 0.0 <= v <= 3600.0 else f"must be finite, >= 0 and <= 3600 s, got {v}"


def _prior_paths(value: Any) -> str | None:
    names = [str(v) for v in value]
    if len(names) > 64 or any(len(n) > 4096 for n in names):
        return "names at most 64 prior files of at most 4096 characters each"
    return None


@dataclass(frozen=True)
class ParameterSpec:
    """One parameter.

    Attributes:
        name: the parameter's name.
        default: its value when not overridden (its type is the parameter's type).
        description: what it means, with its unit.
        check: returns why a value is refused, or None.
        read_only: changing it after the node started is refused (it shapes what was loaded).
        float_range: ``(low, high)`` advertised in the descriptor (metres or radians), or None.
        int_range: ``(low, high)`` advertised in the descriptor, or None.
        deprecated_for: the parameter that replaces this one (a deprecated alias, read only while the
            new one is left at its default), or None.
    """

    name: str
    default: Any
    description: str
    check: Callable[[Any], str | None] | None = None
    read_only: bool = False
    float_range: tuple[float, float] | None = None
    int_range: tuple[int, int] | None = None
    deprecated_for: str | None = None

    @property
    def full_description(self) -> str:
        """The description, after ``Deprecated: use <new name>.`` for a deprecated alias."""
        if self.deprecated_for is None:
            return self.description
        return f"Deprecated: use {self.deprecated_for}. {self.description}"

    def descriptor(self) -> ParameterDescriptor:
        """The rclpy descriptor (shown by ``ros2 param describe``)."""
        descriptor = ParameterDescriptor(description=self.full_description, read_only=self.read_only)
        if self.float_range is not None:
            descriptor.floating_point_range = [
                FloatingPointRange(from_value=self.float_range[0], to_value=self.float_range[1], step=0.0)
            ]
        if self.int_range is not None:
            descriptor.integer_range = [IntegerRange(from_value=self.int_range[0], to_value=self.int_range[1], step=0)]
        return descriptor


INT64_MAX = 2**63 - 1

#: Every parameter of the node.
PARAMETERS: tuple[ParameterSpec, ...] = (
    ParameterSpec(
        "prior_paths",
        [""],
        "World prior files (.npz; a tree file loads as a prior of its one query), or the names of shipped "
        "priors such as heli_wires; read at configure.",
        _prior_paths,
    ),
    ParameterSpec(
        "tree_paths",
        [""],
        "Alias of prior_paths, removed in the next release: read at configure only while prior_paths is "
        "left at its default; setting both fails configure.",
        _prior_paths,
        deprecated_for="prior_paths",
    ),
    ParameterSpec("frame_id", "map", "The planning frame: maps and goals must be in it; read at configure.", _frame),
    ParameterSpec("seed", 0, "Seed of every random choice of a plan (same seed, same checks).", _non_negative),
    ParameterSpec(
        "max_checks",
        0,
        "Most edge checks per plan (0: no cap); read at configure.",
        _non_negative,
        int_range=(0, INT64_MAX),
    ),
    ParameterSpec(
        "goal_tolerance",
        1.0,
        "Metres per axis within which a goal position is a graph vertex (the prior's stored goal first; "
        "farther, a helicopter goal is joined by new motions, an arm's end-effector goal is refused); read "
        "at configure.",
        _positive_at_most(MAX_GOAL_TOLERANCE_M, "m"),
        float_range=(0.0, MAX_GOAL_TOLERANCE_M),
    ),
    ParameterSpec(
        "joint_tolerance",
        0.05,
        "Radians per joint within which an arm goal is a roadmap vertex (the prior's stored goal first; "
        "farther, new motions join it); read at configure.",
        _positive_at_most(MAX_JOINT_TOLERANCE_RAD, "rad"),
        float_range=(0.0, MAX_JOINT_TOLERANCE_RAD),
    ),
    ParameterSpec(
        "goal_yaw_tolerance",
        0.1,
        "Radians within which a helicopter goal's yaw matches a vertex's heading (else the path ends at exactly "
        "that yaw; a goal with the zero quaternion has no yaw: any heading); read at configure.",
        _positive_at_most(math.pi, "rad"),
        float_range=(0.0, math.pi),
    ),
    ParameterSpec("autostart", False, "planner_node configures and activates itself at start.", read_only=True),
    ParameterSpec(
        "map_subscribe_transient_local",
        True,
        "Map subscriptions (obstacles, terrain, robot_description) ask for transient_local durability, so "
        "they get a latched map published before the node started; false: volatile, which also hears "
        "volatile publishers (most perception nodes, RViz tools) but no history. Read at activate; "
        "qos_overrides.<topic>.subscription.* parameters tune depth, reliability and history.",
    ),
    ParameterSpec(
        "odom_topic",
        "odom",
        "nav_msgs/Odometry of the helicopter (pose in frame_id): where its plans start. Read at activate.",
        _topic,
    ),
    ParameterSpec(
        "joint_states_topic",
        "joint_states",
        "sensor_msgs/JointState of the arm (extra joints are ignored): where its plans start. Read at activate.",
        _topic,
    ),
    ParameterSpec(
        "start_without_robot_state",
        "refuse",
        "A request before any robot state arrived: 'refuse' it, or plan from the prior's stored start "
        "('prior_start', for replays and tests without odometry).",
        _one_of("refuse", "prior_start"),
    ),
    ParameterSpec(
        "planning_time_budget",
        0.0,
        "Seconds a plan may take before it ends with status budget_exhausted (cause time_budget; 0: no limit); "
        "read at configure.",
        _non_negative_seconds,
        float_range=(0.0, 3600.0),
    ),
    ParameterSpec(
        "check_cost_ms",
        0.0,
        "What one collision check costs on this robot, in ms of CPU (0: not stated). Stated, a query without a "
        "precomputed tree first runs a lazy search for at most as many checks as building its path library "
        "would cost (that cost is measured at configure) and builds the library only if the search verified no "
        "path: faster where checks are cheap. Read at configure.",
        _check_cost,
        float_range=(0.0, MAX_CHECK_COST_MS),
    ),
    ParameterSpec(
        "improve_checks",
        0,
        "Anytime improvement: most extra edge checks per plan after its first verified path, spent looking "
        "for shorter verified paths (0: no check limit). The improvement runs when improve_checks or "
        "improve_time_budget is > 0 (both 0: off, the first path is published); max_checks and "
        "planning_time_budget bound it too. Read at configure.",
        _non_negative,
        int_range=(0, INT64_MAX),
    ),
    ParameterSpec(
        "improve_time_budget",
        0.0,
        "Anytime improvement: most seconds per plan after its first verified path (0: no time limit); "
        "see improve_checks for when the improvement runs. Read at configure.",
        _non_negative_seconds,
        float_range=(0.0, 3600.0),
    ),
    ParameterSpec(
        "replan_on_map_update",
        True,
        "Re-check the published plan on every map update and replan (or withdraw it) when it is blocked.",
    ),
)


def _limit_check(name: str) -> Callable[[Any], str | None]:
    return lambda value: MapLimits.check_value(name, value)


#: The map limits (:class:`~drd_planner.geometry.map_limits.MapLimits`), one parameter each: checked
#: before a map message is decoded; a map beyond one is refused naming it. Read at configure.
MAP_LIMIT_PARAMETERS: tuple[ParameterSpec, ...] = tuple(
    ParameterSpec(
        name, default, f"{MapLimits.descriptions()[name].rstrip('.')}; read at configure.", _limit_check(name)
    )
    for name, default in MapLimits.DEFAULT.as_parameters().items()
)
PARAMETERS = PARAMETERS + MAP_LIMIT_PARAMETERS


def map_limits_of(values: Mapping[str, Any]) -> MapLimits:
    """The :class:`MapLimits` of the node's parameter values (name -> value; other names are ignored)."""
    return MapLimits.from_parameters(values)


def _names(value: Any) -> list[str]:
    return [str(v) for v in value if str(v)]


def prior_paths_of(values: Mapping[str, Any]) -> tuple[list[str], str | None]:
    """The prior files to load (empty entries dropped) and the deprecation warning to log, or None.

    ``prior_paths`` is read; while it names no file, the deprecated alias ``tree_paths`` is read instead
    and the warning names the new parameter. A parameter counts as set when it names a file (its default
    ``[""]`` names none). Missing names count as unset.

    Raises:
        ValueError: both ``prior_paths`` and ``tree_paths`` are set (the message names both).
    """
    priors = _names(values.get("prior_paths", []))
    trees = _names(values.get("tree_paths", []))
    if priors and trees:
        raise ValueError(
            "parameters prior_paths and tree_paths are both set; tree_paths is the deprecated name of "
            "prior_paths: set prior_paths only"
        )
    if trees:
        return trees, "parameter tree_paths is deprecated and will be removed: use prior_paths instead"
    return priors, None


def goal_tolerances_of(values: Mapping[str, Any]) -> GoalTolerances:
    """The goal tolerances of the parameter values (``goal_tolerance``, ``joint_tolerance``, ``goal_yaw_tolerance``)."""
    from drd_planner.planning.requests import GoalTolerances

    return GoalTolerances(
        position_m=float(values["goal_tolerance"]),
        joint_rad=float(values["joint_tolerance"]),
        yaw_rad=float(values["goal_yaw_tolerance"]),
    )


def plan_budgets_of(values: Mapping[str, Any]) -> SessionBudgets:
    """The plan budgets of the node's priors (``QuerySession`` keyword arguments) from checked parameter values.

    ``max_checks``, ``planning_time_budget``, ``improve_checks`` and ``improve_time_budget`` (missing: 0);
    0 means no limit, and the anytime improvement is off when both of its parameters are 0.
    """
    # Imported here, not with the module: ``planner_node --help`` reads PARAMETERS and stays light.
    from drd_planner.planner.anytime import ImproveBudget

    max_checks = int(values.get("max_checks", 0))
    seconds = float(values.get("planning_time_budget", 0.0))
    improve_checks = int(values.get("improve_checks", 0))
    improve_seconds = float(values.get("improve_time_budget", 0.0))
    improve = None
    if improve_checks > 0 or improve_seconds > 0:
        improve = ImproveBudget(
            checks=improve_checks if improve_checks > 0 else None,
            seconds=improve_seconds if improve_seconds > 0 else None,
        )
    return {
        "max_checks": max_checks if max_checks > 0 else None,
        "time_budget_s": seconds if seconds > 0 else None,
        "improve_budget": improve,
    }


def declare_parameters(node: Any) -> None:
    """Declare every parameter of :data:`PARAMETERS` on ``node`` with its descriptor."""
    for spec in PARAMETERS:
        node.declare_parameter(spec.name, spec.default, spec.descriptor())


def parameter_problems(values: Mapping[str, Any]) -> list[str]:
    """Why each of ``values`` (name -> value) is refused: ``"name: reason"`` lines; empty if all pass.

    Names not in :data:`PARAMETERS` are not this function's business (rclpy refuses undeclared ones).
    """
    specs = {spec.name: spec for spec in PARAMETERS}
    problems = []
    for name, value in values.items():
        spec = specs.get(name)
        if spec is None or spec.check is None:
            continue
        try:
            reason = spec.check(value)
        except (TypeError, ValueError, OverflowError) as exc:
            reason = f"has the wrong type ({type(exc).__name__})"
        if reason is not None:
            problems.append(f"{name} {reason}")
    return problems
