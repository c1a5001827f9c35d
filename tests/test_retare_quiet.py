"""Re-tare readings must be quiet: the one rule (``check_quiet``) for a model's raw readings and a tool's wrenches.

Readings taken while something loads the sensor (a hand, a collision, a tool still mounted and moving) would give
a wrong zero; the tool re-tare refuses them as the model re-tare does, and writes nothing.
"""

from __future__ import annotations

import numpy as np
import pytest

from ftcal import LinearCalibrator
from ftcal.cli import main
from ftcal.core import CalibrationInputError
from ftcal.experiment import ToolLoad

BIAS = np.array([1.0, -2.0, 0.5, 0.01, -0.02, 0.03])


def _tool(tmp_path):
    tool = ToolLoad(mass=1.2, center_of_mass=np.array([0.0, 0.0, 0.08]), bias=BIAS,
                    residual_rms=np.array([0.2, 0.01]))
    return tool.save(tmp_path / "gripper.tool.json")


def _readings(path, wrench):
    path.write_text("Fx,Fy,Fz,Tx,Ty,Tz\n" + "".join(",".join(f"{v:.6f}" for v in row) + "\n" for row in wrench))
    return path


def test_a_tool_retare_from_loaded_readings_is_refused_and_writes_nothing(tmp_path, capsys):
    rng = np.random.default_rng(0)
    quiet = BIAS + np.array([0.3, 0, 0, 0, 0, 0]) + rng.normal(0.0, [0.2, 0.2, 0.2, 0.01, 0.01, 0.01], (40, 6))
    loaded = quiet.copy()
    loaded[:, 1] += 900.0 * np.sin(np.linspace(0.0, 6.0, 40))  # pushed on, +-900 N in Fy
    tool = _tool(tmp_path)
    out = tmp_path / "new.tool.json"
    assert main(["retare", str(tool), str(_readings(tmp_path / "loaded.csv", loaded)), "--tool-off", "-q",
                 "--time", "0", "--output", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "wrenches is not quiet: Fy varies by" in err[0] and "residual RMS" in err[0], err
    assert not out.exists()
    assert main(["retare", str(tool), str(_readings(tmp_path / "quiet.csv", quiet)), "--tool-off", "-q",
                 "--output", str(out)]) == 0
    new = ToolLoad.load(out)
    np.testing.assert_allclose(new.bias, quiet.mean(axis=0), atol=1e-6)  # the file holds 6 decimals
    # a looser --max-spread is the user's call, and is honoured
    assert main(["retare", str(tool), str(tmp_path / "loaded.csv"), "--tool-off", "-q", "--max-spread", "1e5",
                 "--output", str(tmp_path / "loose.tool.json")]) == 0


def test_model_and_tool_retares_refuse_with_the_same_rule():
    rng = np.random.default_rng(1)
    wrench = rng.normal(size=(200, 6))
    raw = wrench @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(200, 6))
    model = LinearCalibrator().fit(raw, wrench)
    moving = np.zeros((20, 6)) + 0.01 * rng.normal(size=(20, 6))
    moving[:, 2] += np.linspace(-5.0, 5.0, 20)
    with pytest.raises(CalibrationInputError, match="X_no_load is not quiet: channel s2 varies by .* more than 5 "
                                                    "times the noise of the training data"):
        model.retare(moving)
    tool = ToolLoad(mass=1.0, center_of_mass=np.zeros(3), bias=np.zeros(6), residual_rms=np.array([0.01, 0.001]))
    with pytest.raises(CalibrationInputError, match="wrenches is not quiet: Fz varies by .* more than 5 times the "
                                                    "residual RMS"):
        tool.retare(moving)
    assert np.allclose(tool.retare(moving, max_spread=1e4).bias, moving.mean(axis=0))
