"""K-fold cross-validation of policies on a world database: every feasible world is a test world once.

A dataset's held-back test split (10 %) is small: on 100 worlds a difference of a check or two between
two policies is within the noise. Cross-validation uses the whole database instead. The feasible worlds
(those with a valid library path, as the test protocol requires) are dealt at random (seeded) into
``folds`` folds; for each fold the tree, the switch threshold (validated on held-out *training* worlds
of that fold, as ``drd build-tree --eta auto`` does, with the region rule when several are given) and the
training bias are learnt from every other world, and each policy runs on the fold's worlds with
:func:`drd_planner.bench.runner.run_benchmark`.
The result pairs the policies world by world, so differences come with a bootstrap confidence interval.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
from tqdm import tqdm

from drd_planner.bench.runner import BenchmarkResult, PolicySettings, run_benchmark
from drd_planner.bench.stats import bootstrap_mean_ci
from drd_planner.core.policies import DEFAULT_ALPHA, TREE_POLICIES
from drd_planner.core.problem import Problem
from drd_planner.core.region_rule import DEFAULT_REGION_RULE, REGION_RULES
from drd_planner.core.switch_threshold import (
    DEFAULT_PSEUDO_COUNTS,
    SwitchThresholdChoice,
    ValidationGrid,
    select_region_rule,
    select_switch_threshold,
)
from drd_planner.core.tree import DEFAULT_EXPAND_THRESHOLD, build_tree
from drd_planner.exceptions import DrdError

__all__ = ["CrossValidationResult", "FoldSettings", "cross_validate"]


@dataclass(frozen=True)
class CrossValidationResult:
    """Checks of each policy on every feasible world, each world tested by the fold that held it out.

    Attributes:
        dataset: the problem's name.
        worlds: (W,) world rows in the order of ``checks``.
        fold_of: (W,) fold of each world.
        checks: policy -> (W,) checks per world.
        failures: policy -> episodes that did not prove a path.
        lower_bound: (W,) oracle bound per world (cheapest valid library path).
        etas: the switch threshold used in each fold.
        settings: folds, seed, alpha, tree options (JSON-safe).
    """

    dataset: str
    worlds: npt.NDArray[np.int64]
    fold_of: npt.NDArray[np.int64]
    checks: dict[str, npt.NDArray[np.int64]]
    failures: dict[str, int]
    lower_bound: npt.NDArray[np.float64]
    etas: tuple[float, ...]
    settings: dict[str, Any] = field(default_factory=dict)

    def mean(self, policy: str) -> float:
        """Mean checks of ``policy`` over every world."""
        return float(self.checks[policy].mean())

    def paired_difference(self, policy: str, reference: str, *, seed: int = 0) -> tuple[float, float, float]:
        """Mean of checks(policy) - checks(reference) per world and its 95 % bootstrap interval."""
        diff = self.checks[policy].astype(np.float64) - self.checks[reference]
        return bootstrap_mean_ci(diff, seed=seed)

    def as_json(self, reference: str | None = None) -> dict[str, Any]:
        """A JSON-able summary (means, medians, failures, paired differences to ``reference``)."""
        out: dict[str, Any] = {
            "dataset": self.dataset,
            "num_worlds": int(self.worlds.size),
            "etas": list(self.etas),
            "oracle_bound": float(self.lower_bound.mean()),
            "settings": self.settings,
            "policies": {},
        }
        for name, values in self.checks.items():
            entry: dict[str, Any] = {
                "mean": float(values.mean()),
                "median": float(np.median(values)),
                "failures": self.failures[name],
            }
            if reference is not None and name != reference:
                mean, lo, hi = self.paired_difference(name, reference)
                entry[f"minus_{reference}"] = {"mean": mean, "ci95": [lo, hi]}
            out["policies"][name] = entry
        return out


@dataclass(frozen=True)
class FoldSettings:
    """What every fold is given or learns.

    Attributes:
        eta: switch threshold; None validates it per fold on that fold's training worlds.
        pseudo_counts: candidate kappas of the posterior leaf (None: fixed leaf bias), validated per
            fold together with eta; a single candidate fixes it.
        alpha: data weight of the bias.
        tree_options: keyword arguments of :func:`drd_planner.core.tree.build_tree`.
        region_rules: region rules validated per fold with eta and kappa
            (:func:`~drd_planner.core.switch_threshold.select_region_rule`; default: every rule, as
            ``drd bench`` does); empty: ``tree_options``' rule.
    """

    eta: float | None = None
    pseudo_counts: Sequence[float | None] = DEFAULT_PSEUDO_COUNTS
    alpha: float = DEFAULT_ALPHA
    tree_options: Mapping[str, Any] | None = None
    region_rules: Sequence[str] = REGION_RULES


def cross_validate(
    problem: Problem,
    *,
    policies: Sequence[str],
    folds: int = 10,
    seed: int = 0,
    settings: FoldSettings | None = None,
    progress: bool | None = None,
) -> CrossValidationResult:
    """Run ``policies`` on every feasible world of ``problem`` by ``folds``-fold cross-validation.

    Args:
        problem: a problem with a world database (its own train/test split is ignored).
        policies: registry names, as for :func:`drd_planner.bench.runner.run_benchmark`.
        folds: number of folds (>= 2).
        seed: seeds the deal of worlds into folds, the eta validation and the policies.
        settings: eta, kappa candidates, alpha and tree options (None: :class:`FoldSettings` defaults).
        progress: show a progress bar over folds (None: only on a terminal).

    Raises:
        DrdError: fewer than 2 folds or fewer feasible worlds than folds.
    """
    settings = settings or FoldSettings()
    if folds < 2:
        raise DrdError(f"cross-validation needs at least 2 folds, got {folds}")
    worlds = problem.require_worlds()
    feasible = np.flatnonzero(worlds.R.any(axis=1)).astype(np.int64)
    if feasible.size < folds:
        raise DrdError(f"{problem.name}: {feasible.size} feasible worlds cannot fill {folds} folds")
    rng = np.random.default_rng(seed)
    deal = np.array_split(rng.permutation(feasible), folds)
    order: list[npt.NDArray[np.int64]] = []
    fold_of: list[npt.NDArray[np.int64]] = []
    checks: dict[str, list[int]] = {p: [] for p in policies}
    failures = dict.fromkeys(policies, 0)
    lower: list[float] = []
    etas: list[float] = []
    chosen_kappas: list[float | None] = []
    chosen_rules: list[str] = []
    kappas = tuple(settings.pseudo_counts)
    if not kappas:
        raise DrdError("pseudo_counts needs at least one candidate (None for the fixed leaf bias)")
    everything = np.arange(worlds.num_worlds, dtype=np.int64)
    for k, held in enumerate(
        tqdm(
            deal,
            desc=f"{problem.name} folds",
            unit="fold",
            disable=None if progress is None else not progress,
        )
    ):
        held = np.sort(held)
        fit = np.setdiff1d(everything, held)
        sub = dataclasses.replace(problem, worlds=worlds.subset(fit, held))
        result = _run_fold(sub, policies, seed, settings)
        etas.append(float(result.settings["eta"]))
        chosen_kappas.append(result.settings["pseudo_count"])
        chosen_rules.append(str(result.tree_info.get("region_rule", DEFAULT_REGION_RULE)))
        order.append(np.asarray(result.test_ids, dtype=np.int64))
        fold_of.append(np.full(len(result.test_ids), k, dtype=np.int64))
        lower.extend(result.lower_bound)
        for name in policies:
            if name not in result.policies:  # a peer that is not installed
                continue
            checks[name].extend(result.policies[name].checks)
            failures[name] += result.policies[name].failures
    present = {name: np.asarray(v, dtype=np.int64) for name, v in checks.items() if len(v) == feasible.size}
    return CrossValidationResult(
        dataset=problem.name,
        worlds=np.concatenate(order),
        fold_of=np.concatenate(fold_of),
        checks=present,
        failures={name: failures[name] for name in present},
        lower_bound=np.asarray(lower, dtype=np.float64),
        etas=tuple(etas),
        settings={
            "folds": folds,
            "seed": seed,
            "alpha": settings.alpha,
            "eta": settings.eta,
            "pseudo_counts": list(kappas),
            "chosen_pseudo_counts": chosen_kappas,
            "chosen_region_rules": chosen_rules,
            "tree_options": dict(settings.tree_options or {}),
        },
    )


def _run_fold(sub: Problem, policies: Sequence[str], seed: int, settings: FoldSettings) -> BenchmarkResult:
    """One fold's benchmark on ``sub``'s test worlds, its eta and kappa validated on its training worlds.

    The eta and kappa used are in the result's ``settings``.
    """
    options = dict(settings.tree_options or {})
    kappas = tuple(settings.pseudo_counts)
    needs_tree = any(p in TREE_POLICIES for p in policies)
    eta, kappa = settings.eta, kappas[0] if len(kappas) == 1 else None
    rules = tuple(settings.region_rules) or (str(options.get("region_rule", DEFAULT_REGION_RULE)),)
    options["region_rule"] = rules[0]  # unless validated below
    if needs_tree and (eta is None or len(kappas) > 1):

        def validate(rule: str) -> SwitchThresholdChoice:
            grid = ValidationGrid.around(eta, kappas, {**options, "region_rule": rule}, alpha=settings.alpha)
            return select_switch_threshold(sub, grid, seed=seed)

        choice = select_region_rule(rules, validate)
        assert choice is not None
        eta, kappa, options["region_rule"] = choice.eta, choice.pseudo_count, choice.region_rule
    elif eta is None:
        eta = 1.0
    expand = float(options.pop("expand_threshold", DEFAULT_EXPAND_THRESHOLD))
    tree = build_tree(sub, expand_threshold=expand, progress=False, **options) if needs_tree else None
    return run_benchmark(
        sub,
        policies=policies,
        tree=tree,
        seed=seed,
        settings=PolicySettings(eta, settings.alpha, kappa),
        progress=False,
    )
