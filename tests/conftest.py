"""Shared fixtures: where the authors' data lives, and skipping cleanly when it is absent."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("DRD_SHARED_DATA", REPO_ROOT.parent / "shared" / "data"))
GCCD = SHARED_DATA / "gccd"


def gccd_folder(name: str) -> Path:
    """Path of an authors' dataset folder, skipping the test with a reason when it is absent."""
    folder = GCCD / name
    if not folder.is_dir():
        pytest.skip(f"shared dataset {folder} not present (set DRD_SHARED_DATA to its parent)")
    return folder


def gccd_graph_datasets() -> list[str]:
    """Names of every graph dataset folder under shared/data/gccd (empty when absent)."""
    if not GCCD.is_dir():
        return []
    return sorted(p.name for p in GCCD.iterdir() if (p / "graph.txt").is_file())


@pytest.fixture(params=["rosbags", "rclpy"])
def msgs(request: pytest.FixtureRequest) -> object:
    """A message factory: every message conversion is tested with rosbags dataclasses and rclpy classes."""
    from rosbags.typesys import Stores, get_typestore

    from drd_msgs_py.factory import RclpyMessages, RosbagsMessages

    if request.param == "rosbags":
        return RosbagsMessages(get_typestore(Stores.ROS2_JAZZY))
    pytest.importorskip("visualization_msgs.msg", reason="rclpy message wheels not installed")
    return RclpyMessages()
