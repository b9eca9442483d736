"""bt_nav: a py_trees behaviour-tree mission executive for ROS 2 Jazzy.

The core (``scan``, ``params``, ``tree``, ``behaviours``, ``core``) imports no rclpy: the same tree runs
under the ROS executive (``bt_nav.executive``) and in the lock-step simulator (``bt_nav.lockstep``).
"""

__version__ = "0.1.0"
