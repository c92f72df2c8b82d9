"""Anytime shorter paths (issue 18, the paper's Q2): path cost ratio before and after the improvement.

On each dataset's own query and every test world with a free path: the default policy's first verified
path, then the anytime improvement with ``factor`` x its checks as extra budget (factor 1: twice the
first path's checks in all), reported side by side (``drd_planner.bench.anytime``).

    python scripts/experiments/bench_anytime.py                       # SE(2) and helicopter sets of ../shared/data/gccd
    python scripts/experiments/bench_anytime.py --factors 1,3 --json results/anytime.json --markdown results/anytime.md
    python scripts/experiments/bench_anytime.py --gccd ../shared/data/gccd/dataset_2d_3 \\
        --dataset datasets/heli_wires.npz

Datasets: the folders named by ``--gccd`` and the files named by ``--dataset``; with neither, the SE(2)
(``dataset_xyh_1,3,4,5``) and helicopter (``dataset_heli_canyon_1``) folders under ``../shared/data/gccd``
(``DRD_SHARED_DATA``). The prior has the dataset's own DiRECt tree and the default eta and kappa.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SHARED = Path(os.environ.get("DRD_SHARED_DATA", ROOT.parent / "shared" / "data"))
DEFAULT_SETS = ("dataset_xyh_1", "dataset_xyh_3", "dataset_xyh_4", "dataset_xyh_5", "dataset_heli_canyon_1")


def _factors(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None
    if not values or any(not v > 0 for v in values):
        raise argparse.ArgumentTypeError(f"factors must be positive numbers, got {text!r}")
    return values


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--gccd", action="append", default=[], help="an authors'-format dataset folder")
    parser.add_argument("--dataset", action="append", default=[], help="a dataset file built by drd")
    parser.add_argument("--factors", type=_factors, default=[1.0], help="extra budgets as multiples of c")
    parser.add_argument("--patience", type=int, default=None, help="draws proposing nothing before stopping")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", type=Path, default=None, help="write the documents here")
    parser.add_argument("--markdown", type=Path, default=None, help="write the table here")
    args = parser.parse_args(argv)

    from drd_planner.bench.anytime import anytime_markdown, anytime_prior, run_anytime_benchmark
    from drd_planner.core.problem import Problem
    from drd_planner.data.dataset_file import load_dataset_problem
    from drd_planner.data.gccd import load_gccd_folder
    from drd_planner.planner.anytime import DEFAULT_PATIENCE
    from drd_planner.planner.planner import Planner

    folders = [Path(g) for g in args.gccd]
    if not folders and not args.dataset:
        folders = [SHARED / "gccd" / name for name in DEFAULT_SETS if (SHARED / "gccd" / name).is_dir()]
        if not folders:
            print(f"no dataset given and none of {', '.join(DEFAULT_SETS)} under {SHARED / 'gccd'}")
            return 2
    sources: list[tuple[str, Callable[[], Problem]]] = [(str(f), partial(load_gccd_folder, f)) for f in folders]
    sources += [(d, partial(load_dataset_problem, d)) for d in args.dataset]
    docs = []
    t0 = time.perf_counter()
    for name, load in sources:
        print(f"{name} ...", file=sys.stderr, flush=True)
        problem = load()
        planner = Planner(anytime_prior(problem, seed=args.seed))
        docs.append(
            run_anytime_benchmark(
                problem,
                planner,
                factors=args.factors,
                seed=args.seed,
                patience=args.patience or DEFAULT_PATIENCE,
            )
        )
    report = anytime_markdown(docs)
    print(report, end="")
    print(f"seed {args.seed}, wall time {time.perf_counter() - t0:.1f} s")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(docs, indent=1) + "\n", encoding="utf-8")
    if args.markdown:
        args.markdown.parent.mkdir(parents=True, exist_ok=True)
        args.markdown.write_text(report, encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
