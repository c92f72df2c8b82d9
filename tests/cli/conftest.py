"""The cli tests build datasets with the grid test domain of ``tests/data/test_dataset_builder.py``.

Its module is named by ``--domain-factory test_dataset_builder:GridDomain``, so ``tests/data`` goes on
``sys.path`` here as it does when pytest collects that folder.
"""

from __future__ import annotations

import sys
from pathlib import Path

DATA_TESTS = str(Path(__file__).resolve().parents[1] / "data")
if DATA_TESTS not in sys.path:
    sys.path.insert(0, DATA_TESTS)
