"""``predict --range`` given a pipe (a shell's ``<(cat report.json)``) or a directory says what it is, not "no such
file"."""

from __future__ import annotations

import os

import numpy as np

from ftcal import LinearCalibrator, save_model
from ftcal.cli import main


def test_range_from_a_pipe_or_a_folder_is_named_as_such(tmp_path, capsys):
    rng = np.random.default_rng(0)
    w = rng.normal(size=(60, 6))
    raw = w @ rng.normal(size=(6, 6))
    model = save_model(LinearCalibrator().fit(raw, w), tmp_path / "m.model.npz")
    readings = tmp_path / "r.csv"
    readings.write_text("".join(",".join(f"{v:.6f}" for v in row) + "\n" for row in raw[:3]))
    pipe = tmp_path / "report.pipe"
    os.mkfifo(pipe)
    for given, said in ((pipe, "is a named pipe, not a regular file; save the data to a file first"),
                        (tmp_path, "is a directory, not a file")):
        assert main(["predict", str(model), str(readings), "--range", str(given)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"--range {given} {said}" in err[0], err
