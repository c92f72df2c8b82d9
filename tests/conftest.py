"""Shared fixtures: where the authors' data lives, and skipping cleanly when it is absent."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("DRD_SHARED_DATA", REPO_ROOT.parent / "shared" / "data"))
GCCD = SHARED_DATA / "gccd"


def libm_numpy() -> bool:
    """Whether numpy's float64 exp/log1p/expm1/log give the C library's numbers here (no AVX-512 forms).

    Then :mod:`math` (the scalar forms of ``drd_planner.core.logmath``) and numpy agree bit for bit.
    """
    import math

    import numpy as np

    x = -np.random.default_rng(0).exponential(3.0, 2000) - 1e-6  # (2000,) values below 0
    y = -np.exp(x)  # in (-1, 0): where log1p is asked
    z = -np.expm1(x)  # in (0, 1): where log is asked
    return (
        np.exp(x).tolist() == [math.exp(v) for v in x.tolist()]
        and np.log1p(y).tolist() == [math.log1p(v) for v in y.tolist()]
        and np.expm1(x).tolist() == [math.expm1(v) for v in x.tolist()]
        and np.log(z).tolist() == [math.log(v) for v in z.tolist()]
    )


def grid_graph(side: int, rng: Any, *, directed: bool = False, equal_lengths: bool = False) -> Any:
    """A side x side grid graph (both directions when directed), lengths uniform in [1, 2) drawn from ``rng``.

    ``equal_lengths``: every length 1 (the draw is still made, so what ``rng`` draws next is the same).
    """
    import numpy as np

    from drd_planner.core.graph import ExplicitGraph

    edges = []
    for i in range(side):
        for j in range(side):
            v = side * i + j
            if j < side - 1:
                edges.append((v, v + 1))
            if i < side - 1:
                edges.append((v, v + side))
    pairs = np.array(edges)
    if directed:
        pairs = np.vstack([pairs, pairs[:, ::-1]])
    lengths = rng.uniform(1.0, 2.0, pairs.shape[0])
    return ExplicitGraph(pairs, np.ones_like(lengths) if equal_lengths else lengths, side * side, directed)


def gccd_folder(name: str) -> Path:
    """Path of an authors' dataset folder, skipping the test with a reason when it is absent."""
    folder = GCCD / name
    if not folder.is_dir():
        pytest.skip(f"shared dataset {folder} not present (set DRD_SHARED_DATA to its parent)")
    return folder


def own_query(session: Any) -> tuple[int, int]:
    """(start, goal) vertex ids of the query stored with a session's prior: a tree file's own query."""
    return int(session.domain.start), int(session.domain.goal)


def require_ompl() -> None:
    """Skip a test that needs OMPL (the 'peer' extra) when it is absent; in CI (``CI`` set) fail instead.

    The README's test command installs the extra, so in CI a missing OMPL is a broken set-up, not a reason to
    leave the comparisons the docs quote untested.
    """
    from drd_planner.bench.ompl_peer import ompl_available

    ok, message = ompl_available()
    if ok:
        return
    if os.environ.get("CI"):
        pytest.fail(f"{message} (CI runs the README's test command, which installs it)")
    pytest.skip(message)


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


#: The spec of the small arm fixtures: a 60-sample, 5-neighbour Panda roadmap (seed 3).
SMALL_ARM_SPEC = {"num_samples": 60, "k": 5, "seed": 3}


@pytest.fixture(scope="module")
def small_arm() -> Any:
    """A 60-sample, 5-neighbour Panda roadmap domain (seed 3); skips when the shared Panda model is absent."""
    if not (SHARED_DATA / "panda" / "panda_spherized.urdf").is_file():
        pytest.skip("shared Panda model not present")
    from drd_planner.domains.arm import ArmDomain
    from drd_planner.domains.base import domain_from_spec

    built = domain_from_spec("arm", SMALL_ARM_SPEC)
    assert isinstance(built, ArmDomain)
    return built


@pytest.fixture(scope="module")
def small_arm_meshes() -> Any:
    """:func:`small_arm` checked with the Panda's collision meshes; skips when the meshes are absent."""
    if not (SHARED_DATA / "panda" / "meshes" / "collision").is_dir():
        pytest.skip("shared Panda collision meshes not present (set DRD_SHARED_DATA)")
    from drd_planner.domains.arm import ArmDomain
    from drd_planner.domains.base import domain_from_spec

    built = domain_from_spec("arm", {**SMALL_ARM_SPEC, "collision_model": "meshes"})
    assert isinstance(built, ArmDomain)
    return built


@pytest.fixture(scope="module")
def forest_problem() -> Any:
    """A planar Forest problem of 200 worlds (seed 11): new queries between its vertices, with test worlds."""
    from drd_planner.data.planar_problem import make_planar_problem

    return make_planar_problem(model="forest", num_worlds=200, seed=11)


@pytest.fixture(scope="module")
def forest_prior(forest_problem: Any) -> Any:
    """The world prior of :func:`forest_problem`'s training worlds, BiSECt from the root (eta 1), no trees."""
    from drd_planner import prior_from_problem

    return prior_from_problem(forest_problem, domain="planar", trees=(), eta=1.0)
