"""Shared basics every layer uses: the domain errors, the wrench conventions (units, torque scaling),
input validation, metrics, CSV columns, safe output files, calibration folds, the thermal drift model
and the Dask scale-out.

Imports only numpy, scipy, scikit-learn and the standard library; never another ftcal package.
"""
