"""The pure parts of benchmarks/before_after.py: its arguments and the summary of paired times (no workload runs)."""

import pytest

import before_after


def test_arguments_default_to_the_redesign_revisions_and_both_workloads():
    args = before_after.parse_args([])
    assert (args.before, args.after, args.repeats) == ("d600b34", "HEAD", 5)
    assert args.workloads == ["network", "auto"]
    assert (args.epochs, args.rows) == (20, 4000)


@pytest.mark.parametrize("argv", [["--repeats", "0"], ["--repeats", "two"], ["--workloads", "gp"],
                                  ["--rows", "50"]])
def test_bad_arguments_exit_with_a_usage_error(argv, capsys):
    with pytest.raises(SystemExit) as exit_info:
        before_after.parse_args(argv)
    assert exit_info.value.code == 2
    assert "error:" in capsys.readouterr().err


def test_summary_ratio_of_medians_and_pair_ratios():
    # medians 4 and 6 (ratio 1.5); the pairs' ratios are 6/4, 3/2, 10/5
    s = before_after.summarize([4.0, 2.0, 5.0], [6.0, 3.0, 10.0])
    assert s["median_before_s"] == 4.0 and s["median_after_s"] == 6.0
    assert s["ratio_of_medians"] == pytest.approx(1.5)
    assert s["pair_ratios"] == pytest.approx([1.5, 1.5, 2.0])
    assert (s["pair_ratio_min"], s["pair_ratio_max"]) == pytest.approx((1.5, 2.0))
    low, high = s["bootstrap_90"]
    assert 1.5 <= low <= s["median_pair_ratio"] <= high <= 2.0


def test_summary_bootstrap_interval_is_a_point_when_every_pair_agrees():
    s = before_after.summarize([1.0, 2.0, 3.0, 4.0], [1.1, 2.2, 3.3, 4.4])
    assert s["bootstrap_90"] == pytest.approx([1.1, 1.1])


@pytest.mark.parametrize("before, after", [([], []), ([1.0], [1.0, 2.0]), ([0.0], [1.0]), ([1.0], [-1.0])])
def test_summary_refuses_unpaired_or_non_positive_times(before, after):
    with pytest.raises(ValueError, match="before"):
        before_after.summarize(before, after)
