"""Your fixture: load configurations from a small file for ``ftcal simulate experiment`` and
``ftcal prepare``; the thesis' fixture the named default; bad fixture files one clear line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ftcal import CalibrationDataset
from ftcal.cli import main
from ftcal.robot._loads import read_load_configurations, reference_wrench

FIXTURE_CSV = """id,name,mass_kg,com_x_m,com_y_m,com_z_m,ixx,iyy,izz,ixy,ixz,iyz
0,plate,1.5,0.10,0.0,0.05,0.01,0.01,0.02,0,0,0
1,arm,3.0,0.0,0.15,0.05,,,,,,
2,low,2.0,-0.1,-0.05,0.02,,,,,,
"""


def test_simulate_and_prepare_with_your_fixture(tmp_path, capsys):
    (tmp_path / "fixture.csv").write_text(FIXTURE_CSV)
    assert main(["simulate", "experiment", "--subdivisions", "0", "--fixture", str(tmp_path / "fixture.csv"),
                 "--preset", "none", "--out", str(tmp_path / "logs")]) == 0
    assert sorted(p.name for p in (tmp_path / "logs").glob("*_load.csv")) == [
        "config0_load.csv", "config1_load.csv", "config2_load.csv"]
    assert main(["prepare", str(tmp_path / "logs"), "--fixture", str(tmp_path / "fixture.csv"), "--out",
                 str(tmp_path / "data")]) == 0
    err = capsys.readouterr().err
    assert err.count("fixture: " + str(tmp_path / "fixture.csv") + " (3 load configurations") == 2
    data = CalibrationDataset.load(tmp_path / "data" / "dataset.csv")
    # each configuration's weight is its own mass times g (eq. 15), its torque r x F with its own centre of mass
    configs = {c.config_id: c for c in read_load_configurations(tmp_path / "fixture.csv")}
    for g, c in configs.items():
        w = data.wrench[data.group == g]
        np.testing.assert_allclose(np.linalg.norm(w[:, :3], axis=1), c.mass_kg * 9.80665, rtol=1e-9)
        np.testing.assert_allclose(w[:, 3:], np.cross(c.position_in_sensor, w[:, :3]), atol=1e-9)
    assert configs[0].inertia_kg_m2 == (0.01, 0.01, 0.02, 0.0, 0.0, 0.0) and configs[1].inertia_kg_m2 is None
    facts = json.loads((tmp_path / "data" / "prepare.json").read_text())
    assert "fixture.csv" in facts["fixture"]


def test_the_thesis_fixture_is_named_and_an_unknown_configuration_points_to_fixture(tmp_path, capsys):
    (tmp_path / "fixture.json").write_text(json.dumps(
        {"configurations": [{"id": 9, "mass_kg": 2.0, "center_of_mass_m": [0.1, 0, 0.05]}]}))
    assert main(["simulate", "experiment", "--subdivisions", "0", "--fixture", str(tmp_path / "fixture.json"),
                 "--out", str(tmp_path / "logs"), "-q"]) == 0
    code = main(["prepare", str(tmp_path / "logs"), "--out", str(tmp_path / "data")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and "fixture: the thesis' fixture (7 load configurations" in err[-2]
    assert err[-1].startswith("ftcal: error:") and "--fixture FILE" in err[-1] and "configuration 9" in err[-1]


@pytest.mark.parametrize("body, message", [
    ("id,name,mass_kg,com_x_m,com_y_m,com_z_m\n0,a,-1.0,0.1,0,0\n", "line 2: mass_kg must be a positive mass"),
    ("id,name,mass_kg,com_x_m,com_y_m,com_z_m\n0,a,1.0,186,0,79\n", "give it in metres"),
    ("id,name,mass_kg,com_x_m,com_y_m,com_z_m\n0,a,1.0,0.1,0,0\n0,b,1.0,0.1,0,0\n", "id 0 appears 2 times"),
    ("id,name,mass_kg,x,y,z\n0,a,1.0,0.1,0,0\n", "line 1: the header lacks"),
])
def test_bad_fixture_file_is_one_line(tmp_path, capsys, body, message):
    (tmp_path / "fixture.csv").write_text(body)
    code = main(["simulate", "experiment", "--subdivisions", "0", "--fixture", str(tmp_path / "fixture.csv"),
                 "--out", str(tmp_path / "logs")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and err.startswith("ftcal: error:") and message in err, err
    assert not (tmp_path / "logs").exists()


def test_reference_wrench_is_linear_in_the_mass():
    """prepare scales a unit-mass wrench per row: the physics it relies on."""
    R = np.eye(3)
    np.testing.assert_allclose(reference_wrench(R, 2.5, [0.1, 0.2, 0.3]), 2.5 * reference_wrench(R, 1.0, [0.1, 0.2, 0.3]))


def test_a_fixture_mass_that_contradicts_the_logs_is_refused(tmp_path, capsys):
    """Logs recorded with 2 kg, prepared with a fixture stating 1.5 / 3 / 2 kg: which is right? Never silent."""
    (tmp_path / "fixture.csv").write_text(FIXTURE_CSV)
    assert main(["simulate", "experiment", "--subdivisions", "0", "--preset", "none", "--mass", "2.0",
                 "--out", str(tmp_path / "logs"), "-q"]) == 0
    code = main(["prepare", str(tmp_path / "logs"), "--fixture", str(tmp_path / "fixture.csv"), "--out",
                 str(tmp_path / "data"), "-q"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert "load_mass_kg 2" in err and "configuration 0 a mass of 1.5 kg" in err
