"""The ROS 2 edge: the executive node, parameter declaration and the node table of the launchers."""
