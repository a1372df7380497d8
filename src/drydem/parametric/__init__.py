"""Parametric studies over many runs: sweeps (``drydem sweep``) and calibration (``drydem calibrate``)."""
