"""Run log format: round trip and every reader error, naming file and line."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal.core import LogFormatError
from ftcal.io import read_run_log, write_run_log


def _write(tmp_path, name="run.csv", n=3, **kw):
    args = dict(timestamp=np.arange(n, dtype=float), run_kind=["load"] * n, config=[2] * n, pose=np.arange(n),
                q=np.linspace(-1, 1, n * 7).reshape(n, 7), raw=np.arange(n * 6, dtype=float).reshape(n, 6),
                load_mass=1.25, robot="kuka_iiwa14", sensor_frame="ft_sensor", meta={"operator": "x"})
    args.update(kw)
    return write_run_log(tmp_path / name, **args)


def test_round_trip(tmp_path):
    p = _write(tmp_path)
    log = read_run_log(p, n_channels=6, n_joints=7)
    np.testing.assert_allclose(log.q, np.linspace(-1, 1, 21).reshape(3, 7))
    np.testing.assert_allclose(log.raw, np.arange(18.0).reshape(3, 6))
    assert list(log.run_kind) == ["load"] * 3 and log.config.tolist() == [2, 2, 2]
    assert log.load_mass == 1.25 and log.robot == "kuka_iiwa14" and log.meta == {"operator": "x"}
    assert log.line.tolist() == [10, 11, 12]  # 8 comment lines, header on line 9


def test_temperature_reads_back_bit_for_bit(tmp_path):
    temperature = np.array([21.123456789012345, -3.0000001234567, 1e-9 + 40.0])  # more digits than %.6g keeps
    log = read_run_log(_write(tmp_path, temperature=temperature), n_channels=6, n_joints=7)
    np.testing.assert_array_equal(log.temperature, temperature)


def test_writer_never_overwrites(tmp_path):
    p = _write(tmp_path)
    before = p.read_text()
    with pytest.raises(LogFormatError, match="exists"):
        _write(tmp_path)
    assert p.read_text() == before


def test_degrees_are_converted_when_declared(tmp_path):
    p = tmp_path / "deg.csv"
    p.write_text("# time_unit: ms\n# joint_unit: deg\ntimestamp,run,config,pose,q1,q2,s0,s1,s2\n"
                 "1500,no-load,-1,0,90,-45,1,2,3\n")
    log = read_run_log(p)
    np.testing.assert_allclose(log.q, [[np.pi / 2, -np.pi / 4]])
    np.testing.assert_allclose(log.timestamp, [1.5])
    assert log.config.tolist() == [-1]


def _edit(p, old, new):
    p.write_text(p.read_text().replace(old, new, 1))
    return p


@pytest.mark.parametrize(
    "old, new, match",
    [
        (",q3,", ",qq3,", r"joint column q3 is missing"),
        ("timestamp,", "time,", r"header lacks columns \['timestamp'\]"),
        (",s0,", ",x0,", r"raw channel column s0 is missing"),
        ("# joint_unit: rad\n", "", r"missing comment '# joint_unit: <unit>'"),
        ("# joint_unit: rad", "# joint_unit: grad", r"unknown joint_unit 'grad'"),
        ("# time_unit: s", "# time_unit: h", r"unknown time_unit"),
        ("# load_mass_kg: 1.25", "# load_mass_kg: heavy", r"load_mass_kg"),
    ],
)
def test_header_errors(tmp_path, old, new, match):
    p = _edit(_write(tmp_path), old, new)
    with pytest.raises(LogFormatError, match=match) as exc:
        read_run_log(p)
    assert str(p) in str(exc.value)


def _break_row(p, line_no, column, value):
    lines = p.read_text().splitlines()
    header = lines[8].split(",")
    fields = lines[line_no - 1].split(",")
    fields[header.index(column)] = value
    lines[line_no - 1] = ",".join(fields)
    p.write_text("\n".join(lines) + "\n")
    return p


@pytest.mark.parametrize(
    "column, value, match",
    [
        ("s3", "nan", r"line 11: column s3 is 'nan' \(NaN or inf\)"),
        ("q2", "inf", r"line 11: column q2 is 'inf'"),
        ("s0", "abc", r"line 11: column s0: 'abc' is not a number"),
        ("run", "loaded", r"line 11: run is 'loaded'"),
        ("pose", "1.5", r"line 11: column pose must be an integer"),
        ("config", "-1", r"line 11: config -1 is invalid"),
        ("q4", "95.0", r"line 11: q4 = 95 exceeds 2\*pi .* degrees"),
    ],
)
def test_row_errors_name_file_and_line(tmp_path, column, value, match):
    p = _break_row(_write(tmp_path), 11, column, value)
    with pytest.raises(LogFormatError, match=match) as exc:
        read_run_log(p)
    assert str(p) in str(exc.value)


def test_field_count_channel_count_and_empty(tmp_path):
    p = _write(tmp_path)
    with pytest.raises(LogFormatError, match=r"6 raw channels \(s0..s5\) but 8 expected"):
        read_run_log(p, n_channels=8)
    with pytest.raises(LogFormatError, match=r"7 joint columns but the robot has 6"):
        read_run_log(p, n_joints=6)
    lines = p.read_text().splitlines()
    lines[10] += ",7"
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(LogFormatError, match=r"line 11: 18 fields but the header names 17"):
        read_run_log(p)
    empty = tmp_path / "empty.csv"
    empty.write_text("# time_unit: s\n# joint_unit: rad\ntimestamp,run,config,pose,q1,s0,s1,s2\n")
    with pytest.raises(LogFormatError, match="no data rows"):
        read_run_log(empty)
    with pytest.raises(LogFormatError, match="no such log file"):
        read_run_log(tmp_path / "missing.csv")
    two = tmp_path / "two.csv"
    two.write_text("# time_unit: s\n# joint_unit: rad\ntimestamp,run,config,pose,q1,s0,s1\n0,load,0,0,0,1,2\n")
    with pytest.raises(LogFormatError, match="2 raw channels; a sensor needs at least 3"):
        read_run_log(two)


def test_a_log_of_another_format_version_is_refused_with_its_line(tmp_path):
    p = _write(tmp_path)
    p.write_text(p.read_text().replace("# ftcal-run-log: 1", "# ftcal-run-log: 99"))
    with pytest.raises(LogFormatError, match=r"run\.csv: line 1: run-log format version '99'; this ftcal reads "
                                             r"version 1"):
        read_run_log(p)


@pytest.mark.parametrize("mass", ["0", "0.0", "-2", "1e300", "20000"])
def test_a_load_mass_that_is_not_positive_is_refused_with_its_line(tmp_path, mass):
    p = _write(tmp_path)
    p.write_text(p.read_text().replace("# load_mass_kg: 1.25", f"# load_mass_kg: {mass}"))
    line = p.read_text().splitlines().index(f"# load_mass_kg: {mass}") + 1
    with pytest.raises(LogFormatError, match=rf"run\.csv: line {line}: load_mass_kg is '{mass}'; it must be the "
                                             "positive mass"):
        read_run_log(p)
    with pytest.raises(LogFormatError, match="give the positive mass of the load in kg"):
        _write(tmp_path, name="zero.csv", load_mass=0.0)
    with pytest.raises(LogFormatError, match=r"give the positive mass of the load in kg \(at most 10000\)"):
        _write(tmp_path, name="huge.csv", load_mass=1e300)


def test_raw_values_no_calibration_can_square_are_refused_with_their_line(tmp_path):
    p = _break_row(_write(tmp_path), 11, "s1", "1e300")
    with pytest.raises(LogFormatError, match=r"run\.csv: line 11: column s1 is 1e\+300, beyond the 1e\+100"):
        read_run_log(p)


@pytest.mark.parametrize("separator, said", [("\t", "tabs"), (";", "';'")])
def test_a_run_log_or_pose_file_in_another_separator_is_refused_with_the_conversion(tmp_path, separator, said):
    # a run log re-saved by a spreadsheet: its header is one field; it was refused as a column name not in ASCII
    from ftcal.io import read_pose_file

    p = _write(tmp_path)
    lines = p.read_text().splitlines()
    p.write_text("\n".join(line if line.startswith("#") else line.replace(",", separator) for line in lines) + "\n")
    with pytest.raises(LogFormatError, match=rf"run\.csv: line 9: the fields are separated by {said}.*Fix: convert"):
        read_run_log(p)
    poses = tmp_path / "poses.csv"
    poses.write_text(separator.join(["qw", "qx", "qy", "qz", "Fx", "Fy", "Fz", "Tx", "Ty", "Tz"]) + "\n"
                     + separator.join(["1", "0", "0", "0", "1", "2", "3", "0.1", "0.2", "0.3"]) + "\n")
    with pytest.raises(LogFormatError, match=rf"poses\.csv: line 1: the fields are separated by {said}"):
        read_pose_file(poses)
