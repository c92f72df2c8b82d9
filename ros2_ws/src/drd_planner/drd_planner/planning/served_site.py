"""Where a map server's site comes from: a site prior file (``--prior``), or a site file (``--site-file``).

:func:`site_of_prior_file` reads a world prior (a path or a shipped name such as ``heli_lines``), rebuilds
its helicopter domain from the stored spec and returns the site it was trained on; a prior of no real site
is refused naming its world model. :func:`site_of_site_file` reads a GIS site file
(:func:`~drd_planner.data.site_file.load_site`) and returns the site of its corridors parameters on the
lattice of its domain spec.
Each failure is one :class:`~drd_planner.exceptions.DrdError` whose text names the file and the reason.
"""

from __future__ import annotations

from collections.abc import Callable

from drd_planner.data.site_file import load_site
from drd_planner.domains.base import domain_from_spec
from drd_planner.domains.helicopter_site import SITE_MODEL, OperatingSite, operating_site
from drd_planner.exceptions import DrdError
from drd_planner.planner.prior_file import load_prior
from drd_planner.planning.prior_domain import rebuild_domain
from drd_planner.planning.prior_site import prior_site, site_world_model
from drd_planner.planning.shipped import resolve_tree_path

__all__ = ["site_of_prior_file", "site_of_site_file"]


def site_of_prior_file(name: str, *, log: Callable[[str], None] = lambda _text: None) -> OperatingSite:
    """The site of the corridors prior ``name`` (a file path, or a shipped prior's name).

    Args:
        name: the prior file or shipped name.
        log: where progress lines go (one per step).

    Raises:
        DrdError: no such file, an unreadable prior, a prior of no real site (its world model named), or a
            site whose DEM cannot be read.
    """
    path = resolve_tree_path(name)
    log(f"loading prior {path}")
    prior = load_prior(path)
    domain = rebuild_domain(prior, path.name)
    try:
        site = prior_site(prior, domain)
    except DrdError as exc:
        raise DrdError(f"prior {path}: its site's elevation grid cannot be read: {exc}") from exc
    if site is None:
        model = site_world_model(prior)
        raise DrdError(
            f"prior {path} is not a prior of a real site (domain {prior.domain!r}, world model "
            f"{model or 'not recorded'}): a map server publishes the site of a {SITE_MODEL!r} prior, such as "
            "the shipped heli_lines"
        )
    return site


def site_of_site_file(path: str, *, log: Callable[[str], None] = lambda _text: None) -> OperatingSite:
    """The site of a GIS site file (its corridors parameters on the lattice of its domain spec).

    Raises:
        DrdError: the file or its site is refused (:class:`~drd_planner.exceptions.SiteFileError` for the file).
    """
    log(f"loading site file {path}")
    site = load_site(path)
    domain = domain_from_spec("helicopter", site.domain_spec)
    found = operating_site(domain, name=site.name, params=site.corridors)
    if found is None:  # a helicopter spec always gives a helicopter domain
        raise DrdError(f"site file {path}: its domain spec is not a helicopter lattice's")
    return found
