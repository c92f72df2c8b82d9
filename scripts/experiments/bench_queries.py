"""Random-query benchmark over every dataset, and the README's table of it.

"lower bound" is the mean of the fewest checks any planner needs knowing each episode's world: the fewest
edges of a free path, or the smallest cut of blocked edges (``bench.queries.certificate_size``).

    python scripts/experiments/bench_queries.py --run      # drd bench --queries 100 --seed 1, every dataset, 25 min
    python scripts/experiments/bench_queries.py            # the table from results/queries/*.json

Datasets: every authors' folder under ``../shared/data/gccd`` (DRD_SHARED_DATA) with a graph, and our
``datasets/heli_wires.npz``, ``heli_terrain.npz`` and ``arm_table_clutter.npz`` when present (built with
the commands in ``trees/README.md``). Each run writes ``results/queries/NAME.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SHARED = Path(os.environ.get("DRD_SHARED_DATA", ROOT.parent / "shared" / "data"))
OURS = ("heli_wires", "heli_terrain", "arm_table_clutter")


def sources() -> list[tuple[str, list[str]]]:
    """(name, drd bench source arguments) of every dataset found."""
    out = []
    gccd = SHARED / "gccd"
    if gccd.is_dir():
        for folder in sorted(p for p in gccd.iterdir() if (p / "graph.txt").is_file()):
            out.append((folder.name, ["--gccd", str(folder)]))
    for name in OURS:
        path = ROOT / "datasets" / f"{name}.npz"
        if path.is_file():
            out.append((name, ["--dataset", str(path)]))
    return out


def run(queries: int, seed: int, out: Path) -> None:
    """Run the benchmark on every dataset (one drd process each)."""
    out.mkdir(parents=True, exist_ok=True)
    drd = [sys.executable, "-m", "drd_planner.cli"]
    for name, source in sources():
        print(f"{name} ...", flush=True)
        argv = ["bench", *source, "--queries", str(queries), "--seed", str(seed)]
        argv += ["--json", str(out / f"{name}.json"), "--markdown", str(out / f"{name}.md")]
        subprocess.run([*drd, *argv], check=True, stdout=subprocess.DEVNULL)


def table(out: Path) -> str:
    """The markdown table of every ``results/queries/*.json``."""
    lines = [
        "| dataset | episodes (no free path) | lower bound | direct_bisect | bisect | lazysp_set | lazysp | "
        "check_all | direct_bisect / lazysp | direct_bisect failures, false no-path | direct_bisect with a free "
        "path: checks, path cost ratio |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---|---|",
    ]
    for path in sorted(out.glob("*.json")):
        doc = json.loads(path.read_text())
        pol = doc["policies"]
        free = np.array([e["free_path"] for e in doc["episodes"]])

        def mean(name: str, pol: dict = pol) -> float:  # type: ignore[type-arg]
            return float(np.mean(pol[name]["checks"])) if name in pol else float("nan")

        db = np.asarray(pol["direct_bisect"]["checks"], dtype=float)
        fails = pol["direct_bisect"]["failures"]
        false_np = pol["direct_bisect"]["false_no_path"]
        others = {k: (v["failures"], v["false_no_path"]) for k, v in pol.items() if k != "direct_bisect"}
        notes = ", ".join(f"{k} {f} failed" for k, (f, _) in others.items() if f)
        lines.append(
            f"| {doc['dataset']} | {len(free)} ({int((~free).sum())}) | {doc['certificate_lower_bound']:.2f} | "
            f"{mean('direct_bisect'):.2f} | "
            f"{mean('bisect'):.2f} | {mean('lazysp_set'):.2f} | {mean('lazysp'):.2f} | {mean('check_all'):.0f} | "
            f"{mean('direct_bisect') / mean('lazysp'):.2f} | {fails}, {false_np} | "
            f"{db[free].mean():.2f}, {pol['direct_bisect']['path_cost_ratio']:.3f}{'; ' + notes if notes else ''} |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--run", action="store_true", help="run the benchmark first")
    parser.add_argument("--queries", type=int, default=100)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "queries")
    args = parser.parse_args()
    if args.run:
        run(args.queries, args.seed, args.out)
    print(table(args.out))


if __name__ == "__main__":
    main()
