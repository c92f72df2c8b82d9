"""Robot files and the loader that keeps parsed models (one object per description)."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import SHARED_DATA

from drd_planner.domains.arm_robot import RobotLoader, default_panda_dir, load_robot, robot_texts
from drd_planner.exceptions import ProblemError

PANDA = SHARED_DATA / "panda"


def test_the_loader_keeps_one_model_per_description() -> None:
    if not (PANDA / "panda_spherized.urdf").is_file():
        pytest.skip("shared Panda model not present")
    texts = robot_texts()
    loader = RobotLoader(capacity=1)
    first = loader.model(*texts)
    assert loader.model(*texts) is first
    assert len(loader) == 1
    other = loader.model(texts[1] or texts[0], None, texts[2])  # the spherized file on its own
    # the older model was dropped
    assert other is not first
    assert len(loader) == 1
    assert loader.model(*texts) is not first
    assert load_robot(loader=loader).chain.joint_names == first.chain.joint_names


def test_missing_files_are_named(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    with pytest.raises(ProblemError, match="cannot read robot description"):
        robot_texts(str(tmp_path / "none.urdf"))
    monkeypatch.setenv("DRD_SHARED_DATA", str(tmp_path))
    with pytest.raises(ProblemError, match="DRD_SHARED_DATA"):
        default_panda_dir()
