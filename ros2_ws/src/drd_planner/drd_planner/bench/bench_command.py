"""``drd bench`` on one dataset or every dataset under a folder, as a library call (:func:`run_bench`).

The command line (:mod:`drd_planner.cli.bench`) makes a :class:`BenchOptions`; ``drd bench --queries N`` is
:mod:`drd_planner.bench.query_command`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from drd_planner.bench.runner import check_policy_names, write_bench_files
from drd_planner.bench.suite import (
    SuiteOptions,
    SuiteResult,
    costs_figure,
    dataset_json,
    leaf_lines,
    run_dataset,
    run_suite,
    suite_json,
    suite_markdown,
)
from drd_planner.data.problem_source import ProblemSource, problem_domain
from drd_planner.exceptions import DrdError

__all__ = ["BenchOptions", "run_bench"]


@dataclass(frozen=True)
class BenchOptions:
    """One ``drd bench`` run (not ``--queries``).

    Attributes:
        suite: the benchmark's settings (policies, eta and kappa candidates, limits, statistics, figures).
        source: the one dataset to run (None: every authors'-format folder under ``all_root``).
        all_root: the folder whose authors'-format dataset folders are all run (None: ``source``).
        prior: use this tree or prior file instead of building a tree (one dataset only); its stored eta
            and kappa apply unless the suite's eta is given or ``kappa_given``.
        kappa_given: the suite's kappa candidates were chosen (``--kappa``), so a ``prior``'s kappa does not
            replace them.
        json: write the results JSON here (None: not written).
        markdown: write the markdown report here (None: not written).
    """

    suite: SuiteOptions
    source: ProblemSource | None = None
    all_root: str | None = None
    prior: str | None = None
    kappa_given: bool = False
    json: str | None = None
    markdown: str | None = None


def run_bench(options: BenchOptions) -> int:
    """Every policy on every test world of one dataset (``source``) or of all (``all_root``); exit status 0.

    Prints the markdown report, skipped datasets, notes, the validated leaf settings, the figures written
    and the wall time; writes the JSON and markdown files asked for.
    """
    suite_options = options.suite
    check_policy_names(suite_options.policies)
    for name, value in (
        ("--max-worlds", suite_options.max_worlds),
        ("--max-checks", suite_options.max_checks),
    ):
        if value is not None and value < 1:
            raise DrdError(f"{name} must be at least 1, got {value}")
    if options.all_root:
        if options.prior:
            raise DrdError("--prior fits one dataset and cannot be used with --all")
        suite = run_suite(options.all_root, suite_options)
        figures = costs_figure(suite.runs, suite_options)
        doc = suite_json(suite, suite_options, figures=figures)
    else:
        suite, figures, doc = _bench_one_dataset(options)
    report = suite_markdown(suite, suite_options)
    _print_bench(report, suite)
    write_bench_files(doc, report, json_path=options.json, markdown_path=options.markdown)
    if suite_options.figures is not None:
        count = sum(len(r.figures) for r in suite.runs) + len(figures)
        print(f"wrote {count} figure files under {suite_options.figures}")
    validation = sum(run.leaf.seconds for run in suite.runs if run.leaf is not None)
    print(f"total wall time {suite.seconds:.1f} s (eta and kappa validation {validation:.1f} s of it)")
    return 0


def _bench_one_dataset(options: BenchOptions) -> tuple[SuiteResult, list[Path], dict[str, Any]]:
    """``drd bench`` on one dataset (with its ``prior``): (suite, figures, JSON doc)."""
    from drd_planner.data.tree_file import check_bundle_fits
    from drd_planner.planner.prior_file import load_tree_bundle

    suite_options = options.suite
    problem = (options.source or ProblemSource()).load()
    tree = None
    if options.prior:
        bundle = load_tree_bundle(options.prior, expected_domain=problem_domain(problem))
        check_bundle_fits(bundle, problem)
        tree = bundle.tree
        if suite_options.eta is None:  # the settings stored with the tree, unless --eta/--kappa say otherwise
            suite_options = dataclasses.replace(suite_options, eta=bundle.eta)
        if not options.kappa_given:
            suite_options = dataclasses.replace(suite_options, pseudo_counts=(bundle.pseudo_count,))
    run = run_dataset(problem, suite_options, tree=tree)
    suite = SuiteResult([run], [], run.seconds)
    figures = list(costs_figure(suite.runs, suite_options))
    doc = dataset_json(run, suite_options)
    doc["figures"] += [str(p) for p in figures]
    return suite, figures, doc


def _print_bench(report: str, suite: SuiteResult) -> None:
    """The markdown report, then skipped datasets, notes and the validated leaf settings."""
    print(report, end="")
    for name, reason in suite.skipped:
        print(f"skipped {name}: {reason}")
    for run in suite.runs:
        for note in run.notes:
            print(f"note: {note}")
    for line in leaf_lines(suite.runs):
        print(line)
