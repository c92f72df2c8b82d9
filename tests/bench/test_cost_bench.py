"""``drd bench --queries N --check-cost-ms C,...``: the JSON's time_ms keys, the cost paid, the errors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from conftest import gccd_folder

from drd_planner.bench.check_cost import Timed
from drd_planner.bench.cost_bench import cost_markdown, episode_records, median_episode, summarize_costs
from drd_planner.bench.cost_episodes import EpisodeTime
from drd_planner.cli.main import main
from drd_planner.exceptions import DrdError


def _argv(folder: Path, out: Path, costs: str) -> list[str]:
    return [
        "bench", "--gccd", str(folder), "--queries", "4", "--eta", "1", "--kappa", "none",
        "--region-rule", "probability", "--policies", "direct_bisect,direct_bisect_lead,lazysp,check_all",
        "--check-cost-ms", costs, "--json", str(out),
    ]  # fmt: skip


def test_time_keys_and_the_cost_paid(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = gccd_folder("dataset_2d_1")
    out = tmp_path / "q.json"
    assert main(_argv(folder, out, "0,2")) == 0
    report = capsys.readouterr().out
    assert "time to a verified plan" in report
    assert "off-graph queries do not apply" in report
    doc = json.loads(out.read_text())
    assert doc["check_cost"]["costs_ms"] == ["0", "2"]
    for name in ("direct_bisect", "direct_bisect_lead", "lazysp", "check_all"):
        entry = doc["policies"][name]
        for key in ("0", "2"):
            t = entry["time_ms"][key]
            assert {"median", "mean", "wall_median", "wall_mean", "n", "kinds"} <= set(t)
            assert t["n"] >= 1
            assert 0 < t["median"]
            assert t["mean"] > 0
            assert set(t["kinds"]) == {"stored", "new"}
        # CPU at 2 ms per check is at least checks x 2 ms (the median query's checks bound it below)
        checks = min(entry["time_checks_at"]["2"].values())
        assert entry["time_ms"]["2"]["median"] >= 2.0 * checks
        assert entry["time_ms"]["2"]["median"] > entry["time_ms"]["0"]["median"]
    assert "direct_bisect_lead / lazysp" in report
    episodes = doc["check_cost"]["episodes"]
    assert len(episodes) == 4 * 2 * 4  # queries x costs x policies, one record each
    assert {e["policy"] for e in episodes} == {"direct_bisect", "direct_bisect_lead", "lazysp", "check_all"}
    lead = doc["policies"]["direct_bisect_lead"]
    assert set(lead["time_ms"]) == {"0", "2"}
    assert "checks" not in lead  # no check-count episodes of its own: its checks are timed ones
    edges = doc["policies"]["check_all"]["checks"][0]
    assert doc["policies"]["check_all"]["time_ms"]["2"]["median"] >= 2.0 * edges


def test_malformed_costs_and_missing_queries_are_one_clear_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = gccd_folder("dataset_2d_1")
    assert main(_argv(folder, tmp_path / "q.json", "0,x")) == 2
    err = capsys.readouterr().err
    assert err.count("error") == 1
    assert "comma-separated non-negative numbers of milliseconds" in err
    assert main(["bench", "--gccd", str(folder), "--check-cost-ms", "1"]) == 2
    assert "--queries" in capsys.readouterr().err
    argv = _argv(folder, tmp_path / "q.json", "1")
    argv[argv.index("--policies") + 1] = "direct_only"
    assert main(argv) == 2
    assert "known:" in capsys.readouterr().err
    no_cost = ["bench", "--gccd", str(folder), "--queries", "2", "--policies", "direct_bisect_lead,lazysp"]
    assert main(no_cost) == 2
    assert "give --check-cost-ms too" in capsys.readouterr().err
    assert main(["bench", "--gccd", str(folder), "--queries", "2", "--repeat", "3"]) == 2
    assert "--repeat repeats the episodes timed at check costs" in capsys.readouterr().err
    assert main([*_argv(folder, tmp_path / "q.json", "1"), "--repeat", "0"]) == 2
    assert "--repeat must be at least 1, got 0" in capsys.readouterr().err


def test_repeated_episodes_keep_one_record_each_and_the_same_checks(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = gccd_folder("dataset_2d_1")
    once, thrice = tmp_path / "1.json", tmp_path / "3.json"
    assert main(_argv(folder, once, "0,1")) == 0
    assert main([*_argv(folder, thrice, "0,1"), "--repeat", "3"]) == 0
    capsys.readouterr()
    a, b = (json.loads(f.read_text())["policies"] for f in (once, thrice))
    for name in ("direct_bisect", "direct_bisect_lead", "lazysp", "check_all"):
        assert a[name]["time_checks_at"] == b[name]["time_checks_at"]  # one episode per query and cost, as before
        assert a[name]["time_ms"]["1"]["n"] == b[name]["time_ms"]["1"]["n"]
        assert b[name]["time_ms"]["1"]["median"] > b[name]["time_ms"]["0"]["median"]


def test_an_episodes_runs_give_the_run_of_median_time() -> None:
    def run(ms: float, ok: bool = True, checks: int = 3) -> EpisodeTime:
        return EpisodeTime("lazysp", 2, "new", 0.2, ok, checks, Timed(ms, 10 * ms))

    one = median_episode([run(5.0, checks=7), run(1.0), run(2.0, checks=4)])
    assert one.time == Timed(2.0, 20.0)
    assert one.checks == 4  # the median run's own checks (a time budget may cut a run short)
    assert (one.policy, one.query, one.kind, one.cost_ms, one.verified) == ("lazysp", 2, "new", 0.2, True)
    assert median_episode([run(3.0), run(1.0)]).time.cpu_ms == 1.0  # even count: the lower middle run
    assert not median_episode([run(1.0), run(1.0, ok=False)]).verified
    with pytest.raises(DrdError, match="at least one run"):
        median_episode([])


def test_medians_compare_the_queries_every_policy_verified() -> None:
    def ep(policy: str, query: int, ok: bool, ms: float) -> EpisodeTime:
        return EpisodeTime(policy, query, "new", 0.0, ok, 3, Timed(ms, 2 * ms))

    episodes = [ep("a", 0, True, 1.0), ep("a", 1, True, 100.0), ep("b", 0, True, 2.0), ep("b", 1, False, 5.0)]
    summary = summarize_costs(episodes, (0.0,))
    assert summary["a"]["time_ms"]["0"]["median"] == 1.0
    assert summary["a"]["time_ms"]["0"]["n"] == 1
    assert summary["b"]["time_ms"]["0"]["kinds"]["new"]["wall_median"] == 4.0
    assert summary["b"]["verified"] == {"new": 1}
    assert summary["a"]["queries"] == {"new": 2}
    assert "| new | 0 | 1 | 1.00 | 2.00 |" in cost_markdown(summary, (0.0,), title="t")


def test_the_paired_ratio_compares_each_query_with_itself() -> None:
    def ep(policy: str, query: int, ms: float, ok: bool = True) -> EpisodeTime:
        return EpisodeTime(policy, query, "new", 0.2, ok, 3, Timed(ms, ms))

    # Two sizes of query: the medians of the times fall between them, the per-query ratios do not.
    lazysp = [ep("lazysp", q, ms) for q, ms in enumerate([2.0, 2.0, 20.0, 20.0])]
    ours = [ep("direct_bisect", q, ms) for q, ms in enumerate([1.8, 1.8, 18.0, 30.0])]
    summary = summarize_costs([*lazysp, *ours, ep("direct_bisect", 4, 1.0), ep("lazysp", 4, 9.0, ok=False)], (0.2,))
    paired = summary["direct_bisect"]["paired_to_lazysp"]["0.2"]["new"]
    assert paired["n"] == 4  # query 4 is not compared: LazySP did not verify it
    assert paired["median"] == pytest.approx(0.9)
    assert summary["lazysp"]["paired_to_lazysp"]["0.2"]["new"]["median"] == 1.0
    table = cost_markdown(summary, (0.2,), title="t")
    assert "| new | 0.2 | 0.90 (4) |" in table
    assert summarize_costs(ours, (0.2,))["direct_bisect"]["paired_to_lazysp"] == {}  # no LazySP, no ratio
    records = episode_records(ours[:1])
    assert records == [
        {"policy": "direct_bisect", "query": 0, "kind": "new", "cost_ms": 0.2, "verified": True, "checks": 3,
         "cpu_ms": 1.8, "wall_ms": 1.8}
    ]  # fmt: skip
