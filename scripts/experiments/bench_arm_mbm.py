"""MotionBenchMaker Panda families: our planner (prior + roadmap growth) beside OMPL RRT-Connect, held-out scenes.

    python scripts/experiments/bench_arm_mbm.py [--families table_pick_panda,box_panda] [--train 80] [--budget 5]
        [--seed 0] [--workers 2] [--work DIR] [--json FILE] [--markdown FILE] [--quick] [--no-rrt]

Per family in ``<shared data>/mbm`` (scenes ``sceneNNNN.yaml`` with their requests ``requestNNNN.yaml``):

1. **Prior from the training scenes only** (the split: the first ``--train`` scenes; the rest are held out):
   ``drd build-dataset --domain arm --scenes DIR --worlds TRAIN --test-fraction 0 --seed SEED`` (the training
   requests' start and goal states become roadmap vertices, as a user's ``--scenes`` build does), then
   ``drd build-tree``. Built once into ``--work`` and reused.
2. **Ours**: each held-out scene's own request planned by
   :func:`drd_planner.planning.scene_plan.plan_moveit_request` (the real sphere checker of the prior's spec,
   from the request's exact start and goal states, roadmap growth on, ``time_budget_s = --budget``); a found
   path is re-checked densely by a fresh checker. Times: wall and CPU of ``Planner.plan``.
3. **RRT-Connect**: OMPL 1.7.0's ``RRTConnect`` in a child process on the same scenes and requests, every state
   and motion answered by the same checker (:mod:`drd_planner.bench.rrt_connect`), time limit ``--budget``; a
   solution counts only when our checker finds its waypoints joined by straight motions free.

Statuses: ``solved`` (a verified path), ``no_path`` (ours: none within the growth budget; RRT-Connect: OMPL
reported no exact solution before its limit, counted as ``budget``), ``budget`` (a time budget ran out),
``refused``. Checks: ours = checks in the plan's log (edges, motions and one-state checks of new vertices);
RRT-Connect = motion checks + state checks. The growth defaults were chosen on training scenes only
(scenes 61-80 of both families planned with a prior of scenes 1-60), never on the scenes reported here.

``--quick``: 20 training scenes and 3 held-out scenes per family (a smoke run, a few minutes).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.bench.ompl_peer import ompl_available
from drd_planner.bench.rrt_connect import RrtTask, run_rrt_connect
from drd_planner.cli.main import main as drd
from drd_planner.planner import load_prior
from drd_planner.planning.prior_domain import rebuild_domain
from drd_planner.planning.scene_plan import SceneRequest, plan_moveit_request
from drd_planner.settings import shared_data_dir

FAMILIES = ("table_pick_panda", "box_panda")
STATUS = {"found": "solved", "no_path": "no_path", "budget_exhausted": "budget", "refused": "refused"}


def parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--families", default=",".join(FAMILIES), help="comma-separated family folders")
    parser.add_argument("--train", type=int, default=80, help="training scenes: the first N (the rest held out)")
    parser.add_argument("--budget", type=float, default=5.0, help="seconds per request, both planners")
    parser.add_argument("--seed", type=int, default=0, help="dataset seed and the planners' seed")
    parser.add_argument("--workers", type=int, default=2, help="processes of the dataset build")
    parser.add_argument("--work", type=Path, default=Path("out/bench_arm_mbm"), help="datasets and priors")
    parser.add_argument("--json", type=Path, default=None, help="write every record here")
    parser.add_argument("--markdown", type=Path, default=None, help="write the table here")
    parser.add_argument("--quick", action="store_true", help="20 training, 3 held-out scenes per family")
    parser.add_argument("--no-rrt", action="store_true", help="leave RRT-Connect out")
    return parser.parse_args()


def build_prior(family: Path, train: int, args: argparse.Namespace) -> Path:
    """The family's prior from its first ``train`` scenes (built once into ``--work``)."""
    args.work.mkdir(parents=True, exist_ok=True)
    dataset: Path = args.work / f"{family.name}_train{train}_seed{args.seed}.npz"
    prior = dataset.with_name(dataset.stem + "_prior.npz")
    if not dataset.is_file():
        argv = ["build-dataset", "--domain", "arm", "--scenes", str(family), "--worlds", str(train)]
        argv += ["--test-fraction", "0", "--seed", str(args.seed), "--workers", str(args.workers)]
        if drd([*argv, "--out", str(dataset)]) != 0:
            raise SystemExit(f"building {dataset} failed")
    if not prior.is_file() and drd(["build-tree", "--dataset", str(dataset), "--out", str(prior)]) != 0:
        raise SystemExit(f"building {prior} failed")
    return prior


def held_out(family: Path, train: int, quick: bool) -> list[str]:
    """Keys (``0081`` ...) of the scenes after the first ``train`` that have a request."""
    keys = sorted(p.stem.removeprefix("scene") for p in family.glob("scene*.yaml"))[train:]
    keys = [k for k in keys if (family / f"request{k}.yaml").is_file()]
    return keys[:3] if quick else keys


def ours(prior_path: Path, family: Path, keys: list[str], args: argparse.Namespace) -> list[dict[str, Any]]:
    """Our planner on each held-out request (one record each)."""
    prior = load_prior(prior_path)
    domain = rebuild_domain(prior, prior_path.name)
    records = []
    for key in keys:
        request = SceneRequest(
            family / f"scene{key}.yaml",
            family / f"request{key}.yaml",
            seed=args.seed,
            time_budget_s=args.budget,
        )
        plan = plan_moveit_request(prior, request, domain=domain)
        record = {"key": key, **plan.to_json()}
        record["outcome"] = STATUS[record["status"]]
        record.pop("path_states")
        records.append(record)
        print(f"  ours {key}: {record['outcome']} in {plan.wall_s:.2f} s, {record['checks']} checks", flush=True)
    return records


def rrt(prior_path: Path, family: Path, keys: list[str], args: argparse.Namespace) -> list[dict[str, Any]]:
    """RRT-Connect on the same requests (one record each)."""
    from drd_planner.geometry.moveit_request import joint_vector, read_motion_plan_request

    prior = load_prior(prior_path)
    domain = rebuild_domain(prior, prior_path.name)
    tasks = []
    for key in keys:
        request = read_motion_plan_request(family / f"request{key}.yaml")
        assert request.start is not None
        start = joint_vector(request.start, domain.joint_names, where=key, allow_extra=True)
        goal = joint_vector(request.goals[0], domain.joint_names, where=key)
        tasks.append(RrtTask(key, family / f"scene{key}.yaml", start, goal))
    records = run_rrt_connect(domain, dict(prior.domain_spec), tasks, time_limit_s=args.budget, seed=args.seed)
    for record in records:
        record["outcome"] = "solved" if record["solved"] else "budget"
        record["checks"] = record["motion_checks"] + record["state_checks"]
        record["time_s"] = record["wall_s"]
        print(f"  rrt  {record['key']}: {record['outcome']} in {record['wall_s']:.2f} s", flush=True)
    return records


def summary(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Counts per outcome, and time (wall, CPU) and checks over the solved requests."""
    solved = [r for r in records if r["outcome"] == "solved"]
    wall = [float(r["time_s"]) for r in solved]
    cpu = [float(r["cpu_s"]) for r in solved]
    checks = [int(r["checks"]) for r in solved]
    return {
        "requests": len(records),
        **{name: sum(r["outcome"] == name for r in records) for name in ("solved", "no_path", "budget", "refused")},
        "wall_median_s": statistics.median(wall) if wall else float("nan"),
        "wall_mean_s": float(np.mean(wall)) if wall else float("nan"),
        "wall_max_s": max(wall) if wall else float("nan"),
        "cpu_median_s": statistics.median(cpu) if cpu else float("nan"),
        "cpu_mean_s": float(np.mean(cpu)) if cpu else float("nan"),
        "checks_median": statistics.median(checks) if checks else float("nan"),
        "checks_mean": float(np.mean(checks)) if checks else float("nan"),
    }


def markdown(results: dict[str, Any], args: argparse.Namespace) -> str:
    """The table: one row per family and planner."""
    lines = [
        "| family (held-out requests) | planner | solved | no_path | budget | wall median / mean / max (s) "
        "| CPU median / mean (s) | checks median / mean |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for family, block in results["families"].items():
        for name in ("ours", "rrt_connect"):
            if name not in block:
                continue
            s = block[name]["summary"]
            label = "ours (prior + growth)" if name == "ours" else "OMPL RRT-Connect"
            lines.append(
                f"| {family} ({s['requests']}) | {label} | {s['solved']} | {s['no_path']} | {s['budget']} | "
                f"{s['wall_median_s']:.2f} / {s['wall_mean_s']:.2f} / {s['wall_max_s']:.2f} | "
                f"{s['cpu_median_s']:.2f} / {s['cpu_mean_s']:.2f} | {s['checks_median']:.0f} / {s['checks_mean']:.1f} |"
            )
    lines.append("")
    lines.append(
        f"Budget {args.budget:g} s per request; priors from scenes 1-{results['train']} of each family, requests "
        f"of the held-out scenes; seed {args.seed}; times and checks over the solved requests."
    )
    return "\n".join(lines) + "\n"


def run() -> int:
    args = parse()
    train = 20 if args.quick else args.train
    root = shared_data_dir() / "mbm"
    use_rrt = not args.no_rrt
    if use_rrt and not ompl_available()[0]:
        print(f"note: {ompl_available()[1]}; RRT-Connect left out")
        use_rrt = False
    results: dict[str, Any] = {"train": train, "budget_s": args.budget, "seed": args.seed, "families": {}}
    t0 = time.perf_counter()
    for name in args.families.split(","):
        family = root / name
        print(f"{name}: prior from scenes 1-{train}", flush=True)
        prior = build_prior(family, train, args)
        keys = held_out(family, train, args.quick)
        block: dict[str, Any] = {"prior": str(prior), "held_out": keys}
        mine = ours(prior, family, keys, args)
        block["ours"] = {"summary": summary(mine), "requests": mine}
        if use_rrt:
            theirs = rrt(prior, family, keys, args)
            block["rrt_connect"] = {"summary": summary(theirs), "requests": theirs}
        results["families"][name] = block
    results["total_s"] = time.perf_counter() - t0
    table = markdown(results, args)
    print(table)
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(results, indent=1) + "\n")
    if args.markdown is not None:
        args.markdown.parent.mkdir(parents=True, exist_ok=True)
        args.markdown.write_text(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(run())
