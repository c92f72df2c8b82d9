#!/usr/bin/env python3
"""Mean checks per policy and the oracle bound on every authors'-format dataset under a folder.

Writes a markdown table (the README's results table) and one JSON per dataset (DESIGN.md section 5).
Usage: python scripts/results_table.py [--gccd ../shared/data/gccd] [--out results]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from drd_planner.bench.runner import benchmark_json, markdown_table, run_benchmark
from drd_planner.data.gccd import load_gccd_folder

POLICIES = ["direct_bisect", "bisect", "direct_only", "bisect_all"]


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--gccd", default=str(Path(__file__).resolve().parents[2] / "shared" / "data" / "gccd")
    )
    parser.add_argument("--out", default="results")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    folders = sorted(p for p in Path(args.gccd).iterdir() if (p / "graph.txt").is_file())
    results = []
    for folder in folders:
        problem = load_gccd_folder(folder)
        result = run_benchmark(problem, policies=POLICIES, progress=False)
        (out / f"{folder.name}.json").write_text(json.dumps(benchmark_json(result), indent=1))
        results.append(result)
        print(markdown_table([result], POLICIES).splitlines()[-1], flush=True)
    table = markdown_table(results, POLICIES)
    (out / "table.md").write_text(table)
    print(table)


if __name__ == "__main__":
    main()
