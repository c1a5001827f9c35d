"""Headers are checked in linear time: a file of 200 000 columns is read (or refused) in the time of its size, not
of its size squared (a count per column took more than 200 s)."""

from __future__ import annotations

import pytest

from ftcal.cli import main
from ftcal.core._columns import read_header, repeated_names

N = 200_000


def test_a_repeated_column_of_a_wide_header_is_named_with_its_count():
    names = [f"s{i}" for i in range(N)] + ["Fx", "s7", "s7"]
    with pytest.raises(ValueError, match=r"w\.csv: line 1: column 's7' appears 3 times"):
        read_header(names, where="w.csv: line 1", error=ValueError)
    assert repeated_names(names) == [("s7", 3)]


def test_a_wide_csv_reaches_the_calibrations_own_check(tmp_path, capsys):
    # 200 000 channels and one row: every header check passes (linearly) and the fit says what is missing
    names = [f"g{i}" for i in range(N)] + ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"]
    path = tmp_path / "wide.csv"
    path.write_text(",".join(names) + "\n" + ",".join(["1"] * len(names)) + "\n")
    assert main(["fit", str(path), "--channels", "g0..g99999", "--out", str(tmp_path / "o"), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "needs at least 100001" in err[0], err
