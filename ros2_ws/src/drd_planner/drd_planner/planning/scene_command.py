"""``drd plan --scene``: a MoveIt request planned in a MoveIt scene with the prior's real checker, as a library call.

:func:`plan_scene` takes a :class:`ScenePlanOptions` (made by :mod:`drd_planner.cli.plan`), plans with
:func:`~drd_planner.planning.scene_plan.plan_moveit_request`, prints the outcome and writes the JSON record.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from drd_planner.exceptions import DrdError
from drd_planner.planner.prior_file import load_prior
from drd_planner.planning.scene_plan import SceneRequest, plan_moveit_request

__all__ = ["ScenePlanOptions", "plan_scene"]


@dataclass(frozen=True)
class ScenePlanOptions:
    """One ``drd plan --scene``.

    Attributes:
        prior: the prior file to plan with.
        scene: the MoveIt PlanningScene YAML file.
        request: the MoveIt MotionPlanRequest YAML file (start state and first joint goal, rad); None is refused.
        json: write the JSON record (:meth:`ScenePlan.to_json`) to this file (None: none).
        time_budget_s: end the plan after this many seconds (None: no budget; must be > 0).
        max_checks: end the plan after this many checks (None: no cap).
        seed: the policy's seed.
    """

    prior: str
    scene: str
    request: str | None = None
    json: str | None = None
    time_budget_s: float | None = None
    max_checks: int | None = None
    seed: int = 0


def plan_scene(options: ScenePlanOptions) -> int:
    """``drd plan --prior P --scene S --request R [--json F]``: a MoveIt request planned with the real checker.

    Prints the outcome in one line (and the path's states when found); exit status 0 when a path was
    found and verified, 1 otherwise; the JSON record (:meth:`ScenePlan.to_json`) with ``json``.
    """
    if not options.request:
        raise DrdError("--scene needs --request REQUEST.yaml (the MoveIt MotionPlanRequest to plan)")
    if options.time_budget_s is not None and not options.time_budget_s > 0:
        raise DrdError(f"--time-budget must be a positive number of seconds, got {options.time_budget_s}")
    request = SceneRequest(
        Path(options.scene),
        Path(options.request),
        seed=options.seed,
        max_checks=options.max_checks,
        time_budget_s=options.time_budget_s,
    )
    plan = plan_moveit_request(load_prior(options.prior), request, label=Path(options.prior).name)
    result = plan.result
    print(
        f"{request.request.name} in {request.scene.name}: {result.status.value} after {result.num_checks} "
        f"checks in {plan.wall_s:.2f} s: {result.reason}"
    )
    for k, state in enumerate(plan.path_states[:: max(1, len(plan.path_states) // 10)]):
        print(f"  path state {k}: " + " ".join(f"{v:7.3f}" for v in state))
    if options.json:
        try:
            Path(options.json).write_text(json.dumps(plan.to_json(), indent=1) + "\n", encoding="utf-8")
        except OSError as exc:
            raise DrdError(f"cannot write --json {options.json}: {exc}") from exc
    return 0 if result.found else 1
