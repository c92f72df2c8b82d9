"""The real site behind a helicopter prior of the ``"corridors"`` world model, when it has one.

A corridors prior was trained on worlds of one real operating site; its site
(:class:`~drd_planner.domains.helicopter_site.OperatingSite`: the DEM seen from the lattice, the datum, the
lattice) is what a map server publishes and what the planner compares a terrain map with.

Which priors are site priors (:func:`site_world_model`): a prior records the world model of its training
worlds in its provenance (``world_model``, written by ``drd build-tree``; the shipped priors carry it too). A
prior without it is not taken for a site prior: its terrain maps are not compared with any site. Guessing from
its spec would be wrong, since every helicopter spec written since the corridors model exists holds that
model's parameters, whatever model drew the worlds, and a wires prior would then refuse its own terrain.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from drd_planner.domains.helicopter_corridors_model import CorridorsModel
from drd_planner.domains.helicopter_site import SITE_MODEL, OperatingSite, operating_site
from drd_planner.domains.online import OnlineDomain
from drd_planner.exceptions import ProblemError
from drd_planner.planner.prior import WorldPrior

__all__ = ["SITE_MODEL", "prior_site", "prior_sites", "site_world_model"]


def site_world_model(prior: WorldPrior) -> str | None:
    """The world model of the prior's training worlds, as its provenance records it; None when it does not."""
    recorded = prior.provenance.get("world_model")
    return recorded if isinstance(recorded, str) and recorded else None


def prior_site(
    prior: WorldPrior, domain: OnlineDomain[Any], *, model: CorridorsModel | None = None
) -> OperatingSite | None:
    """The site of a corridors prior (``domain``: the prior's, rebuilt from its spec), else None.

    Raises:
        ProblemError: a corridors prior whose DEM is missing or unusable.
    """
    if site_world_model(prior) != SITE_MODEL:
        return None
    return operating_site(domain, name=prior.name, model=model)


def prior_sites(
    priors: Sequence[tuple[WorldPrior, OnlineDomain[Any]]],
) -> tuple[list[OperatingSite | None], list[str]]:
    """The site of each (prior, its domain), None for a prior of no site, and a note per site not loaded.

    A corridors prior whose DEM cannot be read plans as before (its terrain is not compared with the site);
    the note says why.
    """
    sites: list[OperatingSite | None] = []
    notes: list[str] = []
    model = CorridorsModel()
    for prior, domain in priors:
        try:
            sites.append(prior_site(prior, domain, model=model))
        except ProblemError as exc:
            sites.append(None)
            notes.append(f"{prior.name}: terrain maps are not compared with the prior's site: {exc}")
    return sites, notes
