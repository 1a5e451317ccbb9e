"""The textbook checks of Sutton & Barto (2018) ch. 8 (docs/sutton-barto.md): Dyna-Q on the Dyna
Maze, Dyna-Q+ on the blocking and shortcut mazes, prioritized sweeping on scaled Dyna Mazes, a
study run by ``skidnav run`` (``kind = "sutton-barto-checks"``): :mod:`.grid` (the config and
its checks), :mod:`.trial` (one run of one check), :mod:`.results` (the runs read back),
:mod:`.report` (tables, plots, files), :mod:`.study` (``STUDY``)."""
