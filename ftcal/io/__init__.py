"""Files of calibration data: the calibration dataset (:class:`~ftcal.CalibrationDataset`, CSV/NPZ)
and the recorded run logs of a robot-held experiment (:class:`~ftcal.RunLog`).

Imports only :mod:`ftcal.core`.
"""
