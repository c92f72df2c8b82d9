"""Run policies over a problem's test worlds against a table-lookup oracle and collect statistics.

The JSON written by :func:`benchmark_json` is the ``drd bench --json`` document of docs/getting-started.md:
``{"dataset", "test_ids", "oracle_lower_bound": {"mean", "per_world"}, "policies": {NAME:
{"mean_checks", "median_checks", "checks", "failures", "mean_select_ms"}}}`` plus a ``tree`` block, the
run ``settings``, per policy ``failed_worlds`` (positions in ``test_ids``) and ``relative`` (Table-1
statistics over the reference ``direct_bisect``, see :mod:`drd_planner.bench.stats`; null when the
reference was not run), ``oracle_lower_bound.relative`` and a ``relative_protocol`` block.
``test_ids`` are 0-based row indices of the dataset's world matrix.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.bench.lazysp_imitation import IMITATION_POLICY, ImitationModel, train_for_problem
from drd_planner.bench.learned_policies import TRAIN_WORLD_POLICIES
from drd_planner.bench.stats import DEFAULT_RESAMPLES, REFERENCE, TIE_SUBSET, Table1, table1_stats
from drd_planner.core.bisect import bias_from_worlds
from drd_planner.core.bounds import oracle_lower_bound
from drd_planner.core.episode import EpisodeResult, TableOracle, run_episode
from drd_planner.core.policies import (
    DEFAULT_ALPHA,
    DEFAULT_ETA,
    PAPER_RULE_POLICIES,
    POLICIES,
    TREE_POLICIES,
    PolicyContext,
)
from drd_planner.core.problem import Problem
from drd_planner.core.region_rule import DEFAULT_REGION_RULE
from drd_planner.core.tree import DecisionTree, build_tree
from drd_planner.exceptions import DrdError
from drd_planner.progress import Progress

#: The policies of the paper's Table 1 (and ours), in table order.
TABLE1_POLICIES = (
    "direct_bisect",
    "direct_bisect_fixed",
    "bisect",
    "lazysp_set",
    "lazysp",
    "max_tally",
    "set_cover",
    "mvoi",
    "random",
    "direct_only",
    "bisect_all",
)
#: Policies ``run_benchmark`` runs when none are named (the Table-1 set as far as it is registered).
DEFAULT_POLICIES = tuple(p for p in TABLE1_POLICIES if p in POLICIES)


def available_policies(names: Sequence[str] = TABLE1_POLICIES) -> tuple[str, ...]:
    """The names among ``names`` that are registered in ``POLICIES`` (order kept)."""
    return tuple(p for p in names if p in POLICIES)


#: External peers run outside the episode runner (in their own process), reported like policies.
PEER_POLICIES = ("ompl_lazyprm",)
#: Wall-clock limit of one peer solve, in seconds.
PEER_TIME_LIMIT_S = 10.0


def check_policy_names(names: Sequence[str]) -> None:
    """Raise a clear DrdError naming every unknown policy."""
    unknown = [p for p in names if p not in POLICIES and p not in PEER_POLICIES]
    if unknown:
        raise DrdError(f"unknown policy {', '.join(unknown)}; known: {', '.join(sorted(POLICIES))}")


@dataclass(frozen=True)
class PolicyStats:
    """Per-policy results over the test worlds (in test-id order).

    Attributes:
        checks: checks per test world; a failed episode counts the checks it made.
        failures: number of episodes that proved no path (gave up, hit the cap, or found none).
        select_ms: selection time of every check, in milliseconds.
        episode_seconds: wall time of all episodes of this policy, in seconds.
        failed_worlds: positions (in the test list) of the failed episodes.
    """

    checks: list[int]
    failures: int
    select_ms: list[float]
    episode_seconds: float
    failed_worlds: list[int] = field(default_factory=list)

    def as_json(self) -> dict[str, Any]:
        """The documented policy block (``drd bench --json``) plus ``failed_worlds``."""
        arr = np.asarray(self.checks, dtype=np.float64)
        return {
            "mean_checks": float(arr.mean()) if arr.size else float("nan"),
            "median_checks": float(np.median(arr)) if arr.size else float("nan"),
            "checks": [int(c) for c in self.checks],
            "failures": int(self.failures),
            "mean_select_ms": self.mean_select_ms,
            "failed_worlds": [int(k) for k in self.failed_worlds],
        }

    @property
    def mean_select_ms(self) -> float:
        """Mean selection time per check in milliseconds (0 when nothing was checked)."""
        return float(np.mean(self.select_ms)) if self.select_ms else 0.0


@dataclass(frozen=True)
class BenchmarkResult:
    """Everything one benchmark run measured.

    Attributes:
        dataset: the problem's name.
        test_ids: 0-based world rows of the episodes, in order.
        lower_bound: (n,) oracle lower bound per test world (NaN where no library path is valid).
        policies: policy name -> its statistics.
        tree_info: size and build provenance of the decision tree used (empty when none).
        settings: seed, eta, alpha, max_worlds and max_checks of the run (and ``imitation`` training stats).
        imitation_model: the ``lazysp_imitation`` selector the run trained (None: not run).
    """

    dataset: str
    test_ids: list[int]
    lower_bound: list[float]
    policies: dict[str, PolicyStats]
    tree_info: dict[str, Any] = field(default_factory=dict)
    settings: dict[str, Any] = field(default_factory=dict)
    imitation_model: ImitationModel | None = None

    def checks(self) -> dict[str, list[int]]:
        """Policy name -> checks per test world."""
        return {name: stats.checks for name, stats in self.policies.items()}


@dataclass(frozen=True)
class PolicySettings:
    """The settings of the Bayesian policies in one benchmark run (the :class:`PolicyContext` fields).

    Attributes:
        eta: switch threshold of ``direct_bisect``.
        alpha: data weight of the bias.
        pseudo_count: kappa of ``direct_bisect``'s posterior leaf; None keeps the leaf bias fixed.
        imitation_model: ``lazysp_imitation``'s selector, trained once per dataset (None: not yet).
    """

    eta: float = DEFAULT_ETA
    alpha: float = DEFAULT_ALPHA
    pseudo_count: float | None = None
    imitation_model: ImitationModel | None = None


#: The defaults of every setting.
DEFAULT_SETTINGS = PolicySettings()


def policy_context(
    problem: Problem,
    *,
    theta: npt.NDArray[np.float64],
    tree: DecisionTree | None,
    seed: int,
    settings: PolicySettings = DEFAULT_SETTINGS,
    policy: str | None = None,
) -> PolicyContext:
    """The context a policy factory gets: library, unit costs, (E,) training bias, tree, seed and graph.

    The graph, start and goal are what the full-graph policies (``lazysp``, ``lazysp_set``) need; the
    (n_train, E) training worlds and their prior weights what the learned ``lazysp_posterior*`` need
    (:data:`~drd_planner.bench.learned_policies.TRAIN_WORLD_POLICIES`). Given the ``policy`` the context is for,
    the training worlds are copied only when it needs them (every episode builds a context).
    """
    worlds = problem.worlds
    train_worlds = train_weights = None
    if worlds is not None and (policy is None or policy in TRAIN_WORLD_POLICIES):
        train_worlds = worlds.X[worlds.train_ids]
        train_weights = None if worlds.prior is None else worlds.weights(worlds.train_ids)
    return PolicyContext(
        problem.library,
        problem.edge_costs,
        theta,
        tree,
        seed,
        eta=settings.eta,
        alpha=settings.alpha,
        pseudo_count=settings.pseudo_count,
        graph=problem.graph,
        start=problem.start,
        goal=problem.goal,
        train_worlds=train_worlds,
        train_weights=train_weights,
        imitation_model=settings.imitation_model,
    )


def train_bias(problem: Problem, *, alpha: float = DEFAULT_ALPHA) -> npt.NDArray[np.float64]:
    """(E,) BiSECt bias learnt from the problem's training worlds."""
    worlds = problem.require_worlds()
    train = worlds.train_ids
    return bias_from_worlds(worlds.X[train], worlds.weights(train), alpha=alpha)


def run_world(
    problem: Problem,
    name: str,
    world: int,
    *,
    theta: npt.NDArray[np.float64],
    tree: DecisionTree | None,
    seed: int,
    settings: PolicySettings = DEFAULT_SETTINGS,
    max_checks: int | None = None,
) -> EpisodeResult:
    """One episode of policy ``name`` on world row ``world`` against its row of X.

    ``run_benchmark`` calls this with ``seed + k`` for the k-th test world, so the same call here
    reproduces any of its episodes (figures use that; ``lazysp_imitation`` also needs the run's
    ``settings.imitation_model``, ``BenchmarkResult.imitation_model``: it is never trained per episode).
    """
    check_policy_names([name])
    worlds = problem.require_worlds()
    if not 0 <= world < worlds.num_worlds:
        raise DrdError(f"world {world} is outside [0, {worlds.num_worlds})")
    context = policy_context(problem, theta=theta, tree=tree, seed=seed, settings=settings, policy=name)
    policy = POLICIES[name](context)
    oracle = TableOracle(worlds.X[world])
    return run_episode(problem.library, problem.edge_costs, policy, oracle, max_checks=max_checks)


def paper_rule_tree(problem: Problem, tree: DecisionTree) -> DecisionTree:
    """``tree`` when it uses the paper's region rule, else a tree built the same way with that rule.

    :data:`~drd_planner.core.policies.PAPER_RULE_POLICIES` (``direct_bisect_fixed``) run on it, so they
    stay the paper's method when the run's tree was built with another rule (:mod:`drd_planner.core.region_rule`).
    """
    if tree.region_rule == DEFAULT_REGION_RULE:
        return tree
    same = ("expand_threshold", "colouring", "top_regions", "max_prob_region")
    options = {key: tree.info[key] for key in same if key in tree.info}
    return build_tree(problem, progress=False, region_rule=DEFAULT_REGION_RULE, **options)


def require_test_worlds(problem: Problem) -> None:
    """Raise DrdError, with what to do, when ``problem`` has no test worlds to benchmark on."""
    worlds = problem.require_worlds()
    if worlds.test_ids.size == 0:
        raise DrdError(
            f"{problem.name} has no test worlds ({worlds.num_worlds} worlds, all for training): the "
            "benchmark runs on test worlds; a dataset from drd build-dataset needs a --test-fraction above 0 "
            "and enough --worlds to hold out at least one"
        )


def run_benchmark(
    problem: Problem,
    *,
    policies: Sequence[str] = DEFAULT_POLICIES,
    tree: DecisionTree | None = None,
    seed: int = 0,
    settings: PolicySettings = DEFAULT_SETTINGS,
    max_worlds: int | None = None,
    max_checks: int | None = None,
    progress: bool | None = None,
) -> BenchmarkResult:
    """Run each policy once per test world (seeded per world) and collect the check counts.

    Args:
        problem: a problem with a world database (train ids train, test ids are the episodes).
        policies: registry names (see ``drd_planner.core.policies.POLICIES``).
        tree: a prebuilt tree; built from the training worlds when a tree policy needs one.
        seed: base seed; world k of the test list uses ``seed + k`` (``lazysp_imitation`` trains once with it).
        settings: eta, alpha and the leaf pseudo-count of the Bayesian policies.
        max_worlds: only the first ``max_worlds`` test worlds (smoke runs).
        max_checks: cap on the checks of one episode (None: no cap); capped episodes are failures.
        progress: report the episodes (policies x worlds) on stderr (a bar on a terminal, plain lines
            otherwise; False: silent).

    Raises:
        DrdError: an unknown policy, a limit below 1, or no test worlds.
    """
    check_policy_names(policies)
    if max_worlds is not None and max_worlds < 1:
        raise DrdError(f"max_worlds must be at least 1, got {max_worlds}")
    if max_checks is not None and max_checks < 1:
        raise DrdError(f"max_checks must be at least 1, got {max_checks}")
    worlds = problem.require_worlds()
    require_test_worlds(problem)
    test_ids = worlds.test_ids if max_worlds is None else worlds.test_ids[:max_worlds]
    tree_info: dict[str, Any] = {}
    if tree is None and any(p in TREE_POLICIES for p in policies):
        tree = build_tree(problem, progress=progress)
    if tree is not None:
        tree_info = {"nodes": tree.num_nodes, "depth": tree.depth(), **tree.info}
    paper_tree = None
    if tree is not None and PAPER_RULE_POLICIES.intersection(policies):
        paper_tree = paper_rule_tree(problem, tree)
    theta = train_bias(problem, alpha=settings.alpha)
    if IMITATION_POLICY in policies and settings.imitation_model is None:
        settings = replace(settings, imitation_model=train_for_problem(problem, seed=seed))
    path_costs = problem.library.path_costs(problem.edge_costs)
    lower = oracle_lower_bound(worlds.R[test_ids], path_costs)
    results: dict[str, PolicyStats] = {}
    bar = Progress(len(policies) * len(test_ids), f"{problem.name} episodes", unit="episode", enabled=progress)
    with bar:
        for name in policies:
            bar.set_postfix_str(name)
            if name in PEER_POLICIES:
                peer = _run_peer(problem, test_ids, seed=seed)
                if peer is not None:
                    results[name] = peer
                bar.update(len(test_ids))
                continue
            checks: list[int] = []
            select_ms: list[float] = []
            failed: list[int] = []
            t0 = time.perf_counter()
            for k, world in enumerate(test_ids):
                result = run_world(
                    problem,
                    name,
                    int(world),
                    theta=theta,
                    tree=paper_tree if name in PAPER_RULE_POLICIES else tree,
                    seed=seed + k,
                    settings=settings,
                    max_checks=max_checks,
                )
                checks.append(result.num_checks)
                select_ms.extend(c.select_ms for c in result.checks)
                if not result.success:
                    failed.append(k)
                bar.update(1)
            results[name] = PolicyStats(checks, len(failed), select_ms, time.perf_counter() - t0, failed)
    run_settings: dict[str, Any] = {
        "seed": seed,
        "eta": settings.eta,
        "pseudo_count": settings.pseudo_count,
        "alpha": settings.alpha,
        "max_worlds": max_worlds,
        "max_checks": max_checks,
    }
    model = settings.imitation_model
    run_settings.update({"imitation": dict(model.stats)} if model else {})
    return BenchmarkResult(
        problem.name, [int(t) for t in test_ids], lower.tolist(), results, tree_info, run_settings, model
    )


def _run_peer(problem: Problem, test_ids: npt.NDArray[np.int64], *, seed: int) -> PolicyStats | None:
    """OMPL's LazyPRM on the same graph (``ompl_lazyprm``); None, with a note on stderr, when OMPL is absent.

    Its ``select_ms`` is the peer's whole solve time per world divided by its checks (search and lazy
    validation together: OMPL does not expose selection time separately).
    """
    from drd_planner.bench.ompl_peer import ompl_available, run_ompl_lazyprm

    available, message = ompl_available()
    if not available:
        print(message, file=sys.stderr)
        return None
    t0 = time.perf_counter()
    out = run_ompl_lazyprm(problem, test_ids, seed=seed, time_limit_s=PEER_TIME_LIMIT_S)
    checks = [int(c) for c in out["checks"]]
    failed = [k for k, w in enumerate(out["worlds"]) if not w["success"]]
    per_check = [1e3 * float(w["wall_s"]) / max(int(w["checks"]), 1) for w in out["worlds"]]
    select_ms = [ms for ms, c in zip(per_check, checks, strict=True) for _ in range(max(c, 1))]
    return PolicyStats(checks, len(failed), select_ms, time.perf_counter() - t0, failed)


def result_table1(
    result: BenchmarkResult,
    *,
    reference: str = REFERENCE,
    tie_subset: Sequence[str] = TIE_SUBSET,
    resamples: int = DEFAULT_RESAMPLES,
    seed: int = 0,
) -> Table1 | None:
    """Table-1 statistics of a run (see :func:`drd_planner.bench.stats.table1_stats`); None without the reference."""
    if reference not in result.policies:
        return None
    return table1_stats(
        result.checks(),
        reference=reference,
        tie_subset=tie_subset,
        lower_bound=result.lower_bound,
        resamples=resamples,
        seed=seed,
    )


def benchmark_json(
    result: BenchmarkResult,
    *,
    reference: str = REFERENCE,
    tie_subset: Sequence[str] = TIE_SUBSET,
    resamples: int = DEFAULT_RESAMPLES,
    seed: int = 0,
) -> dict[str, Any]:
    """The ``drd bench --json`` document (docs/getting-started.md) with the Table-1 ``relative`` statistics.

    Args:
        result: a benchmark run.
        reference: the policy the relative extra costs are normalised by (no ``relative`` blocks,
            i.e. nulls, when it was not run).
        tie_subset: the tie-filter policies (see :func:`drd_planner.bench.stats.tie_filter`).
        resamples: bootstrap resamples of the means' 95% intervals.
        seed: bootstrap seed.
    """
    lb = np.asarray(result.lower_bound, dtype=np.float64)
    table = result_table1(result, reference=reference, tie_subset=tie_subset, resamples=resamples, seed=seed)
    policies: dict[str, Any] = {}
    for name, stats in result.policies.items():
        block = stats.as_json()
        block["relative"] = None if table is None else table.policies[name].as_json()
        policies[name] = block
    oracle_relative = None if table is None or table.oracle is None else table.oracle.as_json()
    return {
        "dataset": result.dataset,
        "test_ids": result.test_ids,
        "oracle_lower_bound": {
            "mean": nanmean_or_nan(lb),
            "per_world": [None if np.isnan(v) else float(v) for v in lb],
            "relative": oracle_relative,
        },
        "policies": policies,
        "relative_protocol": None if table is None else table.protocol_json(),
        "tree": result.tree_info,
        "settings": result.settings,
    }


def markdown_table(results: Sequence[BenchmarkResult], policies: Sequence[str]) -> str:
    """One row per dataset: mean checks per policy (failures in brackets) and the oracle bound."""
    head = "| dataset | " + " | ".join(policies) + " | oracle bound |"
    rule = "|---|" + "---|" * (len(policies) + 1)
    rows = [head, rule]
    for res in results:
        cells = []
        for name in policies:
            stats = res.policies.get(name)
            if stats is None:
                cells.append("—")
                continue
            mean = float(np.mean(stats.checks)) if stats.checks else float("nan")
            cells.append(f"{mean:.2f}" + (f" ({stats.failures} failed)" if stats.failures else ""))
        lb = nanmean_or_nan(np.asarray(res.lower_bound, dtype=np.float64))
        rows.append(f"| {res.dataset} | " + " | ".join(cells) + f" | {lb:.2f} |")
    return "\n".join(rows) + "\n"


def json_safe(value: Any) -> Any:
    """``value`` with every non-finite float (NaN, inf) replaced by None, recursively (dicts, lists, tuples)."""
    if isinstance(value, float):
        return value if np.isfinite(value) else None
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    return value


def write_bench_files(doc: dict[str, Any], report: str, *, json_path: str | None, markdown_path: str | None) -> None:
    """Write a benchmark's JSON document and markdown report where asked (folders made), saying so on stdout.

    Raises:
        DrdError: a file cannot be written.
    """
    if json_path:
        _write_text(json_path, json.dumps(json_safe(doc), indent=1, allow_nan=False))
    if markdown_path:
        _write_text(markdown_path, report)


def _write_text(path: str, text: str) -> None:
    target = Path(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text)
    except OSError as exc:
        raise DrdError(f"cannot write {target}: {exc.strerror or exc}") from exc
    print(f"wrote {path}")


def nanmean_or_nan(values: np.ndarray) -> float:
    """Mean of the finite entries; NaN (without a warning) when there are none."""
    finite = values[np.isfinite(values)]
    return float(finite.mean()) if finite.size else float("nan")
