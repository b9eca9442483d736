"""The run layer: how a mission is run, for one robot or several, in lock-step or over DDS.

Between the commands (:mod:`bt_nav.cli`, argument parsing and printing) and the layers below (the mission
core, the ROS edge, the simulator): every command that runs a mission calls this package (directly or through
:mod:`bt_nav.grading`), so demo, lockstep, grade, sim-run and the benchmarks cannot drift apart.

- :mod:`bt_nav.run.settings`: one way to choose a mission's parameters (profile, ``--set``, defaults).
- :mod:`bt_nav.run.lockstep`: the one lock-step loop over :class:`bt_nav_sim.multi.MultiSimCore` and a list
  of robots (one robot is a list of one), with a pluggable referee.
- :mod:`bt_nav.run.result`: what a lock-step run produced, per robot and for the run.
- :mod:`bt_nav.run.sinks`: the sink protocol a recorder of the run implements (the rosbag2 writer does).
- :mod:`bt_nav.run.session`: the one DDS mission runner every ROS path goes through (``grade --exe``, ``demo``,
  ``sim-run``, the bench): the run's domain lease, its log files, its launcher, the verdict wait and reader.
- :mod:`bt_nav.run.recorder`, :mod:`bt_nav.run.rosmission`, :mod:`bt_nav.run.rundir`: a mission over DDS
  (start the graph, a recorder and a referee per robot, wait, collect) and where it writes its files;
  :mod:`bt_nav.run.bagrecorder`: ``bt-nav record`` in a process of its own, started and stopped by a run.
- :mod:`bt_nav.run.lab`: which judge a lab run gets, each maneuver's announced against its measured angle;
  :mod:`bt_nav.run.terminal`: the lab's terminal of a check-off over DDS (and a student's node's).

Grading many missions (grids, the ``--exe`` grader, reports) is the layer above: :mod:`bt_nav.grading`.
"""
