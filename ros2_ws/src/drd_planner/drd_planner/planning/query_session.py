"""Deprecated: the online session is :mod:`drd_planner.planning.session` now (this module goes in the next release).

``from drd_planner.planning.query_session import QuerySession`` (and ``SessionBudgets``,
``DEFAULT_SNAP_TOLERANCE``, ``DEFAULT_POSITION_TOLERANCE``) keeps working for this release with a
:class:`DeprecationWarning` naming the new module; ``QueryPlanResult`` is
:class:`~drd_planner.planning.session_plan.SessionPlan`, the one result of a session.
"""

from __future__ import annotations

import importlib
import warnings
from typing import Any

#: Old name -> (its module now, its name there).
_MOVED = {
    "QuerySession": ("drd_planner.planning.session", "QuerySession"),
    "SessionBudgets": ("drd_planner.planning.session", "SessionBudgets"),
    "DEFAULT_SNAP_TOLERANCE": ("drd_planner.planning.session", "DEFAULT_SNAP_TOLERANCE"),
    "DEFAULT_POSITION_TOLERANCE": ("drd_planner.planning.session", "DEFAULT_POSITION_TOLERANCE"),
    "QueryPlanResult": ("drd_planner.planning.session_plan", "SessionPlan"),
}


def __getattr__(name: str) -> Any:
    moved = _MOVED.get(name)
    if moved is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r} (it has {sorted(_MOVED)})")
    module, new_name = moved
    warnings.warn(
        f"drd_planner.planning.query_session.{name} is deprecated and will be removed: use {module}.{new_name}",
        DeprecationWarning,
        stacklevel=2,
    )
    return getattr(importlib.import_module(module), new_name)
