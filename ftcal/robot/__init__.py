"""The robot side of a robot-held calibration (Pinocchio): robot models and forward kinematics, inverse
kinematics for orientation targets, geodesic, random and D-optimal calibration poses, and the load
configurations whose reference wrench gravity gives.

Layer: above :mod:`ftcal.core`. Imports only :mod:`ftcal.core`. A new robot is a URDF in ``robots/`` and an
entry of ``BUILTIN_ROBOTS`` in ``_robot.py``.
"""

from ..core._lazy import lazy_namespace

#: Public names of this package -> the private module holding each.
_PUBLIC = dict(
    BUILTIN_ROBOTS="_robot", RobotModel="_robot", load_robot="_robot", example_robot_data_dir="_robot",
    frame_pose_in_base="_robot", sensor_pose_in_base="_robot",
    IKResult="_ik", solve_gravity_direction_ik="_ik", solve_orientation_ik="_ik",
    LoadConfiguration="_loads", STANDARD_GRAVITY="_loads", read_load_configurations="_loads",
    reference_wrench="_loads", reference_wrench_at_joints="_loads", thesis_load_configurations="_loads",
    CalibrationPlan="_pose_planning", CandidatePoses="_pose_planning", PLAN_STRATEGIES="_pose_planning",
    plan_calibration_poses="_pose_planning", reachable_candidates="_pose_planning", select_poses="_pose_planning",
    select_load_configurations="_pose_planning", d_criterion="_pose_planning", icosphere="_pose_planning",
    gravity_directions_in_sensor="_pose_planning", gravity_in_sensor_from_pitch_yaw="_pose_planning",
    pitch_yaw_from_gravity_in_sensor="_pose_planning", sensor_rotation_from_pitch_yaw="_pose_planning",
)
_PUBLIC.update(  # names the CLI uses
    LINEAR_MODEL_PARAMETERS="_pose_planning", load_fixture="_loads",
)
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
