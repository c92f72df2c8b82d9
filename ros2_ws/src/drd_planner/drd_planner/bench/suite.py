"""Run the benchmark over one dataset or every dataset folder under a root, with figures and reports.

:func:`run_dataset` benchmarks one loaded problem (and draws its figures); :func:`run_suite` does that for
every authors'-format folder under a root (sorted by name), skipping folders that lack the required files
with a note. :func:`suite_json` and :func:`suite_markdown` turn the runs into one document each.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from drd_planner import __version__
from drd_planner.bench.extras import require_extra
from drd_planner.bench.learning_curve import DEFAULT_SIZES, TrainingCurve, training_size_curve
from drd_planner.bench.report import full_report
from drd_planner.bench.runner import (
    DEFAULT_POLICIES,
    BenchmarkResult,
    PolicySettings,
    available_policies,
    benchmark_json,
    check_policy_names,
    require_test_worlds,
    result_table1,
    run_benchmark,
    run_world,
    train_bias,
)
from drd_planner.bench.stats import DEFAULT_RESAMPLES, REFERENCE, TIE_SUBSET, Table1
from drd_planner.core.policies import DEFAULT_ALPHA, DEFAULT_ETA, TREE_POLICIES
from drd_planner.core.problem import Problem
from drd_planner.core.region_rule import REGION_RULES
from drd_planner.core.switch_threshold import (
    DEFAULT_PSEUDO_COUNTS,
    SwitchThresholdChoice,
    ValidationGrid,
    select_region_rule,
    select_switch_threshold,
)
from drd_planner.core.tree import DecisionTree, build_tree
from drd_planner.data.gccd import REQUIRED_FILES, load_gccd_folder
from drd_planner.exceptions import DrdError
from drd_planner.progress import Progress


@dataclass(frozen=True)
class SuiteOptions:
    """Settings of a benchmark run (one dataset or many).

    Attributes:
        policies: policies to run, in report column order.
        seed: base seed of the episodes (test world k uses seed + k), the bootstrap and the subsets.
        eta: switch threshold of ``direct_bisect``; None chooses it per dataset by validation on held-out
            training worlds (:func:`drd_planner.core.switch_threshold.select_switch_threshold`).
        pseudo_counts: candidate kappas of ``direct_bisect``'s posterior leaf (None: fixed leaf bias),
            validated together with eta; one candidate fixes it.
        alpha: data weight of the tree policies' bias.
        max_worlds: only the first K test worlds of each dataset (None: all).
        max_checks: per-episode check cap (None: none); capped episodes count as failures.
        tree_options: keyword arguments for :func:`drd_planner.core.tree.build_tree`.
        reference, tie_subset, resamples: Table-1 statistics settings (see :mod:`drd_planner.bench.stats`).
        figures: folder for the figures, or None for none; figures need the ``plots`` extra (matplotlib),
            checked when the options are made (:class:`~drd_planner.bench.extras.MissingExtraError`).
        training_sizes: training-set sizes of the checks-vs-training-size figure (empty: no such figure).
        figure_world: position in the test list of the world drawn in the checked-edges figure.
        validation_folds: folds of the eta / kappa validation (1: one held-out split; k > 1: k-fold with
            the one-standard-error rule, :func:`~drd_planner.core.switch_threshold.select_switch_threshold`).
        region_rules: region rules to validate (:mod:`~drd_planner.core.region_rule`): each gets its own
            eta / kappa validation with a tree built by it, and the first (the paper's) is kept unless
            another's validated mean is lower by more than its standard error (any lower with one
            split); default: every rule; empty: ``tree_options``' rule, not validated.
    """

    policies: tuple[str, ...] = DEFAULT_POLICIES
    seed: int = 0
    eta: float | None = None
    pseudo_counts: tuple[float | None, ...] = DEFAULT_PSEUDO_COUNTS
    alpha: float = DEFAULT_ALPHA
    max_worlds: int | None = None
    max_checks: int | None = None
    tree_options: Mapping[str, Any] = field(default_factory=dict)
    reference: str = REFERENCE
    tie_subset: tuple[str, ...] = TIE_SUBSET
    resamples: int = DEFAULT_RESAMPLES
    figures: Path | None = None
    training_sizes: tuple[int, ...] = DEFAULT_SIZES
    figure_world: int = 0
    validation_folds: int = 1
    region_rules: tuple[str, ...] = REGION_RULES

    def __post_init__(self) -> None:
        """Fail early, naming the extra, when figures are asked for without matplotlib."""
        if self.figures is not None:
            require_extra("plots", "drd bench --figures")


@dataclass(frozen=True)
class DatasetRun:
    """One dataset's benchmark, statistics, figures and notes; ``leaf``: the eta/kappa validation, if run.

    ``seconds`` is the whole run's wall time, the validation's (``leaf.seconds``) included.
    """

    result: BenchmarkResult
    table: Table1 | None
    figures: list[Path]
    notes: list[str]
    curve: TrainingCurve | None
    seconds: float
    leaf: SwitchThresholdChoice | None = None


@dataclass(frozen=True)
class SuiteResult:
    """Every dataset's run, the skipped folders (name, reason) and the total wall time in seconds."""

    runs: list[DatasetRun]
    skipped: list[tuple[str, str]]
    seconds: float


def discover_datasets(root: str | Path) -> tuple[list[Path], list[tuple[str, str]]]:
    """The authors'-format folders under ``root`` (sorted) and, for the others, why they are skipped.

    Raises:
        DrdError: ``root`` is not a folder, or holds no runnable dataset folder.
    """
    base = Path(root)
    if not base.is_dir():
        raise DrdError(f"dataset root not found: {base}")
    runnable: list[Path] = []
    skipped: list[tuple[str, str]] = []
    for folder in sorted(p for p in base.iterdir() if p.is_dir()):
        missing = [f for f in REQUIRED_FILES if not (folder / f).is_file()]
        if missing:
            more = f" and {len(missing) - 1} more required files" if len(missing) > 1 else ""
            skipped.append((folder.name, f"not an authors'-format graph dataset (missing {missing[0]}{more})"))
        else:
            runnable.append(folder)
    if not runnable:
        raise DrdError(f"no dataset folder under {base} has all of {', '.join(REQUIRED_FILES)}")
    return runnable, skipped


def _needs_tree(options: SuiteOptions) -> bool:
    return any(p in TREE_POLICIES for p in options.policies) or options.figures is not None


def run_dataset(
    problem: Problem,
    options: SuiteOptions,
    *,
    tree: DecisionTree | None = None,
    progress: bool | None = None,
) -> DatasetRun:
    """Benchmark one problem, compute its Table-1 statistics and write its figures.

    Args:
        problem: a problem with a world database.
        options: the run settings.
        tree: a prebuilt tree (built from ``options.tree_options`` when needed and not given).
        progress: progress of the validation and of each policy on stderr (a bar on a terminal, plain
            lines otherwise; False: silent).

    Raises:
        DrdError: the problem has no test worlds, or a setting is invalid.
    """
    t0 = time.perf_counter()
    check_policy_names(options.policies)
    require_test_worlds(problem)
    options, eta_choice, rule_scores = resolve_settings(problem, options, progress=progress)
    if tree is None and _needs_tree(options):
        tree = build_tree(problem, progress=False, **dict(options.tree_options))
    result = run_benchmark(
        problem,
        policies=options.policies,
        tree=tree,
        seed=options.seed,
        settings=_settings(options),
        max_worlds=options.max_worlds,
        max_checks=options.max_checks,
        progress=progress,
    )
    if eta_choice is not None:
        result.settings["eta_selection"] = eta_choice.as_json()
    if rule_scores:
        result.settings["region_rule_selection"] = {
            "chosen": options.tree_options["region_rule"],
            "validated_mean_checks": rule_scores,
        }
    table = result_table1(
        result,
        reference=options.reference,
        tie_subset=options.tie_subset,
        resamples=options.resamples,
        seed=options.seed,
    )
    figures: list[Path] = []
    notes: list[str] = []
    curve = None
    if options.figures is not None:
        assert tree is not None
        figures += _checked_edges_figure(problem, result, tree, options, notes)
        curve = _training_figure(problem, options, figures, notes)
        figures += _checks_vs_cost_figure(problem, result, options, notes)
    return DatasetRun(result, table, figures, notes, curve, time.perf_counter() - t0, eta_choice)


def resolve_settings(
    problem: Problem, options: SuiteOptions, *, progress: bool | None = False
) -> tuple[SuiteOptions, SwitchThresholdChoice | None, dict[str, float]]:
    """The options with a concrete eta, kappa and region rule; the eta/kappa validation; each rule's score.

    Without ``options.region_rules`` this is :func:`resolve_leaf`. With them, every rule is validated
    (its own tree, eta and kappa) and the rule chosen as :class:`SuiteOptions` says; its validated mean
    checks are the returned scores.
    """
    if not options.region_rules:
        eta, kappa, choice = resolve_leaf(problem, options, progress=progress)
        return dataclasses.replace(options, eta=eta, pseudo_counts=(kappa,)), choice, {}

    def with_rule(rule: str) -> SuiteOptions:
        return dataclasses.replace(options, tree_options={**options.tree_options, "region_rule": rule})

    choice = select_region_rule(
        options.region_rules, lambda rule: resolve_leaf(problem, with_rule(rule), progress=progress)[2]
    )
    if choice is None:  # nothing validated (eta and kappa fixed, or no tree): the first rule
        trial = with_rule(options.region_rules[0])
        eta, kappa, _ = resolve_leaf(problem, trial, progress=progress)
        return dataclasses.replace(trial, eta=eta, pseudo_counts=(kappa,)), None, {}
    chosen = with_rule(choice.region_rule)
    return (
        dataclasses.replace(chosen, eta=choice.eta, pseudo_counts=(choice.pseudo_count,)),
        choice,
        dict(choice.rule_means),
    )


def resolve_leaf(
    problem: Problem, options: SuiteOptions, *, progress: bool | None = False
) -> tuple[float, float | None, SwitchThresholdChoice | None]:
    """A concrete eta and kappa: validated unless both are fixed or no tree is used.

    The validation holds out at most ``options.max_worlds`` training worlds (a quick run stays quick);
    ``progress`` reports its episodes on stderr.
    """
    if not options.pseudo_counts:
        raise DrdError("pseudo_counts needs at least one candidate (None for the fixed leaf bias)")
    fixed_kappa = len(options.pseudo_counts) == 1
    if not _needs_tree(options) or (options.eta is not None and fixed_kappa):
        eta = DEFAULT_ETA if options.eta is None else options.eta
        return eta, options.pseudo_counts[0] if fixed_kappa else None, None
    choice = select_switch_threshold(
        problem,
        ValidationGrid.around(options.eta, options.pseudo_counts, options.tree_options, alpha=options.alpha),
        seed=options.seed,
        max_worlds=options.max_worlds,
        progress=progress,
        folds=options.validation_folds,
    )
    return choice.eta, choice.pseudo_count, choice


def _settings(options: SuiteOptions) -> PolicySettings:
    """The policy settings after :func:`resolve_leaf` (eta set, one kappa candidate left)."""
    eta = DEFAULT_ETA if options.eta is None else options.eta
    return PolicySettings(eta, options.alpha, options.pseudo_counts[0] if options.pseudo_counts else None)


def _checked_edges_figure(
    problem: Problem, result: BenchmarkResult, tree: DecisionTree, options: SuiteOptions, notes: list[str]
) -> list[Path]:
    from drd_planner.bench.plots import FIG3_POLICIES, has_vertex_xy, plot_checked_edges

    assert options.figures is not None
    if not has_vertex_xy(problem):
        notes.append(f"{problem.name}: no vertex coordinates, checked-edges figure skipped")
        return []
    k = options.figure_world
    if not 0 <= k < len(result.test_ids):
        raise DrdError(f"figure world {k} is outside the {len(result.test_ids)} test worlds run")
    world = result.test_ids[k]
    theta = train_bias(problem, alpha=options.alpha)
    episodes = {
        name: run_world(
            problem,
            name,
            world,
            theta=theta,
            tree=tree,
            seed=options.seed + k,
            settings=_settings(options),
            max_checks=options.max_checks,
        )
        for name in available_policies(FIG3_POLICIES)
    }
    out = options.figures / f"checked_edges_{problem.name}"
    return plot_checked_edges(problem, episodes, out, world=world)


def _checks_vs_cost_figure(
    problem: Problem, result: BenchmarkResult, options: SuiteOptions, notes: list[str]
) -> list[Path]:
    """Checks versus path cost (:mod:`drd_planner.bench.anytime_figure`), for a dataset with its own query."""
    assert options.figures is not None
    if problem.graph is None or problem.start is None or problem.goal is None:
        notes.append(f"{problem.name}: no graph query, checks-versus-cost figure skipped")
        return []
    from drd_planner.bench.anytime_figure import checks_vs_cost, plot_checks_vs_cost

    try:
        data = checks_vs_cost(problem, result, seed=options.seed, settings=_settings(options))
    except DrdError as exc:
        notes.append(f"checks-versus-cost figure skipped: {exc}")
        return []
    return plot_checks_vs_cost(data, problem.name, options.figures / f"checks_vs_cost_{problem.name}")


def _training_figure(
    problem: Problem, options: SuiteOptions, figures: list[Path], notes: list[str]
) -> TrainingCurve | None:
    assert options.figures is not None
    if not options.training_sizes:
        return None
    limit = problem.require_worlds().train_ids.size
    sizes = [s for s in options.training_sizes if 1 <= s <= limit]
    if len(sizes) < len(options.training_sizes):
        notes.append(f"{problem.name}: training sizes above {limit} (the training set) left out")
    if not sizes:
        return None
    curve = training_size_curve(
        problem,
        sizes=sizes,
        seed=options.seed,
        max_worlds=options.max_worlds,
        settings=_settings(options),
        tree_options=options.tree_options,
    )
    from drd_planner.bench.plots import plot_training_curve

    figures += plot_training_curve(curve, options.figures / f"training_size_{problem.name}")
    return curve


def costs_figure(runs: Sequence[DatasetRun], options: SuiteOptions) -> list[Path]:
    """The normalised-cost figure over every run that has Table-1 statistics (none: nothing written)."""
    if options.figures is None:
        return []
    from drd_planner.bench.plots import plot_normalised_costs

    tables = {run.result.dataset: run.table for run in runs if run.table is not None}
    if not tables:
        return []
    baselines = [p for p in options.policies if p != options.reference]
    failures = {
        run.result.dataset: {name: stats.failures for name, stats in run.result.policies.items()} for run in runs
    }
    return plot_normalised_costs(tables, baselines, options.figures / "normalised_costs", failures=failures)


def run_suite(root: str | Path, options: SuiteOptions, *, progress: bool | None = None) -> SuiteResult:
    """Run :func:`run_dataset` on every dataset folder under ``root`` (sorted), reporting progress on stderr.

    Folders without the required files, or without test worlds, are skipped (listed in the result with
    the reason); a folder that has the files but is malformed raises its DatasetError.
    """
    t0 = time.perf_counter()
    check_policy_names(options.policies)
    folders, skipped = discover_datasets(root)
    runs: list[DatasetRun] = []
    with Progress(len(folders), "datasets", unit="dataset", enabled=progress, announce=True) as bar:
        for folder in folders:
            bar.set_postfix_str(folder.name)
            problem = load_gccd_folder(folder)
            if problem.require_worlds().test_ids.size == 0:
                skipped.append((folder.name, "no test worlds"))
            else:
                runs.append(run_dataset(problem, options, progress=False))
            bar.update(1)
    return SuiteResult(runs, skipped, time.perf_counter() - t0)


def leaf_lines(runs: Sequence[DatasetRun]) -> list[str]:
    """How each run's eta and kappa were validated: with the table for one dataset, one line each for many."""
    lines: list[str] = []
    for run in runs:
        if run.leaf is None:
            continue
        summary = run.leaf.summary_lines()
        lines.append(f"{run.result.dataset}: {summary[0]} (--eta/--kappa fix them)")
        if len(runs) == 1:
            lines += summary[1:]
    return lines


def dataset_json(run: DatasetRun, options: SuiteOptions) -> dict[str, Any]:
    """One dataset's ``drd bench --json`` document with ``wall_seconds``, ``notes`` and ``figures``.

    A ``training_curve`` block is added when that figure was drawn.
    """
    doc = benchmark_json(
        run.result,
        reference=options.reference,
        tie_subset=options.tie_subset,
        resamples=options.resamples,
        seed=options.seed,
    )
    doc["wall_seconds"] = run.seconds
    doc["notes"] = run.notes
    doc["figures"] = [str(p) for p in run.figures]
    if run.curve is not None:
        doc["training_curve"] = run.curve.as_json()
    return doc


def suite_json(suite: SuiteResult, options: SuiteOptions, *, figures: Sequence[Path] = ()) -> dict[str, Any]:
    """One document for many datasets: each dataset's :func:`dataset_json` under ``datasets``.

    ``figures`` lists figures drawn over all datasets (the normalised-cost chart).
    """
    return {
        "software": f"drd_planner {__version__}",
        "policies": list(options.policies),
        "reference": options.reference,
        "datasets": [dataset_json(run, options) for run in suite.runs],
        "skipped": [{"folder": name, "reason": reason} for name, reason in suite.skipped],
        "figures": [str(p) for p in figures],
        "wall_seconds": suite.seconds,
    }


def suite_markdown(suite: SuiteResult, options: SuiteOptions) -> str:
    """The full markdown report over every dataset of the suite."""
    return full_report(
        [run.result for run in suite.runs],
        [run.table for run in suite.runs],
        options.policies,
        reference=options.reference,
        skipped=suite.skipped,
    )
