"""The command lines: ``drd``, ``drd_replay`` and ``planner_demo``.

``drd`` is :mod:`drd_planner.cli.main` (one module per subcommand), ``drd_replay`` :mod:`drd_planner.cli.replay`
and ``planner_demo`` :mod:`drd_planner.cli.planner_demo`.

Each module parses its flags, turns them into the typed options of a library function and calls it; argparse
stays in this package. ``python -m drd_planner.cli`` runs ``drd``.
"""
