"""``drd plan --prior --scene --request``: a MoveIt request in a MoveIt scene, the real checker, its JSON."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO_ROOT, SHARED_DATA

from drd_planner.cli.main import main
from drd_planner.planner import WorldPrior, load_prior
from drd_planner.planning.prior_domain import rebuild_domain
from drd_planner.planning.scene_plan import SceneRequest, plan_moveit_request

FAMILY = SHARED_DATA / "mbm" / "table_pick_panda"
PRIOR = REPO_ROOT / "trees" / "arm_table_clutter.npz"
#: A table_pick scene whose request the shipped Table+Clutter prior plans only after growing its roadmap.
SCENE = "0003"

HOME = "[0, -0.785, 0, -2.356, 0, 1.571, 0.785]"
NAMES = "[panda_joint1, panda_joint2, panda_joint3, panda_joint4, panda_joint5, panda_joint6, panda_joint7]"


@pytest.fixture(scope="module")
def prior() -> WorldPrior:
    if not (SHARED_DATA / "panda" / "panda_spherized.urdf").is_file() or not FAMILY.is_dir():
        pytest.skip("shared Panda model or MotionBenchMaker scenes not present (set DRD_SHARED_DATA)")
    return load_prior(PRIOR)


def _request(folder: Path, goal: list[float]) -> Path:
    constraints = "\n".join(
        f"      - joint_name: panda_joint{k + 1}\n        position: {value}" for k, value in enumerate(goal)
    )
    path = folder / "request.yaml"
    path.write_text(
        f"start_state:\n  joint_state:\n    name: {NAMES}\n    position: {HOME}\n"
        f"goal_constraints:\n  - joint_constraints:\n{constraints}\n"
    )
    return path


def test_a_request_that_needs_growth_is_planned_and_verified(prior: WorldPrior) -> None:
    request = SceneRequest(FAMILY / f"scene{SCENE}.yaml", FAMILY / f"request{SCENE}.yaml", seed=0)
    plan = plan_moveit_request(prior, request)
    result = plan.result
    assert result.found
    assert result.growth is not None
    assert result.growth.stop == "path"
    np.testing.assert_allclose(plan.path_states[0], plan.start)
    np.testing.assert_allclose(plan.path_states[-1], plan.goal)
    assert np.allclose(plan.start, [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])  # the fingers are ignored
    domain = rebuild_domain(prior, "again")
    assert np.abs(np.diff(plan.path_states, axis=0)).max() <= domain.resolution + 1e-9
    record = plan.to_json()
    assert {"status", "checks", "path_edges", "time_s", "reason"} <= set(record)
    assert record["status"] == "found"
    assert record["checks"] == result.num_checks
    assert record["growth"]["rounds"] >= 1
    assert record["path_edges"] == [int(e) for e in result.edges]
    assert record["time_s"] > 0


def test_the_command_writes_the_json(prior: WorldPrior, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "plan.json"
    scene, request = FAMILY / f"scene{SCENE}.yaml", FAMILY / f"request{SCENE}.yaml"
    argv = [
        "plan",
        "--prior",
        str(PRIOR),
        "--scene",
        str(scene),
        "--request",
        str(request),
        "--json",
        str(out),
    ]
    assert main(argv) == 0
    assert f"request{SCENE}.yaml in scene{SCENE}.yaml: found after" in capsys.readouterr().out
    record = json.loads(out.read_text())
    assert record["status"] == "found"
    assert record["checks"] > 0
    assert record["path_edges"]
    assert record["scene"] == str(scene)
    assert len(record["path_states"][0]) == 7


def test_a_goal_in_degrees_is_refused_with_the_limits(prior: WorldPrior, tmp_path: Path) -> None:
    request = _request(tmp_path, [0.0, -45.0, 0.0, -135.0, 0.0, 90.0, 45.0])
    out = tmp_path / "refused.json"
    argv = [
        "plan",
        "--prior",
        str(PRIOR),
        "--scene",
        str(FAMILY / "scene0001.yaml"),
        "--request",
        str(request),
    ]
    assert main([*argv, "--json", str(out)]) == 1
    record = json.loads(out.read_text())
    assert record["status"] == "refused"
    assert record["checks"] == 0
    assert record["reason"].startswith("goal joint values are beyond the joint limits: panda_joint2 = -45.000 not in")
    assert "(rad); the values look like degrees" in record["reason"]


def test_errors_are_one_line_and_exit_2(prior: WorldPrior, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scene = str(FAMILY / "scene0001.yaml")
    assert main(["plan", "--prior", str(PRIOR), "--scene", scene]) == 2
    assert (
        capsys.readouterr().err.strip()
        == "drd: error: --scene needs --request REQUEST.yaml (the MoveIt MotionPlanRequest to plan)"
    )
    assert main(["plan", "--prior", str(PRIOR), "--scene", scene, "--request", str(tmp_path / "none.yaml")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("drd: error: cannot read motion plan request")
    assert "\n" not in err
    bad_scene = tmp_path / "scene.yaml"
    bad_scene.write_text("world: {collision_objects: [{id: m, meshes: [{}]}]}\n")
    request = FAMILY / "request0001.yaml"
    assert main(["plan", "--prior", str(PRIOR), "--scene", str(bad_scene), "--request", str(request)]) == 2
    assert capsys.readouterr().err.startswith("drd: error: ")
    assert main(["plan", "--prior", str(PRIOR), "--bag", "arm_table_clutter", "--request", "x"]) == 2
