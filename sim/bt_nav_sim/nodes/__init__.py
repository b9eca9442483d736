"""The ROS 2 nodes of the simulator package: the simulator (clock source) and the homework referee."""
