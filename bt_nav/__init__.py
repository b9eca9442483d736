"""bt_nav: a py_trees behaviour-tree mission executive for ROS 2 Jazzy, with its simulator, judges and grader.

The code is in layers, each importing only its own and the ones below it (docs/architecture.md draws all eleven,
tests/arch/test_layers.py enforces them), bottom to top:

- :mod:`bt_nav.mission`: the pure mission core (scan geometry, parameters, the maneuver and assignment specs,
  the tree and its leaves, ``MissionCore``, tree snapshots); no rclpy, so the same tree runs under ROS and in
  lock-step;
- :mod:`bt_nav.judge`: the two judges (the lab's check-off, the homework's referee) and the feeds they read, pure
  (no rclpy, no simulator): the simulator, a robot's bag or a live robot feeds them;
- :mod:`bt_nav_sim` (``sim/``): the 2D simulator and its worlds, with its truth feed for the judges, pure too;
- :mod:`bt_nav.media`: bags, videos, pictures and the browser view, without rclpy;
- :mod:`bt_nav.ros` and :mod:`bt_nav.ros.nodes`: the ROS 2 edge (the executive, simulator and judge nodes);
- :mod:`bt_nav.run`: one mission, in lock-step or over DDS;
- :mod:`bt_nav.grading`: many missions judged and reported (grids, a student's node, a class);
- :mod:`bt_nav.cli`: the user commands (``bt-nav demo``, ``lockstep``, ``grade``, ``dump-tree``...): they parse
  options and print.
"""

__version__ = "0.1.0"
