"""The RRT-Connect peer: OMPL in a child process, every query answered by our checker, solutions re-verified."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import REPO_ROOT, SHARED_DATA, require_ompl

from drd_planner.bench.ompl_peer import OmplPeerError
from drd_planner.bench.rrt_connect import RrtTask, run_rrt_connect, verify_waypoints
from drd_planner.data.scene_source import scene_of, scene_primitives
from drd_planner.geometry.moveit_request import joint_vector, read_motion_plan_request
from drd_planner.planner import load_prior
from drd_planner.planning.prior_domain import rebuild_domain

FAMILY = SHARED_DATA / "mbm" / "table_pick_panda"


def _task(domain: object, key: str) -> RrtTask:
    names = domain.joint_names  # type: ignore[attr-defined]
    request = read_motion_plan_request(FAMILY / f"request{key}.yaml")
    assert request.start is not None
    start = joint_vector(request.start, names, where="start", allow_extra=True)
    return RrtTask(key, FAMILY / f"scene{key}.yaml", start, joint_vector(request.goals[0], names, where="goal"))


@pytest.fixture(scope="module")
def shipped() -> tuple[object, dict[str, object]]:
    if not (SHARED_DATA / "panda" / "panda_spherized.urdf").is_file() or not FAMILY.is_dir():
        pytest.skip("shared Panda model or MotionBenchMaker scenes not present (set DRD_SHARED_DATA)")
    prior = load_prior(REPO_ROOT / "trees" / "arm_table_clutter.npz")
    return rebuild_domain(prior, "arm"), dict(prior.domain_spec)


def test_verify_waypoints_is_one_dense_check_by_a_fresh_checker(
    shipped: tuple[object, dict[str, object]],
) -> None:
    domain, _ = shipped
    task = _task(domain, "0003")
    scene_file = Path(task.scene)
    checker = domain.scene_checker(scene_of(scene_primitives(str(scene_file), scene_file.read_bytes()), 0.0))  # type: ignore[attr-defined]
    direct = [task.start.tolist(), task.goal.tolist()]
    dense = np.linspace(task.start, task.goal, 400)
    assert verify_waypoints(domain, scene_file, direct) == checker.check_motion(dense)  # type: ignore[arg-type]
    assert not verify_waypoints(domain, scene_file, [task.start.tolist()])  # type: ignore[arg-type]


@pytest.mark.slow
def test_rrt_connect_solves_and_its_path_is_verified_by_our_checker(
    shipped: tuple[object, dict[str, object]],
) -> None:
    require_ompl()
    domain, spec = shipped
    records = run_rrt_connect(domain, spec, [_task(domain, "0001"), _task(domain, "0003")], time_limit_s=10.0)  # type: ignore[arg-type]
    assert [r["key"] for r in records] == ["0001", "0003"]
    for record in records:
        assert record["ompl_solved"]
        assert record["verified"]
        assert record["solved"]
        assert record["motion_checks"] > 0
        assert record["state_checks"] > 0
        assert record["waypoints"] >= 2
        assert 0 < record["wall_s"] < 10.0


def test_a_worker_failure_is_one_error(shipped: tuple[object, dict[str, object]]) -> None:
    require_ompl()
    domain, _ = shipped
    with pytest.raises(OmplPeerError, match="worker failed"):
        run_rrt_connect(domain, {"no_such_key": 1}, [_task(domain, "0001")], time_limit_s=1.0)  # type: ignore[arg-type]
