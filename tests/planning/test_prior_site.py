"""Which priors are priors of a real site, and the site they hold (DEM, datum, lattice frame)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from drd_planner.domains.helicopter import HelicopterDomain
from drd_planner.planner import load_prior
from drd_planner.planner.prior import WorldPrior, prior_from_problem
from drd_planner.planning.prior_domain import rebuild_domain
from drd_planner.planning.prior_site import SITE_MODEL, prior_site, prior_sites, site_world_model

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def heli_lines() -> tuple[WorldPrior, HelicopterDomain]:
    prior = load_prior(ROOT / "trees" / "heli_lines.npz")
    domain = rebuild_domain(prior, "heli_lines")
    assert isinstance(domain, HelicopterDomain)
    return prior, domain


def test_the_recorded_world_model_decides_and_an_unrecorded_one_is_no_site(
    heli_lines: tuple[WorldPrior, HelicopterDomain],
) -> None:
    prior, domain = heli_lines
    assert site_world_model(prior) == SITE_MODEL  # the shipped prior records its world model
    wires = dataclasses.replace(prior, provenance={**prior.provenance, "world_model": "wires"})
    assert site_world_model(wires) == "wires"
    assert prior_site(wires, domain) is None
    # A prior of before the record: its spec holds the corridors model (every helicopter spec does), yet it is
    # not taken for a site prior, so a wires prior of that time keeps taking its own terrain.
    unrecorded = dataclasses.replace(
        prior, provenance={k: v for k, v in prior.provenance.items() if k != "world_model"}
    )
    assert "corridors" in unrecorded.domain_spec["models"]
    assert site_world_model(unrecorded) is None
    assert prior_site(unrecorded, domain) is None
    shipped_wires = load_prior(ROOT / "trees" / "heli_wires.npz")
    assert site_world_model(shipped_wires) == "wires"
    assert prior_site(shipped_wires, rebuild_domain(shipped_wires, "heli_wires")) is None


def test_the_site_is_the_dem_seen_from_the_lattice_with_z_zero_at_the_lattice_origin(
    heli_lines: tuple[WorldPrior, HelicopterDomain],
) -> None:
    prior, domain = heli_lines
    site = prior_site(prior, domain)
    assert site is not None
    assert site.name == "heli_lines"
    assert site.params.site_origin == (-105.4617, 40.1825)
    assert site.frame == domain.frame
    assert site.wire_segments == 8
    assert site.heights(np.zeros(1), np.zeros(1))[0] == pytest.approx(0.0, abs=1e-9)  # datum: the DEM there
    assert 1000.0 < site.datum < 4500.0  # metres above sea level in the Front Range
    far = site.heights(np.array([1e6]), np.array([0.0]))
    assert np.isnan(far[0])


def test_a_site_prior_whose_dem_is_missing_plans_on_with_a_note(
    heli_lines: tuple[WorldPrior, HelicopterDomain], tmp_path: Path
) -> None:
    prior, _ = heli_lines
    spec = dict(prior.domain_spec)
    spec["models"] = {**spec["models"], "corridors": {**spec["models"]["corridors"], "path": str(tmp_path / "x.asc")}}
    moved = dataclasses.replace(prior, domain_spec=spec)
    domain = rebuild_domain(moved, "moved")
    sites, notes = prior_sites([(moved, domain)])
    assert sites == [None]
    (note,) = notes
    assert note.startswith("heli_lines: terrain maps are not compared with the prior's site:")
    assert "x.asc not found" in note


def test_a_prior_built_from_a_problem_records_its_world_model(heli_lines: tuple[WorldPrior, HelicopterDomain]) -> None:
    from drd_planner.core.problem import Problem
    from drd_planner.core.worlds import WorldDatabase

    prior, _ = heli_lines
    assert prior.worlds is not None
    qt = prior.trees[0]
    x = prior.worlds[:4]
    r = qt.library.valid_paths(x)
    worlds = WorldDatabase(x, r, np.arange(4), np.zeros(0, dtype=np.int64))
    problem = Problem(
        name="small",
        library=qt.library,
        edge_costs=prior.edge_costs,
        graph=prior.graph,
        start=qt.start,
        goal=qt.goal,
        worlds=worlds,
        metadata={"domain_spec": prior.domain_spec, "world_model": "corridors"},
    )
    built = prior_from_problem(problem, domain="helicopter", provenance={"dataset": "small"})
    assert built.provenance == {"dataset": "small", "world_model": "corridors"}
    assert site_world_model(built) == "corridors"
