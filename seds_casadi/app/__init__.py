"""The application: the ``seds-casadi`` command line, the main job ``play``, the LASA, Table 1
and validation commands, replays, the rows of ``shots.csv``, plotting, and executors (local
processes or a Dask cluster, extra ``[dask]``); the game itself (scenes, shots, the robot's
launch and reach) is :mod:`seds_casadi.game`. It may import
every other layer; nothing imports it. Submodules are imported on demand, so ``seds-casadi
fit`` and ``lasa`` need only the core's dependencies.
"""
