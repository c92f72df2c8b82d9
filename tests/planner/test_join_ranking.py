"""The prior's ranking of an off-graph state's joins, imputed only as far as asked: the order of imputing all."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drd_planner.exceptions import ProblemError
from drd_planner.planner import load_prior
from drd_planner.planner.connect import POINTS_PER_EDGE
from drd_planner.planner.dubins_connector import DubinsConnector
from drd_planner.planner.join_ranking import FIRST_IMPUTED, PriorRanking, length_terms, prior_surprise
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior import WorldPrior

PRIOR = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"
START = np.array([212.0, 33.0, 60.0, 2.9])


def _whole(
    ranking: np.ndarray, lengths: np.ndarray, points: np.ndarray, planner: Planner, columns: object
) -> np.ndarray:
    """Every motion imputed at once, sorted by weight (ties: the connector's order)."""
    prior = planner.prior
    weight = prior_surprise(points, planner._models.sample_index(), prior, columns) + length_terms(lengths, prior)
    return ranking[np.argsort(weight, kind="stable")]


@pytest.fixture(scope="module")
def sketched() -> tuple[WorldPrior, Planner, np.ndarray, np.ndarray, np.ndarray]:
    prior = load_prior(PRIOR)
    planner = Planner(prior, snap_tolerance=1e-6)
    connector = planner.connector
    assert isinstance(connector, DubinsConnector)
    ranking = connector.ranked(START, prior.graph, outgoing=True)
    lengths, points = connector.sketches(
        START, prior.graph, ranking, outgoing=True, fractions=np.linspace(0, 1, POINTS_PER_EDGE)
    )
    return prior, planner, ranking, lengths, points


def test_a_motions_surprise_does_not_depend_on_which_motions_are_imputed_with_it(sketched: tuple) -> None:
    prior, planner, _, _, points = sketched
    index = planner._models.sample_index()
    whole = prior_surprise(points, index, prior)
    parts = np.concatenate([prior_surprise(points[i : i + 37], index, prior) for i in range(0, len(points), 37)])
    assert np.array_equal(whole, parts)
    assert (whole >= 0).all()
    assert whole.max() > 0


@pytest.mark.parametrize("columns", [False, True])
def test_the_first_vertices_asked_for_are_those_of_the_whole_ranking(sketched: tuple, columns: bool) -> None:
    prior, planner, ranking, lengths, points = sketched
    index = planner._models.sample_index()
    packed = planner._models.columns if columns else None
    whole = _whole(ranking, lengths, points, planner, packed)
    lazy = PriorRanking.of_prior(ranking, lengths, points, index, prior, packed)
    head = lazy.first(64)
    assert head.size >= 64
    assert np.array_equal(head, whole[: head.size])
    assert lazy.imputed < lazy.size  # the rest of the lattice's joins not imputed for the first round
    for count in (100, 400, ranking.size):
        head = lazy.first(count)
        assert np.array_equal(head, whole[: head.size])
        assert head.size >= min(count, ranking.size)
    assert lazy.imputed == lazy.size


def test_a_ranking_stops_imputing_once_no_motion_left_can_weigh_less() -> None:
    ranking = np.arange(600, 0, -1)  # vertex ids in the connector's order
    floor = np.linspace(0.0, 6.0, 600)  # non-decreasing length terms
    surprise = np.zeros(600)
    surprise[[3, 10]] = 5.0  # two likely-blocked joins among the shortest
    asked: list[int] = []

    def rest(at: np.ndarray) -> np.ndarray:
        asked.append(int(at.size))
        return surprise[at]

    lazy = PriorRanking(ranking, floor, rest)
    head = lazy.first(5)
    assert asked == [FIRST_IMPUTED]
    expected = ranking[np.argsort(surprise + floor, kind="stable")]
    assert np.array_equal(head, expected[: head.size])
    assert ranking[3] not in head[:5]  # a likely-blocked join moved down
    assert lazy.first(600).tolist() == expected.tolist()
    assert sum(asked) == 600
    with pytest.raises(ProblemError, match="a weight floor per ranked vertex"):
        PriorRanking(ranking, floor[:5], rest)


def test_without_training_worlds_the_connectors_order_is_kept() -> None:
    ranking = np.array([4, 2, 9])
    lazy = PriorRanking.as_given(ranking)
    assert lazy.first(2).tolist() == [4, 2, 9]
