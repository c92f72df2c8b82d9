"""``drd build-dataset``: its flags, made into the options of a dataset build.

They become a :class:`~drd_planner.data.dataset_options.DatasetRecipe` and
:class:`~drd_planner.data.dataset_options.BuildOptions` for :func:`~drd_planner.data.dataset_builder.build_dataset`.

:mod:`drd_planner.cli.main` registers it with ``add_build_dataset_parser(sub)``; the world-source flags are
:mod:`drd_planner.cli.dataset_sources`. The module also runs on its own:
``python -m drd_planner.cli.build_dataset build-dataset ...``.
"""

from __future__ import annotations

import argparse
import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from drd_planner.cli.argtypes import bounded_float, bounded_int
from drd_planner.cli.dataset_sources import add_source_arguments
from drd_planner.cli.errors import run_command
from drd_planner.domains.base import DOMAIN_CLASSES
from drd_planner.exceptions import DatasetError

__all__ = [
    "add_build_dataset_parser",
    "cmd_build_dataset",
    "default_workers",
    "main",
    "parse_domain_spec",
]


_positive_int = bounded_int(at_least=1)
_non_negative_int = bounded_int(at_least=0)
_fraction = bounded_float(at_least=0.0, at_most=1.0)


def default_workers() -> int:
    """Local worker processes by default: the CPUs this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def parse_domain_spec(text: str | None) -> dict[str, Any] | None:
    """``--domain-spec``: a JSON object given inline (starts with ``{``) or the path of a JSON file.

    Raises:
        DatasetError: neither valid inline JSON nor a readable file holding a JSON object.
    """
    if text is None:
        return None
    if text.lstrip().startswith("{"):
        source, raw = "the inline JSON", text
    else:
        path = Path(text)
        if not path.is_file():
            raise DatasetError(f"--domain-spec: {text!r} is neither a JSON object nor an existing file")
        source, raw = str(path), path.read_text()
    try:
        spec = json.loads(raw)
    except json.JSONDecodeError as exc:
        raise DatasetError(f"--domain-spec: {source} is not valid JSON ({exc})") from None
    if not isinstance(spec, dict):
        raise DatasetError(f"--domain-spec: {source} must hold a JSON object, not {type(spec).__name__}")
    return spec


def cmd_build_dataset(args: argparse.Namespace) -> int:
    """``drd build-dataset``: sample worlds, check every edge in parallel, build library/R/split, save.

    Raises:
        DrdError: any user-triggered failure (the caller prints one line and exits 2).
    """
    from drd_planner.cli.dataset_sources import (
        check_required,
        print_spec,
        site_file_defaults,
        source_from_args,
        source_summary,
    )
    from drd_planner.data.dataset_builder import build_dataset
    from drd_planner.data.dataset_options import ALL_WORLDS, BuildOptions, DatasetRecipe

    error = getattr(args, "build_dataset_error", None) or _raise
    if getattr(args, "print_spec", False):
        if args.domain is None:
            error("the following arguments are required: --domain")
        return print_spec(args.domain)
    site_file_defaults(args)
    check_required(args, error)
    source = source_from_args(args, error)
    workers = args.workers if args.workers is not None else default_workers()
    recipe = DatasetRecipe(
        domain=args.domain,
        world_model=args.world_model or "",
        num_worlds=args.worlds if args.worlds is not None else ALL_WORLDS,
        seed=args.seed,
        domain_spec=parse_domain_spec(args.domain_spec),
        domain_factory=args.domain_factory,
        k=args.k,
        max_paths=args.max_paths,
        test_fraction=args.test_fraction,
        include_trajectories=not args.no_trajectories,
        source=source,
    )
    options = BuildOptions(
        workers=workers,
        scheduler=args.scheduler,
        chunk_size=args.chunk_size,
        max_chunks=args.max_chunks,
        keep_parts=args.keep_parts,
        command=recipe.command(),
    )
    report = build_dataset(args.out, recipe, options)
    where = f"Dask scheduler {args.scheduler}" if args.scheduler else f"{workers} local worker(s)"
    done = report.resumed_chunks + report.evaluated_chunks
    if not report.complete or report.dataset is None:
        print(
            f"stopped after {report.evaluated_chunks} new chunk(s): {done}/{report.num_chunks} done in "
            f"{report.out}.parts; run the same command again to resume"
        )
        return 0
    ds = report.dataset
    print(
        f"wrote {report.out}: {ds.num_worlds} worlds x {ds.graph.num_edges} edges "
        f"({100 * float(np.mean(ds.X)):.1f}% free), {ds.library.num_paths} library paths "
        f"(of {report.union_size} distinct), {ds.train_ids.size} train / {ds.test_ids.size} test worlds; "
        f"{report.num_chunks} chunks ({report.resumed_chunks} resumed) checked in "
        f"{report.eval_seconds:.2f} s on {where}, {report.total_seconds:.2f} s total"
    )
    summary = source_summary(ds.provenance)
    if summary is not None:
        print(summary)
    if ds.test_ids.size == 0:
        print(
            f"note: no test worlds (--test-fraction {args.test_fraction:g} of {ds.num_worlds} worlds, or no "
            "world with a valid library path): drd build-tree can use this file, drd bench cannot"
        )
    return 0


def _raise(message: str) -> NoReturn:
    """The argument error of a namespace that was not made by :func:`add_build_dataset_parser`."""
    raise DatasetError(message)


def add_build_dataset_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``build-dataset`` on an ``add_subparsers()`` object; returns the new parser."""
    p: argparse.ArgumentParser = subparsers.add_parser(
        "build-dataset",
        help="sample worlds (or read them from files), check every edge in parallel, build library and split",
        description=(
            "Sample worlds from a domain's world model (or take them from files: MoveIt scenes, a terrain "
            "grid, recorded map bags), check every graph edge in every world (local processes, or a Dask "
            "cluster with --scheduler), build the path library (Yen k shortest paths per world, union, "
            "seeded subsample), R and the train/test split, and write a dataset file. Finished chunks are "
            "kept in OUT.parts, so an interrupted build resumes where it stopped."
        ),
    )
    p.add_argument(
        "--domain",
        help=f"domain name ({', '.join(sorted(DOMAIN_CLASSES))}; required, except with --site-file: helicopter)",
    )
    p.add_argument("--world-model", help="the domain's world model to sample (required without a file source)")
    p.add_argument(
        "--worlds",
        type=_positive_int,
        help="number of worlds n (required with --world-model and --terrain; files: the first n, default all; "
        "--site-file: default its dataset.worlds)",
    )
    p.add_argument("--seed", type=_non_negative_int, help="base seed (non-negative; required, except with --site-file)")
    p.add_argument("--out", help="dataset file to write (.npz; required)")
    p.add_argument("--workers", type=_positive_int, default=None, help="local worker processes (default: all CPUs)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="run on this Dask scheduler (tcp://host:port)")
    p.add_argument("--chunk-size", type=_positive_int, default=16, help="worlds per task (default 16)")
    p.add_argument("--max-paths", type=_positive_int, default=500, help="library size cap m (default 500)")
    p.add_argument("--test-fraction", type=_fraction, default=0.1, help="held-out share (default 0.1)")
    p.add_argument("--k", type=_positive_int, default=5, help="Yen's k shortest paths per world (default 5)")
    p.add_argument("--domain-spec", metavar="JSON|FILE", help="domain parameters: inline JSON or a JSON file")
    p.add_argument(
        "--domain-factory",
        metavar="MODULE:ATTR",
        help="build a domain outside the registry with this class (from_spec) or function",
    )
    p.add_argument("--no-trajectories", action="store_true", help="do not store edge trajectories")
    p.add_argument("--keep-parts", action="store_true", help="keep OUT.parts after writing OUT")
    p.add_argument("--max-chunks", type=_positive_int, help="stop after this many new chunks (resume later)")
    add_source_arguments(p)
    p.set_defaults(func=cmd_build_dataset, build_dataset_error=p.error)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``build-dataset`` without the rest of ``drd``; errors print one line and exit 2."""
    parser = argparse.ArgumentParser(prog="drd", description="drd_planner dataset tools")
    sub = parser.add_subparsers(dest="command", required=True)
    add_build_dataset_parser(sub)
    return run_command(
        parser.parse_args(argv),
        interrupted="drd: interrupted (finished chunks are kept; run the same command again to resume)",
    )


if __name__ == "__main__":
    raise SystemExit(main())
