"""``python -m drd_planner.cli``: the ``drd`` command line (:func:`drd_planner.cli.main.main`)."""

from __future__ import annotations

from drd_planner.cli.main import main

if __name__ == "__main__":
    raise SystemExit(main())
