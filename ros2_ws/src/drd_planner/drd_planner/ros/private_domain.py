"""A ROS domain nobody else on this host uses, for a demo that must not meet a robot stack (or another demo).

:func:`private_domain` tries the domain ids 215-232 (above the range that Linux's ephemeral ports may take from
the DDS ports of ids 102-214), starting at one chosen by the process id so that demos started together try
different ones first. For each it joins the domain with a probe node for ``listen_s`` seconds, with discovery
limited to this host unless the environment says otherwise (``ROS_AUTOMATIC_DISCOVERY_RANGE``), and takes the
first where it sees no other node. Two probes that meet on one id settle it by their process ids: the lower
one keeps the id, the other moves on.
"""

from __future__ import annotations

import os
import time

import rclpy
from rclpy.context import Context

from drd_planner.exceptions import DrdError

__all__ = ["PRIVATE_DOMAIN_IDS", "PROBE_PREFIX", "private_domain"]

#: The ids tried, in order from a process-dependent start.
PRIVATE_DOMAIN_IDS: tuple[int, ...] = tuple(range(215, 233))
#: Probe nodes are named ``<prefix><pid>``.
PROBE_PREFIX = "drd_domain_probe_"


def _others(context: Context, pid: int, listen_s: float) -> list[str]:
    """The nodes another process has in ``context``'s domain (probes with a higher pid do not count)."""
    node = rclpy.create_node(f"{PROBE_PREFIX}{pid}", context=context)
    try:
        end = time.monotonic() + listen_s
        seen: set[str] = set()
        while time.monotonic() < end:
            time.sleep(0.05)
            seen.update(name for name, _ns in node.get_node_names_and_namespaces())
        others = []
        for name in sorted(seen - {node.get_name()}):
            probe_pid = name.removeprefix(PROBE_PREFIX)
            if name.startswith(PROBE_PREFIX) and probe_pid.isdigit() and int(probe_pid) > pid:
                continue  # a later probe moves on
            others.append(name)
        return others
    finally:
        node.destroy_node()


def private_domain(listen_s: float = 0.5, pid: int | None = None) -> int:
    """A domain id in :data:`PRIVATE_DOMAIN_IDS` where no other node was seen for ``listen_s`` seconds.

    Raises:
        DrdError: every id is taken (the ids and what was seen named).
    """
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    pid = os.getpid() if pid is None else pid
    ids = PRIVATE_DOMAIN_IDS
    start = pid % len(ids)
    taken: list[str] = []
    for domain_id in ids[start:] + ids[:start]:
        context = Context()
        rclpy.init(context=context, domain_id=domain_id)
        try:
            others = _others(context, pid, listen_s)
        finally:
            context.try_shutdown()
        if not others:
            return domain_id
        taken.append(f"{domain_id} ({', '.join(others[:3])})")
    raise DrdError(
        f"no private ROS domain is free among {ids[0]}-{ids[-1]}: seen {'; '.join(taken)}; give one with --domain-id N"
    )
