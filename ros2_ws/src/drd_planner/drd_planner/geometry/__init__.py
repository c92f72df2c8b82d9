"""Collision geometry: FCL scenes, terrain, wires and robot models. Units are metres and radians throughout.

Importing this package imports nothing; use the modules:

- :mod:`~drd_planner.geometry.pose`: :class:`Pose` (position (3,), quaternion in ROS order (x, y, z, w)),
  ``from_matrix``, ``matrix``, ``to_fcl`` (the one place that reorders to FCL's (w, x, y, z)).
- :mod:`~drd_planner.geometry.shapes`: frozen, validated ``Box(size)``, ``Sphere(radius)``,
  ``Cylinder(radius, length)``, ``Capsule(radius, length)`` (both along local +z, centred) and
  ``TriangleMesh(vertices, faces)``; ``Shape`` is their union; ``make_fcl_geometry(shape)``.
- :mod:`~drd_planner.geometry.terrain`: ``Heightfield(origin, cell_size, heights, unknown="blocked")`` with
  bilinear or triangulated ``height_at``, ``below``, ``crop``, ``to_mesh``, ``with_cell_size``; unknown (NaN)
  heights count in collisions as ``unknown`` says (``surface_heights``); ``read_esri_ascii``.
- :mod:`~drd_planner.geometry.wires`: ``Wire(start, end, sag, diameter)``: parabolic sag, ``points(n)``,
  ``capsule_chain(segments)`` (a chain that contains the wire).
- :mod:`~drd_planner.geometry.scene`: ``Scene(margin=...)`` with named obstacles, one terrain and wires, and the
  queries ``collides(shape, pose)``, ``spheres_collide``, ``spheres_collide_mask`` and ``sphere_sweep_free``
  (bisection order, early exit). Every query includes the margin, the below-terrain test and the inside test
  of closed meshes (FCL alone treats meshes as hollow surfaces).
- Helpers: :mod:`~drd_planner.geometry.aabb` (world AABBs, the numpy sphere prefilter),
  :mod:`~drd_planner.geometry.fcl_queries` (fresh FCL requests/results, the first-hit broadphase callback),
  :mod:`~drd_planner.geometry.solid` (inside tests for watertight meshes),
  :mod:`~drd_planner.geometry.terrain_collider` (terrain tiles, grid prefilter, linear-time window maxima),
  :mod:`~drd_planner.geometry.ordering` (bisection order of trajectory samples).
- Robot models (URDF parsing, batched forward kinematics, sphere models) live in the ``urdf_model``,
  ``kinematics`` and ``robot`` modules.

The python-fcl traps (docs/architecture.md, "Known traps") are handled in one place each: quaternion order in
``Pose.to_fcl``; fresh ``CollisionRequest``/``CollisionResult`` per narrowphase call and the first-hit
callback in ``fcl_queries``; below-terrain and closed-mesh inside tests in ``Scene``; ``manager.update`` after
every change; ``continuousCollide`` is never used (trajectories are sampled).
"""
