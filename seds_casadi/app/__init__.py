"""The application: the ``seds-casadi`` command line, the main job ``play``, the LASA, Table 1
and validation commands, plotting, the robot's reach and speed over a field's situations
(``reach``), and executors (local processes or a Dask cluster, extra ``[dask]``). It may import
every other layer; nothing imports it. Submodules are imported on demand, so ``seds-casadi
fit`` and ``lasa`` need only the core's dependencies.
"""
