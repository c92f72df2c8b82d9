"""Reading MATLAB files with clear errors (scipy.io.loadmat never executes file content)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import scipy.io

from drd_planner.exceptions import DatasetError


def load_mat_variable(path: Path, name: str) -> npt.NDArray[Any]:
    """The variable ``name`` of the MATLAB file ``path``, or a DatasetError naming the file."""
    if not path.is_file():
        raise DatasetError(f"missing file: {path}")
    try:
        contents = scipy.io.loadmat(str(path), variable_names=[name])
    except Exception as exc:  # scipy raises many types for malformed files
        raise DatasetError(f"cannot read {path}: {exc}") from exc
    if name not in contents:
        raise DatasetError(f"{path} has no variable {name!r}")
    return np.asarray(contents[name])
