"""Tool load identification and gravity compensation, re-taring."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import ftcal
from ftcal import (AutoCalibrator, AxisNonlinearCalibrator, ComparativeCalibrator, DirectionalCalibrator,
                   EnsembleCalibrator, GaussianProcessCalibrator, LinearCalibrator, PolynomialCalibrator)
from ftcal.core import CalibrationInputError
from ftcal.experiment import ToolLoad, identify_tool_load
from ftcal.cli import main

G = np.array([0.0, 0.0, -9.81])
FORCE_NOISE, TORQUE_NOISE = 0.05, 0.005  # the noise: [N], [N·m]


def tool_wrenches(rotations, mass, com, bias, rng=None, noise=(FORCE_NOISE, TORQUE_NOISE)):
    """Reference wrenches written out independently of ftcal: F = m Rᵀ g, τ = c × F, plus bias and noise (the
    standard deviations of force [N] and torque [N·m])."""
    out = []
    for R in rotations:
        force = mass * (R.T @ G)
        out.append(np.concatenate([force, np.cross(com, force)]) + bias)
    out = np.array(out)
    if rng is not None:
        out[:, :3] += noise[0] * rng.normal(size=(len(out), 3))
        out[:, 3:] += noise[1] * rng.normal(size=(len(out), 3))
    return out


MASS, COM, BIAS = 1.5, np.array([0.012, -0.021, 0.085]), np.array([2.0, -1.5, 0.7, 0.12, -0.08, 0.03])


@pytest.mark.parametrize("seed", range(5))
def test_identification_is_within_half_a_percent_of_the_mass_and_2_mm_of_the_com_on_40_random_poses(seed):
    rng = np.random.default_rng(seed)
    rotations = Rotation.random(40, random_state=seed).as_matrix()
    wrenches = tool_wrenches(rotations, MASS, COM, BIAS, rng)
    tool = identify_tool_load(rotations, wrenches, gravity=G)
    assert abs(tool.mass - MASS) <= 0.005 * MASS
    assert np.linalg.norm(tool.center_of_mass - COM) <= 0.002
    assert np.all(np.abs(tool.bias[:3] - BIAS[:3]) <= 0.05)
    external = tool.compensate(rotations, wrenches)
    assert np.sqrt(np.mean(external[:, :3] ** 2)) <= 2 * FORCE_NOISE
    # the reported standard errors describe the actual errors (within a few of them)
    assert abs(tool.mass - MASS) <= 5 * tool.mass_std_error


def test_noise_free_identification_is_exact():
    rotations = Rotation.random(8, random_state=3).as_matrix()
    tool = identify_tool_load(rotations, tool_wrenches(rotations, MASS, COM, BIAS), gravity=G)
    np.testing.assert_allclose([tool.mass, *tool.center_of_mass, *tool.bias], [MASS, *COM, *BIAS], atol=1e-9)


def test_poses_that_do_not_excite_the_load_are_refused():
    # rotations about the gravity axis only: the tool never tilts, mass and bias are confounded
    rotations = Rotation.from_euler("z", np.linspace(0, 300, 12)[:, None], degrees=True).as_matrix()
    with pytest.raises(CalibrationInputError, match="do not excite the tool load"):
        identify_tool_load(rotations, tool_wrenches(rotations, MASS, COM, BIAS), gravity=G)
    # small tilts about one axis only: gravity directions nearly on a line, mass and bias barely separable
    rotations = Rotation.from_euler("x", np.linspace(-8, 8, 12)[:, None], degrees=True).as_matrix()
    with pytest.raises(CalibrationInputError, match="two independent directions"):
        identify_tool_load(rotations, tool_wrenches(rotations, MASS, COM, BIAS), gravity=G)


def test_too_few_poses_are_refused_by_their_count_not_by_their_tilt():
    # three random orientations tilt the tool about two axes: the only problem is their number
    rotations = Rotation.random(3, random_state=5).as_matrix()
    with pytest.raises(CalibrationInputError, match=r"^3 poses; at least 4 are needed") as info:
        identify_tool_load(rotations, tool_wrenches(rotations, MASS, COM, BIAS), gravity=G)
    assert "excite" not in str(info.value) and "one axis" not in str(info.value)
    # samples of one pose are one pose: 3 poses x 5 samples are 3 poses
    pose = np.repeat(np.arange(3), 5)
    with pytest.raises(CalibrationInputError, match=r"^3 poses; at least 4 are needed"):
        identify_tool_load(rotations[pose], tool_wrenches(rotations[pose], MASS, COM, BIAS), gravity=G, groups=pose)


def test_the_planned_minimal_pose_set_is_well_conditioned():
    robot = ftcal.robot.load_robot("kuka_iiwa14")
    plan = ftcal.robot.plan_calibration_poses(robot, subdivisions=0)
    rotations = ftcal.robot.sensor_pose_in_base(robot, plan.q)[:, :3, :3]
    assert len(rotations) == 11
    rng = np.random.default_rng(0)
    tool = identify_tool_load(rotations, tool_wrenches(rotations, MASS, COM, BIAS, rng), gravity=G)
    assert abs(tool.mass - MASS) <= 0.005 * MASS and np.linalg.norm(tool.center_of_mass - COM) <= 0.002


@pytest.mark.parametrize("bad, message", [
    (np.eye(3), r"shape \(n, 3, 3\)"),
    (np.tile(2 * np.eye(3), (5, 1, 1)), "not a rotation matrix"),
])
def test_bad_rotations(bad, message):
    with pytest.raises(CalibrationInputError, match=message):
        identify_tool_load(bad, np.zeros((5, 6)))


def test_tool_file_round_trip_and_bad_file(tmp_path):
    rotations = Rotation.random(10, random_state=1).as_matrix()
    tool = identify_tool_load(rotations, tool_wrenches(rotations, MASS, COM, BIAS), gravity=G)
    path = tool.save(tmp_path / "t.tool.json")
    back = ToolLoad.load(path)
    np.testing.assert_array_equal(back.compensate(rotations, np.zeros((10, 6))),
                                  tool.compensate(rotations, np.zeros((10, 6))))
    with pytest.raises(CalibrationInputError, match="already exists"):
        tool.save(path)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"format": "ftcal-tool-load", "mass_kg": 1.0, "center_of_mass_m": [0, 0],
                               "bias": [0] * 6}))
    with pytest.raises(CalibrationInputError, match="center_of_mass_m must be 3 numbers"):
        ToolLoad.load(bad)


@pytest.mark.parametrize("key, value, field", [
    ("gravity_m_s2", [0, 0, 1e308], "gravity_m_s2 has magnitude 1e\\+308 m/s²"),
    ("mass_kg", 1e300, "mass_kg has magnitude 1e\\+300 kg"),
    ("center_of_mass_m", [1e300, 1e300, 0], "center_of_mass_m has magnitude 1.41e\\+300 m"),
    ("bias", [1e300, 0, 0, 0, 0, 0], "bias has magnitude 1e\\+300 N, N·m"),
])
def test_a_tool_file_with_an_impossible_value_is_refused_not_compensated_to_inf(tmp_path, key, value, field):
    # a tool file edited by hand (a unit or typing error): refused on loading, never an inf in the compensated
    # wrenches, and the same bounds for identify_tool_load's gravity
    rotations = Rotation.random(10, random_state=1).as_matrix()
    tool = identify_tool_load(rotations, tool_wrenches(rotations, MASS, COM, BIAS), gravity=G)
    record = json.loads(tool.save(tmp_path / "t.tool.json").read_text())
    record[key] = value
    (tmp_path / "bad.tool.json").write_text(json.dumps(record))
    with pytest.raises(CalibrationInputError, match=f"bad.tool.json: {field}, beyond the .* a tool on a force/torque sensor can have"):
        ToolLoad.load(tmp_path / "bad.tool.json")
    if key == "gravity_m_s2":
        with pytest.raises(CalibrationInputError, match="gravity has magnitude"):
            identify_tool_load(rotations, tool_wrenches(rotations, MASS, COM, BIAS), gravity=value)


def test_identify_load_and_compensate_through_the_cli(tmp_path, capsys):
    logs, data, models = tmp_path / "logs", tmp_path / "data", tmp_path / "models"
    mounting = ftcal.experiment.MountingDevice(mass=0.9, center_of_mass_in_sensor=(0.09, 0.0, 0.045))
    ftcal.experiment.simulate_experiment(logs, subdivisions=1, mounting=mounting, random_state=0)
    assert main(["prepare", str(logs), "--out", str(data), "-q"]) == 0
    assert main(["fit", str(data / "dataset.csv"), "--model", "linear", "--out", str(models), "-q"]) == 0
    model = str(models / "linear.model.npz")
    assert main(["identify-load", str(logs / "config0_no-load.csv"), "--model", model,
                 "--gravity", "0,0,-9.80665", "--out", str(tmp_path / "tool"), "-q"]) == 0
    tool = ToolLoad.load(tmp_path / "tool" / "tool.tool.json")
    # the mounting device is the tool the no-load runs carry; noise and robot accuracy set the tolerances
    assert abs(tool.mass - 0.9) <= 5 * tool.mass_std_error + 0.005 * 0.9
    assert np.linalg.norm(tool.center_of_mass - np.array([0.09, 0.0, 0.045])) <= 0.002
    capsys.readouterr()
    assert main(["compensate", str(logs / "config0_no-load.csv"), "--model", model, "--tool",
                 str(tmp_path / "tool" / "tool.tool.json")]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "timestamp,pose,Fx,Fy,Fz,Tx,Ty,Tz"
    external = np.array([[float(v) for v in line.split(",")[2:]] for line in out[1:]])
    assert np.sqrt(np.mean(external[:, :3] ** 2)) <= 2 * tool.residual_rms[0] + 1e-9  # nothing but the tool


# ------------------------------------------------------------------ re-tare
SENSOR_NOISE = 0.0005  # raw units; the gain is ~0.01 raw units per N


def linear_sensor(n, rng, zero, noise=SENSOR_NOISE):
    w = rng.uniform(-50, 50, size=(n, 6))
    w[:, 3:] /= 50.0
    raw = w @ np.random.default_rng(42).normal(size=(6, 6)) * 0.01 + zero + noise * rng.normal(size=(n, 6))
    return raw, w


TINY = dict(hidden_layer_sizes=(16,), phase1_epochs=30, plateau_epochs=3, max_recover_epochs=3, random_state=0)
CALIBRATORS = {
    "linear": lambda: LinearCalibrator(),
    "polynomial": lambda: PolynomialCalibrator(degree=2),
    "axis_nonlinear": lambda: AxisNonlinearCalibrator(),
    "gaussian_process": lambda: GaussianProcessCalibrator(max_samples=300, random_state=0),
    "directional": lambda: DirectionalCalibrator(**TINY),
    "comparative": lambda: ComparativeCalibrator(**TINY),
    "ensemble": lambda: EnsembleCalibrator(DirectionalCalibrator(**TINY), n_members=2, random_state=0),
    "auto": lambda: AutoCalibrator(candidates=[("linear", LinearCalibrator()),
                                              ("poly", PolynomialCalibrator(degree=2))], baselines=False),
}


@pytest.mark.parametrize("kind", list(CALIBRATORS))
def test_retare_recovers_a_tare_shift_of_3_percent_of_the_span(kind, tmp_path):
    rng = np.random.default_rng(0)
    zero = np.array([0.5, -0.3, 0.2, 0.1, -0.2, 0.4])
    raw, w = linear_sensor(600, rng, zero)
    test_raw, test_w = linear_sensor(300, rng, zero)
    model = CALIBRATORS[kind]().fit(raw, w)
    alpha = model.alpha_
    reference = model.predict(test_raw)
    before = ftcal.core.wrench_rmse(test_w, reference, alpha=alpha)
    shift = 0.03 * (raw.max(axis=0) - raw.min(axis=0)) * np.sign(rng.normal(size=6))
    n_quiet = 1000  # e.g. 1 s at 1 kHz
    no_load = zero + shift + SENSOR_NOISE * rng.normal(size=(n_quiet, 6))  # no load: the new zero and noise
    # The input shift is (new tare) - (training tare): the first is known to sigma / sqrt(n_quiet), the second
    # (estimated by the sign-gated fit, 13 unknowns per channel) to about sigma * sqrt(13 / n_train). Through the
    # sensor's inverse gain (the LTM's torque-scaled matrix) that is an RMS wrench error of
    # |C|_F * sigma * sqrt(1 / n_quiet + 13 / n_train) / sqrt(6). Allow 3x for the models' local gain and chance.
    gain = LinearCalibrator(alpha=alpha).fit(raw, w).calibration_matrix_ * np.array([1, 1, 1, alpha, alpha, alpha])[:, None]
    tolerance = 3 * np.linalg.norm(gain) * SENSOR_NOISE * np.sqrt(1 / n_quiet + 13 / len(raw)) / np.sqrt(6)
    assert ftcal.core.wrench_rmse(reference, model.predict(test_raw + shift), alpha=alpha) > 2 * tolerance
    model.retare(no_load)
    shifted_prediction = model.predict(test_raw + shift)
    assert ftcal.core.wrench_rmse(reference, shifted_prediction, alpha=alpha) <= tolerance
    assert ftcal.core.wrench_rmse(test_w, shifted_prediction, alpha=alpha) <= 1.1 * before  # the target
    back = ftcal.load_model(ftcal.save_model(model, tmp_path / "m.model.npz"))
    np.testing.assert_array_equal(back.predict(test_raw), model.predict(test_raw))


def test_retare_refuses_readings_that_are_not_quiet():
    rng = np.random.default_rng(0)
    raw, w = linear_sensor(400, rng, np.zeros(6))
    model = LinearCalibrator().fit(raw, w)
    moving = linear_sensor(50, rng, np.zeros(6))[0]  # readings under changing loads
    with pytest.raises(CalibrationInputError, match="not quiet: channel s0"):
        model.retare(moving)
    with pytest.raises(ValueError, match="4 features"):
        model.retare(np.zeros((5, 4)))


def test_retare_through_the_cli_never_replaces_the_old_model(tmp_path, capsys):
    rng = np.random.default_rng(0)
    raw, w = linear_sensor(400, rng, np.zeros(6))
    path = ftcal.save_model(LinearCalibrator().fit(raw, w), tmp_path / "ltm.model.npz")
    before = path.read_bytes()
    readings = tmp_path / "zero.csv"
    np.savetxt(readings, 0.05 + SENSOR_NOISE * rng.normal(size=(30, 6)), delimiter=",")
    assert main(["retare", str(path), str(readings), "-q"]) == 0
    new = tmp_path / "ltm-retared.model.npz"
    np.testing.assert_allclose(ftcal.load_model(new).tare_reading_, 0.05, atol=0.002)
    assert path.read_bytes() == before
    assert main(["retare", str(path), str(readings), "--output", str(path), "-q"]) == 2
    assert "is the model file itself" in capsys.readouterr().err
    assert path.read_bytes() == before
