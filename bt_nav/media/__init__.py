"""Keep and show what the robot did: rosbag2 (MCAP) bags, mission videos and the live browser view.

- :mod:`bt_nav.media.bag`: :class:`~bt_nav.media.bag.MissionBag`, a rosbag2 writer for in-process data
  (lock-step) and raw CDR from DDS (``bt-nav record``); topic names, types and QoS live here.
- :mod:`bt_nav.media.bagread`: :func:`~bt_nav.media.bagread.read_bag` turns a bag (even one cut short by a
  kill) into a :class:`~bt_nav.media.bagread.MissionRecord` of numpy arrays for replay, plots and video; the
  executive's ``~/tree`` and ``~/events`` come back as documents (:mod:`bt_nav.mission.snapshot`), never as text.
- :mod:`bt_nav.media.video`: the mission video (H.264 MP4 through imageio-ffmpeg's bundled ffmpeg).
- :mod:`bt_nav.media.view`: the browser view's HTTP + server-sent-events server.

Nothing here imports rclpy. What the live graph holds reaches these modules as raw CDR through one ROS edge,
``bt_nav.ros.graphtap.GraphTap``: a recording (``bt_nav.run.bagrecorder``, ``bt-nav record``) and the live view
(``bt-nav view``) both subscribe through it; a lock-step run hands its data in directly (``bt_nav.run.sinks``).
"""
