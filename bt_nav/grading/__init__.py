"""The grading layer: many missions judged and reported, for a student checking a node or an instructor
grading a class.

It sits above the run layer (:mod:`bt_nav.run`, how *one* mission runs) and below the commands:

- :mod:`bt_nav.grading.grid`: lock-step grids (worlds x maneuvers x seeds) in local processes or on Dask,
  their summary figures.
- :mod:`bt_nav.grading.exe.run`: one run of any robot node over DDS (``bt-nav grade --exe``): the simulator
  and the profile's judge around a foreign command, isolated in a ROS domain and a directory of its own.
- :mod:`bt_nav.grading.exe.bag`: that run's bag (``bt-nav record`` as one more child of the run).
- :mod:`bt_nav.grading.exe.grid`: a grid of such runs, here or on Dask, resumable;
  :mod:`bt_nav.grading.admission`: how many of them run at once with ``--jobs auto``.
- :mod:`bt_nav.grading.plan`: a grid's worlds, seeds, maneuvers and LiDARs from the options (defaults per kind).
- :mod:`bt_nav.grading.classroom`: a class in one command (a manifest, one pool, the class page).
- :mod:`bt_nav.grading.exe.pace`: a grade's speed (1x, the verdict; or a preview) and whether a 1x run kept real
  time; :mod:`bt_nav.grading.exe.realtime`: a cell's verdict from a valid 1x run (a preview's failure graded again
  at 1x, a run that fell behind run again, then not graded).
- :mod:`bt_nav.grading.report`, :mod:`bt_nav.grading.media`, :mod:`bt_nav.grading.html`: the grid's report
  (``grade.json``, ``summary.md``, ``report.html``) with its pictures and videos.
- :mod:`bt_nav.grading.formats`: a finished grade in the formats platforms and CI read (Gradescope's
  ``results.json``, JUnit XML, a gradebook's CSV), from its ``grade.json`` / ``class.json``; its points and verdicts
  from :mod:`bt_nav.grading.scores`, its fix hints from :mod:`bt_nav.grading.hints`; :mod:`bt_nav.grading.classpage`
  the class page (``class.html``).
- :mod:`bt_nav.grading.handins`: a folder of hand-ins (each one's files found by
  :mod:`bt_nav.grading.handin_files`); their launch files checked by :mod:`bt_nav.grading.launch`, launch-file
  checking in a room of its own used through its entry points (``bt-nav check-launch``): the file evaluated as
  ``ros2 launch`` would run it (in a child process, against recording stand-ins), read statically as the fallback;
  the hand-in video's stand-in line (:mod:`bt_nav.grading.handin_film`).
- :mod:`bt_nav.grading.rules`: what a node must do, from the judges' own rules (``bt-nav rules``, ``rules.md``).
"""
