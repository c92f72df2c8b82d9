"""``drd build-tree`` as a library call: queries read from their text, the note on an unused tree, refusals."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drd_planner.exceptions import DrdError
from drd_planner.planner import load_prior
from drd_planner.planner.endpoints import endpoint_value
from drd_planner.planner.prior import LeafSetting
from drd_planner.planner.prior_build import BuildTreeOptions, build_prior, resolve_query, unused_tree_note

HELI_WIRES = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"


def test_a_query_is_vertex_ids_or_states_snapped_to_their_vertex() -> None:
    assert endpoint_value("12") == 12
    np.testing.assert_array_equal(endpoint_value("1.5; 2 3"), [1.5, 2.0, 3.0])
    with pytest.raises(DrdError, match="neither a vertex id nor a state"):
        endpoint_value("north")
    prior = load_prior(HELI_WIRES)
    states = prior.graph.vertex_states
    assert states is not None
    goal = " ".join(str(float(v)) for v in states[5])
    assert resolve_query(prior, ("3", goal)) == (3, 5)


def test_the_note_on_a_tree_that_is_never_used_names_the_worlds() -> None:
    assert unused_tree_note(LeafSetting(0.5, 10.0), 40) == []
    note = unused_tree_note(LeafSetting(1.0, None), 40)
    assert "never used" in note[0]
    assert "now 40" in note[1]


def test_adding_trees_to_a_prior_needs_a_query() -> None:
    with pytest.raises(DrdError, match="give at least one --query"):
        build_prior(BuildTreeOptions(out="unused.npz", prior=str(HELI_WIRES)))
    tree = load_prior(HELI_WIRES).trees[0]
    with pytest.raises(DrdError, match="already has a tree"):
        build_prior(BuildTreeOptions(out="x.npz", prior=str(HELI_WIRES), queries=((str(tree.start), str(tree.goal)),)))
