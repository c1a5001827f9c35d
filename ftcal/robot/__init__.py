"""The robot side of a robot-held calibration (Pinocchio): robot models and forward kinematics, inverse
kinematics for orientation targets, geodesic calibration poses, and the load configurations whose
reference wrench gravity gives.

Imports only :mod:`ftcal.core`. A new robot is a URDF in ``robots/`` and an entry of ``BUILTIN_ROBOTS``
in ``_robot.py``.
"""
