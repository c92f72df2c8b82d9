"""The demo's private ROS domain: the first id of 215-232 where no other node is seen, probes settled by pid."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import pytest

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from harness import use_domain  # noqa: E402

from drd_planner.ros.private_domain import PRIVATE_DOMAIN_IDS, PROBE_PREFIX, private_domain  # noqa: E402

use_domain(60)

#: A process id whose first candidate is the first private id (215).
FIRST = len(PRIVATE_DOMAIN_IDS) * 1000


@contextmanager
def _someone(domain_id: int, name: str) -> Iterator[None]:
    """A node named ``name`` on ``domain_id`` (as another process on this host would have)."""
    context = rclpy.context.Context()
    rclpy.init(context=context, domain_id=domain_id)
    node = rclpy.create_node(name, context=context)
    try:
        yield
    finally:
        node.destroy_node()
        context.try_shutdown()


def test_a_domain_with_another_node_is_skipped() -> None:
    first, second = PRIVATE_DOMAIN_IDS[:2]
    with _someone(first, "robot_stack"):
        assert private_domain(listen_s=1.0, pid=FIRST) == second


def test_two_probes_on_one_id_leave_it_to_the_lower_process_id() -> None:
    first, second = PRIVATE_DOMAIN_IDS[:2]
    with _someone(first, f"{PROBE_PREFIX}{FIRST + 18}"):  # a later demo's probe: this one keeps the id
        assert private_domain(listen_s=1.0, pid=FIRST) == first
    with _someone(first, f"{PROBE_PREFIX}{FIRST - 18}"):  # an earlier demo's probe: this one moves on
        assert private_domain(listen_s=1.0, pid=FIRST) == second
