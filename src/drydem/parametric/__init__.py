"""Parametric studies over many runs: sweeps (``drydem sweep``) and calibration (``drydem calibrate``).

Its modules, each importing only those before it: ``study`` (a study file and its runs),
``records`` (a run's record on disk), ``sweep`` (running the runs not yet recorded), ``workers``
(where they run: local processes or a Dask cluster), ``calibrate`` (the joint stiffness, by sweeps).
"""
