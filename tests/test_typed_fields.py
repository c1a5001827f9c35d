"""Typed fields of what a user writes: a bool is no number, a huge integer gets ftcal's message, an ambient
temperature lies in an ambient range (kelvin written as °C refused, with the conversion), NaN refused."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ftcal.cli import main
from ftcal.core import CalibrationInputError
from ftcal.experiment import ToolLoad
from ftcal.reporting._calibration_report import check_conditions


def _tool_file(tmp_path, **changes):
    path = ToolLoad(mass=1.2, center_of_mass=np.array([0.0, 0.0, 0.08]), bias=np.zeros(6)).save(
        tmp_path / "t.tool.json")
    record = json.loads(path.read_text())
    record.update(changes)
    path.write_text(json.dumps(record) if "huge" not in changes else
                    json.dumps(record).replace('"huge": 1', '"mass_kg": ' + "9" * 400))
    return path


@pytest.mark.parametrize("changes, said", [
    ({"mass_kg": True}, "mass_kg must be a number; got true (a bool)"),
    ({"mass_kg": "1.2"}, "mass_kg must be a number; got '1.2'"),
    ({"bias": [0, 0, False, 0, 0, 0]}, "bias must be a number; got false (a bool)"),
    ({"center_of_mass_m": [0, 0]}, "center_of_mass_m must be 3 numbers; got [0, 0]"),
    ({"mass_kg": None, "huge": 1}, "mass_kg must be a number a float holds; got an integer of 400 digits"),
])
def test_a_tampered_tool_file_is_refused_naming_the_field_and_the_file(tmp_path, capsys, changes, said):
    path = _tool_file(tmp_path, **changes)
    with pytest.raises(CalibrationInputError) as info:
        ToolLoad.load(path)
    assert str(info.value) == f"{path}: {said}." or str(info.value).startswith(f"{path}: {said}"), str(info.value)
    readings = tmp_path / "r.csv"
    readings.write_text("Fx,Fy,Fz,Tx,Ty,Tz\n0,0,0,0,0,0\n")
    assert main(["retare", str(path), str(readings), "--tool-off", "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and said in err[0] and "Traceback" not in err[0], err


@pytest.mark.parametrize("given, said", [
    (296, "ambient_temperature 296 °C is not an ambient temperature (-60 to 80 °C); if it is in kelvin (22.85 °C), "
          "write '296 K'"),
    ("nan", "ambient_temperature must be a finite temperature"),
    (float("nan"), "must be a finite number"),
    (True, "must be text or a number; got bool True"),
    ("warm", "ambient_temperature 'warm' is not a temperature"),
])
def test_conditions_refuse_an_unphysical_or_untyped_temperature(given, said):
    with pytest.raises(CalibrationInputError, match=None) as info:
        check_conditions({"ambient_temperature": given})
    assert said in str(info.value), str(info.value)


def test_conditions_read_a_temperature_in_its_unit_as_celsius():
    assert check_conditions({"ambient_temperature": "296 K"})["ambient_temperature"] == "22.85 °C"
    assert check_conditions({"ambient_temperature": "71.6 °F"})["ambient_temperature"] == "22 °C"
    assert check_conditions({"ambient_temperature": 22.5})["ambient_temperature"] == "22.5 °C"
    assert check_conditions({"ambient_temperature": "22.5 °C"})["ambient_temperature"] == "22.5 °C"
    with pytest.raises(CalibrationInputError, match="must be text or a number; got bool"):
        check_conditions({"operator": False})
