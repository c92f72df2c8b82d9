"""Choose the tree-to-BiSECt switch threshold eta on held-out *training* worlds.

The paper treats eta (hand over to BiSECt once the consistent fraction of training worlds is at
or below eta) as a tuning parameter. Which value is best depends on the domain: on sets whose
worlds share structure (walls, baffles, canyons) a deep tree pays off, while on sets with many
infeasible training worlds (the HERB arm set) the node-conditioned leaf bias can be worse than the
global one, and switching at the root (eta = 1, i.e. plain BiSECt with the training bias) is best.

:func:`select_switch_threshold` decides this from the training worlds alone: it holds out a
seeded fraction of the *feasible* training worlds (the test protocol draws test worlds among
feasible ones), builds a tree on the rest, runs the combined policy for every candidate eta on
the held-out worlds and returns the eta with the fewest mean checks (ties go to the larger eta,
which relies less on the tree). The test worlds are never looked at.

The same validation also chooses the leaf's posterior pseudo-count kappa
(:mod:`drd_planner.core.posterior`) among ``pseudo_counts``; None there is the paper's fixed leaf
bias, and it wins ties, as does the larger eta and then the larger kappa.

One split of 27-90 worlds is noisy. With ``folds`` = k > 1 the validation is k-fold: k disjoint seeded
sets of held-out feasible training worlds (each the size of the single split), a tree built on the
training worlds outside each, every candidate run on every held-out world. A candidate's score is its
mean over all of them; its standard error is the spread of its k fold means over sqrt(k). The choice is
the *simplest* candidate within one standard error of the best mean (the one-standard-error rule: the
larger eta, then the fixed leaf, then the larger kappa), so a setting must beat a simpler one by more
than the noise to be chosen.

:func:`select_region_rule` repeats the validation for each region rule (:mod:`~drd_planner.core.region_rule`),
each with its own tree, eta and kappa, and keeps the first rule (the paper's) unless another one's best
mean is lower by more than its standard error (with one split: lower at all).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from drd_planner.arrays import IntArray
from drd_planner.core.episode import TableOracle, run_episode
from drd_planner.core.policies import DEFAULT_ALPHA, DirectBisectPolicy
from drd_planner.core.problem import Problem
from drd_planner.core.region_rule import DEFAULT_REGION_RULE
from drd_planner.core.tree import DEFAULT_EXPAND_THRESHOLD, DecisionTree, build_tree
from drd_planner.exceptions import ProblemError
from drd_planner.progress import Progress

#: Candidate thresholds; 1.0 means "switch at the root" (BiSECt with the training bias).
DEFAULT_ETA_CANDIDATES: tuple[float, ...] = (0.01, 0.02, 0.05, 0.1, 0.2, 0.4, 0.6, 1.0)
#: Candidate posterior pseudo-counts of the leaf; None keeps the bias fixed after the switch.
DEFAULT_PSEUDO_COUNTS: tuple[float | None, ...] = (None, 5.0, 20.0, 50.0)
#: Fraction of the feasible training worlds held out for validation.
DEFAULT_VALIDATION_FRACTION = 0.1


@dataclass(frozen=True)
class SwitchThresholdChoice:
    """The chosen eta and leaf pseudo-count, and the validation evidence behind them.

    Attributes:
        eta: the chosen threshold.
        pseudo_count: the chosen posterior pseudo-count, None for the fixed leaf bias.
        mean_checks: (eta, pseudo_count) candidate -> mean checks on the validation worlds.
        validation_ids: (k,) world rows held out (0-based rows of the problem's world database).
        seconds: wall time of the validation (not compared: equal choices may take different times).
        basis: what every candidate was run on, for reports (default: "K held-out training worlds").
        fold_means: with k-fold validation, candidate -> its mean checks on each fold (empty otherwise).
        region_rule: the region rule every candidate ran with (:mod:`~drd_planner.core.region_rule`).
        rule_means: when several rules were validated (:func:`select_region_rule`), rule -> the mean
            checks of its best candidate (empty otherwise).
    """

    eta: float
    pseudo_count: float | None
    mean_checks: dict[tuple[float, float | None], float]
    validation_ids: tuple[int, ...]
    seconds: float = field(default=0.0, compare=False)
    basis: str = ""
    fold_means: dict[tuple[float, float | None], tuple[float, ...]] = field(default_factory=dict)
    region_rule: str = DEFAULT_REGION_RULE
    rule_means: dict[str, float] = field(default_factory=dict)

    @property
    def best_mean(self) -> float:
        """The chosen candidate's mean checks."""
        return self.mean_checks[(self.eta, self.pseudo_count)]

    def standard_error(self, candidate: tuple[float, float | None]) -> float:
        """The standard error of a candidate's mean over the folds (0.0 with one split)."""
        means = self.fold_means.get(candidate, ())
        if len(means) < 2:
            return 0.0
        return float(np.std(means, ddof=1) / np.sqrt(len(means)))

    def as_json(self) -> dict[str, object]:
        """A JSON-able summary (for benchmark files and tree provenance)."""
        return {
            "eta": self.eta,
            "pseudo_count": self.pseudo_count,
            "mean_checks": {_label(*k): v for k, v in sorted(self.mean_checks.items(), key=_order)},
            "num_validation_worlds": len(self.validation_ids),
            "seconds": self.seconds,
            "region_rule": self.region_rule,
            **({"rule_mean_checks": dict(self.rule_means)} if self.rule_means else {}),
            **(
                {
                    "folds": len(next(iter(self.fold_means.values()))),
                    "standard_error": {
                        _label(*k): self.standard_error(k) for k in sorted(self.fold_means, key=_order_key)
                    },
                }
                if self.fold_means
                else {}
            ),
        }

    def describe(self) -> str:
        """One line for logs and provenance: the choice and every candidate's mean."""
        means = ", ".join(f"{_label(*k)}: {v:.2f}" for k, v in sorted(self.mean_checks.items(), key=_order))
        return (
            f"{_label(self.eta, self.pseudo_count)}{self._rule_text()} (validated on {self._basis()}; "
            f"mean checks {means})"
        )

    def summary_lines(self) -> list[str]:
        """A short report for people: the choice and the time taken, then mean checks per candidate.

        One row per eta and one column per kappa ("fixed" is the fixed leaf bias); ``*`` marks the choice.
        """
        etas = sorted({e for e, _ in self.mean_checks})
        kappas = sorted({k for _, k in self.mean_checks}, key=lambda k: -1.0 if k is None else k)
        heads = ["fixed" if k is None else f"kappa {k:g}" for k in kappas]
        width = max(9, *(len(h) for h in heads))
        leaf = "fixed leaf" if self.pseudo_count is None else f"kappa {self.pseudo_count:g}"
        lines = [
            f"eta {self.eta:g}, {leaf}: validated in {self.seconds:.1f} s on {self._basis()}",
            *([f"  {self._rule_text().lstrip(', ')}"] if self._rule_text() else []),
            "  mean checks " + "".join(f"{h:>{width - 1}} " for h in heads).rstrip(),
        ]
        for eta in etas:
            row = f"  eta {eta:<8g}"
            for kappa in kappas:
                value = self.mean_checks.get((eta, kappa))
                mark = "*" if (eta, kappa) == (self.eta, self.pseudo_count) else " "
                row += f"{'-' if value is None else f'{value:.2f}':>{width - 1}}{mark}"
            lines.append(row.rstrip())
        return lines

    def _rule_text(self) -> str:
        """The rule's part of a summary: the rule and each validated rule's best mean; empty for the paper's alone."""
        if self.region_rule == DEFAULT_REGION_RULE and not self.rule_means:
            return ""
        means = ", ".join(f"{r} {v:.2f}" for r, v in self.rule_means.items())
        return f", region rule {self.region_rule}" + (f" (best mean checks: {means})" if means else "")

    def _basis(self) -> str:
        return self.basis or f"{len(self.validation_ids)} held-out training worlds"


def _label(eta: float, pseudo_count: float | None) -> str:
    return f"eta {eta:g}" + ("" if pseudo_count is None else f" kappa {pseudo_count:g}")


def _order(item: tuple[tuple[float, float | None], float]) -> tuple[float, float]:
    return _order_key(item[0])


def _order_key(candidate: tuple[float, float | None]) -> tuple[float, float]:
    eta, kappa = candidate
    return (eta, -1.0 if kappa is None else kappa)


def _simplest(candidates: Sequence[tuple[float, float | None]]) -> tuple[float, float | None]:
    """The larger eta, then the fixed leaf (None), then the larger kappa."""
    return max(candidates, key=lambda k: (k[0], k[1] is None, -1.0 if k[1] is None else k[1]))


@dataclass(frozen=True)
class ValidationGrid:
    """The eta x kappa candidates a validation tries, and how its policy and tree are set up.

    Attributes:
        candidates: thresholds to try, each in (0, 1] (None: :data:`DEFAULT_ETA_CANDIDATES`).
        pseudo_counts: leaf posterior pseudo-counts to try (None: the fixed leaf bias).
        alpha: data weight of the leaf bias.
        expand_threshold: the tree's expansion threshold (as for the final tree).
        tree_options: further keyword arguments of :func:`drd_planner.core.tree.build_tree`
            (candidates, IncDRD, colouring), the same as for the final tree, so the validation
            tree is built the way the tree that will use eta is.
    """

    candidates: Sequence[float] | None = None
    pseudo_counts: Sequence[float | None] = DEFAULT_PSEUDO_COUNTS
    alpha: float = DEFAULT_ALPHA
    expand_threshold: float = DEFAULT_EXPAND_THRESHOLD
    tree_options: Mapping[str, Any] | None = None

    @classmethod
    def around(
        cls,
        eta: float | None,
        pseudo_counts: Sequence[float | None],
        tree_options: Mapping[str, Any],
        *,
        alpha: float = DEFAULT_ALPHA,
    ) -> ValidationGrid:
        """The grid of a run whose eta is given (only that one is tried) or open (None: the defaults).

        The tree's expansion threshold is ``tree_options``' ``expand_threshold`` (the default when absent).
        """
        return cls(
            candidates=None if eta is None else (eta,),
            pseudo_counts=pseudo_counts,
            alpha=alpha,
            expand_threshold=float(tree_options.get("expand_threshold", DEFAULT_EXPAND_THRESHOLD)),
            tree_options=tree_options,
        )


def select_switch_threshold(
    problem: Problem,
    grid: ValidationGrid | None = None,
    *,
    validation_fraction: float = DEFAULT_VALIDATION_FRACTION,
    seed: int = 0,
    max_worlds: int | None = None,
    progress: bool | None = False,
    folds: int = 1,
) -> SwitchThresholdChoice:
    """Pick eta and the leaf pseudo-count by validation on held-out feasible training worlds (see the module docstring).

    Args:
        problem: a problem with a world database; only its training worlds are used.
        grid: the candidates and the policy and tree settings (None: :class:`ValidationGrid` defaults).
        validation_fraction: share of the training worlds held out per fold (at least one world).
        seed: seeds the hold-out draw.
        max_worlds: hold out at most this many worlds per fold (a quick run; None: the validation fraction).
        progress: report the episodes on stderr (:class:`drd_planner.progress.Progress`; False: silent).
        folds: 1: one held-out split, the best mean wins (ties to the simpler setting); k > 1: k disjoint
            held-out sets, each with its own tree, and the one-standard-error rule (module docstring).
            Fewer folds are used when the feasible training worlds do not fill k of them.

    Raises:
        ProblemError: no candidates, a candidate outside (0, 1], a pseudo-count that is not
            positive, ``max_worlds`` or ``folds`` below 1, or fewer than two feasible training worlds.
    """
    t0 = time.perf_counter()
    grid = grid or ValidationGrid()
    cands, kappas = _checked_candidates(grid)
    if not 0.0 < validation_fraction < 1.0:
        raise ProblemError(f"validation_fraction must lie in (0, 1); got {validation_fraction}")
    if int(folds) != folds or folds < 1:
        raise ProblemError(f"folds must be an integer >= 1, got {folds!r}")
    worlds = problem.require_worlds()
    train = worlds.train_ids
    feasible = train[worlds.R[train].any(axis=1)]
    if feasible.size < 2:
        raise ProblemError("need at least two feasible training worlds to validate eta")
    if max_worlds is not None and max_worlds < 1:
        raise ProblemError(f"max_worlds must be at least 1, got {max_worlds}")
    k = min(feasible.size - 1, max(1, round(validation_fraction * train.size)), max_worlds or feasible.size)
    num_folds = max(1, min(int(folds), (feasible.size - 1) // k))
    rng = np.random.default_rng(seed)
    drawn = rng.choice(feasible, size=k * num_folds, replace=False)
    options = {key: v for key, v in (grid.tree_options or {}).items() if key not in ("expand_threshold", "progress")}
    per_fold: list[dict[tuple[float, float | None], float]] = []
    for fold in range(num_folds):
        held_out = np.sort(drawn[fold * k : (fold + 1) * k])
        fit = np.setdiff1d(train, held_out)
        sub = dataclasses.replace(problem, worlds=worlds.subset(fit, held_out))
        tree = build_tree(sub, expand_threshold=grid.expand_threshold, progress=False, **options)
        per_fold.append(_mean_checks(problem, tree, (cands, kappas), held_out, alpha=grid.alpha, progress=progress))
    means = {c: float(np.mean([f[c] for f in per_fold])) for c in per_fold[0]}
    fold_means = {c: tuple(f[c] for f in per_fold) for c in per_fold[0]} if num_folds > 1 else {}
    best = min(means, key=lambda c: (means[c], -_order_key(c)[0]))
    choice = SwitchThresholdChoice(
        0.0,
        None,
        means,
        tuple(int(h) for h in np.sort(drawn)),
        seconds=0.0,
        basis=f"{num_folds} folds x {k} held-out training worlds" if num_folds > 1 else "",
        fold_means=fold_means,
        region_rule=str(options.get("region_rule", DEFAULT_REGION_RULE)),
    )
    margin = choice.standard_error(best) + 1e-12
    eta, kappa = _simplest([c for c, v in means.items() if v <= means[best] + margin])
    return dataclasses.replace(choice, eta=eta, pseudo_count=kappa, seconds=time.perf_counter() - t0)


def select_region_rule(
    rules: Sequence[str], validate: Callable[[str], SwitchThresholdChoice | None]
) -> SwitchThresholdChoice | None:
    """The validation of the best region rule, each rule validated by ``validate(rule)``.

    The first rule is kept unless a later one's best mean is lower than the kept one's by more than its
    standard error (one split: any amount). The returned choice has ``region_rule`` and ``rule_means``
    set. None when ``validate`` validated nothing (it returned None: eta and kappa are fixed).

    Raises:
        ProblemError: no rule.
    """
    if not rules:
        raise ProblemError("give at least one region rule to validate")
    best: SwitchThresholdChoice | None = None
    scores: dict[str, float] = {}
    for rule in rules:
        choice = validate(rule)
        if choice is None:
            return None
        choice = dataclasses.replace(choice, region_rule=rule)
        scores[rule] = choice.best_mean
        margin = choice.standard_error((choice.eta, choice.pseudo_count)) + 1e-12
        if best is None or choice.best_mean < best.best_mean - margin:
            best = choice
    assert best is not None
    return dataclasses.replace(best, rule_means=scores if len(scores) > 1 else {})


def _checked_candidates(grid: ValidationGrid) -> tuple[list[float], list[float | None]]:
    """The grid's eta candidates (sorted, distinct) and kappas (None first, then increasing).

    Raises:
        ProblemError: no eta candidate, one outside (0, 1], no kappa, or a kappa that is not positive.
    """
    candidates = DEFAULT_ETA_CANDIDATES if grid.candidates is None else grid.candidates
    cands = sorted({float(c) for c in candidates})
    if not cands or cands[0] <= 0.0 or cands[-1] > 1.0:
        raise ProblemError(f"eta candidates must be non-empty and lie in (0, 1]; got {list(candidates)}")
    kappas = sorted(
        {None if k is None else float(k) for k in grid.pseudo_counts}, key=lambda k: -1.0 if k is None else k
    )
    if not kappas or any(k is not None and not (k > 0 and np.isfinite(k)) for k in kappas):
        raise ProblemError(f"pseudo-counts must be non-empty, each None or > 0; got {list(grid.pseudo_counts)}")
    return cands, kappas


def _mean_checks(
    problem: Problem,
    tree: DecisionTree,
    grid: tuple[list[float], list[float | None]],
    held_out: IntArray,
    *,
    alpha: float,
    progress: bool | None,
) -> dict[tuple[float, float | None], float]:
    """(eta, kappa) -> mean checks of ``direct_bisect`` with ``tree`` over the ``held_out`` world rows."""
    worlds = problem.require_worlds()
    costs = problem.edge_costs
    cands, kappas = grid
    means: dict[tuple[float, float | None], float] = {}
    total_episodes = len(cands) * len(kappas) * held_out.size
    with Progress(total_episodes, "validating eta x kappa", unit="episode", enabled=progress, announce=True) as bar:
        for eta in cands:
            for kappa in kappas:
                total = 0
                for world in held_out:
                    policy = DirectBisectPolicy(tree, problem.library, costs, eta=eta, alpha=alpha, pseudo_count=kappa)
                    result = run_episode(problem.library, costs, policy, TableOracle(worlds.X[world]))
                    total += result.num_checks
                    bar.update(1)
                means[(eta, kappa)] = total / held_out.size
    return means
