"""The pure mission core: scan geometry, the parameter table, the tree and its leaves, ``MissionCore``.

Nothing here imports rclpy: ROS I/O reaches the tree only through the node handed to ``setup()``
(the arm server, the evaluation client) and through blackboard values the drivers write.
"""
