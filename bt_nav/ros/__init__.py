"""The ROS 2 edge: the executive node, parameter declaration, the node table of the launchers, processes and domains,
the recorder's raw DDS tap; in :mod:`bt_nav.ros.nodes`, a layer above, the simulator and judge nodes."""
