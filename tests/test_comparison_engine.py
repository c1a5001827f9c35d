"""The one fold rule and the one comparison engine: FoldPlan, compare, paired differences in symmetric words,
racing of costly models, progress, and a typed comparison that survives JSON."""

from __future__ import annotations

import json

import numpy as np
import pytest
from sklearn.linear_model import LinearRegression, Ridge
from sklearn.neighbors import KNeighborsRegressor

from ftcal.model_selection import (Comparison, FoldPlan, PairedDifference, RowStatus, choice_stability, compare)

class TaggedOLS(LinearRegression):
    """A user's regressor declaring ftcal's optional tags: a closed form."""

    def __sklearn_tags__(self):
        from ftcal.calibrators import declare

        return declare(super().__sklearn_tags__(), cost="closed_form")


ANY_ROWS = lambda estimator, n_channels: 5  # noqa: E731 - plain regressors judged on any fold


def linear_data(n=120, seed=0, noise=0.05):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, 4))
    return X, X @ rng.normal(size=(4, 3)) + noise * rng.normal(size=(n, 3))


def test_one_group_per_loaded_axis_replaces_the_grouped_folds_and_says_so():
    y = np.repeat(np.eye(6)[:3] * 10, 8, axis=0) * np.tile(np.linspace(-1, 1, 8), 3)[:, None]
    X = y[:, :3] + np.random.default_rng(0).normal(size=(24, 3))
    plan = FoldPlan.for_data(X, y, np.repeat([0, 1, 2], 8))
    assert plan.kind == "replaced" and "missing from a training fold" in plan.note
    assert plan.units_name == "fold" and sorted(np.unique(plan.units)) == list(range(plan.n_splits))
    for train, test in plan.folds:  # every fold's training rows load every axis
        assert all(np.ptp(y[train][:, j]) > 0 for j in range(3))


def test_grouped_plan_holds_out_whole_groups_with_group_units_and_a_stable_fingerprint():
    X, y = linear_data(100)
    groups = np.repeat(np.arange(10), 10)
    plan = FoldPlan.for_data(X, y, groups)
    assert plan.kind == "group" and plan.units_name == "group" and plan.n_splits == 5
    for train, test in plan.folds:
        assert not set(groups[train]) & set(groups[test])
    again = FoldPlan.for_data(X, y, groups)
    assert plan.same_folds(again) and plan.same_folds(again.to_dict())
    assert not plan.same_folds(FoldPlan.for_data(X, y))
    json.dumps(plan.to_dict())


def test_ordered_plan_uses_contiguous_blocks():
    X, y = linear_data(50)
    plan = FoldPlan.for_data(X, y, ordered=True)
    assert plan.kind == "ordered"
    for _, test in plan.folds:
        assert np.all(np.diff(test) == 1)


def test_paired_words_are_mirrored_when_the_sides_swap():
    X, y = linear_data(150, noise=0.2)
    plan = FoldPlan.for_data(X, y)
    c = compare([("ols", LinearRegression()), ("ridge", Ridge(alpha=200.0)), ("ridge_tiny", Ridge(alpha=1e-3))],
                X, y, plan, min_rows=ANY_ROWS)
    ab, ba = c.paired("ols", "ridge"), c.paired("ridge", "ols")
    assert isinstance(ab, PairedDifference)
    assert ab.difference == pytest.approx(-ba.difference) and ab.paired_se == pytest.approx(ba.paired_se)
    assert (ab.verdict, ba.verdict) == ("better", "worse")
    figures = lambda a, b: f"({a:.4g} vs {b:.4g} N, paired SE {ab.paired_se:.2g} N)"  # noqa: E731
    assert ab.words() == f"ols is {ab.percent:.1f} % better than ridge " + figures(ab.rmse_a, ab.rmse_b)
    assert ba.words() == f"ridge is {ab.percent:.1f} % worse than ols " + figures(ab.rmse_b, ab.rmse_a)
    assert f"{ab.percent:.1f} % better" in ab.words() and f"{ba.percent:.1f} % worse" in ba.words()
    tie, eit = c.paired("ols", "ridge_tiny"), c.paired("ridge_tiny", "ols")
    assert tie.verdict == eit.verdict == "equivalent"
    assert "equivalent within noise" in tie.words() and "equivalent within noise" in eit.words()


def test_any_regressor_is_a_model_and_a_costly_bad_one_is_raced_out_with_its_reason():
    X, y = linear_data(200, noise=0.01)
    seen = []
    c = compare([("ols", TaggedOLS()), ("knn", KNeighborsRegressor(n_neighbors=30))], X, y,
                FoldPlan.for_data(X, y), min_rows=ANY_ROWS, progress=seen.append)
    knn = c.row("knn")
    assert knn.status is RowStatus.STOPPED and "after fold 1 of 5" in knn.reason and knn.rmse is None
    assert [r.name for r in seen] == ["ols", "knn"]  # each row reported as it finished
    assert c.choose() == "ols" and "Stopped early" in c.table() and "knn" in c.table()
    full = compare([("ols", TaggedOLS()), ("knn", KNeighborsRegressor(n_neighbors=30))], X, y,
                   FoldPlan.for_data(X, y), min_rows=ANY_ROWS, race=False)
    assert full.row("knn").status is RowStatus.SCORED and full.choose() == "ols"  # the same choice in full
    assert full.paired("knn", "ols").verdict == "worse"


def test_the_race_stops_by_the_paired_se_of_the_difference_not_by_the_references_own_se():
    from ftcal.model_selection._comparison import RACE_SIGMAS, race_stop
    from ftcal.model_selection._selection import TIE_TOLERANCE, mean_and_se

    rng = np.random.default_rng(0)
    units = np.repeat(np.arange(5), 40)  # 5 folds of 40 rows; the candidate was scored on the first
    first = units == 0

    def standardised(n):
        z = rng.normal(size=n)
        return (z - z.mean()) / z.std(ddof=1)

    def old_rule(candidate, reference):  # the reference's unpaired SE over every unit as the margin
        excess, se = mean_and_se(candidate - reference[first])
        margin = max(mean_and_se(reference, units)[1], TIE_TOLERANCE * reference[first].mean())
        return excess - RACE_SIGMAS * se > margin

    # errors spread widely over the rows (a wide unpaired SE); the candidate worse on every row by 0.05 N²
    reference = rng.exponential(2.0, 200) * np.repeat(rng.uniform(0.2, 3.0, 5), 40)
    candidate = reference[first] + 0.05 + 0.001 * standardised(40)
    stop, excess, se, threshold = race_stop(candidate, reference[first], None, 0.0)
    assert stop and excess == pytest.approx(0.05) and se == pytest.approx(0.001 / np.sqrt(40))
    assert not old_rule(candidate, reference)  # its unpaired SE would have kept it
    # the converse: the reference's errors nearly constant, the difference noisy, its excess 2.5 paired SE
    reference = 1.0 + 0.001 * rng.normal(size=200)
    spread = 0.3
    candidate = reference[first] + 2.5 * spread / np.sqrt(40) + spread * standardised(40)
    stop, excess, se, threshold = race_stop(candidate, reference[first], None, TIE_TOLERANCE)
    assert not stop and excess == pytest.approx(2.5 * se) and threshold == pytest.approx(se)
    assert old_rule(candidate, reference)  # the reference's small unpaired SE would have stopped it


def test_too_few_rows_skips_from_the_tags_rule_and_a_failing_model_is_a_failed_row():
    class Broken(LinearRegression):
        def fit(self, X, y):
            raise RuntimeError("cannot fit")

    X, y = linear_data(30)
    c = compare([("ols", LinearRegression()), ("broken", Broken())], X, y, FoldPlan.for_data(X, y),
                min_rows=lambda est, n: 5 if type(est) is LinearRegression else 5)
    assert c.row("broken").status is RowStatus.FAILED and "cannot fit" in c.row("broken").reason
    skipped = compare([("ols", LinearRegression())], X, y, FoldPlan.for_data(X, y))  # untagged: 25 N rows needed
    assert skipped.row("ols").status is RowStatus.SKIPPED and "< the 100 it needs" in skipped.row("ols").reason


def test_to_dict_is_json_and_reads_back_with_its_statuses():
    X, y = linear_data(200, noise=0.01)
    c = compare([("ols", TaggedOLS()), ("knn", KNeighborsRegressor(n_neighbors=30))], X, y,
                FoldPlan.for_data(X, y), min_rows=ANY_ROWS)
    c.choose()
    data = json.loads(json.dumps(c.to_dict()))
    back = Comparison.from_dict(data)
    assert [r.status for r in back.rows] == [RowStatus.SCORED, RowStatus.STOPPED]
    assert back.chosen == "ols" and back.row("ols").rmse == pytest.approx(c.row("ols").rmse)
    assert back.facts["fingerprint"] == c.plan.fingerprint()


def test_choice_stability_counts_the_repeats_that_choose_the_same():
    X, y = linear_data(120, noise=0.05)
    models = [("ols", LinearRegression()), ("ridge", Ridge(alpha=500.0))]
    stab = choice_stability(models, X, y, FoldPlan.for_data(X, y), chosen="ols", min_rows=ANY_ROWS)
    assert (stab.count, stab.repeats) == (5, 5) and stab.words().startswith("chosen in 5 of 5 repeats")


def test_the_race_and_the_one_se_rule_share_one_tie_margin_averaged_per_group():
    from ftcal.model_selection._comparison import race_stop
    from ftcal.model_selection._selection import paired_excess, tie_margin

    # a reference whose rows are uneven over its groups: the per-row mean (2.0) and the per-group mean (3.0) differ
    reference = np.array([1.0, 1.0, 1.0, 5.0])
    units = np.array([0, 0, 0, 1])
    _, _, tie = paired_excess(np.vstack([reference, reference + 0.025]), best=0, units=units)
    assert tie == pytest.approx(tie_margin(reference, units)) == pytest.approx(0.03)
    # worse by 0.025 on every row: beyond a per-row margin (0.02), within the per-group one the race is given
    assert race_stop(reference + 0.025, reference, units, tie_margin(reference, units))[3] == pytest.approx(0.03)


def test_on_large_data_a_raced_model_that_cannot_win_is_stopped_and_one_that_wins_races_on():
    rng = np.random.default_rng(1)
    X = rng.uniform(-1, 1, size=(300, 2))
    y = np.column_stack([3 * np.sin(3 * X[:, 0]), 3 * np.cos(3 * X[:, 1])]) + 0.05 * rng.normal(size=(300, 2))
    plan = FoldPlan.for_data(X, y)
    # the same least squares, untagged (a costly model: raced), and a neighbours model far better on the sine
    models = [("ols", TaggedOLS()), ("ols_again", LinearRegression()), ("knn", KNeighborsRegressor(5))]
    tied = compare(models, X, y, plan, min_rows=ANY_ROWS, race_ties=True)
    assert tied.row("ols_again").status is RowStatus.STOPPED and "cannot come better" in tied.row("ols_again").reason
    assert tied.row("knn").status is RowStatus.SCORED
    full = compare(models, X, y, plan, min_rows=ANY_ROWS)  # without: the tie races on, and the choice is the same
    assert full.row("ols_again").status is RowStatus.SCORED and full.choose() == tied.choose() == "knn"


def test_the_tie_stop_asks_a_gain_beyond_the_all_folds_se_so_a_gain_of_a_few_first_fold_se_races_on():
    from ftcal.model_selection._comparison import race_stop

    rng = np.random.default_rng(2)
    z = rng.normal(size=100)
    noise = (z - z.mean()) / z.std(ddof=1)  # exactly unit SD: the paired SE on these 100 rows is 0.1
    reference = rng.exponential(1.0, 100) + 5.0
    # the all-folds bar: 0.1 * sqrt(0.2) = 0.045 N²; stopped when gain + one SE falls short of it
    for gain_in_se, stopped in [(-1.0, True), (-0.6, True), (-0.4, False), (0.5, False), (3.0, False)]:
        candidate = reference - gain_in_se * 0.1 - noise
        stop, excess, se, _ = race_stop(candidate, reference, None, 0.0, ties=True, share=0.2)
        assert se == pytest.approx(0.1) and -excess == pytest.approx(gain_in_se * 0.1) and stop is stopped
        assert not race_stop(candidate, reference, None, 0.0, share=0.2)[0]  # without ties: never stopped here


def _lucky_comparison(flexible_gain_everywhere: bool) -> tuple[Comparison, FoldPlan]:
    """The LTM (every row off by 0.1) and a flexible model far better on the first fold's groups only and a little
    worse on all others (a win by luck on 6 of 30 poses), or a little better on every fold."""
    rng = np.random.default_rng(0)
    y = rng.normal(size=(300, 6))
    groups = np.repeat(np.arange(30), 10)
    plan = FoldPlan.for_data(rng.normal(size=(300, 4)), y, groups)
    off = np.full(300, 0.09 if flexible_gain_everywhere else 0.105)
    if not flexible_gain_everywhere:
        off[plan.folds[0][1]] = 0.03
    c = Comparison(rows=[], plan=plan)
    c.add_scored("ltm", "candidate", y + 0.1, y, complexity=0.0)
    c.add_scored("flexible", "candidate", y + off[:, None], y, complexity=1.0)
    return c, plan


def test_a_flexible_winner_that_does_not_beat_the_ltm_when_the_choice_is_cross_validated_is_not_kept():
    from ftcal.model_selection._selection import choice_beats_simplest, simplest_within_one_se

    c, plan = _lucky_comparison(False)
    errors = np.vstack([r.row_errors for r in c.rows])
    # the one-SE rule alone keeps it: on all folds together it is better than the LTM beyond one paired SE
    assert simplest_within_one_se(errors, plan.units, complexity=[0, 1]) == 1
    # the choice made again without each fold picks the LTM without the lucky fold and the flexible model elsewhere,
    # where it is worse: the cross-validated choice loses to the LTM
    beats, simplest, gain, _ = choice_beats_simplest(errors, plan.units, plan.folds, complexity=[0, 1], eligible=[1, 1])
    assert not beats and simplest == 0 and gain < 0
    assert c.choose() == "ltm"
    assert c.row("flexible").verdict.startswith("not kept") and "cross-validated" in c.why and "flexible" in c.why
    # a model better on every fold is kept
    c, plan = _lucky_comparison(True)
    assert c.choose() == "flexible" and c.row("ltm").verdict == "beyond one SE"


@pytest.mark.parametrize("grouping", ["cv=2", "2 groups"])
def test_with_two_folds_a_clearly_better_model_is_still_chosen_over_the_ltm(grouping):
    """With two folds the choice cannot be made again without a fold (one fold left has no SE: every candidate would
    be within it and the LTM always chosen again), so the cross-validated check does not judge and a quadratic
    twenty times better than the LTM on quadratic data is chosen, as with 3 or 5 folds."""
    from sklearn.linear_model import LinearRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import PolynomialFeatures

    rng = np.random.default_rng(0)
    X = rng.normal(size=(200, 3))
    y = np.column_stack([X[:, 0] ** 2 + X[:, 1], X[:, 2]]) + 0.05 * rng.normal(size=(200, 2))
    models = [("lin", LinearRegression()), ("quad", make_pipeline(PolynomialFeatures(2), LinearRegression()))]
    groups = None if grouping == "cv=2" else np.arange(200) % 2
    plan = FoldPlan.for_data(X, y, groups, cv=2 if groups is None else 5)
    assert plan.n_splits == 2
    c = compare(models, X, y, plan, groups=groups, min_rows=lambda e, n: 5, complexity=[0, 1])
    assert c.row("quad").rmse < 0.1 * c.row("lin").rmse
    assert c.choose() == "quad"
