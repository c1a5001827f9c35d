"""The comparison table lets a reader check every one-SE verdict (the paired SE the rule used, not only each row's
own SE); with few groups the rule's SE is the larger of the rows' and the groups'."""

from __future__ import annotations

import re

import numpy as np

from ftcal import AutoCalibrator, LinearCalibrator, PolynomialCalibrator
from ftcal.model_selection._selection import rmse_and_se
from ftcal.compose._auto import comparison_table
from ftcal.model_selection import Comparison, ComparisonRow, FoldPlan, RowStatus


def _cells(table: str, name: str) -> list[str]:
    row = next(line for line in table.splitlines() if line.startswith(f"| {name}"))
    return [c.strip() for c in row.strip("|").split("|")]


def test_a_row_beyond_one_se_shows_the_paired_se_though_its_own_se_overlaps_the_best():
    rng = np.random.default_rng(0)
    hard = rng.exponential(1.0, size=200)  # rows both models find hard or easy: a wide spread of each's errors
    errors = np.vstack([hard + 0.05 + 0.005 * rng.normal(size=200), hard])  # simpler one: consistently worse
    stats = [rmse_and_se(e) for e in errors]
    rows = [ComparisonRow(name=name, kind="candidate", status=RowStatus.SCORED, rmse=st[0], rmse_se=st[1],
                          seconds=sec, complexity=rank, row_errors=e)
            for name, st, sec, rank, e in zip(["simple", "complex"], stats, [0.1, 0.2], [0, 1], errors)]
    comparison = Comparison(rows=rows, plan=FoldPlan((), None, "kfold", "", 5, 0, 200))  # SEs over the rows
    assert comparison.choose() == "complex"
    results = comparison.to_dict()
    (rmse_simple, _), (rmse_complex, se_complex) = stats
    assert rmse_simple - rmse_complex < se_complex  # within the chosen row's own ± SE ...
    assert results["verdict"] == ["beyond one SE", "chosen"]  # ... yet beyond one (paired) SE
    table = comparison_table(comparison)
    assert comparison_table(results) == table  # the JSON columns give the same table
    assert "excess MSE over best [N²] | ± paired SE [N²]" in table.splitlines()[0]
    simple = _cells(table, "simple")
    excess, paired = float(simple[6]), float(simple[7])
    assert abs(excess - 0.05) < 0.01 and 0 < paired < 0.002 and excess > paired  # the reader sees why
    assert _cells(table, "complex **(chosen)**")[6:8] == ["0", "0"]
    assert "paired SE" in table and "not the row's own ± SE" in table and "differences from the best over the rows" in table


def test_every_verdict_of_a_real_fit_follows_from_the_printed_excess_and_paired_se():
    rng = np.random.default_rng(1)
    w = rng.uniform(-1, 1, size=(150, 6))
    raw = w @ rng.normal(size=(6, 6))
    raw = raw + 0.02 * raw**2 + 0.01 * rng.normal(size=raw.shape)
    groups = np.repeat(np.arange(6), 25)
    auto = AutoCalibrator(candidates=[("linear", LinearCalibrator()), ("quadratic", PolynomialCalibrator(degree=2)),
                                      ("cubic", PolynomialCalibrator(degree=3))], random_state=0)
    table = auto.fit(raw, w, groups=groups).summary()
    rule = auto.comparison_["rule"]
    tie = float(re.search(r"tie margin ([0-9.eE+-]+) N²", table).group(1))
    assert rule["units"] == "groups" and "over the groups, not" in table and tie > 0
    checked = 0
    for name, verdict in zip(auto.comparison_["name"], auto.comparison_["verdict"]):
        if not verdict.startswith(("within one SE", "beyond one SE")):
            continue
        cells = _cells(table, name)
        excess, paired = float(cells[6]), float(cells[7])
        margin = max(paired, tie)
        if abs(excess - margin) > 0.05 * margin:  # clear of the printed numbers' rounding
            assert (verdict == "beyond one SE") == (excess > margin), (name, verdict, excess, paired, tie)
            checked += 1
    assert checked >= 5


def test_with_few_groups_a_gain_in_one_group_only_does_not_make_the_complex_model_win():
    from ftcal.model_selection._selection import mean_and_se, se_units, simplest_within_one_se

    # 3 groups of 40 rows: the complex model gains a lot in group 0 and loses a little in groups 1 and 2. Over the
    # rows the gain looks sure (the rows' SE of the difference is small); between the groups it is not.
    rng = np.random.default_rng(2)
    units = np.repeat([0, 1, 2], 40)
    simple = 1.0 + 0.01 * rng.normal(size=120)
    gain = np.where(units == 0, 0.3, -0.05) + 0.01 * rng.normal(size=120)
    errors = np.vstack([simple, simple - gain])
    rows_mean, rows_se = mean_and_se(gain)
    assert rows_mean > rows_se  # the rows alone would choose the complex model
    assert simplest_within_one_se(errors, None) == 1
    groups_mean, se = mean_and_se(gain, units)
    assert se > rows_se and se > groups_mean  # the groups' spread is the larger, and the gain is within it
    assert simplest_within_one_se(errors, units) == 0
    assert simplest_within_one_se(errors, se_units(units)) == 0  # what auto passes: the groups, even only 3
    # 3 groups that happen to agree (their SE ~0) while the rows scatter: the rows' SE, the larger
    agreeing = np.tile([0.0, 2.0], 60) + np.repeat([0.0, 1e-9, 2e-9], 40)
    assert mean_and_se(agreeing, units)[1] == mean_and_se(agreeing)[1] > 0.09
    # consistent gains in every group still win with few groups
    errors = np.vstack([simple, simple - 0.1 - 0.01 * rng.normal(size=120)])
    assert simplest_within_one_se(errors, units) == 1


def test_auto_with_three_groups_says_which_standard_errors_it_used():
    rng = np.random.default_rng(3)
    w = rng.uniform(-1, 1, size=(90, 6))
    raw = w @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(90, 6))
    auto = AutoCalibrator(candidates=[("linear", LinearCalibrator()), ("quadratic", PolynomialCalibrator(degree=2))],
                          baselines=False, stack=False, random_state=0).fit(raw, w, groups=np.repeat([0, 1, 2], 30))
    assert auto.comparison_["se_units"] == "rows or groups, the larger (fewer than 5 groups)"
    assert "over the rows or groups, the larger" in auto.summary()
