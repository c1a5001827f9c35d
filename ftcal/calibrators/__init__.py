"""The calibrators with closed-form or kernel fits: the shared scikit-learn base (validation, torque
scale, zero-load reading, re-tare), the linear transformation model, polynomial, axis-nonlinear and
Gaussian-process calibrators, and the temperature-compensating and load-history wrappers.

Imports only :mod:`ftcal.core`. A new closed-form calibrator goes here (subclass
:class:`~ftcal.calibrators._base.BaseCalibrator`, implement ``_fit`` and ``_predict_wrench``).
"""
