"""Where a command's problem comes from: an authors'-format folder (``--gccd``) or our dataset file (``--dataset``).

:class:`ProblemSource` names one of them and loads it as a :class:`~drd_planner.core.problem.Problem` with
worlds; :func:`problem_domain` says which domain a prior built from that problem must have.
"""

from __future__ import annotations

from dataclasses import dataclass

from drd_planner.core.problem import Problem
from drd_planner.exceptions import DatasetError

__all__ = ["ProblemSource", "problem_domain"]


@dataclass(frozen=True)
class ProblemSource:
    """A dataset to load: the authors'-format folder ``gccd`` or the dataset file ``dataset`` (one of them).

    Attributes:
        gccd: path of an authors'-format dataset folder, or None.
        dataset: path of a dataset file written by ``drd build-dataset`` (``.npz``), or None; it wins when
            both are given.
    """

    gccd: str | None = None
    dataset: str | None = None

    def load(self) -> Problem:
        """The problem (with worlds) of the file or folder.

        Raises:
            DatasetError: neither is given, or the file or folder is missing, corrupt or inconsistent.
        """
        from drd_planner.data.dataset_file import load_dataset_problem
        from drd_planner.data.gccd import load_gccd_folder

        if self.dataset:
            return load_dataset_problem(self.dataset)
        if self.gccd:
            return load_gccd_folder(self.gccd)
        raise DatasetError("give a dataset: --gccd DIR or --dataset FILE")


def problem_domain(problem: Problem) -> str:
    """The domain a tree for ``problem`` must be built for: the dataset's domain, or "gccd"."""
    return str(problem.metadata.get("domain", "gccd"))
