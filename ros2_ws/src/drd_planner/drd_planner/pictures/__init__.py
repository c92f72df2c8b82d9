"""Pictures of plans: the maps, the library, every check and the plan, per domain view (the ``plots`` extra).

:mod:`~drd_planner.pictures.plan` draws and writes a plan picture; the helicopter and arm views, the
shared drawing pieces, the label placement, the world-coordinate geometry and the palette are one module
each. Nothing here imports the benchmark package.
"""
