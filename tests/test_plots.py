"""PNG plots of ftcal.reporting._plots: real files, the right content on the axes, clear errors on bad input."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from ftcal.core import CalibrationInputError
from ftcal.reporting import _plots


def png_size(path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG file"
    width, height = struct.unpack(">II", data[16:24])  # IHDR
    return width, height


def test_error_distributions_png_and_content(tmp_path):
    errors = {"linear": [3.0, 4.0, 5.0], "directional": [1.0, 2.0, 3.0]}
    path = _plots.plot_error_distributions(errors, tmp_path / "d.png", noise_floor=0.5)
    # figure 8 in wide at 120 dpi; 1.2 + 1.1 per model inches high
    assert png_size(path) == (960, int(round((1.2 + 2 * 1.1) * 120)))
    fig = _plots.error_distributions_figure(errors, noise_floor=0.5)
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_yticklabels()] == ["linear", "directional"]
    assert "[N]" in ax.get_xlabel()
    assert "noise floor 0.5" in [t.get_text() for t in ax.get_legend().get_texts()]
    marked = _plots.error_distributions_figure(errors, overall={"linear": 4.1, "directional": 2.2}).axes[0]
    assert [t.get_text() for t in marked.get_legend().get_texts()] == ["RMSE over the set"]
    notes = [t.get_text() for t in ax.texts]
    assert "mean 4 ± 0.82" in notes and "mean 2 ± 0.82" in notes  # std of (3, 4, 5) = sqrt(2/3)


def test_axis_errors_bars_are_the_values_with_units(tmp_path):
    lin = [1.0, 2.0, 3.0, 0.1, 0.2, 0.3]
    dnn = [0.5, 0.5, 0.5, 0.05, 0.05, 0.05]
    fig = _plots.axis_errors_figure({"linear": lin, "directional": dnn})
    forces, torques = fig.axes
    assert forces.get_ylabel() == "RMSE [N]" and torques.get_ylabel() == "RMSE [N·m]"
    heights = sorted(round(p.get_height(), 6) for p in torques.patches)
    assert heights == sorted([0.1, 0.2, 0.3, 0.05, 0.05, 0.05])
    assert [t.get_text() for t in forces.get_xticklabels()] == ["Fx", "Fy", "Fz"]
    assert png_size(_plots.plot_axis_errors({"linear": lin}, tmp_path / "a.png")) == (1080, 480)


def test_predicted_vs_reference_titles_carry_hand_computed_rmse(tmp_path):
    rng = np.random.default_rng(0)
    y = rng.normal(size=(50, 6)) * [100, 100, 100, 2, 2, 2]
    pred = y + [3.0, 0, 0, 0, 0, -0.5]  # constant errors: RMSE is exactly 3 N and 0.5 N·m
    fig = _plots.predicted_vs_reference_figure(y, pred, model_name="directional")
    titles = [ax.get_title() for ax in fig.axes]
    assert titles[0] == "Fx   RMSE 3 N" and titles[1] == "Fy   RMSE 0 N" and titles[5] == "Tz   RMSE 0.5 N·m"
    assert fig.axes[3].get_ylabel() == "predicted - reference [N·m]"
    value_fig = _plots.predicted_vs_reference_figure(y, pred, kind="value")
    assert value_fig.axes[0].get_ylabel() == "predicted [N]"
    assert png_size(_plots.plot_predicted_vs_reference(y, pred, tmp_path / "p.png")) == (1320, 780)


def test_axis_and_prediction_figures_show_the_axes_of_a_three_and_one_axis_cell(tmp_path):
    fig = _plots.axis_errors_figure({"linear": [1.0, 2.0, 3.0], "directional": [0.5, 0.25, 0.125]},
                                    axes=("Fx", "Fy", "Fz"))
    (forces,) = fig.axes  # no torque panel for a force-only cell
    assert forces.get_ylabel() == "RMSE [N]" and forces.get_title() == "forces"
    assert [t.get_text() for t in forces.get_xticklabels()] == ["Fx", "Fy", "Fz"]
    assert sorted(round(p.get_height(), 6) for p in forces.patches) == [0.125, 0.25, 0.5, 1.0, 2.0, 3.0]
    (torque,) = _plots.axis_errors_figure({"m": [0.5]}, axes=("Tz",)).axes
    assert torque.get_ylabel() == "RMSE [N·m]" and [t.get_text() for t in torque.get_xticklabels()] == ["Tz"]
    y = np.linspace(-50.0, 50.0, 40)[:, None] * [1.0, -1.0, 0.5]
    fig = _plots.predicted_vs_reference_figure(y, y + [2.0, 0.0, -4.0], axes=("Fx", "Fy", "Fz"))
    assert [ax.get_title() for ax in fig.axes if ax.get_visible()] == ["Fx   RMSE 2 N", "Fy   RMSE 0 N", "Fz   RMSE 4 N"]
    fig = _plots.predicted_vs_reference_figure(y[:, :1], y[:, :1] + 1.5, axes=("Fz",))
    assert [ax.get_title() for ax in fig.axes if ax.get_visible()] == ["Fz   RMSE 1.5 N"]
    assert fig.axes[0].get_xlabel() == "reference Fz [N]"
    assert png_size(_plots.plot_predicted_vs_reference(y, y, tmp_path / "p3.png", axes=("Fx", "Fy", "Fz")))[0] > 0


def test_sphere_coverage_counts_reachable_and_unreachable(tmp_path):
    d = np.array([[0, 0, 1.0], [0, 0, -2.0], [1.0, 0, 0], [0, 3.0, 0]])  # not normalised on purpose
    fig = _plots.sphere_coverage_figure(d, reached=[True, True, True, False])
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert legend == ["reachable (3)", "unreachable (1)"]
    # map view: elevation of (0, 0, -2) is -90 deg, azimuth of (0, 3, 0) is 90 deg
    offsets = np.vstack([c.get_offsets() for c in fig.axes[1].collections])
    assert [-0.0, -90.0] in offsets.round(6).tolist() or [0.0, -90.0] in offsets.round(6).tolist()
    assert [90.0, 0.0] in offsets.round(6).tolist()
    assert png_size(_plots.plot_sphere_coverage(d, tmp_path / "s.png")) == (1320, 600)


def test_wrench_coverage_histogram_of_scaled_magnitude(tmp_path):
    w = np.array([[300.0, 0, 0, 0, 0, 0], [0, 0, 0, 8.0, 0, 0]])  # |[F, 50 T]| = 300 and 400
    fig = _plots.wrench_coverage_figure(w, alpha=50.0)
    counts = [p.get_height() for p in fig.axes[0].patches]
    assert sum(counts) == 2
    edges = [p.get_x() for p in fig.axes[0].patches]
    assert min(edges) == pytest.approx(300.0) and max(edges) + fig.axes[0].patches[-1].get_width() == pytest.approx(400.0)
    assert png_size(_plots.plot_wrench_coverage(w, tmp_path / "w.png", alpha=50.0)) == (1440, 480)


@pytest.mark.parametrize("axes, panels", [
    (("Fz",), [("‖F‖ [N]", "samples"), ("Fz [N]", "samples")]),
    (("Fx", "Fy", "Fz"), [("‖F‖ [N]", "samples"), ("Fx [N]", "Fy [N]")]),
    (("Fz", "Tx", "Ty"), [("‖[F, α·T]‖ [N]", "samples"), ("Fz [N]", "samples"), ("Tx [N·m]", "Ty [N·m]")]),
    (("Tz",), [("‖T‖ [N·m]", "samples"), ("Tz [N·m]", "samples")]),
])
def test_wrench_coverage_of_any_axis_set_shows_the_panels_that_exist(axes, panels, tmp_path):
    w = np.random.default_rng(0).uniform(-1, 1, (40, len(axes))) * [100.0 if a[0] == "F" else 2.0 for a in axes]
    fig = _plots.wrench_coverage_figure(w, alpha=50.0, axes=axes)
    got = [(ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes]
    assert [(x.split("   (")[0], y) for x, y in got] == panels
    # the magnitude scales the torques that exist: a plate row of Fz 0 and Tx 2 N·m counts as 100 N
    scaled = np.where([a[0] == "T" for a in axes], 50.0, 1.0) * w if "F" in "".join(a[0] for a in axes) else w
    edges = [p.get_x() for p in fig.axes[0].patches]
    assert max(edges) + fig.axes[0].patches[-1].get_width() == pytest.approx(np.linalg.norm(scaled, axis=1).max())
    assert png_size(_plots.plot_wrench_coverage(w, tmp_path / "w.png", alpha=50.0, axes=axes))[1] == 480


@pytest.mark.parametrize(
    "call, fragment",
    [
        (lambda p: _plots.plot_error_distributions({}, p), "errors is empty"),
        (lambda p: _plots.plot_error_distributions({"m": []}, p), "errors['m']"),
        (lambda p: _plots.plot_axis_errors({"m": [1, 2, 3]}, p, axes=("Fx", "Fy", "Fz", "Tx", "Ty", "Tz")), "6 values"),
        (lambda p: _plots.plot_axis_errors({"m": [1, 2, 3], "n": [1, 2]}, p), "3 values"),
        (lambda p: _plots.plot_axis_errors({"m": [1, 2]}, p, axes=("Fz", "Fz")), "name each of the"),
        (lambda p: _plots.plot_predicted_vs_reference(np.zeros((3, 6)), np.zeros((4, 6)), p), "must match"),
        (lambda p: _plots.plot_predicted_vs_reference(np.zeros((3, 5)), np.zeros((3, 5)), p, axes=("Fx", "Fy", "Fz")),
         "(n_samples >= 1, 3 [Fx, Fy, Fz])"),
        (lambda p: _plots.plot_predicted_vs_reference(np.zeros((3, 3)), np.zeros((3, 2)), p), "(n_samples >= 1, 3"),
        (lambda p: _plots.plot_wrench_coverage(np.ones((2, 3)), p, axes=("Fz", "Tx", "Ty", "Tz")),
         "(n_samples >= 1, 4 [Fz, Tx, Ty, Tz])"),
        (lambda p: _plots.plot_sphere_coverage(np.zeros((2, 3)), p), "non-zero"),
        (lambda p: _plots.plot_sphere_coverage(np.ones((2, 3)), p, reached=[True]), "reached"),
        (lambda p: _plots.plot_wrench_coverage(np.ones((2, 6)), p, alpha=-1.0), "alpha"),
    ],
)
def test_bad_input_raises_a_clear_error(tmp_path, call, fragment):
    with pytest.raises(CalibrationInputError, match=None) as info:
        call(tmp_path / "x.png")
    assert fragment in str(info.value)
    assert not (tmp_path / "x.png").exists()


def test_plot_path_must_be_png(tmp_path):
    with pytest.raises(CalibrationInputError, match=r"\.png"):
        _plots.plot_axis_errors({"m": np.ones(6)}, tmp_path / "plot.jpg")


def test_model_colours_follow_the_thesis():
    assert _plots.model_color("directional") == "#1f77b4"  # blue, as in Fig. 5
    assert _plots.model_color("comparative") == "#d62728"  # red
    # one colour per name, whatever the model's position in a figure (one model never gets two colours)
    assert _plots.model_color("polynomial", 0) == _plots.model_color("polynomial", 1)
