"""auto's choice: against the stock baselines, one RMSE, one 1-SE rule, stacking, the small-data guard, the GP,
parallel scoring."""

from __future__ import annotations

import os
from numbers import Real
from pathlib import Path

import numpy as np
import pytest
from sklearn.linear_model import LinearRegression
from sklearn.model_selection import cross_val_predict
from sklearn.utils._param_validation import Interval, StrOptions

import ftcal
from ftcal import AutoCalibrator, GaussianProcessCalibrator, LinearCalibrator, PolynomialCalibrator
from ftcal.core import CalibrationInputError
from ftcal.core._memory import MemoryLimitError
from ftcal.model_selection._selection import calibration_folds, simplest_within_one_se
from ftcal.calibrators import STOCK_BASELINE_NAMES, declare
from ftcal.compose._auto import StackedCalibrator, complexity_ranks, minimum_training_rows
from ftcal.calibrators._baselines import StockCalibrator
from ftcal.simulation._field_sensors import make_dead_weight_dataset, make_robot_held_dataset, \
    make_soft_sensor_dataset


def affine(n=120, seed=0, n_groups=6):
    rng = np.random.default_rng(seed)
    w = rng.uniform(-1, 1, size=(n, 6))
    raw = w @ rng.normal(size=(6, 6)) + 0.3 + 0.01 * rng.normal(size=(n, 6))
    return raw, w, np.repeat(np.arange(n_groups), n // n_groups)


def cubic(n=240, seed=0):
    rng = np.random.default_rng(seed)
    w = rng.uniform(-1, 1, size=(n, 6))
    raw = (w + 0.3 * w**3) @ rng.normal(size=(6, 6)) + 0.005 * rng.normal(size=(n, 6))
    return raw, w


FAST = [("linear", LinearCalibrator()), ("polynomial2", PolynomialCalibrator(degree=2)),
        ("polynomial3", PolynomialCalibrator(degree=3))]
#: A GP whose structure is given (nothing to choose: one fit of its hyperparameters), where a test is about what
#: auto does with a GP, not about the GP's choice of structure (its own tests; the parallel-scoring test keeps it)
GIVEN_GP = dict(mean="linear", kernel="rbf", per_output=False, kernel_bounds="ftcal")
#: The same as ``ftcal fit`` options
GIVEN_GP_CLI = [arg for key, value in GIVEN_GP.items() for arg in ("--param", f"{key}={str(value).lower()}")]


# ------------------------------------------------------------------ one RMSE (eq. 18)
def test_cv_rmse_is_eq_18_over_all_torque_scaled_values():
    raw, w, groups = affine()
    auto = AutoCalibrator(candidates=FAST[:1], alpha=3.0, baselines=False, stack=False).fit(raw, w, groups=groups)
    folds = calibration_folds(len(raw), groups, 5, 0)
    pred = cross_val_predict(LinearCalibrator(alpha=3.0), raw, w, cv=folds)
    assert auto.comparison_["rmse"][0] == pytest.approx(ftcal.core.wrench_rmse(w, pred, alpha=3.0), rel=1e-9)


# ------------------------------------------------------------------ the one 1-SE rule
def test_one_se_rule_goes_to_the_simplest_by_complexity_not_by_position():
    tied = np.array([[1.0, 1.2, 0.8, 1.0], [1.0, 1.2, 0.8, 1.0], [1.0, 1.2, 0.8, 1.0]])
    assert simplest_within_one_se(tied) == 0
    assert simplest_within_one_se(tied, complexity=[2, 0, 1]) == 1
    assert simplest_within_one_se(tied, complexity=[1, 1, 0]) == 2
    # a clearly better flexible model wins; a not-eligible one never does
    clear = np.array([[2.0, 2.1, 1.9, 2.0], [1.0, 1.1, 0.9, 1.0]])
    assert simplest_within_one_se(clear) == 1
    assert simplest_within_one_se(clear, eligible=[True, False]) == 0


def test_between_equally_simple_candidates_the_lower_error_wins():
    # three rows, all within noise of each other; 0 and 1 share the lowest complexity: the better of them (1)
    errors = np.array([[1.2, 0.8, 1.3, 0.9], [1.0, 1.0, 1.1, 0.9], [1.0, 0.9, 1.1, 0.9]])  # means 1.05, 1.0, 0.975
    assert simplest_within_one_se(errors) == 0  # distinct ranks: the first qualified (excess 0.075, SE 0.1)
    assert simplest_within_one_se(errors, complexity=[0, 0, 1]) == 1
    assert simplest_within_one_se(errors, complexity=[1, 0, 0]) == 2


def test_a_twin_with_group_offsets_ranks_with_its_model_without_them():
    """The twin predicts with the same map and one intercept: as flexible as its model without offsets, so the
    one-SE rule lets the CV score decide between the two (the LTM's twin is the degree-1 polynomial)."""
    cands = [("linear", LinearCalibrator()), ("ridge linear", LinearCalibrator(ridge=1.0)),
             ("linear twin", PolynomialCalibrator(degree=1, ridge=0.3, group_offsets=True)),
             ("cubic", PolynomialCalibrator(degree=3, ridge=1e-2)),
             ("cubic twin", PolynomialCalibrator(degree=3, ridge=1e-2, group_offsets=True)),
             ("other cubic twin", PolynomialCalibrator(degree=3, ridge=1e-4, group_offsets=True))]
    assert complexity_ranks(cands, 8).tolist() == [0, 1, 0, 3, 3, 5, 6, 7]
    # listed before its model, the twin shares its own (earlier) position; numpy's True counts; alpha and tare are
    # auto's to set
    assert complexity_ranks(cands[3:5][::-1], 2).tolist() == [0, 0]
    assert complexity_ranks([cands[0], ("t", PolynomialCalibrator(degree=1, group_offsets=np.True_))], 2).tolist() == [0, 0]
    assert complexity_ranks([("q", PolynomialCalibrator(degree=2, alpha=2.0)),
                             ("t", PolynomialCalibrator(degree=2, group_offsets=True, zero_reading=np.zeros(7)))],
                            2).tolist() == [0, 0]


@pytest.mark.parametrize("pose_offset, seed", [(0.0, 1), (0.0, 2), (0.0, 3), (0.3, 1), (0.3, 2), (0.3, 3),
                                              (0.03, 2), (0.03, 3)])
def test_auto_keeps_the_better_of_the_ltm_and_its_twin(pose_offset, seed):
    """Equally simple, so whichever scores lower is chosen: the twin where 8 poses shift the readings (the pooled
    LTM is biased by offsets that line up with the poses' loads), the LTM where they do not (loads vary mostly
    between the poses, and the twin, fitted within them, throws that variation away). With small offsets (0.03)
    the twin wins by less than one SE: ranked after the LTM, as before, the LTM would have been kept."""
    rng = np.random.default_rng(seed)
    groups = np.repeat(np.arange(8), 25)
    w = (rng.normal(size=(8, 6)) * 2.0)[groups] + rng.normal(size=(200, 6))
    raw = w @ rng.normal(size=(6, 7)) + pose_offset * rng.normal(size=(8, 7))[groups] + 0.05 * rng.normal(size=(200, 7))
    cands = AutoCalibrator()._candidates(grouped=True)[:2]
    auto = AutoCalibrator(candidates=cands, alpha=1.0, baselines=False, stack=False).fit(raw, w, groups=groups)
    assert auto.best_name_ == cands[int(np.argmin(auto.comparison_["rmse"][:2]))][0]
    assert auto.best_name_ == ("linear(group offsets)" if pose_offset else "linear")


@pytest.mark.parametrize("names", [["q", "q"], ["q", ""], ["q", 3]])
def test_candidate_names_must_differ(names):
    cands = list(zip(names, [PolynomialCalibrator(degree=2, group_offsets=True), PolynomialCalibrator(degree=2)]))
    raw, w, groups = affine()
    with pytest.raises(CalibrationInputError, match="one distinct, non-empty text name each"):
        AutoCalibrator(candidates=cands, baselines=False).fit(raw, w, groups=groups)


@pytest.mark.parametrize("bad, match", [(PolynomialCalibrator(degree=2, zero_reading="abc"), "'zero_reading'"),
                                        (PolynomialCalibrator(degree=2.5), "'degree'"),
                                        (PolynomialCalibrator(degree=2, ridge=-1), "'ridge'")])
def test_a_candidate_with_a_bad_parameter_is_refused_before_fitting_by_name(bad, match):
    raw, w, _ = affine()
    with pytest.raises(CalibrationInputError, match=f"candidate 'q': .*{match}"):
        AutoCalibrator(candidates=[("linear", LinearCalibrator()), ("q", bad)], baselines=False).fit(raw, w)


def test_a_stack_hands_the_groups_to_its_members_also_when_refitted_from_a_clone():
    """auto's stack of the LTM and its twin, cloned (as HistoryCalibrator(auto) and GridSearchCV do) and fitted with
    the groups, is auto's own stack: the twin member gets them, nothing warns about offsets without groups."""
    import warnings
    rng = np.random.default_rng(2)
    groups = np.repeat(np.arange(8), 25)
    w = (rng.normal(size=(8, 6)) * 2.0)[groups] + rng.normal(size=(200, 6))
    raw = w @ rng.normal(size=(6, 7)) + 0.3 * rng.normal(size=(8, 7))[groups] + 0.05 * rng.normal(size=(200, 7))
    members = [LinearCalibrator(), PolynomialCalibrator(degree=1, group_offsets=True)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        stack = StackedCalibrator(estimators=members, weights=[0.5, 0.5], alpha=1.0).fit(raw, w, groups=groups)
    twin = PolynomialCalibrator(degree=1, group_offsets=True, alpha=1.0).fit(raw, w, groups=groups)
    np.testing.assert_allclose(stack.estimators_[1].predict(raw), twin.predict(raw), atol=1e-9)
    with pytest.raises(CalibrationInputError, match="groups"):
        StackedCalibrator(estimators=members, weights=[0.5, 0.5]).fit(raw, w, groups=groups[:-1])


def test_a_candidates_own_measured_tare_is_kept_unless_auto_is_given_one():
    raw, w, _ = affine()
    own = raw[0] - w[0] @ np.linalg.lstsq(w, raw - raw.mean(0), rcond=None)[0] + 0.01  # any reading: it is used as is
    cands = [("linear", LinearCalibrator(zero_reading=own))]
    auto = AutoCalibrator(candidates=cands, alpha=1.0, baselines=False, stack=False).fit(raw, w)
    np.testing.assert_array_equal(auto.best_estimator_.zero_reading_, own)
    np.testing.assert_array_equal(auto.zero_reading_, own)
    shared = own + 1.0
    auto = AutoCalibrator(candidates=cands, alpha=1.0, zero_reading=shared, baselines=False, stack=False).fit(raw, w)
    np.testing.assert_array_equal(auto.best_estimator_.zero_reading_, shared)


def test_without_groups_a_twin_is_ranked_by_its_position():
    """Without groups a twin fits the same model as its plain twin (same figures up to rounding): the earlier one
    stays, whatever the last bit says."""
    raw, w, _ = affine(seed=1)  # a seed where the twin's figure happens to be lower in the last bits
    cands = [("linear", LinearCalibrator()), ("twin", PolynomialCalibrator(degree=1, group_offsets=True))]
    auto = AutoCalibrator(candidates=cands, alpha=1.0, baselines=False, stack=False).fit(raw, w)
    assert auto.comparison_["rmse"][1] == pytest.approx(auto.comparison_["rmse"][0], rel=1e-9)
    assert auto.best_name_ == "linear"


def test_the_tie_tolerance_is_per_group_like_the_differences():
    # one big group (90 rows, error 1.0 for both) and two small ones where candidate 1 gains 0.012 per row.
    # Per group, candidate 0's mean excess (0.008) exceeds its paired SE (0.004) and 1 % of the best's per-group
    # mean error (0.0033): a real gain. Compared with 1 % of the best's per-ROW mean (0.009), as before, it tied.
    units = np.repeat([0, 1, 2], [90, 5, 5])
    best = np.concatenate([np.full(90, 1.0), np.full(10, 0.0)])
    other = best + np.concatenate([np.zeros(90), np.full(10, 0.012)])
    errors = np.vstack([other, best])
    assert simplest_within_one_se(errors, units) == 1  # the per-group gain (0.008) is no tie
    assert simplest_within_one_se(errors) == 0  # per row: 0.0012 < 1 % of the per-row mean (0.009): a tie


def test_a_consistent_but_negligible_gain_is_a_tie():
    # noise-free data: the flexible model is better on every row, so the paired SE is ~0; a 0.4 % lower mean
    # squared error (0.2 % in RMSE) is below the tie tolerance and the simpler model wins; 3 % lower is not
    base = np.linspace(1.0, 2.0, 40)
    assert simplest_within_one_se(np.vstack([base, base * (1 - 0.004)])) == 0
    assert simplest_within_one_se(np.vstack([base, base * (1 - 0.03)])) == 1


# ------------------------------------------------------------------ baselines, stacking, determinism
def test_the_stock_baselines_are_choosable_candidates_on_the_same_folds():
    # (they were reported and never chosen before; now they compete under the same one-SE rule)
    raw, w = cubic(160)
    auto = AutoCalibrator(candidates=FAST[:2], alpha=1.0, stack=False).fit(raw, w)
    r = auto.comparison_
    stock = [n for n, k in zip(r["name"], r["kind"]) if k == "stock"]
    assert stock == list(STOCK_BASELINE_NAMES)
    assert all(r["rmse"][r["name"].index(n)] is not None for n in stock)
    assert all(e for e, k in zip(r["eligible"], r["kind"]) if k == "stock")
    # sk_linear is the LTM: same folds, same eq. 18 figure
    assert r["rmse"][r["name"].index("sk_linear")] == pytest.approx(r["rmse"][0], rel=1e-6)
    assert "sk_gp" in auto.summary() and "/ best stock model" in auto.summary()


def test_stack_is_scored_held_out_with_non_negative_weights_and_saved(tmp_path):
    raw, w = cubic(240)
    auto = AutoCalibrator(candidates=FAST, alpha=1.0, baselines=False).fit(raw, w)
    r = auto.comparison_
    assert r["kind"][-1] == "stack" and r["rmse"][-1] is not None
    assert len(r["stack_members"]) == 3 and min(r["stack_weights"]) >= 0
    stack = StackedCalibrator(estimators=[e for _, e in FAST], weights=r["stack_weights"], alpha=1.0).fit(raw, w)
    back = ftcal.load_model(ftcal.save_model(stack, tmp_path / "stack.model.npz"))
    np.testing.assert_allclose(back.predict(raw[:5]), stack.predict(raw[:5]))
    with pytest.raises(CalibrationInputError, match="one non-negative weight each"):
        StackedCalibrator(estimators=[LinearCalibrator()], weights=[-1.0]).fit(raw, w)


def test_auto_is_deterministic_and_has_no_time_budget():
    raw, w, groups = affine()
    params = AutoCalibrator().get_params()
    assert "time_budget" not in params
    a = AutoCalibrator(candidates=FAST, alpha=1.0, baselines=False).fit(raw, w, groups=groups)
    b = AutoCalibrator(candidates=FAST, alpha=1.0, baselines=False).fit(raw, w, groups=groups)
    assert a.comparison_["rmse"] == b.comparison_["rmse"] and a.best_name_ == b.best_name_


class PidRecorder(LinearRegression):
    """A stock linear regression that appends the id of the process fitting it to ``path`` (a real file)."""

    def __init__(self, *, path=None):
        super().__init__()
        self.path = path

    def __sklearn_tags__(self):  # a free model of the user's declares its cost (else it counts as heavy work)
        from ftcal.calibrators._base import declare

        return declare(super().__sklearn_tags__(), cost="closed_form")

    def fit(self, X, y):
        with open(self.path, "a") as f:
            f.write(f"{os.getpid()}\n")
        return super().fit(X, y)


class HeavyPidRecorder(PidRecorder):
    """The same regressor declaring no cost: a model of unknown cost, scored in worker processes."""

    def __sklearn_tags__(self):
        from ftcal.calibrators._base import declare

        return declare(super().__sklearn_tags__(), cost="heavy")


def fitting_processes(path) -> set[int]:
    return {int(line) for line in Path(path).read_text().split()}


def test_light_work_is_scored_in_this_process_whatever_n_jobs(tmp_path):
    # no network, kernel models on <= LIGHT_KERNEL_ROWS training rows: starting workers would cost more than the fits
    from ftcal.compose._auto import LIGHT_KERNEL_ROWS, score_candidates
    from ftcal.calibrators._baselines import stock_baselines

    raw, w, groups = affine(n=120, n_groups=6)  # 100-row training folds
    assert 100 <= LIGHT_KERNEL_ROWS
    baselines = {"pid": PidRecorder(path=str(tmp_path / "pids")), "sk_gp": StockCalibrator(baseline="sk_gp")}
    score_candidates(FAST, raw, w, groups=groups, alpha=1.0, baselines=baselines, n_jobs=2)
    assert fitting_processes(tmp_path / "pids") == {os.getpid()}


def test_what_counts_as_light_work_is_a_list_of_closed_forms_and_small_kernel_fits():
    from skorch.callbacks import Callback

    from ftcal.compose._auto import LIGHT_KERNEL_ROWS, is_light
    from ftcal.calibrators._baselines import stock_baselines

    stock = {name: StockCalibrator(baseline=name) for name in STOCK_BASELINE_NAMES}
    assert all(is_light(stock[n], 10**6) for n in ("sk_linear", "sk_poly2", "sk_poly3"))
    assert all(is_light(m, LIGHT_KERNEL_ROWS) and not is_light(m, LIGHT_KERNEL_ROWS + 1)
               for m in (stock["sk_gp"], stock["sk_kernel_ridge"], GaussianProcessCalibrator()))
    # networks however wrapped or configured, ensembles and unknown regressors are heavy
    # (and a regressor that declares no cost: the raw stock GP pipeline)
    for heavy in (ftcal.DirectionalCalibrator(callbacks=[Callback()]), ftcal.EnsembleCalibrator(LinearCalibrator()),
                  ftcal.ComparativeCalibrator(), stock_baselines(6)["sk_gp"]):
        assert not is_light(heavy, 10)


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="worker processes are capped at the cores: needs 2")
def test_heavy_work_is_scored_in_worker_processes(tmp_path, monkeypatch):
    from ftcal.compose import _auto
    from ftcal.calibrators._baselines import stock_baselines
    from ftcal.model_selection import _comparison

    monkeypatch.setattr(_comparison, "LIGHT_KERNEL_ROWS", 50)  # the 100-row folds of the stock GP now count as heavy
    raw, w, groups = affine(n=120, n_groups=6)
    baselines = {"pid": HeavyPidRecorder(path=str(tmp_path / "pids")), "sk_gp": stock_baselines(6)["sk_gp"]}
    _auto.score_candidates(FAST[:1], raw, w, groups=groups, alpha=1.0, baselines=baselines, n_jobs=2)
    assert fitting_processes(tmp_path / "pids") - {os.getpid()}, "no worker process fitted anything"


def test_stock_kernel_baselines_have_the_gp_candidates_budget():
    from ftcal.calibrators._baselines import KERNEL_SAMPLES, stock_baselines

    assert KERNEL_SAMPLES == GaussianProcessCalibrator().max_samples
    assert {stock_baselines(6)[n].max_samples for n in ("sk_kernel_ridge", "sk_gp")} == {KERNEL_SAMPLES}


def test_parallel_scoring_gives_the_same_table_and_choice_as_sequential(monkeypatch):
    # real joblib worker processes; the GP (structure chosen inside its task) and a stock baseline among them
    from ftcal.model_selection import _comparison

    monkeypatch.setattr(_comparison, "LIGHT_KERNEL_ROWS", 50)  # the 100-row folds count as heavy: workers are used
    raw, w, groups = affine(n=120, n_groups=6)
    cands = FAST[:2] + [("gaussian_process", GaussianProcessCalibrator(max_samples=60, random_state=0))]
    kw = dict(candidates=cands, alpha=1.0, random_state=0)
    one = AutoCalibrator(n_jobs=1, **kw).fit(raw, w, groups=groups)
    two = AutoCalibrator(n_jobs=2, **kw).fit(raw, w, groups=groups)
    assert one.comparison_["name"] == two.comparison_["name"]
    assert one.comparison_["kind"][-1] == "stack" and "stock" in one.comparison_["kind"]
    # closed forms to rounding; an iterative fit (the GP's L-BFGS, the stock GP's, the stack over them) to the
    # optimiser's tolerance: its path may differ by rounding between processes, whose arrays are aligned otherwise
    iterative = [n in ("gaussian_process", "sk_gp", "sk_kernel_ridge") or n.startswith("stack")
                 for n in one.comparison_["name"]]
    for rows, rtol in (([not i for i in iterative], 1e-9), (iterative, 1e-4)):
        np.testing.assert_allclose([r for r, k in zip(one.comparison_["rmse"], rows) if k and r is not None],
                                   [r for r, k in zip(two.comparison_["rmse"], rows) if k and r is not None],
                                   rtol=rtol)
    assert one.best_name_ == two.best_name_
    np.testing.assert_allclose(one.predict(raw[:5]), two.predict(raw[:5]), rtol=1e-4)


def test_the_stack_auto_chose_holds_the_cross_validated_members_and_a_clone_refits():
    from sklearn.base import clone
    from sklearn.model_selection import cross_val_score

    raw, w = cubic(240)
    cands = FAST + [("gaussian_process", GaussianProcessCalibrator(max_samples=60, random_state=0, **GIVEN_GP))]
    auto = AutoCalibrator(candidates=cands, alpha=1.0, baselines=False, random_state=0).fit(raw, w)
    r = auto.comparison_
    assert r["kind"] == ["candidate"] * 4 + ["stack"]  # the stack row right after the candidates
    if r["chosen"].startswith("stack"):  # its members are fitted on all rows with the cross-validated weights
        best = auto.best_estimator_
        assert len(best.estimators_) == len(r["stack_members"]) and best.weights_.tolist() == r["stack_weights"]
        assert all(e.n_features_in_ == raw.shape[1] for e in best.estimators_)
    stack = StackedCalibrator(estimators=[e for _, e in FAST], weights=[0.2, 0.3, 0.5], alpha=1.0).fit(raw, w)
    again = clone(stack).fit(raw, w)  # a clone refits its templates
    np.testing.assert_allclose(again.predict(raw[:4]), stack.predict(raw[:4]), rtol=1e-10)
    assert np.all(np.isfinite(cross_val_score(clone(auto.best_estimator_), raw, w, cv=3)))


@pytest.mark.parametrize("n_jobs", [0, True, 1.5, "2"])
def test_auto_n_jobs_is_checked(n_jobs):
    raw, w, groups = affine()
    with pytest.raises(ValueError, match="n_jobs"):
        AutoCalibrator(candidates=FAST[:1], baselines=False, n_jobs=n_jobs).fit(raw, w)


def test_network_candidates_are_trained_as_one_stacked_fit_on_a_grouped_subsample():
    raw, w, groups = affine(n=240, n_groups=8)
    net = ftcal.make_calibrator("directional", phase1_epochs=3, plateau_epochs=1, max_recover_epochs=1, random_state=0)
    kw = dict(candidates=[FAST[0], ("directional", net)], alpha=1.0, baselines=False, stack=False,
              network_samples=100, race=False)  # scored on every fold, not raced out by the LTM
    a = AutoCalibrator(**kw).fit(raw, w, groups=groups)
    b = AutoCalibrator(**kw).fit(raw, w, groups=groups)
    assert a.comparison_["status"][1].startswith("scored")
    assert a.comparison_["rmse"] == b.comparison_["rmse"]  # the same seed and data: the same scores


# ------------------------------------------------------------------ small data, extrapolation, bad input
@pytest.mark.parametrize("n_rows", [15, 30, 50])
def test_few_dead_weight_rows_auto_is_never_worse_than_1_1x_the_ltm_at_2x_the_range(n_rows):
    cal, val = make_dead_weight_dataset(n_rows, random_state=0)
    alpha = ftcal.core.alpha_from_wrenches(cal.wrench)
    auto = AutoCalibrator(alpha=alpha, baselines=False,
                          candidates=[c for c in ftcal.compose._auto.default_candidates()
                                      if c[0] not in ("directional", "comparative")]).fit(cal.raw, cal.wrench)
    r = auto.comparison_
    chosen = r["name"].index(auto.best_name_)
    assert r["eligible"][chosen]
    for k, name in enumerate(r["name"]):
        if r["kind"][k] == "candidate" and name != "linear":
            est = dict(ftcal.compose._auto.default_candidates())[name]
            assert r["eligible"][k] == (r["min_training_rows"] >= minimum_training_rows(est, cal.n_channels))
    ltm = LinearCalibrator(alpha=alpha).fit(cal.raw, cal.wrench)
    rmse_auto = ftcal.core.wrench_rmse(val.wrench, auto.predict(val.raw), alpha)
    assert rmse_auto <= 1.1 * ftcal.core.wrench_rmse(val.wrench, ltm.predict(val.raw), alpha)
    # readings beyond the calibrated range are flagged, those inside are not
    assert not auto.out_of_range(cal.raw).any()
    assert auto.out_of_range(val.raw).mean() > 0.5


@pytest.mark.parametrize(
    "kwargs, n, groups, message",
    [
        ({}, 120, np.zeros(7), r"groups must have shape \(120,\)"),
        ({}, 120, np.zeros(120), "one group only"),
        ({"cv": 10}, 8, None, "X has 8 rows, fewer than the cv=10 folds"),
        ({"cv": 5}, 4, None, r"X has 4 sample\(s\), but AutoCalibrator needs at least 7"),
    ],
)
def test_auto_bad_input_is_a_clear_error(kwargs, n, groups, message):
    raw, w, _ = affine()
    with pytest.raises(CalibrationInputError, match=message):
        AutoCalibrator(candidates=FAST[:1], baselines=False, **kwargs).fit(raw[:n], w[:n], groups=groups)


# ------------------------------------------------------------------ the GP
def test_gp_return_std_through_auto_and_a_saved_auto(tmp_path):
    raw, w = cubic(120)
    auto = AutoCalibrator(candidates=[("gaussian_process", GaussianProcessCalibrator(random_state=0, **GIVEN_GP))],
                          alpha=1.0, baselines=False, stack=False).fit(raw, w)
    mean, std = auto.predict(raw[:4], return_std=True)
    back = ftcal.load_model(ftcal.save_model(auto, tmp_path / "auto.model.npz"))
    mean2, std2 = back.predict(raw[:4], return_std=True)
    np.testing.assert_allclose(mean, mean2)
    np.testing.assert_allclose(std, std2)
    assert (std > 0).all()
    linear = AutoCalibrator(candidates=FAST[:1], alpha=1.0, baselines=False).fit(raw, w)
    with pytest.raises(CalibrationInputError, match="gives no standard deviation"):
        linear.predict(raw[:2], return_std=True)


def test_gp_predict_is_chunked_and_equal_to_one_block(monkeypatch):
    import ftcal.calibrators._gaussian_process as gpm

    raw, w = cubic(120)
    gp = GaussianProcessCalibrator(mean="linear", kernel="rbf", per_output=False, alpha=1.0, random_state=0)
    gp.fit(raw, w)
    whole = gp.predict(raw, return_std=True)
    monkeypatch.setattr(gpm, "_CHUNK_BYTES", 8 * gp.train_inputs_.shape[0] * 7)  # 7 rows per chunk
    for a, b in zip(whole, gp.predict(raw, return_std=True)):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-12)


def test_gp_with_1000_channels_is_refused_before_allocating():
    rng = np.random.default_rng(0)
    raw = rng.normal(size=(1200, 1000))
    w = rng.normal(size=(1200, 6))
    with pytest.raises(MemoryLimitError, match=r"pass max_samples=\d+ \(the most rows within the limit\)"):
        GaussianProcessCalibrator(alpha=1.0).fit(raw, w)


def test_gp_chooses_a_linear_trend_where_the_data_are_affine_and_extrapolates_like_the_ltm():
    raw, w, _ = affine(n=150)
    gp = GaussianProcessCalibrator(alpha=1.0, random_state=0).fit(raw, w)
    assert gp.mean_ == "linear" or gp.kernel_.endswith("+linear")
    far = 2.0 * raw[:20]  # loads twice the calibrated range
    ltm = LinearCalibrator(alpha=1.0).fit(raw, w)
    assert np.abs(gp.predict(far) - ltm.predict(far)).max() < 0.1 * np.abs(ltm.predict(far)).max()


# ------------------------------------------------------------------ simulated sensors
def test_simulated_presets_have_the_documented_shape_and_a_noise_floor():
    soft = make_soft_sensor_dataset(random_state=3)
    assert soft.raw.shape == (418, 8) and soft.meta["noise_floor_rmse"] > 0
    robot = make_robot_held_dataset(20_000, n_poses=45, random_state=1)
    assert robot.raw.shape == (20_000, 8) and np.unique(robot.group).size == 45
    # the soft sensor is strongly nonlinear: the LTM is far above the floor even on its own training rows
    ltm = LinearCalibrator(alpha=soft.meta["alpha"]).fit(soft.raw, soft.wrench)
    assert ftcal.core.wrench_rmse(soft.wrench, ltm.predict(soft.raw), soft.meta["alpha"]) > 4 * soft.meta["noise_floor_rmse"]


# ------------------------------------------------------------------ CLI: predict --std
def test_cli_predict_std_writes_std_columns_and_refuses_models_without_one(tmp_path, capsys):
    from ftcal.cli import main

    raw, w = cubic(100)
    data = ftcal.CalibrationDataset(raw=raw, wrench=w).save(tmp_path / "d.csv")
    np.savetxt(tmp_path / "r.csv", raw[:5], delimiter=",")
    for model, given in (("gaussian_process", GIVEN_GP_CLI), ("linear", [])):
        assert main(["fit", str(data), "--model", model, *given, "--out", str(tmp_path / "m"), "-q"]) == 0
    out = tmp_path / "w.csv"
    assert main(["predict", str(tmp_path / "m" / "gaussian_process.model.npz"), str(tmp_path / "r.csv"), "--std",
                 "--output", str(out)]) == 0
    lines = out.read_text().splitlines()
    assert lines[0].split(",")[6:] == ["std_Fx", "std_Fy", "std_Fz", "std_Tx", "std_Ty", "std_Tz"]
    table = np.loadtxt(out, delimiter=",", skiprows=1)
    assert table.shape == (5, 12) and (table[:, 6:] > 0).all()
    capsys.readouterr()
    assert main(["predict", str(tmp_path / "m" / "linear.model.npz"), str(tmp_path / "r.csv"), "--std"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("ftcal: error: --std:") and "no standard deviation" in err[0]


def test_cli_fit_auto_uses_the_short_schedule_and_jobs(tmp_path):
    import json

    from ftcal.cli import main

    raw, w = cubic(100)  # 75-row training folds: the networks (they need 25 N rows) are skipped, the GP is scored
    data = ftcal.CalibrationDataset(raw=raw, wrench=w).save(tmp_path / "d.csv")
    # (the stock baselines left out: what is tested is the schedule, the jobs and the folds of ftcal's candidates)
    assert main(["fit", str(data), "--model", "auto", "--jobs", "1", "--cv", "4", "--param", "baselines=false",
                 "--out", str(tmp_path / "m"), "-q"]) == 0
    summary = json.loads((tmp_path / "m" / "auto.fit.json").read_text())
    assert summary["schedule"] == "short"
    auto = ftcal.load_model(tmp_path / "m" / "auto.model.npz")
    assert auto.n_jobs == 1 and auto.schedule == "short"
    assert auto.cv == 4 and auto.comparison_["n_splits"] == 4  # the folds --cv asks for, as its report's
    status = dict(zip(auto.comparison_["name"], auto.comparison_["status"]))
    assert status["gaussian_process"] == "scored" and status["directional"].startswith("skipped")


def test_cli_jobs_is_refused_for_a_model_that_scores_no_candidates(tmp_path, capsys):
    from ftcal.cli import main

    raw, w = cubic(60)
    data = ftcal.CalibrationDataset(raw=raw, wrench=w).save(tmp_path / "d.csv")
    assert main(["fit", str(data), "--model", "linear", "--jobs", "2", "--out", str(tmp_path / "m"), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("ftcal: error: --jobs: linear") and "drop --jobs" in err[-1]
    assert not (tmp_path / "m").exists() or not any((tmp_path / "m").iterdir())


def test_cross_validate_routes_groups_to_auto_through_metadata_routing():
    import sklearn
    from sklearn.model_selection import GroupKFold, cross_validate

    raw, w, groups = affine(n=120, n_groups=6)
    with sklearn.config_context(enable_metadata_routing=True):
        auto = AutoCalibrator(candidates=FAST[:2], alpha=1.0, baselines=False, stack=False).set_fit_request(
            groups=True)
        out = cross_validate(auto, raw, w, cv=GroupKFold(2), params={"groups": groups},
                             scoring=ftcal.neg_scaled_rmse, return_estimator=True)
    assert [e.comparison_["folds"] for e in out["estimator"]] == ["group", "group"]


@pytest.mark.parametrize("mean, kernel, per_output", [("none", "matern52", True), ("linear", "rbf+linear", False)])
def test_gp_onnx_export_equals_predict_for_each_kernel_family(mean, kernel, per_output, tmp_path):
    import onnxruntime

    raw, w = cubic(80)
    gp = GaussianProcessCalibrator(mean=mean, kernel=kernel, per_output=per_output, alpha=1.0, random_state=0)
    gp.fit(raw, w)
    path = ftcal.export_onnx(gp, tmp_path / "gp.onnx")
    session = onnxruntime.InferenceSession(str(path))
    out = session.run(None, {session.get_inputs()[0].name: raw[:10]})[0]
    # both are float64 sums of dual weight x kernel value over the training rows, in other orders: they agree to
    # the rounding of that sum, which grows with the dual weights (large when the kernel matrix is ill-conditioned)
    rounding = np.finfo(np.float64).eps * len(gp.dual_coef_) * np.abs(gp.dual_coef_).sum(axis=0).max()
    scale = max(1.0, float(np.max(gp.target_scale_)), float(np.exp(np.max(gp.theta_))))
    np.testing.assert_allclose(out, gp.predict(raw[:10]), rtol=1e-9, atol=max(1e-9, 10 * rounding * scale))


@pytest.mark.parametrize("width", [1, 3])
def test_gp_with_automatic_choices_fits_targets_of_any_width(width):
    # per_output="auto" compared six components and priced six LTM means whatever the width: IndexError before
    raw, w = cubic(120)
    gp = GaussianProcessCalibrator(alpha=1.0, random_state=0).fit(raw, w[:, :width])
    mean, std = gp.predict(raw[:4], return_std=True)
    assert mean.shape == std.shape == (4, width) and np.all(std > 0)
    assert np.sqrt(np.mean((gp.predict(raw) - w[:, :width]) ** 2)) < 0.1 * w[:, :width].std()


def test_grouped_subsample_is_exactly_the_size_with_each_groups_share():
    from ftcal.model_selection._selection import grouped_subsample

    rows = np.arange(9000)
    many_small = rows // 3  # 3000 groups of 3 rows: a share of 1/9 cannot give each group a row
    picked = grouped_subsample(rows, many_small, 1000, seed=0)
    assert len(picked) == 1000 and len(np.unique(picked)) == 1000 and np.all(np.diff(picked) > 0)
    uneven = np.repeat(np.arange(4), [6000, 2000, 900, 100])
    counts = np.bincount(uneven[grouped_subsample(rows, uneven, 900, seed=1)], minlength=4)
    assert counts.sum() == 900
    np.testing.assert_allclose(counts, [600, 200, 90, 10], atol=3)  # floor of the share, the rest at random
    assert np.array_equal(grouped_subsample(rows[:50], uneven, 100, seed=0), rows[:50])  # all fit: all rows


class _ChoosesRidge(LinearCalibrator):
    """The LTM choosing its ridge on the rows it is given (``ridge="choose"``): a candidate that chooses its
    structure, recording every fit's (ridge asked, rows) in a class list (in-process scoring)."""

    fits: list = []
    _parameter_constraints = {**LinearCalibrator._parameter_constraints,
                              "ridge": [StrOptions({"choose", "fail"}), Interval(Real, 0, None, closed="left")]}

    def fit(self, X, y):
        type(self).fits.append((self.ridge, len(X)))
        if self.ridge == "fail":
            raise ValueError("no structure fits these rows")
        if self.ridge == "choose":  # the structure: a ridge that depends on the rows seen
            chosen = float(len(X)) * 1e-6
            fitted = LinearCalibrator(ridge=chosen, alpha=self.alpha).fit(X, y)
            self.__dict__.update({k: v for k, v in vars(fitted).items() if k.endswith("_")})
            self.ridge_chosen_ = chosen
            return self
        return super().fit(X, y)

    def structure_params(self) -> dict:
        return {"ridge": self.ridge_chosen_}

    def __sklearn_tags__(self):
        return declare(super().__sklearn_tags__(), chooses_structure=True)


@pytest.mark.parametrize("n_jobs", [1, 2])
def test_a_candidate_that_chooses_its_structure_chooses_on_the_first_fold_and_keeps_it(n_jobs):
    raw, w = cubic(120)
    _ChoosesRidge.fits = []
    auto = AutoCalibrator(candidates=[("choosing", _ChoosesRidge(ridge="choose"))], cv=4, stack=False,
                          baselines=False, n_jobs=n_jobs, random_state=0).fit(raw, w)
    if n_jobs == 1:  # in this process: every fit is seen
        assert _ChoosesRidge.fits[0] == ("choose", 90)  # once, on the first fold's 90 training rows: its model
        assert sorted(_ChoosesRidge.fits[1:4]) == [(90 * 1e-6, 90)] * 3  # the other folds with that structure
        assert _ChoosesRidge.fits[4:] == [(90 * 1e-6, 120)]  # the refit on all rows keeps it
    assert auto.best_estimator_.ridge == pytest.approx(90e-6)  # the structure scored, refitted on all rows
    assert auto.comparison_.structures == {"choosing": {"ridge": pytest.approx(90e-6)}}
    assert auto.comparison_["status"] == ["scored"]


def test_on_more_rows_than_choice_samples_it_chooses_on_a_grouped_subsample_and_refits_on_all_rows():
    rng = np.random.default_rng(0)
    groups = np.repeat(np.arange(30), 100)
    w = rng.normal(size=(3000, 6))
    raw = w @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(3000, 6)) + 0.05 * rng.normal(size=(30, 6))[groups]
    auto = AutoCalibrator(candidates=[("linear", LinearCalibrator()), ("quadratic", PolynomialCalibrator(degree=2))],
                          baselines=False, stack=False, choice_samples=600, random_state=0, n_jobs=1)
    auto.fit(raw, w, groups=groups)
    plan = auto.fold_plan_
    assert plan.n_rows == 600 and plan.kind == "group"
    assert np.array_equal(np.unique(plan.units, return_counts=True)[1], np.full(30, 20))  # 20 rows of each group
    assert "Chosen on 600 of the 3000 rows" in auto.comparison_.why and auto.held_out_predictions_.shape == (600, 6)
    assert auto.best_name_ == "linear"
    all_rows = LinearCalibrator(alpha=auto.alpha_).fit(raw, w)  # the winner refitted on every row
    np.testing.assert_allclose(auto.predict(raw[:50]), all_rows.predict(raw[:50]), rtol=1e-9, atol=1e-12)


def test_a_structure_fit_that_fails_is_recorded_as_failed_not_fatal():
    raw, w = cubic(120)
    auto = AutoCalibrator(candidates=[("linear", LinearCalibrator()), ("failing", _ChoosesRidge(ridge="fail"))],
                          cv=4, stack=False, baselines=False, n_jobs=1, random_state=0).fit(raw, w)
    status = dict(zip(auto.comparison_["name"], auto.comparison_["status"]))
    assert status["failing"].startswith("failed: ValueError: no structure fits these rows")
    assert auto.best_name_ == "linear"


class _SearchRecordingGP(GaussianProcessCalibrator):
    """The real GP; the rows of each fit that has its structure to choose (a parameter left "auto") are kept."""

    searched_on: list = []

    def fit(self, X, y, **fit_params):
        if "auto" in (self.mean, self.kernel, self.per_output, self.kernel_bounds):
            type(self).searched_on.append(frozenset(np.asarray(X, dtype=float).tobytes(order="C")[i * 32:(i + 1) * 32]
                                                    for i in range(len(X))))
        return super().fit(X, y, **fit_params)


def test_each_stability_repeat_chooses_the_structure_on_its_own_training_rows_never_on_its_test_rows():
    rng = np.random.default_rng(0)  # noisy affine data: the GP within one SE of the LTM, so the repeats run
    w = rng.uniform(-1, 1, size=(60, 4))  # 4 channels, 4 outputs: the GP needs 40 training rows
    raw = w @ rng.normal(size=(4, 4)) + 0.3 + 0.3 * rng.normal(size=(60, 4))
    _SearchRecordingGP.searched_on = []
    # one structure choice left to the GP (its bounds: two shared fits on 48 rows), the rest given
    gp = _SearchRecordingGP(mean="none", kernel="rbf+linear", per_output=False, kernel_bounds="auto", max_samples=60)
    auto = AutoCalibrator(candidates=[("linear", LinearCalibrator()), ("gp", gp)],
                          alpha=1.0, baselines=False, stack=False).fit(raw, w)
    stability = auto.comparison_.stability
    assert stability is not None and stability.repeats == 5  # the repeats ran, the GP among the compared
    row = lambda i: raw[i].astype(float).tobytes()  # noqa: E731
    for seed in stability.seeds:  # each repeat's structure was chosen on its own first training fold, and only there
        plan = auto.fold_plan_ if seed == auto.fold_plan_.seed else auto.fold_plan_.with_seed(seed, raw, w, None)
        train, test = plan.folds[0]
        assert frozenset(row(i) for i in train) in _SearchRecordingGP.searched_on
    # one search per repeat and no other (a structure chosen once on seed 0's first fold saw the repeats' test rows)
    assert len(_SearchRecordingGP.searched_on) == stability.repeats


def test_on_two_groups_a_candidate_with_its_own_grouped_choice_is_scored_on_training_folds_of_one_group():
    # each training fold holds one group: the candidate's inner choice makes row folds, where it failed with
    # the Python-API advice "pass groups=None" printed by the command line
    raw, w, _ = affine(n=60, seed=1)
    groups = np.repeat([0, 1], 30)
    auto = AutoCalibrator(candidates=[("linear", LinearCalibrator()),
                                      ("axis_nonlinear", ftcal.make_calibrator("axis_nonlinear"))],
                          alpha=1.0, baselines=False, stack=False).fit(raw, w, groups=groups)
    row = auto.comparison_.row("axis_nonlinear")
    assert row.status.value == "scored" and row.rmse is not None and np.isfinite(row.rmse), row.reason
    with pytest.raises(CalibrationInputError, match="one group only"):  # a user's one group is still refused
        ftcal.make_calibrator("axis_nonlinear").fit(raw, w, groups=np.zeros(60, int))
