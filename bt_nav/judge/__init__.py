"""The judges: the lab's check-off judge and the homework's referee, their rules, words and findings, and the feeds
they read (poses, commands, scan readings, service calls, announcements). Pure Python (no rclpy).

A judge reads a feed: the simulator's truth (ground-truth poses, readings cast in its world), a real robot's
recording (:mod:`bt_nav.judge.recorded`), or a live robot (:mod:`bt_nav.ros.nodes.robotcheck`, which hands what it
heard to the recorded feed). The ROS nodes (:mod:`bt_nav.ros.nodes`) and the lock-step runner (:mod:`bt_nav.run`)
put a judge and its feed together.
"""
