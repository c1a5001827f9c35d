"""Scale-out: the artificial benchmark and the search on a real Dask LocalCluster; bad scheduler addresses."""

from __future__ import annotations

import json

import pytest

from ftcal.cli._scale_out import SchedulerError, dask_backend
from ftcal.cli import main


def test_quick_benchmark_runs_on_a_local_cluster(tmp_path, capsys):
    out = tmp_path / "bench"
    argv = ["benchmark", "artificial", "--quick", "--n-datasets", "2", "--preset", "thesis", "--model", "linear",
            "--model", "polynomial", "--scheduler", "local", "--out", str(out), "-q"]
    assert main(argv) == 0, capsys.readouterr().err
    results = json.loads((out / "artificial_results.json").read_text())
    text = json.dumps(results)
    assert "linear" in text and "polynomial" in text
    assert len(list((out / "cache").rglob("*.json"))) == 4  # 2 datasets x 2 models, written by this process


def test_an_unreachable_scheduler_is_a_clear_error_within_seconds(capsys):
    # a 2 s connection timeout: the call returns with the error instead of waiting for a scheduler forever
    with pytest.raises(SchedulerError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:9"):
        with dask_backend("tcp://127.0.0.1:9", timeout_s=2.0):
            pass
    assert main(["benchmark", "artificial", "--quick", "--scheduler", "not an address", "--out", "x"]) == 2
    assert "is not 'local' nor a scheduler address" in capsys.readouterr().err
