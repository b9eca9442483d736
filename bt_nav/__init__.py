"""bt_nav: a py_trees behaviour-tree mission executive for ROS 2 Jazzy.

Three layers, each importing only the ones below it (docs/architecture.md draws them):

- :mod:`bt_nav.mission`: the pure mission core (scan geometry, parameters, the tree and its leaves,
  ``MissionCore``); no rclpy, so the same tree runs under ROS and in lock-step;
- :mod:`bt_nav.ros`: the ROS 2 edge (the executive node, parameter declaration, the node table that
  launch files and ``bt-nav sim-run`` share);
- :mod:`bt_nav.cli`: the user commands (``bt-nav demo``, ``lockstep``, ``grade``, ``dump-tree``...).

The simulator and referee are a package of their own, :mod:`bt_nav_sim`.
"""

__version__ = "0.1.0"
