"""Launch-file checking, one room: a hand-in's launch file read as ``ros2 launch`` would run it (``bt-nav
check-launch``, the sheet's Task 3) -- evaluated in a sandboxed child against recording stand-ins of ``launch`` and
``launch_ros``, read statically when it cannot be evaluated, its checks reported -- and which launch file and node a
check is about.
"""
