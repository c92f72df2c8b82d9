"""The deprecated module path of the online session: the same objects, each with one warning naming the new path."""

from __future__ import annotations

import pytest

import drd_planner.planning.query_session as old
from drd_planner.planning import session, session_plan


@pytest.mark.parametrize(
    ("name", "new"),
    [
        ("QuerySession", session.QuerySession),
        ("SessionBudgets", session.SessionBudgets),
        ("DEFAULT_SNAP_TOLERANCE", session.DEFAULT_SNAP_TOLERANCE),
        ("DEFAULT_POSITION_TOLERANCE", session.DEFAULT_POSITION_TOLERANCE),
        ("QueryPlanResult", session_plan.SessionPlan),
    ],
)
def test_old_names_are_the_new_objects_with_a_deprecation_warning(name: str, new: object) -> None:
    with pytest.warns(DeprecationWarning, match=r"query_session\." + name + r" is deprecated.*use drd_planner\."):
        assert getattr(old, name) is new


def test_an_unknown_name_is_an_attribute_error_naming_the_old_ones() -> None:
    with pytest.raises(AttributeError, match="QuerySession"):
        _ = old.PlanningSession
