"""The ROS 2 nodes around the robot: the simulator (the clock source), the homework's referee and the lab's check-off
judge (their rules are pure, in :mod:`bt_nav.judge.referee_core` and :mod:`bt_nav.judge.checkoff_core`), their shared
driver (:mod:`bt_nav.ros.nodes.judging`) and the graph audit of a judged node. They sit with the other ROS nodes, a
layer above the ROS edge, so the simulator's folder (``sim/``) holds no rclpy and imports nothing above it."""
