"""What a reader must be able to see in ftcal's figures: a colour of its own per model (the same in every
figure), bar labels that do not overprint, a legend over no value, and the largest errors drawn on top (not
hidden under the crowd). Each is checked on the rendered figure (artist geometry after a draw), not on the code."""

from __future__ import annotations

import itertools

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_hex

import ftcal
from ftcal.reporting import _plots
from ftcal.calibrators import stock_baselines

#: Every name a figure of ftcal can show: the registry's calibrators and the stock baselines.
ALL_MODELS = list(ftcal.compose.CALIBRATOR_NAMES) + list(stock_baselines(6))


def _draw(fig):
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return canvas.get_renderer()


def _bar_colours(ax) -> dict[str, str]:
    handles, labels = ax.get_legend_handles_labels()
    if not labels:
        handles, labels = ax.figure.legends[0].legend_handles, [t.get_text() for t in ax.figure.legends[0].texts]
    return {label: to_hex(h.get_facecolor()) for h, label in zip(handles, labels)}


def test_every_model_of_a_dataset_comparison_has_its_own_colour():
    """dataset_rmse.png showed linear and axis_nonlinear (and sk_linear) in the same grey."""
    fig = _plots.axis_errors_figure({name: np.linspace(1, 2, 6) + k for k, name in enumerate(ALL_MODELS)})
    colours = {}
    for patch in fig.axes[0].patches:
        colours.setdefault(patch.get_label(), to_hex(patch.get_facecolor()))
    drawn = {name: to_hex(_plots.model_color(name)) for name in ALL_MODELS}
    assert len(set(drawn.values())) == len(ALL_MODELS), drawn
    legend = {t.get_text(): to_hex(h.get_facecolor()) for t, h in zip(fig.legends[0].texts, fig.legends[0].legend_handles)}
    assert len(set(legend.values())) == len(ALL_MODELS) and legend == drawn


def test_a_model_keeps_its_colour_across_figures_and_positions():
    """One colour table by name: the same model is drawn alike wherever it appears."""
    rng = np.random.default_rng(0)
    first = _plots.axis_errors_figure({"linear": np.ones(6), "polynomial": np.ones(6)})
    second = _plots.axis_errors_figure({"gaussian_process": np.ones(6), "sk_gp": np.ones(6), "polynomial": np.ones(6)})
    dist = _plots.error_distributions_figure({"sk_gp": rng.random(5), "polynomial": rng.random(5)})
    colour = lambda fig, name: next(to_hex(h.get_facecolor()) for t, h in zip(fig.legends[0].texts, fig.legends[0].legend_handles)
                                    if t.get_text() == name)
    assert colour(first, "polynomial") == colour(second, "polynomial") == to_hex(_plots.model_color("polynomial"))
    # the box of 'polynomial' in the distribution plot carries the same colour
    boxes = [line for line in dist.axes[0].lines if to_hex(line.get_color()) == to_hex(_plots.model_color("polynomial"))]
    assert boxes
    # a name outside the table keeps one colour too (derived from the name, not the position)
    assert _plots.model_colors(["a", "my_model"])["my_model"] == _plots.model_colors(["my_model"])["my_model"]
    assert len(set(_plots.model_colors([f"custom{i}" for i in range(8)]).values())) == 8


def _overlaps(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def test_equal_bars_labels_do_not_overprint():
    """Two models with equal per-axis RMSE printed '0.1680.168' as one blur."""
    values = np.full(6, 0.168)
    fig = _plots.axis_errors_figure({"linear": values, "sk_linear": values, "polynomial": values, "sk_poly2": values})
    renderer = _draw(fig)
    for ax in fig.axes:
        labels = [t for t in ax.texts if t.get_text() == "0.168"]
        assert len(labels) == 3 * 4
        boxes = [t.get_window_extent(renderer) for t in labels]
        for a, b in itertools.combinations(boxes, 2):
            assert not _overlaps(a, b)


def test_the_legend_hides_no_bar_and_no_value():
    """In axis_rmse.png the legend sat on top of the Fx bars and their values."""
    fig = _plots.axis_errors_figure({"linear": [5.0, 0.1, 0.1, 0.2, 0.1, 0.1], "directional": [4.8, 0.1, 0.1, 0.2, 0.1, 0.1],
                                     "auto": [4.9, 0.1, 0.1, 0.2, 0.1, 0.1]})
    renderer = _draw(fig)
    legend = fig.legends[0].get_window_extent(renderer)
    for ax in fig.axes:
        for artist in list(ax.patches) + list(ax.texts):
            assert not _overlaps(legend, artist.get_window_extent(renderer)), artist


def test_the_largest_errors_are_drawn_on_top_and_marked_beyond_the_band():
    """The report's error-vs-load panels: a few large errors among many small ones are drawn last, in their own
    colour, and a band half-width of 1 % FS is shaded."""
    rng = np.random.default_rng(0)
    applied = rng.uniform(-100, 100, size=(3000, 3))
    err = 0.2 * rng.normal(size=(3000, 3))
    big = rng.choice(3000, size=5, replace=False)
    err[big, 1] = [5.0, -7.0, 6.0, -4.0, 9.0]
    fig = _plots.error_vs_load_figure(applied, err, axis_names=["Fx", "Fy", "Fz"], units=["N"] * 3,
                                      band_pct_fs=[1.0, 1.0, 1.0], max_points=1000)
    _draw(fig)
    ax = fig.axes[1]
    collections = [c for c in ax.collections if len(c.get_offsets())]
    last = collections[-1]  # drawn last = on top
    assert sorted(np.abs(last.get_offsets()[:, 1])) == sorted(np.abs(err[big, 1]))
    assert to_hex(last.get_facecolor()[0]) != to_hex(collections[-2].get_facecolor()[0])
    # the subsample of a crowd keeps every large error, and draws no more than asked
    assert sum(len(c.get_offsets()) for c in collections) <= 1000
    band = [p for p in ax.patches if p.get_label().startswith("±1 % FS")]
    assert len(band) == 1
