"""In situ, checked: the held-out residual of a tool, the wrench's frame, a drift in the row order, and the
sensor's mounting rotation identified with the tool (with what the poses can tell)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import ftcal
from ftcal.cli import main
from ftcal.core import CalibrationInputError
from ftcal.experiment import (ToolLoad, check_wrench_frame, drift_in_recording_order, identify_tool_load,
                              tool_load_observability)
from test_in_situ import tool_wrenches

G = np.array([0.0, 0.0, -9.81])
MASS, COM, BIAS = 1.24, np.array([0.004, -0.011, 0.062]), np.array([1.5, -0.8, 0.4, 0.06, -0.03, 0.02])
FORCE_NOISE, TORQUE_NOISE = 0.05, 0.004  # [N], [N·m]
MOUNTING_DEG = np.array([2.0, -1.5, 2.5])  # the sensor's true frame turned from the URDF's (rx, ry, rz) [deg]


@pytest.fixture(scope="module")
def robot():
    return ftcal.robot.load_robot("kuka_iiwa14")


@pytest.fixture(scope="module")
def plan_q(robot):
    return ftcal.robot.plan_calibration_poses(robot, subdivisions=1).q  # 41 well-spread poses


def sensor_wrenches(true_rotations, rng=None, bias=BIAS):
    """The tool's weight and the bias in the sensor's true frame, written out independently of ftcal."""
    return tool_wrenches(true_rotations, MASS, COM, bias, rng, noise=(FORCE_NOISE, TORQUE_NOISE))


def write_pose_file(path, rotations, wrenches, time=None):
    quat = Rotation.from_matrix(rotations).as_quat()
    names = ([] if time is None else ["time"]) + ["qx", "qy", "qz", "qw", "Fx", "Fy", "Fz", "Tx", "Ty", "Tz"]
    columns = ([] if time is None else [time[:, None]]) + [quat, wrenches]
    np.savetxt(path, np.hstack(columns), delimiter=",", header=",".join(names), comments="", fmt="%.10g")
    return path


def hand_leave_one_pose_out(rotations, wrenches):
    """Each pose compensated by the tool identified on the other poses (the user's 70/30 split, done per pose)."""
    residual = np.empty_like(wrenches)
    for i in range(len(wrenches)):
        keep = np.arange(len(wrenches)) != i
        tool = identify_tool_load(rotations[keep], wrenches[keep], gravity=G, drift="none")
        residual[i] = tool.compensate(rotations[i:i + 1], wrenches[i:i + 1])[0]
    return np.sqrt(np.mean(residual[:, :3] ** 2)), np.sqrt(np.mean(residual[:, 3:] ** 2))


# ------------------------------------------------------------------ the held-out figure
def test_held_out_residual_is_a_leave_poses_out_figure_matching_a_hand_made_one(robot, plan_q):
    rng = np.random.default_rng(0)
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q[:15])[:, :3, :3]
    wrenches = sensor_wrenches(rotations, rng)
    tool = identify_tool_load(rotations, wrenches, gravity=G)  # 15 poses <= cv = 20: leave one pose out
    np.testing.assert_allclose(tool.held_out_residual_rms, hand_leave_one_pose_out(rotations, wrenches), rtol=1e-9)
    # held out is worse than in-sample (13 parameters fitted to 15 poses), and near the noise
    assert (tool.held_out_residual_rms > tool.residual_rms).all()
    assert tool.held_out_residual_rms[0] < 2 * FORCE_NOISE
    # 41 poses in 20 folds (two poses held out at a time): the hand leave-one-out within noise (a few %)
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q)[:, :3, :3]
    wrenches = sensor_wrenches(rotations, rng)
    tool = identify_tool_load(rotations, wrenches, gravity=G)
    hand = np.array(hand_leave_one_pose_out(rotations, wrenches))
    relative_se = 1 / np.sqrt(2 * 3 * len(wrenches))  # SE of an RMS of 3n roughly normal residuals, relative
    np.testing.assert_allclose(tool.held_out_residual_rms, hand, rtol=3 * relative_se)
    assert not np.allclose(tool.held_out_residual_rms, hand, rtol=1e-6)  # a K-fold figure, not the same LOO


def test_the_tool_file_and_the_printed_line_carry_both_residuals(tmp_path, capsys, robot, plan_q):
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q)[:, :3, :3]
    wrenches = sensor_wrenches(rotations, np.random.default_rng(1))
    path = write_pose_file(tmp_path / "poses.csv", rotations, wrenches)
    assert main(["identify-load", str(path), "--out", str(tmp_path / "tool")]) == 0
    err = capsys.readouterr().err
    line = next(ln for ln in err.splitlines() if ln.startswith("tool: "))
    tool = ToolLoad.load(tmp_path / "tool" / "tool.tool.json")
    assert f"residual RMS {tool.residual_rms[0]:.3g} N" in line and "in-sample" in line
    assert f"held out (leave-poses-out) {tool.held_out_residual_rms[0]:.3g} N" in line
    record = json.loads((tmp_path / "tool" / "tool.tool.json").read_text())
    assert len(record["held_out_residual_rms"]) == 2
    np.testing.assert_allclose(record["held_out_residual_rms"], hand_leave_one_pose_out(rotations, wrenches),
                               rtol=3 / np.sqrt(6 * len(wrenches)))
    assert "ftcal: warning" not in err and "ftcal: note" not in err  # the right frame, no drift: nothing else said


# ------------------------------------------------------------------ the frame checked
def test_a_recording_declared_in_the_wrong_frame_is_named_and_the_right_one_is_not(tmp_path, capsys, robot, plan_q):
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q)[:, :3, :3]
    wrenches = sensor_wrenches(rotations, np.random.default_rng(2))  # the sensor frame, continuously recorded
    rec = ftcal.experiment.continuous_recording(
        wrenches, rotations=rotations, still_s=3.0, move_s=1.0, sensor_rate_hz=10.0, pose_rate_hz=10.0,
        settle_amplitude=0.2, noise=[FORCE_NOISE] * 3 + [TORQUE_NOISE] * 3, random_state=0)
    path = write_pose_file(tmp_path / "recording.csv", rec.rotations, rec.reading, time=rec.sensor_time)
    # declared in the sensor frame (right): no warning
    assert main(["identify-load", str(path), "--out", str(tmp_path / "right"), "-q"]) == 0
    assert "--wrench-frame" not in capsys.readouterr().err
    # declared in the base frame (wrong): one warning line with both residuals and the option, said before the
    # identification fails on it (here the bias turning with the sensor leaves no tool's weight: a mass <= ~0)
    assert main(["identify-load", str(path), "--wrench-frame", "base", "--out", str(tmp_path / "wrong"), "-q"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2 and "mass" in err[1] and ("not positive" in err[1] or "not distinguishable from zero" in err[1])
    warning = [ln for ln in err if ln.startswith("ftcal: warning")]
    assert len(warning) == 1 and "far better in the sensor frame than in the declared base frame" in warning[0]
    assert "use --wrench-frame sensor" in warning[0]
    # compensate with the right tool: declaring base warns, declaring sensor does not
    tool = str(tmp_path / "right" / "tool.tool.json")
    assert main(["compensate", str(path), "--tool", tool, "--wrench-frame", "base", "--output",
                 str(tmp_path / "wrong.csv")]) == 0
    err = capsys.readouterr().err
    assert "ftcal: warning" in err and "use --wrench-frame sensor" in err
    assert main(["compensate", str(path), "--tool", tool, "--output", str(tmp_path / "right.csv")]) == 0
    assert "ftcal: warning" not in capsys.readouterr().err


def test_a_base_frame_wrench_declared_in_the_sensor_frame_is_named_in_the_library(robot, plan_q):
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q)[:, :3, :3]
    in_sensor = sensor_wrenches(rotations, np.random.default_rng(3))
    in_base = np.hstack([np.einsum("nij,nj->ni", rotations, in_sensor[:, :3]),
                         np.einsum("nij,nj->ni", rotations, in_sensor[:, 3:])])
    wrong = check_wrench_frame(rotations, in_base, "sensor", gravity=G)
    assert wrong.other_fits_better and wrong.other == "base"
    assert wrong.residual_other[0] < 2 * FORCE_NOISE < wrong.residual_declared[0]
    right = check_wrench_frame(rotations, ftcal.experiment.wrench_in_sensor_frame(rotations, in_base), "base",
                               gravity=G)
    assert not right.other_fits_better and right.residual_declared[0] < 2 * FORCE_NOISE


# ------------------------------------------------------------------ the drift said
def test_a_drift_over_the_row_order_is_said_in_one_line_with_the_mass_change(tmp_path, capsys, robot, plan_q):
    q = np.vstack([plan_q, plan_q[::-1]])  # 82 static poses in recording order
    rotations = ftcal.robot.sensor_pose_in_base(robot, q)[:, :3, :3]
    warm_up = 1.2 * (1 - np.exp(-np.arange(len(q)) / 15.0))  # [N] the bias settling over the recording
    wrenches = sensor_wrenches(rotations, np.random.default_rng(4))
    wrenches[:, 2] += warm_up
    wrenches[:, 0] -= 0.5 * warm_up
    path = write_pose_file(tmp_path / "poses.csv", rotations, wrenches)  # no time column
    assert main(["identify-load", str(path), "--out", str(tmp_path / "tool"), "-q"]) == 0
    notes = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("ftcal: note")]
    assert len(notes) == 1 and "bias drift over the row order" in notes[0] and "use it with --time-from-order" in notes[0]
    found = drift_in_recording_order(rotations, wrenches, G)
    assert f"from {found.held_out_constant[0]:.3g} to {found.held_out_drift[0]:.3g} N" in notes[0]
    assert found.held_out_constant[0] - found.held_out_drift[0] > found.paired_se[0]
    assert f"the mass is {found.mass_drift:.4f} kg instead of {found.mass_constant:.4f} kg" in notes[0]
    # the drift's mass is the truth's; the constant bias' is off by more than its standard error
    assert abs(found.mass_drift - MASS) < abs(found.mass_constant - MASS)
    # the option named does what the line says
    assert main(["identify-load", str(path), "--time-from-order", "--out", str(tmp_path / "drift"), "-q"]) == 0
    assert ToolLoad.load(tmp_path / "drift" / "tool.tool.json").mass == pytest.approx(found.mass_drift, rel=1e-9)
    # without a drift, nothing is said (recording order or not)
    steady = sensor_wrenches(rotations, np.random.default_rng(5))
    assert drift_in_recording_order(rotations, steady, G) is None


# ------------------------------------------------------------------ the mounting identified
def test_a_small_mounting_rotation_is_recovered_within_its_standard_error(tmp_path, capsys, plan_q):
    nominal = ftcal.robot.load_robot("kuka_iiwa14")
    mounted = ftcal.robot.load_robot("kuka_iiwa14", sensor_mounting=(*MOUNTING_DEG, 0.0, 0.0, 0.0))
    robot_frame = ftcal.robot.sensor_pose_in_base(nominal, plan_q)[:, :3, :3]
    true_frame = ftcal.robot.sensor_pose_in_base(mounted, plan_q)[:, :3, :3]
    rng = np.random.default_rng(6)
    wrenches = sensor_wrenches(true_frame, rng)
    truth = np.radians(MOUNTING_DEG)
    tool = identify_tool_load(robot_frame, wrenches, gravity=G, mounting=True)
    error = tool.mounting_rotation - truth
    assert (np.abs(error) <= 3 * tool.mounting_rotation_std_error).all()
    assert (np.degrees(tool.mounting_rotation_std_error) < 0.3).all()  # told well below the rotation's size
    assert abs(tool.mass - MASS) <= 3 * tool.mass_std_error
    assert (np.abs(tool.center_of_mass - COM) <= 3 * tool.center_of_mass_std_error + 1e-4).all()
    # without the mounting the bias and the centre of mass absorb it: the residual is much larger
    plain = identify_tool_load(robot_frame, wrenches, gravity=G)
    assert plain.residual_rms[0] > 2 * tool.residual_rms[0]
    # the standard errors are honest: over seeds, about 2 in 3 components within one SE
    within = []
    for seed in range(12):
        t = identify_tool_load(robot_frame, sensor_wrenches(true_frame, np.random.default_rng(100 + seed)),
                               gravity=G, mounting=True)
        within += list(np.abs(t.mounting_rotation - truth) <= t.mounting_rotation_std_error)
    assert 0.45 <= np.mean(within) <= 0.9
    # the tool file keeps it and compensates in the mounted frame; the command line prints it
    tool.save(tmp_path / "m.tool.json")
    back = ToolLoad.load(tmp_path / "m.tool.json")
    np.testing.assert_array_equal(back.mounting_rotation, tool.mounting_rotation)
    external = back.compensate(robot_frame, wrenches)
    assert np.sqrt(np.mean(external[:, :3] ** 2)) < 1.5 * FORCE_NOISE
    path = write_pose_file(tmp_path / "poses.csv", robot_frame, wrenches)
    assert main(["identify-load", str(path), "--mounting", "--out", str(tmp_path / "tool")]) == 0
    line = next(ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("tool: "))
    r = np.degrees(tool.mounting_rotation)
    assert f"mounting rotation [{r[0]:.2f}±" in line


def test_poses_that_cannot_tell_the_mounting_are_named(robot):
    rng = np.random.default_rng(7)
    # six poses within 20 deg of upright: enough for mass and bias, too similar for a mounting rotation
    tilts = Rotation.from_euler("xy", [[20, 0], [-20, 0], [0, 20], [0, -20], [14, 14], [-14, -14]], degrees=True)
    rotations = tilts.as_matrix()
    wrenches = sensor_wrenches(rotations, rng)
    wrenches[:, :3] += 0.3 * rng.normal(size=(6, 3))  # a noisy sensor
    identify_tool_load(rotations, wrenches, gravity=G)  # the tool alone is fine
    with pytest.raises(CalibrationInputError, match="cannot tell the sensor's mounting rotation") as info:
        identify_tool_load(rotations, wrenches, gravity=G, mounting=True)
    message = str(info.value)
    assert "mounting rotation about the sensor's" in message and "standard error would be about" in message
    # structurally: never tilted (all about the vertical axis): each block named with what absorbs it
    spun = Rotation.from_euler("z", np.linspace(0, 300, 6)[:, None], degrees=True).as_matrix()
    problems = tool_load_observability(spun, mass=MASS, center_of_mass=COM).problems()
    assert any(p.startswith("the mass is not identifiable from these 6 poses: the force bias absorbs it")
               for p in problems)
    assert any("mounting rotation about the sensor's" in p and "not identifiable" in p for p in problems)
    # the planner's 11 poses tell every block
    plan = ftcal.robot.plan_calibration_poses(robot, subdivisions=0)
    well = tool_load_observability(ftcal.robot.sensor_pose_in_base(robot, plan.q)[:, :3, :3], mass=MASS,
                                   center_of_mass=COM, noise=[FORCE_NOISE, TORQUE_NOISE])
    assert well.problems() == [] and all(b.rank == b.n_parameters for b in well.blocks)


def test_a_mounted_tool_exports_to_onnx_and_compensates_like_the_library(robot, plan_q):
    ort = pytest.importorskip("onnxruntime")
    from ftcal.experiment._drift import tool_onnx_model

    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q)[:, :3, :3]
    tool = ToolLoad(mass=MASS, center_of_mass=COM, bias=BIAS, mounting_rotation=np.radians(MOUNTING_DEG))
    wrenches = sensor_wrenches(rotations, np.random.default_rng(8))
    session = ort.InferenceSession(tool_onnx_model(tool).SerializeToString())
    external = session.run(None, {"rotation": rotations, "wrench": wrenches})[0]
    np.testing.assert_allclose(external, tool.compensate(rotations, wrenches), atol=1e-9)
    assert "mounted turned by the rotation vector" in ftcal.experiment.tool_gravity_compensation_yaml(tool)


# ------------------------------------------------------------------ the workflow in the library
def test_static_poses_gives_a_python_user_the_poses_the_command_used(tmp_path, capsys, robot, plan_q):
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q[:20])[:, :3, :3]
    wrenches = sensor_wrenches(rotations, np.random.default_rng(9))
    rec = ftcal.experiment.continuous_recording(
        wrenches, rotations=rotations, still_s=3.0, move_s=1.0, sensor_rate_hz=20.0, pose_rate_hz=20.0,
        settle_amplitude=0.3, noise=[FORCE_NOISE] * 3 + [TORQUE_NOISE] * 3, random_state=1)
    path = write_pose_file(tmp_path / "recording.csv", rec.rotations, rec.reading, time=rec.sensor_time)
    assert main(["identify-load", str(path), "--drift", "none", "--out", str(tmp_path / "tool")]) == 0
    err = capsys.readouterr().err
    poses = ftcal.experiment.static_poses(path)
    assert poses.kind == "pose file" and poses.n_poses == 20 and len(poses.still) == 1
    assert f"{path}: {poses.notes[0][1]}" in err  # the command printed the library's note
    tool = identify_tool_load(poses.rotations, poses.wrenches, gravity=G, drift="none")
    record = json.loads((tmp_path / "tool" / "tool.tool.json").read_text())
    assert record["mass_kg"] == pytest.approx(tool.mass, rel=1e-12)
    np.testing.assert_allclose(record["held_out_residual_rms"], tool.held_out_residual_rms, rtol=1e-12)
    assert (tmp_path / "tool" / "tool.poses.csv").read_text() == poses.to_csv()
    # the poses found are the recording's: within a few noise levels of the settled readings
    assert np.abs(poses.wrenches[:, :3] - wrenches[:, :3]).max() < 10 * FORCE_NOISE


def test_the_frame_check_of_a_drifting_tool_compensates_each_row_at_its_time(robot, plan_q):
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q)[:, :3, :3]
    t = np.linspace(0.0, 3600.0, len(rotations))
    wrenches = sensor_wrenches(rotations, np.random.default_rng(10))
    wrenches[:, 0] += 0.8 * t / 3600.0  # 0.8 N/h
    tool = identify_tool_load(rotations, wrenches, gravity=G, times=t)
    assert tool.drift is not None
    right = check_wrench_frame(rotations, wrenches, "sensor", tool=tool, times=t)
    assert not right.other_fits_better and right.residual_declared[0] < 2 * FORCE_NOISE
    wrong = check_wrench_frame(rotations, ftcal.experiment.wrench_in_sensor_frame(rotations, wrenches), "base",
                               tool=tool, times=t)
    assert wrong.other_fits_better and wrong.other == "sensor"
    np.testing.assert_allclose(wrong.residual_other, right.residual_declared, rtol=1e-9)


def test_the_held_out_residual_with_a_mounting_refits_the_rotation_without_the_held_out_pose(robot, plan_q):
    """With ``mounting=True`` the held-out figure is a leave-poses-out one for the rotation too: each held-out pose
    is compensated by the tool *and rotation* identified on the other poses (a rotation fitted on all poses saw it)."""
    rng = np.random.default_rng(5)
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q[:15])[:, :3, :3]
    wrenches = sensor_wrenches(rotations, rng)  # no true rotation: three parameters the data do not need
    tool = identify_tool_load(rotations, wrenches, gravity=G, drift="none", mounting=True)
    residual = np.empty_like(wrenches)
    for i in range(len(wrenches)):
        keep = np.arange(len(wrenches)) != i
        held = identify_tool_load(rotations[keep], wrenches[keep], gravity=G, drift="none", mounting=True)
        residual[i] = held.compensate(rotations[i:i + 1], wrenches[i:i + 1])[0]
    hand = np.sqrt(np.mean(residual[:, :3] ** 2)), np.sqrt(np.mean(residual[:, 3:] ** 2))
    np.testing.assert_allclose(tool.held_out_residual_rms, hand, rtol=1e-6)


def test_a_base_frame_wrench_identified_as_a_sensor_frame_one_is_refused_not_a_massless_tool(robot, plan_q):
    """A wrench left in the base frame does not turn with the poses: under the sensor-frame hypothesis the bias takes
    the whole weight and the mass comes out ~0 kg with a CoM metres away. Refused, naming the base frame."""
    rng = np.random.default_rng(2)
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q)[:, :3, :3]
    force = np.tile(MASS * G, (len(rotations), 1))  # the weight as the base frame sees it: the same in every pose
    wrenches = np.hstack([force, np.cross(COM, force)]) + BIAS + 0.02 * rng.normal(size=(len(rotations), 6))
    with pytest.raises(CalibrationInputError, match="not distinguishable from zero.*base frame"):
        identify_tool_load(rotations, wrenches, gravity=G)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_mass_within_its_noise_of_zero_is_named_as_such_whatever_its_sign(robot, plan_q, seed):
    """A base-frame wrench gives a mass within a few SE of 0 kg, slightly above or below zero by the noise drawn: both
    signs get the same advice (the base frame), never "not positive" for one draw and the base frame for another."""
    rng = np.random.default_rng(seed)
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q)[:, :3, :3]
    force = np.tile(MASS * G, (len(rotations), 1))
    wrenches = np.hstack([force, np.cross(COM, force)]) + BIAS + 0.02 * rng.normal(size=(len(rotations), 6))
    with pytest.raises(CalibrationInputError, match="not distinguishable from zero.*base frame"):
        identify_tool_load(rotations, wrenches, gravity=G)


def test_gravity_declared_the_wrong_way_gives_a_negative_mass_refused_as_not_positive(robot, plan_q):
    """The tool's weight with gravity declared upwards: a mass far below zero (many SE), which says the gravity
    direction is wrong, not that the tool weighs nothing."""
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q)[:, :3, :3]
    wrenches = sensor_wrenches(rotations, np.random.default_rng(0))
    with pytest.raises(CalibrationInputError, match=r"mass is -1\.2\d* kg \(not positive\).*gravity direction"):
        identify_tool_load(rotations, wrenches, gravity=-G)


@pytest.mark.parametrize("gravity, slip", [((0, 0, -981.0), r"cm/s² \(divide by 100\)"),
                                           ((0, 0, -0.00981), r"km/s² \(multiply by 1000\)"),
                                           ((0, 0, -1.0), r"in g \(multiply by 9\.81\)"),
                                           ((0, 0, -9810.0), r"mm/s² \(divide by 1000\)"),
                                           ((0, 0, -32.17), r"ft/s² \(multiply by 0\.3048\)"),
                                           ((0, 0, -386.1), r"in/s² \(multiply by 0\.0254\)")])
def test_a_gravity_in_another_unit_is_refused_naming_its_magnitude_and_the_slip(robot, plan_q, gravity, slip):
    """A gravity of 981 (cm/s²) would give a tool 100 times too light, without a word: its magnitude is not the
    Earth's surface gravity (9.78-9.84 m/s²), so it is refused, its magnitude and the likely unit named."""
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q)[:, :3, :3]
    wrenches = sensor_wrenches(rotations, np.random.default_rng(0))
    magnitude = f"{np.linalg.norm(gravity):.4g}".replace(".", r"\.")
    with pytest.raises(CalibrationInputError, match=rf"gravity has magnitude {magnitude} m/s².*{slip}"):
        identify_tool_load(rotations, wrenches, gravity=gravity)


@pytest.mark.parametrize("gravity", [(0, 0, -9.8), (0, 0, -9.78), (0, 0, -9.84), (-9.80665, 0, 0)])
def test_every_surface_gravity_in_m_s2_is_accepted_and_the_mass_follows_it(robot, plan_q, gravity):
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q)[:, :3, :3]
    g = np.asarray(gravity, dtype=float)
    force = MASS * np.einsum("nji,j->ni", rotations, g)  # Rᵀ g, written out for this gravity
    wrenches = np.hstack([force, np.cross(COM, force)]) + BIAS
    assert identify_tool_load(rotations, wrenches, gravity=gravity).mass == pytest.approx(MASS, rel=1e-9)


def test_the_zero_mass_advice_follows_the_declared_frame_and_names_the_gravity_direction(tmp_path, capsys, robot,
                                                                                         plan_q):
    """Wrenches declared in the base frame but recorded in the sensor frame: the advice is the sensor frame (as the
    warning says), never the base frame the user declared; gravity along a wrong axis is named as the other cause."""
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan_q)[:, :3, :3]
    wrenches = sensor_wrenches(rotations, np.random.default_rng(3))
    with pytest.raises(CalibrationInputError, match=r"not distinguishable from zero.*declared in the robot's base "
                       r"frame.*gravity is not along \[0\.0, 0\.0, -9\.81\].*declared_frame='sensor'"):
        identify_tool_load(rotations, ftcal.experiment.wrench_in_sensor_frame(rotations, wrenches), gravity=G,
                           declared_frame="base")
    path = write_pose_file(tmp_path / "poses.csv", rotations, wrenches)
    assert main(["identify-load", str(path), "--wrench-frame", "base", "--out", str(tmp_path / "a"), "-q"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert "use --wrench-frame sensor" in err[0]
    assert "not distinguishable from zero" in err[1] and "(--wrench-frame sensor)" in err[1]
    assert "--wrench-frame base" not in err[1] and "declare its frame as the base frame" not in err[1]
    # gravity along another axis than the tool's weight: the gravity direction named, with the base-frame advice
    assert main(["identify-load", str(path), "--gravity", "0,9.81,0", "--out", str(tmp_path / "b"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "not distinguishable from zero" in err and "gravity is not along [0.0, 9.81, 0.0] m/s²" in err
    assert "(--wrench-frame base)" in err and "check the gravity's axis and sign" in err
