"""Benchmark harness: run policies over test worlds and report statistics.

Importing the package registers its research policies (the learned LazySP selectors,
:mod:`drd_planner.bench.learned_policies`) in the planner's policy registry.
"""

from drd_planner.bench import learned_policies as _learned_policies  # noqa: F401  (registers on import)
