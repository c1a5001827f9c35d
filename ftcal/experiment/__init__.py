"""The robot-held experiment and in-situ use: pairing load / no-load runs into a calibration dataset
(R_delta, reference wrenches), the virtual experiment that writes such runs, and the identification of
a tool's load for gravity compensation, and which poses to measure next (:func:`ftcal.propose_next_poses`).

Imports :mod:`ftcal.core`, :mod:`ftcal.io`, :mod:`ftcal.robot` and :mod:`ftcal.simulation`.
"""
