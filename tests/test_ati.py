"""ATI .cal reader: both matrix forms, units, and malformed files."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal.core import CalFileError
from ftcal.simulation import read_ati_calibration

AXES = ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"]

# Published rows of an ATI Gamma SI-130-10 and a Nano17 SI-25-0.25 calibration file (ATI's own
# "Axis" = scaled basic-frame rows, and "UserAxis" = the user matrix ATI computed from them).
GAMMA = dict(
    units='ForceUnits="N" TorqueUnits="N-m" DistUnits="m"', dz="0.0120142", maxima=[130, 130, 400, 10, 10, 10],
    axis=[("-0.27053 -0.14278 0.35224 -32.30108 -0.22111 32.83006", 2.33993181642138),
          ("0.21616 37.46357 0.05722 -18.83819 0.35126 -18.85998", 2.33993181642138),
          ("18.48980 -0.25078 18.75502 -0.41293 18.60017 -0.58878", 0.747981765296576),
          ("0.05325 0.15667 -32.28492 0.82744 32.26505 -1.25235", 44.8196831994584),
          ("37.31421 -0.62445 -18.43472 0.63319 -18.48677 0.60638", 44.8196831994584),
          ("-0.13536 -18.46474 0.04406 -18.57097 0.27123 -18.80438", 43.1398206760749)],
    user=["-0.11562 -0.06102 0.15054 -13.80428 -0.09449 14.03035",
          "0.09238 16.01054 0.02446 -8.05074 0.15012 -8.06005",
          "24.71959 -0.33527 25.07417 -0.55206 24.86714 -0.78715",
          "0.00230 0.19585 -0.72004 -0.07826 0.72169 -0.12478",
          "0.83393 -0.01320 -0.41312 0.17997 -0.41133 -0.15503",
          "-0.00314 -0.42802 0.00102 -0.43048 0.00629 -0.43589"],
)
NANO17 = dict(
    units='ForceUnits="N" TorqueUnits="N-mm" DistUnits="mm"', dz="6.096", maxima=[25, 25, 35, 250, 250, 250],
    axis=[("-0.06744 -0.06253 0.34834 37.34247 1.90538 -37.39899", 11.3650042049178),
          ("0.55821 -45.57953 -0.51071 22.00831 -0.39426 21.28868", 11.3650042049178),
          ("22.07572 0.66524 22.64229 0.15088 21.81132 -0.64550", 5.89341666193018),
          ("0.25495 0.07335 38.61586 0.30585 -38.71584 1.08341", 1.82292883446332),
          ("-43.12768 -1.34402 23.17737 0.13073 21.67933 -0.58572", 1.82292883446332),
          ("0.23141 -23.28809 -0.53681 -22.47927 1.56779 -22.44391", 1.57420173377595)],
    user=["-0.00593 -0.00550 0.03065 3.28574 0.16765 -3.29072",
          "0.04912 -4.01052 -0.04494 1.93650 -0.03469 1.87318",
          "3.74583 0.11288 3.84196 0.02560 3.70096 -0.10953",
          "0.43927 -24.40787 20.90948 11.97267 -21.44973 12.01322",
          "-23.62228 -0.70375 12.52751 -19.95816 10.87057 19.73889",
          "0.14700 -14.79358 -0.34100 -14.27979 0.99593 -14.25733"],
)


def cal_file(path, sensor, form, extra_root=""):
    rows = []
    if form in ("Axis", "both"):
        rows += [f'<Axis Name="{a}" values="{v}" max="{m}" scale="{s}"/>'
                 for a, (v, s), m in zip(AXES, sensor["axis"], sensor["maxima"])]
        rows.append(f'<BasicTransform Dx="0" Dy="0" Dz="{sensor["dz"]}" Rx="0" Ry="0" Rz="0"/>')
    if form in ("UserAxis", "both"):
        rows += [f'<UserAxis Name="{a}" values="{v}" max="{m}"/>' for a, v, m in zip(AXES, sensor["user"], sensor["maxima"])]
    path.write_text(
        '<?xml version="1.0" encoding="utf-8"?>\n'
        f'<FTSensor Serial="FT0001" BodyStyle="Test" NumGages="6" CalFileVersion="1.1" {extra_root}>\n'
        f'<Calibration PartNumber="SI-T" CalDate="1/2/2020" {sensor["units"]}>\n' + "\n".join(rows)
        + "\n</Calibration>\n</FTSensor>\n"
    )
    return path


@pytest.mark.parametrize("sensor, torque_si", [(GAMMA, 1.0), (NANO17, 1e-3)])
def test_axis_rows_with_scale_and_transform_reproduce_atis_user_matrix(tmp_path, sensor, torque_si):
    from_axis = read_ati_calibration(cal_file(tmp_path / "a.cal", sensor, "Axis"))
    from_user = read_ati_calibration(cal_file(tmp_path / "u.cal", sensor, "UserAxis"))
    assert from_axis.meta["form"] == "Axis" and from_user.meta["form"] == "UserAxis"
    user = np.array([[float(v) for v in row.split()] for row in sensor["user"]])
    user[3:] *= torque_si  # file units -> N·m
    np.testing.assert_allclose(from_user.calibration_matrix, user, rtol=0, atol=1e-12)
    # ATI printed 5 decimals of the user rows: agree to that precision (relative to each row's size)
    tol = 6e-5 * np.abs(user).max(axis=1, keepdims=True) + 1e-5 * torque_si
    assert np.all(np.abs(from_axis.calibration_matrix - user) <= tol)


def test_rated_ranges_units_and_meta(tmp_path):
    p = read_ati_calibration(cal_file(tmp_path / "n.cal", NANO17, "both"))
    assert p.meta["form"] == "UserAxis"  # preferred when both are present
    assert p.axis_max == (25.0, 25.0, 35.0, 0.25, 0.25, 0.25)  # 250 N-mm = 0.25 N·m
    assert (p.fmax, p.tmax) == (35.0, 0.25)
    assert p.meta["file_units"] == {"force": "N", "torque": "N-mm", "distance": "mm"}
    assert p.meta["serial"] == "FT0001" and p.raw_unit == "V"


def test_imperial_units_are_converted(tmp_path):
    sensor = dict(GAMMA, units='ForceUnits="lbf" TorqueUnits="lbf-in" DistUnits="in"')
    p = read_ati_calibration(cal_file(tmp_path / "i.cal", sensor, "UserAxis"))
    assert p.calibration_matrix[2, 0] == pytest.approx(24.71959 * 4.4482216152605)
    assert p.calibration_matrix[5, 1] == pytest.approx(-0.42802 * 0.0254 * 4.4482216152605)
    assert p.axis_max[2] == pytest.approx(400 * 4.4482216152605)


def test_hand_made_translation_moves_the_torque_reference(tmp_path):
    # identity basic matrix, tool point Dz = 10 mm: T_user = T - D x F, so Tx += 0.01 Fy, Ty -= 0.01 Fx
    eye = [(" ".join("1" if j == i else "0" for j in range(6)), 1.0) for i in range(6)]
    sensor = dict(units='ForceUnits="N" TorqueUnits="N-m" DistUnits="mm"', dz="10", maxima=[1] * 6, axis=eye, user=[])
    c = read_ati_calibration(cal_file(tmp_path / "t.cal", sensor, "Axis")).calibration_matrix
    expected = np.eye(6)
    expected[3, 1], expected[4, 0] = 0.01, -0.01
    np.testing.assert_allclose(c, expected, atol=1e-15)


def test_rotation_keeps_forces_lengths(tmp_path):
    p = cal_file(tmp_path / "r.cal", GAMMA, "Axis")
    p.write_text(p.read_text().replace('Rz="0"', 'Rz="30"').replace('Dz="0.0120142"', 'Dz="0"'))
    rotated = read_ati_calibration(p).calibration_matrix
    plain = read_ati_calibration(cal_file(tmp_path / "a.cal", dict(GAMMA, dz="0"), "Axis")).calibration_matrix
    raw = np.random.default_rng(0).normal(size=(6, 10))
    np.testing.assert_allclose(np.linalg.norm(rotated[:3] @ raw, axis=0), np.linalg.norm(plain[:3] @ raw, axis=0))
    np.testing.assert_allclose(rotated[2], plain[2])  # a rotation about z leaves Fz alone
    assert not np.allclose(rotated[0], plain[0])


def _broken(tmp_path, old, new, form="both"):
    p = cal_file(tmp_path / "bad.cal", GAMMA, form)
    text = p.read_text()
    assert old in text
    p.write_text(text.replace(old, new, 1))
    return p


@pytest.mark.parametrize(
    "old, new, form, words",
    [
        ('<UserAxis Name="Tz"', '<UserAxis Name="Tq"', "UserAxis", "Name='Tq'"),
        ('<UserAxis Name="Tz"', '<UserAxis Name="Fz"', "UserAxis", "appears twice"),
        ("0.00629 -0.43589", "0.00629", "UserAxis", "different numbers of gauge values"),
        ("-0.33527", "-0.3x527", "UserAxis", "non-number"),
        ('scale="43.1398206760749"', 'scale="0"', "Axis", r"\['Tz'\] have scale=0"),
        ('scale="43.1398206760749"', "", "Axis", "no 'scale' attribute"),
        ('TorqueUnits="N-m"', 'TorqueUnits="furlong-lb"', "both", "TorqueUnits='furlong-lb' is not a known unit"),
        ('max="400"/>', 'max="-1"/>', "UserAxis", "max <= 0"),
        ('NumGages="6"', 'NumGages="8"', "UserAxis", "NumGages=8 but"),
        ("</FTSensor>", "</FTSens", "both", "not well-formed XML"),
        ("<Calibration ", "<Calib ", "both", "no <Calibration> element"),
    ],
)
def test_malformed_files_name_the_file_and_the_problem(tmp_path, old, new, form, words):
    path = _broken(tmp_path, old, new, form)
    if new.startswith("<Calib "):
        path.write_text(path.read_text().replace("</Calibration>", "</Calib>"))
    with pytest.raises(CalFileError, match=words) as info:
        read_ati_calibration(path)
    assert "bad.cal" in str(info.value)


def test_missing_axis_and_missing_file(tmp_path):
    p = cal_file(tmp_path / "m.cal", GAMMA, "UserAxis")
    p.write_text("\n".join(line for line in p.read_text().splitlines() if 'Name="Ty"' not in line))
    with pytest.raises(CalFileError, match=r"m.cal: <UserAxis> rows for \['Ty'\] are missing"):
        read_ati_calibration(p)
    with pytest.raises(CalFileError, match="no such calibration file"):
        read_ati_calibration(tmp_path / "absent.cal")
