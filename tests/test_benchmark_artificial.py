"""The artificial benchmark: statistics by hand, resumable cache, output safety, smoke run."""

from __future__ import annotations

import hashlib
import importlib.util
import json
import math
import os
import re
from pathlib import Path

import joblib
import numpy as np
import pytest
import sklearn

from ftcal.core import BenchmarkOutputExistsError, CalibrationInputError
from ftcal.simulation import ErrorModel
from ftcal.benchmark import run_artificial_benchmark
from ftcal.benchmark import OutputFiles
from ftcal.benchmark._artificial import summarize_results, wilcoxon_pvalue

ROOT = Path(__file__).resolve().parents[1]


def records(rmse_by_model: dict, preset="p"):
    return [
        dict(preset=preset, dataset=i, model=m, rmse=r, rel_force_mean=r / 100, rel_torque_mean=r / 200,
             noise_floor=1.0 + i)
        for m, values in rmse_by_model.items() for i, r in enumerate(values)
    ]


def test_summary_against_hand_computed_values():
    s = summarize_results(records({"a": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0], "b": [2.0, 3.0, 4.0, 5.0, 6.0, 7.5]}), ["a", "b"], ["p"])["p"]
    a = s["models"]["a"]
    assert a["rmse"]["mean"] == 3.5
    assert a["rmse"]["std"] == pytest.approx(math.sqrt(17.5 / 5))  # sample std: sum of squares 17.5, n-1 = 5
    assert a["rel_force"]["mean"] == pytest.approx(0.035) and a["rel_torque"]["mean"] == pytest.approx(0.0175)
    assert s["noise_floor"]["mean"] == 3.5 and s["noise_floor"]["n"] == 6
    # b > a in all 6 pairs: exact two-sided p = 2 / 2**6
    w = s["wilcoxon"]["a vs b"]
    assert w["p"] == pytest.approx(2 / 64) and w["n"] == 6 and w["note"] == ""


def test_wilcoxon_edge_cases_give_nan_with_a_note():
    p, note = wilcoxon_pvalue([1, 2, 3], [2, 3, 4])
    assert math.isnan(p) and "only 3 paired datasets" in note
    p, note = wilcoxon_pvalue([1.0] * 8, [1.0] * 8)
    assert math.isnan(p) and "all paired differences are zero" in note
    s = summarize_results(records({"a": [1.0], "b": []}), ["a", "b"], ["p"])["p"]
    assert s["models"]["b"]["n_datasets"] == 0 and math.isnan(s["models"]["b"]["rmse"]["mean"])
    assert s["models"]["a"]["rmse"]["std"] == 0.0 and math.isnan(s["wilcoxon"]["a vs b"]["p"])


def test_quick_smoke_run_writes_outputs_and_resumes_from_cache(tmp_path):
    done = []
    first = run_artificial_benchmark(quick=True, out_dir=tmp_path, progress=lambda d, t, r: done.append((d, t)))
    meta = first["meta"]
    assert meta["n_expected"] == meta["n_complete"] == meta["n_computed"] == 9  # 3 datasets x 3 models
    assert done[-1] == (9, 9)
    for key in ("json", "markdown", "png_thesis"):
        assert Path(first["files"][key]).stat().st_size > 0
    saved = json.loads((tmp_path / "artificial_results.json").read_text())
    table = saved["summary"]["thesis"]
    assert set(table["models"]) == {"linear", "comparative", "directional"}
    floor = table["noise_floor"]["mean"]
    assert 2.0 < floor < 10.0
    assert table["models"]["linear"]["rmse"]["mean"] > 0.9 * floor  # nobody beats the noise floor
    assert "| linear | 3 |" in (tmp_path / "artificial_results.md").read_text()
    assert len(list((tmp_path / "cache" / "thesis").glob("*.json"))) == 9
    again = run_artificial_benchmark(quick=True, out_dir=tmp_path)
    assert again["meta"]["n_from_cache"] == 9 and again["meta"]["n_computed"] == 0
    assert json.dumps(again["summary"], sort_keys=True) == json.dumps(first["summary"], sort_keys=True)


def test_ensemble_records_keep_every_members_rmse(tmp_path):
    res = run_artificial_benchmark(quick=True, n_datasets=1, models=("directional_ensemble", "linear"),
                                   out_dir=tmp_path, plot=False)
    by_model = {r["model"]: r for r in res["results"]}
    members = by_model["directional_ensemble"]["member_rmse"]
    assert len(members) == 5 and len(set(members)) == 5  # five seeds, five different networks
    # the RMSE is a norm of the error: the mean prediction's RMSE is at most the members' mean RMSE (convexity)
    assert by_model["directional_ensemble"]["rmse"] <= np.mean(members)
    assert by_model["linear"]["member_rmse"] is None


def test_other_configuration_is_not_mixed_in_and_parallel_backend_is_pluggable(tmp_path):
    kw = dict(quick=True, models=("linear",), presets=("thesis", "stress"), plot=False)
    serial = run_artificial_benchmark(out_dir=tmp_path / "s", seed=0, **kw)
    other_seed = run_artificial_benchmark(out_dir=tmp_path / "s", seed=1, **kw)
    assert other_seed["meta"]["n_from_cache"] == 0 and other_seed["meta"]["n_computed"] == 6
    with joblib.parallel_config(backend="threading"):
        threaded = run_artificial_benchmark(out_dir=tmp_path / "t", seed=0, n_jobs=2, **kw)
    assert json.dumps(threaded["summary"], sort_keys=True) == json.dumps(serial["summary"], sort_keys=True)
    stress, thesis = serial["summary"]["stress"]["models"]["linear"], serial["summary"]["thesis"]["models"]["linear"]
    assert stress["rmse"]["mean"] > 1.5 * thesis["rmse"]["mean"]  # strong nonlinearity hurts the LTM


def test_user_files_are_never_overwritten_without_force(tmp_path):
    mine = tmp_path / "artificial_results.md"
    mine.write_text("my notes")
    with pytest.raises(BenchmarkOutputExistsError, match="artificial_results.md exists.*force"):
        run_artificial_benchmark(out_dir=tmp_path, compute=False)
    assert mine.read_text() == "my notes"
    result = run_artificial_benchmark(out_dir=tmp_path, compute=False, force=True)
    assert result["meta"]["n_complete"] == 0 and mine.read_text() != "my notes"
    run_artificial_benchmark(out_dir=tmp_path, compute=False)  # its own, unchanged file: rewritten freely


@pytest.mark.parametrize(
    "kwargs, words",
    [
        (dict(models=("linear", "svm")), "unknown models"),
        (dict(presets=("thesis", "bogus")), "unknown error preset"),
        (dict(schedule="long"), "unknown schedule"),
        (dict(n_datasets=0), r"'n_datasets' parameter of run_artificial_benchmark must be an int in the range \[1, "
                             r"1000\]\. Got 0"),
        (dict(n_datasets=True), "'n_datasets' .* must be a number, not a bool"),
        (dict(n_datasets=2.5), "'n_datasets' .* Got 2.5"),
        (dict(seed=-1), "'seed' .* Got -1"),
        (dict(n_jobs=0), "'n_jobs' .* Got 0"),
        (dict(n_per_sphere=2.5), "'n_per_sphere' .* Got 2.5"),
        (dict(n_test=10**9), r"'n_test' .* \[1, 1000000\] or None\. Got 1000000000"),
        (dict(test_distribution="cube"), "'test_distribution' .* Got 'cube'"),
        (dict(n_spheres=5), r"'n_spheres' .* \[1, 4\]\. Got 5"),
        (dict(force="no"), r"force must be True or False; got 'no' \(str\)"),  # "no" is truthy: it overwrote
        (dict(compute="no"), "compute must be True or False"),
        (dict(progress=3), "progress must be a function"),
        (dict(presets=[]), "presets is empty"),
        (dict(presets=None), r"presets must be a list of names, e.g. \('thesis',\); got None"),
        (dict(models=None), "models must be a list of names"),
        (dict(presets={"../escape": ErrorModel()}), r"a preset name must be a plain name.*got '\.\./escape'"),
        (dict(presets={"/tmp/abs": ErrorModel()}), "a preset name must be a plain name"),
    ],
)
def test_bad_arguments_are_rejected_before_any_work(tmp_path, kwargs, words):
    with pytest.raises(CalibrationInputError, match=words):
        run_artificial_benchmark(out_dir=tmp_path, **kwargs)
    assert not (tmp_path / "cache").exists()


@pytest.mark.parametrize("out_dir", ["", None, 3])
def test_an_empty_or_non_path_out_dir_is_refused_not_the_working_directory(out_dir, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(CalibrationInputError, match="out_dir must be a folder path"):
        run_artificial_benchmark(out_dir=out_dir, quick=True, models="linear", plot=False)
    assert list(tmp_path.iterdir()) == []


def test_one_name_is_a_list_of_one_not_its_letters(tmp_path):
    result = run_artificial_benchmark(n_datasets=1, presets="thesis", models="linear", quick=True, plot=False,
                                      out_dir=tmp_path)
    assert result["meta"]["presets"] == ["thesis"] and result["meta"]["models"] == ["linear"]
    assert result["meta"]["n_complete"] == 1


@pytest.mark.parametrize("content", [b"[1, 2]", b"42", b"null", b"NaN", b"\xff\xfe", b"[" * 100_000, b"{}",
                                     b'{"rmse": 1'])
def test_a_cache_file_that_is_not_a_record_is_recomputed(tmp_path, content):
    first = run_artificial_benchmark(n_datasets=1, models="linear", quick=True, plot=False, out_dir=tmp_path)
    cached = next((tmp_path / "cache").rglob("*.json"))
    cached.write_bytes(content)
    again = run_artificial_benchmark(n_datasets=1, models="linear", quick=True, plot=False, out_dir=tmp_path)
    assert again["meta"]["n_computed"] == 1 and again["results"][0]["rmse"] == first["results"][0]["rmse"]
    assert json.loads(cached.read_text())["rmse"] == first["results"][0]["rmse"]  # rewritten whole


@pytest.mark.parametrize("change", [dict(rmse=float("nan")), dict(rmse="abc"), dict(rmse=None), dict(model="x")])
def test_a_tampered_record_is_recomputed_not_hidden_from_the_table(tmp_path, change):
    first = run_artificial_benchmark(n_datasets=1, models="linear", quick=True, plot=False, out_dir=tmp_path)
    cached = next((tmp_path / "cache").rglob("*.json"))
    cached.write_text(json.dumps({**json.loads(cached.read_text()), **change}))
    again = run_artificial_benchmark(n_datasets=1, models="linear", quick=True, plot=False, out_dir=tmp_path)
    assert again["meta"]["n_computed"] == 1 and again["results"][0]["rmse"] == first["results"][0]["rmse"]


@pytest.mark.parametrize("bad, words", [
    ([1 + 2j], "of dtype complex128"), (np.array(["1.5"]), "of dtype <U3"), ([None, 1.0], "of dtype object"),
    (np.ma.array([1.0, 2.0], mask=[True, False]), "a masked array"), ([[1.0, 2.0], [3.0]], "not a rectangular array"),
])
def test_data_fingerprint_refuses_what_is_not_an_array_of_real_numbers(bad, words):
    from ftcal.benchmark import data_fingerprint

    with pytest.raises(CalibrationInputError, match=f"data_fingerprint: argument 1 is {re.escape(words)}"):
        data_fingerprint(np.zeros(3), bad)


def test_data_fingerprint_tells_values_shapes_and_order_apart():
    from ftcal.benchmark import data_fingerprint

    a = np.arange(12.0).reshape(3, 4)
    same = [data_fingerprint(a), data_fingerprint(a.copy(order="F")), data_fingerprint(a.astype(np.float32)),
            data_fingerprint(a.astype(int))]  # the values as float64: layout and dtype do not count
    other = [data_fingerprint(a.reshape(4, 3)), data_fingerprint(a.T), data_fingerprint(np.nextafter(a, 99)),
             data_fingerprint(a[:2], a[2:]), data_fingerprint(a[:1], a[1:]), data_fingerprint(a, [])]
    assert len(set(same)) == 1 and len({same[0], *other}) == 1 + len(other)


def test_sensor_maker_aggregates_only_predictions_of_the_current_data_and_never_fits_then(tmp_path, capsys):
    sm = _script("sensor_maker")
    argv = ["--presets", "thesis", "--datasets", "1", "--models", "linear", "--out", str(tmp_path)]
    assert sm.main(argv) == 0
    assert "fitted" in capsys.readouterr().out
    assert sm.main([*argv, "--aggregate-only", "--force"]) == 0  # its own cached prediction: used, nothing fitted
    assert "fitted" not in capsys.readouterr().out
    cached, = (tmp_path / "cache").glob("*.npz")
    cached.rename(cached.with_name("thesis_ds000_linear_0123456789ab.npz"))  # another key: other data, older code
    capsys.readouterr()
    with pytest.raises(SystemExit) as stop:
        sm.main([*argv, "--aggregate-only"])
    assert stop.value.code == 2 and "nothing to aggregate" in capsys.readouterr().err
    assert [p.name for p in (tmp_path / "cache").glob("*.npz")] == ["thesis_ds000_linear_0123456789ab.npz"]


def test_a_record_of_other_data_is_recomputed_and_one_from_before_fingerprints_is_checked_by_its_floor(tmp_path):
    """The data a record was computed on is part of its key: a fingerprint, or (older records) the noise floor."""
    first = run_artificial_benchmark(n_datasets=1, models="linear", quick=True, plot=False, out_dir=tmp_path)
    cached = next((tmp_path / "cache").rglob("*.json"))
    record = json.loads(cached.read_text())
    assert len(record["data"]) == 16 and record["versions"]["scikit-learn"] == sklearn.__version__
    legacy = {k: v for k, v in record.items() if k != "data"}
    for stale, computed in ((dict(record, data="f" * 16), 1), (legacy, 0), (dict(record, noise_floor=0.0), 1),
                            (dict(legacy, noise_floor=record["noise_floor"] * (1 + 1e-9)), 1)):
        cached.write_text(json.dumps(stale))
        again = run_artificial_benchmark(n_datasets=1, models="linear", quick=True, plot=False, out_dir=tmp_path)
        assert again["meta"]["n_computed"] == computed and again["results"][0]["rmse"] == first["results"][0]["rmse"]


def test_an_unreadable_manifest_is_named_and_a_folder_in_the_way_is_refused(tmp_path):
    run_artificial_benchmark(n_datasets=1, models="linear", quick=True, plot=False, out_dir=tmp_path)
    (tmp_path / ".ftcal-benchmark-manifest.json").write_text("[1, 2]")
    with pytest.raises(BenchmarkOutputExistsError, match="was not written by this benchmark.*manifest.*unreadable"):
        run_artificial_benchmark(n_datasets=1, models="linear", quick=True, plot=False, out_dir=tmp_path)
    other = tmp_path / "other"
    (other / "artificial_results.json").mkdir(parents=True)
    with pytest.raises(BenchmarkOutputExistsError, match="is a folder, where this benchmark writes a file"):
        run_artificial_benchmark(n_datasets=1, models="linear", quick=True, plot=False, out_dir=other, force=True)
    assert not (other / "cache").exists() and not (other / "artificial_results.md").exists()  # before any work


def test_output_files_keep_a_file_that_appeared_during_the_run(tmp_path):
    files = OutputFiles(tmp_path)
    files.check(["table.md"])
    (tmp_path / "table.md").write_text("written by someone else meanwhile")
    with pytest.raises(BenchmarkOutputExistsError, match="appeared while this run was working"):
        files.write_text("table.md", "ours")
    assert (tmp_path / "table.md").read_text() == "written by someone else meanwhile"
    assert [p.read_text() for p in tmp_path.glob("table.*.md")] == ["ours"]  # kept beside it, not lost
    files.write_text("plot.md", "v1")
    assert OutputFiles(tmp_path).write_text("plot.md", "v2").read_text() == "v2"  # its own: rewritten
    assert not list(tmp_path.glob("*.partial*"))


def _load_script():
    return _script("artificial")


def test_command_line_wrapper(tmp_path, capsys):
    module = _load_script()
    out = tmp_path / "cli"
    assert module.main(["--quick", "--models", "linear", "--no-plot", "--out", str(out)]) == 0
    assert "3/3 results" in capsys.readouterr().out
    (out / "artificial_results.md").write_text("edited by hand")
    assert module.main(["--quick", "--models", "linear", "--no-plot", "--out", str(out)]) == 2
    assert "--force" in capsys.readouterr().err
    assert (out / "artificial_results.md").read_text() == "edited by hand"


def test_stock_baselines_sit_beside_the_calibrators_and_presets_bring_their_test_loads(tmp_path):
    res = run_artificial_benchmark(quick=True, n_datasets=1, presets=("reconstructed", "thesis"),
                                   models=("linear", "sk_linear"), out_dir=tmp_path, plot=False)
    assert res["meta"]["test_distributions"] == {"reconstructed": "ball", "thesis": "radial"}
    table = res["summary"]["reconstructed"]["models"]
    # the same estimator (unregularised affine least squares) on the same data: the same error
    assert table["sk_linear"]["rmse"]["mean"] == pytest.approx(table["linear"]["rmse"]["mean"], rel=1e-6)
    md = (tmp_path / "artificial_results.md").read_text()
    assert "| sk_linear | 1 |" in md and "Test loads: `ball`" in md
    assert "62.3" in md.split("### Preset `thesis`")[0]  # the thesis' Table II beside `reconstructed`


def test_custom_error_models_by_name_and_fewer_spheres(tmp_path):
    from ftcal.simulation import ErrorModel

    presets = {"clean": ErrorModel(), "gain10": ErrorModel(asymmetry=0.1, asymmetry_axes=6)}
    res = run_artificial_benchmark(quick=True, n_datasets=1, presets=presets, models=("linear",), out_dir=tmp_path,
                                   plot=False, n_spheres=1, test_distribution="ball")
    rmse = {p: res["summary"][p]["models"]["linear"]["rmse"]["mean"] for p in presets}
    assert rmse["clean"] < 1e-6 < rmse["gain10"]  # no errors: the LTM is exact; a sign-dependent gain it cannot fit
    assert res["results"][0]["config"]["n_spheres"] == 1
    with pytest.raises(CalibrationInputError, match="ErrorModel"):
        run_artificial_benchmark(presets={"x": "thesis"}, out_dir=tmp_path / "bad")


def test_command_lines_add_the_stock_baselines_unless_only_named_models_are_asked_for():
    import argparse

    from ftcal.cli._benchmark import _artificial_models
    from ftcal.calibrators import STOCK_BASELINE_NAMES

    def models(names, baselines):
        return _artificial_models(argparse.Namespace(models=names, baselines=baselines))

    assert models(None, None) == ("linear", "comparative", "directional") + STOCK_BASELINE_NAMES
    assert models(["linear"], None) == ("linear",)
    assert models(["linear"], True) == ("linear",) + STOCK_BASELINE_NAMES
    assert models(None, False) == ("linear", "comparative", "directional")
    script = _load_script()
    assert script._models(script.build_parser().parse_args([]))[-5:] == list(STOCK_BASELINE_NAMES)
    assert script._models(script.build_parser().parse_args(["--models", "linear"])) == ["linear"]


def _script(name):
    import sys

    spec = importlib.util.spec_from_file_location(f"bench_{name}", ROOT / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def test_crossover_level_interpolates_the_first_sign_change():
    crossover = _script("crossover")
    assert crossover.crossover_level([0.0, 0.1, 0.2], [-2.0, 2.0, 5.0]) == pytest.approx(0.05)
    assert crossover.crossover_level([0.0, 0.1], [-1.0, -0.5]) is None
    assert crossover.crossover_level([0.0, 0.1], [1.0, 2.0]) == 0.0
    models = crossover.level_presets([0.0, 0.2])
    assert models["asym0.200"].asymmetry_axes == 6 and models["asym0.000"].asymmetry == 0.0


def test_learning_curve_sizes_are_the_outermost_spheres_and_the_first_points():
    from ftcal.core._wrench import scale_torques

    lc = _script("learning_curves")
    factory = lc.artificial_factory("none", spheres=(1, 2), points=(3, 7))
    assert factory.sizes == ((1, 3), (1, 7), (2, 3), (2, 7))
    pool = factory.make(0)
    rows = pool.select((2, 3))
    radius = np.linalg.norm(scale_torques(pool.y[rows], 50.0), axis=1)
    np.testing.assert_allclose(sorted(radius), [1200.0] * 3 + [1600.0] * 3)
    assert set(pool.select((1, 3))) <= set(pool.select((1, 7)))  # nested: more data adds, never swaps
    assert pool.X_test.shape == (1250, 6)


def test_learning_curves_of_the_soft_sensor_hold_out_whole_presses():
    lc = _script("learning_curves")
    train, test, info = lc.soft_split(0)
    assert not set(train.group.tolist()) & set(test.group.tolist()) and len(set(test.group.tolist())) == 8
    pool = lc.FACTORIES["soft"].make(0)
    assert pool.X.shape[1] == 8 and len(pool.X_test) == test.n_samples and info["noise_floor"] is None
    small, large = pool.select((25,)), pool.select((300,))
    assert len(small) == 25 and len(large) == 300 and set(small) <= set(large)


def _learning_curve_cache(tmp_path):
    """A quick learning-curve run of the LTM on `reconstructed` (8 sizes): its module, argv, cache files, records."""
    lc = _script("learning_curves")
    argv = ["--quick", "--datasets", "reconstructed", "--models", "linear", "--out", str(tmp_path)]
    assert lc.main(argv) == 0
    paths = sorted((tmp_path / "cache" / "reconstructed").glob("*.json"))
    return lc, argv, paths, [json.loads(p.read_text()) for p in paths]


def test_learning_curve_records_of_other_data_are_fitted_again(tmp_path, capsys):
    """A cached fit is used only for the data the current code makes (its fingerprint)."""
    lc, argv, paths, records = _learning_curve_cache(tmp_path)
    assert len(records) == 8 and all(len(r["data"]) == 16 for r in records)
    assert all(r["versions"]["numpy"] == np.__version__ and r["versions"]["ftcal"] for r in records)
    assert "Package versions recorded with 8 of the 8 records (1 distinct sets" in \
        (tmp_path / "learning_curves.md").read_text()
    paths[0].write_text(json.dumps(dict(records[0], data="0" * 16, rmse=1.0)))  # another simulator's data
    capsys.readouterr()
    assert lc.main([*argv, "--aggregate-only"]) == 0  # not used, and said so
    out = capsys.readouterr().out
    assert "1 cached records are of other data" in out and "7/8 fits complete" in out
    assert lc.main(argv) == 0
    out = capsys.readouterr().out
    assert out.count("] reconstructed (") == 1 and "[8/8]" in out  # one fit ran, the other seven came from the cache
    refit = json.loads(paths[0].read_text())
    assert refit["data"] == records[0]["data"] and refit["rmse"] == pytest.approx(records[0]["rmse"], rel=1e-9)
    paths[2].write_text(json.dumps(dict(records[2], rmse=0)))  # not a figure this script writes: fitted again
    assert lc.main(argv) == 0 and json.loads(paths[2].read_text())["rmse"] == pytest.approx(records[2]["rmse"])


def test_learning_curves_verify_replaces_what_the_current_code_does_not_reproduce(tmp_path, capsys, monkeypatch):
    lc, argv, paths, records = _learning_curve_cache(tmp_path)
    # same data, other code (a figure the current code does not reproduce); a failure the current code fits
    paths[1].write_text(json.dumps(dict(records[1], rmse=records[1]["rmse"] * 1.01)))
    paths[3].write_text(json.dumps(dict(records[3], rmse=float("nan"), error="LinAlgError: simulated")))
    assert lc.main([*argv, "--verify", "8"]) == 0
    for k in (1, 3):
        assert json.loads(paths[k].read_text())["rmse"] == pytest.approx(records[k]["rmse"], rel=1e-9)
    assert "| linear | 8 | 6 | 2 | 0 | 9.9e-03 |" in (tmp_path / "learning_curves.md").read_text()
    assert lc.main(argv) == 0  # a run without --verify keeps the last verification's report
    assert "| linear | 8 | 6 | 2 | 0 | 9.9e-03 |" in (tmp_path / "learning_curves.md").read_text()
    report = tmp_path / "cache" / "verification.json"
    kept = json.loads(report.read_text())
    for edited in ({**kept, "models": {"linear": "x"}}, {**kept, "models": {"linear": {}}}, {**kept, "tolerance": "a"},
                   {**kept, "models": {"linear": {**kept["models"]["linear"], "largest": 1e400}}},
                   {**kept, "models": {"a | b": kept["models"]["linear"]}}, {**kept, "scope": {}}):
        report.write_text(json.dumps(edited))  # an edited or another run's report is not shown, never a traceback
        assert lc.main(argv) == 0 and "Verification" not in (tmp_path / "learning_curves.md").read_text()
    # a refit that fails, or gives no finite RMSE: the cached record is kept and the refit counted as failed
    real = lc.run_unit
    monkeypatch.setattr(lc, "run_unit", lambda unit: [dict(r, rmse=float("nan")) for r in real(unit)])
    assert lc.main([*argv, "--verify", "2"]) == 0
    assert "| linear | 2 | 0 | 0 | 2 | — |" in (tmp_path / "learning_curves.md").read_text()
    assert [json.loads(p.read_text())["rmse"] for p in paths[:2]] == pytest.approx([r["rmse"] for r in records[:2]])
    with pytest.raises(SystemExit) as stop:
        lc.main([*argv, "--verify", "1", "--aggregate-only"])
    assert stop.value.code == 2 and "choose one" in capsys.readouterr().err


def test_learning_curves_verify_takes_records_per_dataset_and_failures_are_strict_json(tmp_path, capsys):
    lc = _script("learning_curves")
    argv = ["--quick", "--datasets", "reconstructed", "soft", "--models", "linear", "--out", str(tmp_path)]
    assert lc.main([*argv, "--verify", "1"]) == 0  # nothing cached yet: nothing verified, no report
    assert "Verification" not in (tmp_path / "learning_curves.md").read_text()
    assert lc.main([*argv, "--verify", "1"]) == 0  # one record of each dataset
    assert "| linear | 2 | 2 | 0 | 0 |" in (tmp_path / "learning_curves.md").read_text()
    path = sorted((tmp_path / "cache" / "soft").glob("*.json"))[0]
    path.write_text(json.dumps({**json.loads(path.read_text()), "rmse": None, "error": "LinAlgError: simulated"}))
    capsys.readouterr()
    assert lc.main([*argv, "--aggregate-only"]) == 0  # a failure is a result: shown as x, written as strict JSON
    assert "1 cached records are of other data" not in capsys.readouterr().out
    assert "| x |" in (tmp_path / "learning_curves.md").read_text()
    strict = json.loads((tmp_path / "learning_curves.json").read_text(),
                        parse_constant=lambda c: pytest.fail(f"{c} in learning_curves.json"))
    assert any(r["error"] and r["rmse"] is None for r in strict["records"])


def test_learning_curves_verify_refits_a_network_in_the_stack_it_was_trained_in(monkeypatch):
    """Refits run in the stored stack (older records: the whole grid's stack); stack members not cached yet are
    returned as new records, fitted once."""
    lc = _script("learning_curves")
    tasks = lc.make_tasks(["soft"], ["directional"], [0], "short")  # 5 sizes, one stack of 5 in a grid run
    hashes = [t["hash"] for t in tasks]
    calls = []

    def fake_run_unit(unit):
        calls.append([t["hash"] for t in unit])
        return [{**t, "n_train": t["size"][0], "rmse": 1.0, "error": None, "noise_floor": None} for t in unit]

    monkeypatch.setattr(lc, "run_unit", fake_run_unit)
    cached = [{**t, "n_train": t["size"][0], "rmse": 1.0, "error": None, "noise_floor": None} for t in tasks[:3]]
    cached[0]["stacked_with"] = hashes[:2]  # trained in a stack of the two smallest sizes
    saved = []
    _, report, new = lc.verify(cached, tasks, 1, 1, 10, saved.append)
    assert calls == [hashes[:2]] and new == [] and report["directional"]["reproduced"] == 1
    calls.clear()
    del cached[0]["stacked_with"]  # written before stacks were recorded: the grid's stack, all 5 sizes
    _, report, new = lc.verify(cached, tasks, 1, 1, 10, saved.append)
    assert calls == [hashes] and sorted(r["hash"] for r in new) == sorted(hashes[3:]) and saved == new


@pytest.mark.parametrize("script, name, argv", [
    ("crossover", "crossover.md", ["--quick", "--models", "linear"]),
    ("learning_curves", "learning_curves.json", ["--quick", "--models", "linear"]),
    ("sensor_maker", "sensor_maker_axes.png", ["--presets", "thesis", "--datasets", "1", "--models", "linear"]),
    ("departures", "departures.json", ["--datasets", "1"]),
])
def test_benchmark_scripts_never_replace_a_users_file_and_refuse_before_any_work(tmp_path, capsys, script, name, argv):
    mine = tmp_path / name
    mine.write_text("my notes")
    with pytest.raises(SystemExit) as stop:
        _script(script).main([*argv, "--out", str(tmp_path)])
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.endswith(f"{mine} exists and was not written by this benchmark (or was edited since). Fix: choose "
                        "another output folder or pass --force to overwrite it.")
    assert mine.read_text() == "my notes" and sorted(p.name for p in tmp_path.iterdir()) == [name]  # no work done


@pytest.mark.parametrize("script, argv, words", [
    ("crossover", ["--datasets", "0"], "argument --datasets: '0' is not an integer from 1 to 1000"),
    ("crossover", ["--quick", "--n-test", "5"], "--quick sets its own small sizes"),
    ("learning_curves", ["--seeds", "0"], "argument --seeds: '0' is not an integer from 1 to 100"),
    ("learning_curves", ["--quick", "--models", "nope"], "unknown models ['nope']"),
    ("learning_curves", ["--jobs", "0"], "argument --jobs: '0' is not a number of jobs from 1 to 256, or -1"),
    ("sensor_maker", ["--datasets", "0"], "argument --datasets: '0' is not an integer from 1 to 1000"),
    ("sensor_maker", ["--aggregate-only"], "nothing to aggregate"),
    ("departures", ["--datasets", "-1"], "argument --datasets: '-1' is not an integer from 1 to 1000"),
])
def test_benchmark_scripts_refuse_bad_arguments_in_one_line(tmp_path, capsys, script, argv, words):
    with pytest.raises(SystemExit) as stop:
        _script(script).main([*argv, "--out", str(tmp_path / "out")])
    assert stop.value.code == 2 and words in capsys.readouterr().err.strip().splitlines()[-1]


def test_output_files_two_runs_in_one_folder_and_links_planted_at_output_names(tmp_path):
    first, second = OutputFiles(tmp_path), OutputFiles(tmp_path)
    first.check(["table.md"])
    second.check(["table.md"])
    first.write_text("table.md", "run 1")
    assert second.write_text("table.md", "run 2").read_text() == "run 2"  # the other run's file is a benchmark's
    user = tmp_path.parent / f"{tmp_path.name}-user.txt"
    user.write_text("my notes")
    (tmp_path / "plot.md").symlink_to(tmp_path / "nowhere")  # dangling: refused before any work, not after it
    with pytest.raises(BenchmarkOutputExistsError, match=r"plot.md is a link \(a benchmark writes regular files\)"):
        OutputFiles(tmp_path).check(["plot.md"])
    (tmp_path / "notes.md").symlink_to(user)
    OutputFiles(tmp_path, force=True).write_text("notes.md", "ours")  # force replaces the link, not its target
    assert user.read_text() == "my notes" and not (tmp_path / "notes.md").is_symlink()


def test_output_files_keep_beside_never_replaces_a_file_and_a_crash_keeps_the_file_its_own(tmp_path, monkeypatch):
    files = OutputFiles(tmp_path)
    (tmp_path / "table.1.md").write_text("my other notes")
    (tmp_path / "table.md").write_text("my notes")
    with pytest.raises(BenchmarkOutputExistsError, match=r"kept as .*table\.2\.md"):
        files.write_text("table.md", "ours")
    assert (tmp_path / "table.1.md").read_text() == "my other notes" and (tmp_path / "table.md").read_text() == \
        "my notes" and (tmp_path / "table.2.md").read_text() == "ours"
    # interrupted between the rename and the final manifest update: the file is still known as the benchmark's
    real_link = os.link

    def link_then_stop(src, dst, *args, **kwargs):  # a new file goes in by a link (never over a user's file)
        real_link(src, dst, *args, **kwargs)
        if Path(dst).name == "result.md":
            raise KeyboardInterrupt

    monkeypatch.setattr(os, "link", link_then_stop)
    with pytest.raises(KeyboardInterrupt):
        files.write_text("result.md", "ours")
    monkeypatch.setattr(os, "link", real_link)
    OutputFiles(tmp_path).check(["result.md"])  # no --force needed to resume
    (tmp_path / ".ftcal-benchmark-manifest.json").unlink()
    (tmp_path / ".ftcal-benchmark-manifest.json").mkdir()
    with pytest.raises(BenchmarkOutputExistsError, match="is a folder, where this benchmark keeps its record"):
        OutputFiles(tmp_path).check([])


def test_output_files_lock_refuses_a_planted_link(tmp_path):
    outside = tmp_path / "outside"
    run = tmp_path / "run"
    run.mkdir()
    (run / ".ftcal-benchmark-manifest.json.lock").symlink_to(outside)
    with pytest.raises(OSError, match="Too many levels of symbolic links"):  # ELOOP: O_NOFOLLOW refused it
        OutputFiles(run).write_text("table.md", "ours")
    assert not outside.exists() and not (run / "table.md").exists()


def test_committed_result_manifests_match_their_files():
    """The documented commands resume without --force only if each committed manifest records the files as they
    are (a results commit that forgot the manifest shows here)."""
    manifests = sorted((ROOT / "benchmarks").rglob(".ftcal-benchmark-manifest.json"))
    assert manifests
    for manifest in manifests:
        for name, digest in json.loads(manifest.read_text()).items():
            path = manifest.parent / name
            if path.is_file():  # a plot not committed is not checked
                assert hashlib.sha256(path.read_bytes()).hexdigest() == digest, f"{path} differs from {manifest}"


def test_committed_learning_curves_hold_only_records_with_their_data_fingerprint():
    """The committed learning-curve table is built from records that carry the fingerprint of their data (a table
    aggregated from records of older data, as session 7's was, shows here), with strict JSON."""
    path = ROOT / "benchmarks" / "results" / "learning_curves" / "learning_curves.json"
    results = json.loads(path.read_text(), parse_constant=lambda c: pytest.fail(f"{c} in {path}"))
    records = results["records"]
    assert len(records) == results["meta"]["n_complete"] > 2000
    assert all(isinstance(r.get("data"), str) and re.fullmatch("[0-9a-f]{16}", r["data"]) for r in records)


def _write_many(folder: str, prefix: str, count: int) -> None:
    files = OutputFiles(folder)
    for i in range(count):
        files.write_text(f"{prefix}{i}.md", f"{prefix} {i}")


def test_two_processes_writing_into_one_folder_keep_every_manifest_entry(tmp_path):
    """The manifest's read-modify-write runs under a lock: without it, the two writers' updates overwrite each
    other and entries are lost (a later run then refuses its own files)."""
    import multiprocessing

    context = multiprocessing.get_context("fork")
    writers = [context.Process(target=_write_many, args=(str(tmp_path), prefix, 40)) for prefix in "ab"]
    for w in writers:
        w.start()
    for w in writers:
        w.join(600)  # a guard against a hang only: the 80 writes take well under a second
    assert [w.exitcode for w in writers] == [0, 0]
    manifest = json.loads((tmp_path / ".ftcal-benchmark-manifest.json").read_text())
    assert sorted(manifest) == sorted(f"{p}{i}.md" for p in "ab" for i in range(40))
    OutputFiles(tmp_path).check(list(manifest))  # every file is known as the benchmark's own


def test_a_result_file_edited_or_not_written_by_the_benchmark_is_not_its_own(tmp_path):
    files = OutputFiles(tmp_path)
    files.write_text("case.json", '{"rmse": 1.0}')
    assert files.is_own("case.json")
    (tmp_path / "case.json").write_text('{"rmse": 0.5}')  # edited since: a resumed run must not reuse it
    assert not files.is_own("case.json")
    (tmp_path / "mine.json").write_text("{}")  # the user's, never written by the benchmark
    assert not OutputFiles(tmp_path, force=True).is_own("mine.json")  # --force lets it be replaced, not reused
    assert not files.is_own("absent.json")

