"""D-optimal and random plans, "which poses next", and their bad input."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import ftcal
from ftcal import CalibrationDataset, GaussianProcessCalibrator, LinearCalibrator
from ftcal.robot import (CalibrationPlan, d_criterion, gravity_directions_in_sensor, load_robot,
                         pitch_yaw_from_gravity_in_sensor, plan_calibration_poses, reachable_candidates, select_poses,
                         sensor_pose_in_base)
from ftcal.core import PlanningError
from ftcal.experiment import prepare_dataset, propose_next_poses, simulate_experiment
from ftcal.cli import main
from ftcal.robot._pose_planning import LINEAR_MODEL_PARAMETERS

CANDIDATES = gravity_directions_in_sensor(2)  # 155 directions: a small candidate set, no robot needed


def _min_separation_deg(u: np.ndarray) -> float:
    cos = u @ u.T
    np.fill_diagonal(cos, -1.0)
    return float(np.degrees(np.arccos(np.clip(cos.max(), -1, 1))))


@pytest.fixture(scope="module")
def robot():
    return load_robot("kuka_iiwa14")


@pytest.fixture(scope="module")
def candidates(robot):
    return reachable_candidates(robot, subdivisions=1, excluded_cap_deg=0)  # 42 directions


def test_design_rows_are_the_physics_of_the_load():
    # [1, u, r x u / l]: with the load on the sensor's x axis and gravity along its z axis the torque is about -y.
    rows = linear_design_rows = ftcal.robot._pose_planning.linear_design_rows([[0, 0, 1.0]], [[0.2, 0, 0]])
    np.testing.assert_allclose(linear_design_rows[0, 0], [1, 0, 0, 1, 0, -1, 0])
    assert rows.shape == (1, 1, LINEAR_MODEL_PARAMETERS)
    # One pose with all seven configurations spans 3 of the 7 design directions.
    one = ftcal.robot._pose_planning.linear_design_rows(CANDIDATES[:1]).reshape(-1, 7)
    assert np.linalg.matrix_rank(one) == 3
    # [1, u] needs 4 directions not on one circle (a plane section): 3 poses never identify the LTM.
    u = np.random.default_rng(0).normal(size=(4, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    assert d_criterion(u[:3]) == -np.inf and np.isfinite(d_criterion(u))
    t = np.array([0.1, 1.0, 2.5, 4.0])
    circle = np.column_stack([0.6 * np.cos(t), 0.6 * np.sin(t), np.full(4, 0.8)])  # 4 directions on one circle
    assert d_criterion(circle) == -np.inf


@pytest.mark.parametrize("space_filling", [0.0, 1.0])
def test_greedy_additions_increase_the_d_criterion(space_filling):
    idx = select_poses(CANDIDATES, 20, space_filling=space_filling, max_exchange_passes=0)
    assert len(set(idx.tolist())) == 20
    path = np.array([d_criterion(CANDIDATES[idx[:k]]) for k in range(4, 21)])  # identifiable from 4 poses
    assert np.all(np.isfinite(path))
    assert np.all(np.diff(path) > 0)


def test_d_optimal_beats_random_plans_of_the_same_size_and_exchanges_help():
    rng = np.random.default_rng(0)
    for n in (8, 15, 30):
        best = d_criterion(CANDIDATES[select_poses(CANDIDATES, n)])
        greedy = d_criterion(CANDIDATES[select_poses(CANDIDATES, n, space_filling=0, max_exchange_passes=0)])
        exchanged = d_criterion(CANDIDATES[select_poses(CANDIDATES, n, space_filling=0)])
        randoms = [d_criterion(CANDIDATES[rng.choice(len(CANDIDATES), n, replace=False)]) for _ in range(50)]
        assert best > max(randoms)
        assert exchanged >= greedy - 1e-9
    # and than the geodesic sphere's evenly spread subsets of the same size: the first 12 vertices (icosahedron)
    assert d_criterion(CANDIDATES[select_poses(CANDIDATES, 12)]) > d_criterion(gravity_directions_in_sensor(0, excluded_cap_deg=0))


def test_space_filling_term_spreads_the_poses_at_little_cost_in_d():
    pure = select_poses(CANDIDATES, 24, space_filling=0)
    spread = select_poses(CANDIDATES, 24)
    # Pure D-optimality piles poses near a few extreme directions; the space-filling term spreads them.
    assert _min_separation_deg(CANDIDATES[spread]) > 1.5 * _min_separation_deg(CANDIDATES[pure])

    def fill_distance_deg(u):  # the largest angle from a candidate direction to its nearest planned pose
        return float(np.degrees(np.arccos(np.clip((CANDIDATES @ u.T).max(axis=1), -1, 1))).max())

    assert fill_distance_deg(CANDIDATES[spread]) < 0.9 * fill_distance_deg(CANDIDATES[pure])
    # ... keeping >= 95 % of the D-efficiency (det^(1/p) ratio)
    efficiency = np.exp((d_criterion(CANDIDATES[spread]) - d_criterion(CANDIDATES[pure])) / LINEAR_MODEL_PARAMETERS)
    assert efficiency > 0.95


def test_plans_are_reproducible_for_a_seed():
    a = select_poses(CANDIDATES, 10, strategy="random", random_state=3)
    b = select_poses(CANDIDATES, 10, strategy="random", random_state=3)
    c = select_poses(CANDIDATES, 10, strategy="random", random_state=4)
    np.testing.assert_array_equal(a, b)
    assert set(a.tolist()) != set(c.tolist())
    np.testing.assert_array_equal(select_poses(CANDIDATES, 10), select_poses(CANDIDATES, 10))


def _reaches(robot, plan) -> float:
    R = sensor_pose_in_base(robot, plan.q)[:, :3, :3]
    seen = np.einsum("nji,j->ni", R, [0, 0, -1.0])
    return float(np.max(np.arccos(np.clip(np.sum(seen * plan.gravity_in_sensor, axis=1), -1, 1))))


@pytest.mark.parametrize("strategy", ["d-optimal", "random"])
def test_robot_plans_are_reachable_and_short(robot, candidates, strategy):
    plan = plan_calibration_poses(robot, strategy=strategy, n_poses=10, candidates=candidates, random_state=1)
    assert plan.n_poses == 10 and plan.settings["strategy"] == strategy
    assert robot.within_limits(plan.q).all()
    assert _reaches(robot, plan) < 1.01e-6
    # the chosen directions are candidates, each once
    match = np.argmax(plan.gravity_in_sensor @ candidates.gravity_in_sensor.T, axis=1)
    assert len(set(match.tolist())) == 10
    np.testing.assert_allclose(candidates.gravity_in_sensor[match], plan.gravity_in_sensor, atol=1e-12)
    # ordered for short motions: the tour is shorter than the candidate order of the same poses
    def tour(u):
        return float(np.sum(np.arccos(np.clip(np.sum(u[1:] * u[:-1], axis=1), -1, 1))))
    assert tour(plan.gravity_in_sensor) <= tour(candidates.gravity_in_sensor[np.sort(match)]) + 1e-9
    again = plan_calibration_poses(robot, strategy=strategy, n_poses=10, candidates=candidates, random_state=1)
    np.testing.assert_allclose(again.q, plan.q)


def test_which_load_configurations(robot, candidates):
    from ftcal.robot import select_load_configurations, thesis_load_configurations

    positions = np.array([c.position_in_sensor for c in thesis_load_configurations()])
    chosen = select_load_configurations(CANDIDATES, 3)
    # the best 3 of 7 beat every other subset of 3 on the D-criterion (exhaustive check, independent of the code path)
    from itertools import combinations
    scores = {c: d_criterion(CANDIDATES, positions[list(c)]) for c in combinations(range(7), 3)}
    assert scores[tuple(chosen.tolist())] == max(scores.values())
    with pytest.raises(PlanningError, match="at least 3 configurations"):
        select_load_configurations(CANDIDATES, 2)
    plan = plan_calibration_poses(robot, strategy="d-optimal", n_poses=8, candidates=candidates, n_load_configurations=4)
    assert len(plan.settings["load_configurations"]) == 4 and plan.n_poses == 8
    np.testing.assert_allclose(plan.settings["load_positions_in_sensor_m"], positions[plan.settings["load_configurations"]])


def test_plan_bad_input_raises_planning_error(robot, candidates):
    with pytest.raises(PlanningError, match="n_poses 43 is more than the 42 reachable candidate directions"):
        plan_calibration_poses(robot, strategy="d-optimal", n_poses=43, candidates=candidates)
    with pytest.raises(ValueError, match="fewer than the 7 parameters"):
        plan_calibration_poses(robot, strategy="random", n_poses=6, candidates=candidates)
    with pytest.raises(PlanningError, match="needs n_poses"):
        plan_calibration_poses(robot, strategy="d-optimal", candidates=candidates)
    with pytest.raises(PlanningError, match="geodesic plan takes every direction"):
        plan_calibration_poses(robot, n_poses=12)
    with pytest.raises(PlanningError, match="strategy must be one of"):
        plan_calibration_poses(robot, strategy="optimal", n_poses=12)


# ------------------------------------------------------------------ which poses next
def _plan_of(robot, cands, keep) -> CalibrationPlan:
    g = cands.gravity_in_sensor[keep]
    pitch, yaw = pitch_yaw_from_gravity_in_sensor(g)
    return CalibrationPlan(q=cands.q[keep], gravity_in_sensor=g, pitch=pitch, yaw=yaw, unreachable=np.zeros((0, 3)),
                           anchor_position_in_base=cands.anchor_position_in_base, robot_name=robot.name,
                           sensor_frame=robot.sensor_frame, anchor_frame=robot.anchor_frame,
                           n_candidates=len(g))


@pytest.fixture(scope="module")
def half_sphere_dataset(robot, candidates, tmp_path_factory):
    """Only the 'tool face down' half of the sphere measured (g_z > 0.1 in the sensor frame)."""
    keep = np.flatnonzero(candidates.gravity_in_sensor[:, 2] > 0.1)
    paths = simulate_experiment(tmp_path_factory.mktemp("half"), robot=robot, plan=_plan_of(robot, candidates, keep),
                                errors="stress", random_state=0)
    return prepare_dataset(paths, robot)


@pytest.mark.parametrize("kind", ["gaussian_process", "linear"])
def test_next_poses_go_where_nothing_was_measured(robot, candidates, half_sphere_dataset, kind):
    ds = half_sphere_dataset
    model = (GaussianProcessCalibrator(random_state=0) if kind == "gaussian_process" else LinearCalibrator())
    model.fit(ds.raw, ds.wrench)
    nxt = propose_next_poses(robot, ds, model, 4, candidates=candidates)
    assert nxt.uncertainty == kind and nxt.n_poses == 4
    # the unmeasured half of the sphere is where the wrench is uncertain
    assert np.all(nxt.gravity_in_sensor[:, 2] < 0.1)
    assert robot.within_limits(nxt.q).all()
    R = sensor_pose_in_base(robot, nxt.q)[:, :3, :3]
    np.testing.assert_allclose(np.einsum("nji,j->ni", R, [0, 0, -1.0]), nxt.gravity_in_sensor, atol=1e-5)
    assert len({tuple(g) for g in nxt.gravity_in_sensor.round(9)}) == 4
    # each proposal removes some predicted variance, and together no more than there was
    assert np.all(nxt.expected_gain > 0) and nxt.expected_gain.sum() < 1
    np.testing.assert_allclose(nxt.total_variance_after, nxt.total_variance_before * (1 - nxt.expected_gain.sum()),
                               rtol=1e-6)
    # the first proposal is the most uncertain pose: its predictive std is the largest of the four
    assert nxt.predicted_std[0] == pytest.approx(nxt.predicted_std.max())


def test_next_poses_gp_uncertainty_agrees_with_predict_return_std(robot, candidates, half_sphere_dataset):
    """The covariance used for ranking is the GP's own: at a measured pose it matches predict(return_std=True)."""
    ds = half_sphere_dataset
    gp = GaussianProcessCalibrator(random_state=0).fit(ds.raw, ds.wrench)
    _, diag, noise = gp.latent_covariance(ds.raw[:5])
    _, std = gp.predict(ds.raw[:5], return_std=True)
    scaled = np.hstack([std[:, :3], gp.alpha_ * std[:, 3:]])
    np.testing.assert_allclose(diag + noise, np.sum(scaled**2, axis=1), rtol=1e-6)


def test_next_poses_bad_input(robot, candidates, half_sphere_dataset):
    ds = half_sphere_dataset
    other = LinearCalibrator().fit(np.hstack([ds.raw, ds.raw[:, :1]]), ds.wrench)  # 7 channels, dataset 6
    with pytest.raises(PlanningError, match="model reads 7 raw channels but the dataset has 6"):
        propose_next_poses(robot, ds, other, 2, candidates=candidates)
    model = LinearCalibrator().fit(ds.raw, ds.wrench)
    with pytest.raises(PlanningError, match=r"n_poses must be an integer in 1\.\.42"):
        propose_next_poses(robot, ds, model, 43, candidates=candidates)
    bare = ftcal.CalibrationDataset(raw=ds.raw, wrench=ds.wrench)
    with pytest.raises(PlanningError, match="load_positions_in_sensor"):
        propose_next_poses(robot, bare, model, 2, candidates=candidates)


# ------------------------------------------------------------------ CLI
def _error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert err and err[-1].startswith("ftcal: error: ")
    return err[-1]


def test_cli_d_optimal_plan_same_format_as_geodesic(tmp_path):
    out = tmp_path / "opt"
    assert main(["plan", "--strategy", "d-optimal", "--poses", "9", "--candidate-subdivisions", "1",
                 "--excluded-cap-deg", "0", "--out", str(out), "-q"]) == 0
    assert main(["plan", "--subdivisions", "0", "--excluded-cap-deg", "0", "--out", str(tmp_path / "geo"), "-q"]) == 0
    header = (out / "poses.csv").read_text().splitlines()[0]
    assert header == (tmp_path / "geo" / "poses.csv").read_text().splitlines()[0]
    table = np.loadtxt(out / "poses.csv", delimiter=",", skiprows=1)
    assert table.shape == (9, 1 + 7 + 3 + 2)
    meta = json.loads((out / "plan.json").read_text())
    assert meta["n_poses"] == 9 and meta["settings"]["strategy"] == "d-optimal"
    assert (out / "coverage.png").stat().st_size > 0


def test_cli_plan_bad_input_one_line(tmp_path, capsys):
    base = ["plan", "--candidate-subdivisions", "1", "--excluded-cap-deg", "0", "-q"]
    assert main([*base, "--strategy", "random", "--poses", "50", "--out", str(tmp_path / "a")]) == 2
    assert "--poses 50 is more than the 42 reachable candidate directions" in _error_line(capsys)
    assert main([*base, "--strategy", "d-optimal", "--poses", "5", "--out", str(tmp_path / "b")]) == 2
    assert "fewer than the 7 parameters" in _error_line(capsys)
    assert main([*base, "--poses", "20", "--out", str(tmp_path / "c")]) == 2
    assert "--strategy d-optimal or random" in _error_line(capsys)
    assert main([*base, "--next", "3", "--out", str(tmp_path / "d")]) == 2
    assert "--next needs --dataset and --model" in _error_line(capsys)
    assert not any((tmp_path / x).exists() for x in "abcd")


def test_cli_next_writes_proposals_and_refuses_mismatched_model(tmp_path, capsys, half_sphere_dataset):
    ds = half_sphere_dataset
    ds.save(tmp_path / "data.csv")
    ftcal.save_model(LinearCalibrator().fit(ds.raw, ds.wrench), tmp_path / "m.model.npz")
    out = tmp_path / "next"
    assert main(["plan", "--next", "3", "--dataset", str(tmp_path / "data.csv"), "--model",
                 str(tmp_path / "m.model.npz"), "--candidate-subdivisions", "1", "--excluded-cap-deg", "0",
                 "--out", str(out), "-q"]) == 0
    table = np.loadtxt(out / "poses.csv", delimiter=",", skiprows=1)
    assert table.shape == (3, 13) and np.all(table[:, 10] < 0.1)  # g_z: the unmeasured half
    meta = json.loads((out / "plan.json").read_text())
    assert meta["uncertainty"] == "linear" and len(meta["expected_gain"]) == 3
    ftcal.save_model(LinearCalibrator().fit(np.hstack([ds.raw, ds.raw[:, :2]]), ds.wrench), tmp_path / "m8.model.npz")
    assert main(["plan", "--next", "3", "--dataset", str(tmp_path / "data.csv"), "--model",
                 str(tmp_path / "m8.model.npz"), "--candidate-subdivisions", "1", "--out", str(tmp_path / "x"), "-q"]) == 2
    assert "model reads 8 raw channels but the dataset has 6" in _error_line(capsys)


def _cli(*args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "ftcal", *map(str, args)], capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("case", ["too_many", "no_load_positions", "no_load_mass", "temperature_model",
                                  "temperature_model_of_another_sensor"])
def test_cli_next_speaks_in_the_commands_options(tmp_path, half_sphere_dataset, case):
    """plan --next: its errors name --next / --load-mass / ftcal prepare (never the API's n_poses or
    load_positions_in_sensor), and a temperature-compensated model's raw channels are counted without the
    temperature."""
    ds = half_sphere_dataset
    meta = dict(ds.meta)
    if case == "no_load_positions":
        meta.pop("load_positions_in_sensor_m")
    if case == "no_load_mass":
        meta.pop("load_mass_kg")
    CalibrationDataset(raw=ds.raw, wrench=ds.wrench, meta=meta).save(tmp_path / "data.csv")
    raw = np.hstack([ds.raw, ds.raw[:, :2]]) if case == "temperature_model_of_another_sensor" else ds.raw
    if case.startswith("temperature_model"):
        temperature = np.linspace(20.0, 30.0, len(raw))
        model = ftcal.TemperatureCompensatedCalibrator(estimator=LinearCalibrator()).fit(
            np.column_stack([raw, temperature]), ds.wrench)
    else:
        model = LinearCalibrator().fit(raw, ds.wrench)
    ftcal.save_model(model, tmp_path / "m.model.npz")
    proc = _cli("plan", "--next", "100000" if case == "too_many" else "2", "--dataset", tmp_path / "data.csv",
                "--model", tmp_path / "m.model.npz", "--candidate-subdivisions", "1", "--excluded-cap-deg", "0",
                "--out", tmp_path / "next", "-q")
    if case == "temperature_model":
        assert proc.returncode == 0, proc.stderr
        assert np.loadtxt(tmp_path / "next" / "poses.csv", delimiter=",", skiprows=1).shape[0] == 2
        return
    assert proc.returncode == 2, proc.stderr
    line = proc.stderr.strip().splitlines()[-1]
    assert line.startswith("ftcal: error: ") and len(proc.stderr.strip().splitlines()) == 1
    expected = {
        "too_many": ["--next must be an integer in 1..", "got 100000", "--candidate-subdivisions"],
        "no_load_positions": ["load_positions_in_sensor_m", "ftcal prepare"],
        "no_load_mass": ["load_mass_kg", "Fix: pass --load-mass KG"],
        "temperature_model_of_another_sensor": ["reads 8 raw channels and the temperature but the dataset has 6"],
    }[case]
    for text in expected:
        assert text in line, line
    for api_name in ("n_poses", "load_positions_in_sensor ", "load_positions_in_sensor to", "candidate_subdivisions",
                     "load_mass (", "propose_next_poses"):
        assert api_name not in line, line
    assert not (tmp_path / "next").exists()
