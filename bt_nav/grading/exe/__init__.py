"""Grading any robot node over DDS (``bt-nav grade --exe 'CMD ...'``): the foreign-node grader.

- :mod:`bt_nav.grading.exe.run`: one run (the simulator hosting the profile's judge around the user's command, on a
  :class:`bt_nav.run.session.MissionSession`), its verdict and its row;
- :mod:`bt_nav.grading.exe.bag`: the run's bag (``bt-nav record`` as one more process of the run);
- :mod:`bt_nav.grading.exe.grid`: a grid of runs (in parallel, or on a Dask cluster), resumable;
- :mod:`bt_nav.grading.exe.log`: what a node's output says of how it ended (its crash, an import it could not make).
"""
