"""Every figure Touchstone writes can be read: panels in a grid (no strips), every axis named,
log axes labelled with plain numbers, no text outside the picture, no empty panels. The study
figures are the ones the studies write (rendered at tiny settings, observed on their way to
TensorBoard); the report figures are drawn from small arrays."""
import math

import matplotlib
import matplotlib.figure
import matplotlib.pyplot
import numpy as np
import pandas as pd
import pytest

from runs.report import plots
from runs.report.analysis import identifiability_map
from runs.report.pareto import figure as pareto_figure
from runs.report.pareto import summarise
from runs.report.tensorboard_logger import TensorBoardLogger
from runs.run import run

MAX_ASPECT = 3.5          # width / height of the PNG
MIN_FONT_PT = 6


def _visible_texts(figure):
    return [t for t in figure.findobj(matplotlib.text.Text) if t.get_visible() and t.get_text().strip()]


def assert_readable(figure, name):
    width, height = figure.get_size_inches()
    assert width / height <= MAX_ASPECT and height / width <= MAX_ASPECT, f"{name}: {width:.1f} x {height:.1f} in"
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    box = figure.bbox
    for text in _visible_texts(figure):
        assert text.get_fontsize() >= MIN_FONT_PT, f"{name}: '{text.get_text()}' at {text.get_fontsize()} pt"
    for ax in figure.axes:
        if ax.get_label() == "<colorbar>":
            assert ax.get_ylabel() or ax.get_xlabel(), f"{name}: a colour bar without its quantity"
            continue
        assert ax.has_data(), f"{name}: an empty panel ({ax.get_title()!r})"
        for axis, shared in ((ax.xaxis, figure.get_supxlabel()), (ax.yaxis, figure.get_supylabel())):
            numbered = axis.get_visible() and any(t.get_visible() and t.get_text() for t in axis.get_ticklabels())
            if numbered:
                assert axis.get_label_text() or shared, f"{name}: panel {ax.get_title()!r} has an unnamed axis"
            if axis.get_scale() == "log" and axis.get_visible():
                low, high = sorted(axis.get_view_interval())
                shown = [label.get_text() for label, at in zip(axis.get_ticklabels(), axis.get_ticklocs())
                         if low <= at <= high and label.get_text()]
                assert len(shown) >= 2 and not any("$" in s or "^" in s for s in shown), \
                    f"{name}: log axis ticks {shown}"
        for text in (ax.title, ax.xaxis.label, ax.yaxis.label):
            if text.get_visible() and text.get_text():
                extent = text.get_window_extent(renderer)
                assert extent.x0 >= box.x0 - 1 and extent.x1 <= box.x1 + 1 and extent.y0 >= box.y0 - 1 \
                    and extent.y1 <= box.y1 + 1, f"{name}: '{text.get_text()}' runs off the picture"
    matplotlib.pyplot.close(figure)


@pytest.fixture
def written_figures(monkeypatch):
    """{name: figure} of every figure a run draws: those it sends to TensorBoard by their tag, and
    any other it closes (the contact animation's frame), kept open for the checks."""
    seen = {}
    original = TensorBoardLogger.log_figure

    def log_figure(self, tag, figure):
        seen[tag] = figure
        original(self, tag, figure)

    def close(figure=None):   # checked, then closed, here
        if isinstance(figure, matplotlib.figure.Figure) and figure not in seen.values():
            seen[f"closed figure {len(seen)}"] = figure

    monkeypatch.setattr(TensorBoardLogger, "log_figure", log_figure)
    monkeypatch.setattr(matplotlib.pyplot, "close", close)
    yield seen
    monkeypatch.undo()
    matplotlib.pyplot.close("all")


def test_the_taxel_study_draws_ten_cover_models_in_a_grid(compose_config, tmp_path, written_figures):
    run(compose_config(["experiment=taxel_receptive_field", "study.thickness_um=[150,300,600]", "study.n_points=101"]),
        tmp_path)
    profiles = written_figures["taxels/receptive_field"]
    assert len([ax for ax in profiles.axes if ax.has_data()]) == 10
    assert "Effects of the elastic cover" in profiles.get_suptitle()
    for tag, figure in written_figures.items():
        assert_readable(figure, tag)


ERT = ["study.seeds=[0,1]", "study.calibration.grid_points_per_side=4", "scene.grid_points_per_side=4",
       "scene.grid_nodes=21", "study.reconstruction.pixels_per_side=8"]


@pytest.mark.parametrize("overrides", [
    ["experiment=ert_injection", "scene=ert_internal", "study.pair_counts=[12,24]"],
    ["experiment=ert_force", "scene=ert_boundary", "scene.injection=adjacent", "study.n_blank=10"],
    ["experiment=ert_localisation", "scene=ert_boundary", "scene.injection=adjacent", "study.n_blank=10",
     "study.compare.kinds=[]"],
])
def test_the_ert_studies_figures_are_readable(compose_config, tmp_path, written_figures, overrides):
    run(compose_config(overrides + ERT), tmp_path)
    assert written_figures
    for tag, figure in written_figures.items():
        assert_readable(figure, tag)


def test_the_contact_animation_frame_is_readable(compose_config, tmp_path, written_figures):
    run(compose_config(["experiment=capacitive_tracking", "scene.sessions=[hold,cross]", "scene.session_s=1.0",
                        "scene.gap_s=0.2", "scene.n_rest_frames=30", "study.force_repetitions=3",
                        "study.animation.max_frames=4", "study.animation.n_panels=2"]), tmp_path)
    assert written_figures
    for tag, figure in written_figures.items():
        assert_readable(figure, tag)


@pytest.mark.parametrize("targets", [["x_mm", "y_mm", "depth_mm", "pressure_pa"],
                                     ["x_mm", "y_mm", "normal_n", "shear_x_n", "shear_y_n"], ["force_n"]])
def test_regression_figures_put_one_panel_per_target_in_a_grid(targets):
    rng = np.random.default_rng(0)
    y = rng.uniform(1, 50, (40, len(targets)))
    pred = y + rng.normal(0, 2, y.shape)
    for name, figure in (("parity", plots.parity_figure(y, pred, targets, dict.fromkeys(targets, 0.9))),
                         ("residuals", plots.residual_figure(y, pred, targets)),
                         ("uncertainty", plots.uncertainty_figure(y, pred, pred - 4, pred + 4, targets))):
        assert len(figure.axes) == len(targets)
        assert "(mm)" in figure.axes[0].get_xlabel() or "(N)" in figure.axes[0].get_xlabel()
        assert_readable(figure, name)


def test_analysis_importance_correlation_and_confusion_figures_are_readable():
    rng = np.random.default_rng(1)
    targets = ["x_mm", "y_mm", "depth_mm", "pressure_pa"]
    xy, depth = rng.uniform(0, 50, (60, 2)), rng.uniform(0.3, 3.0, 60)
    sigma, error = rng.uniform(0.1, 2, (60, 4)), rng.uniform(0, 2, (60, 4))
    figures = {"identifiability": plots.identifiability_figure(identifiability_map(xy, depth, sigma, error, targets)),
               "importances": plots.importance_figure([f"raw:r_{k:02d}_ohm" for k in range(30)], rng.random(30),
                                                      "feature importances"),
               "correlation": plots.correlation_figure(np.corrcoef(rng.random((8, 50))), [f"f{k}" for k in range(8)]),
               "confusion": plots.confusion_figure(rng.integers(0, 5, (13, 13)), [f"class_{k}" for k in range(13)],
                                                   "validation accuracy")}
    for name, figure in figures.items():
        assert_readable(figure, name)


@pytest.mark.parametrize("latency", [[5.0, 30.0, 80.0], [np.nan] * 3])
def test_the_sweep_figure_labels_its_log_axes_and_draws_no_empty_panel(latency):
    jobs = pd.DataFrame({"job": ["0", "1", "2"], "status": "ok", "score_metric": "R² (mean over targets)",
                         "label": ["model=a", "model=b", "model=c"], "seed": "0", "val_score": [0.8, 0.85, 0.9],
                         "test_score": 0.8, "fit_time_s": [0.5, 1.2, 4.0], "latency_p50_us": latency,
                         "model_size_bytes": 1e6})
    figure = pareto_figure(summarise(jobs))
    assert len(figure.axes) == (1 if np.isnan(latency).all() else 2)
    assert_readable(figure, "pareto")


@pytest.mark.parametrize("n, columns", [(1, 1), (3, 3), (4, 2), (5, 3), (10, 4), (16, 4)])
def test_panel_grid_never_makes_a_strip(n, columns):
    figure, axes = plots.panel_grid(n)
    assert len(axes) == len(figure.axes) == n
    assert axes[0].get_gridspec().ncols == columns and axes[0].get_gridspec().nrows == math.ceil(n / columns)
    matplotlib.pyplot.close(figure)


@pytest.mark.parametrize("column, label", [("depth_mm", "depth (mm)"), ("shear_x_n", "shear x (N)"),
                                           ("pressure_pa", "pressure (Pa)"), ("thickness_um", "thickness (µm)"),
                                           ("quality", "quality"), ("r_01_ohm", "r 01 (Ω)")])
def test_a_column_name_becomes_its_quantity_and_unit(column, label):
    assert plots.quantity_label(column) == label


# -- a figure says what it shows (issue 45) ---------------------------------------------------

SHEET = ["x_mm", "y_mm", "depth_mm", "pressure_pa"]


def _sheet_predictions(seed=0):
    """Test rows of the default run's size and ranges: pressures up to 240 kPa in pascals."""
    rng = np.random.default_rng(seed)
    y = np.column_stack([rng.choice([12.5, 25, 37.5], 70), rng.choice([12.5, 25, 37.5], 70),
                         rng.uniform(0.3, 3.0, 70), rng.uniform(2e3, 2.4e5, 70)])
    mean = y + rng.normal(0, 1, y.shape) * [3, 3, 0.2, 1.5e4]
    return y, mean, mean - [10, 10, 0.4, 3e4], mean + [10, 10, 0.4, 3e4]


def _overlapping_ticks(figure) -> list[str]:
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    found = []
    for ax in figure.axes:
        for axis in (ax.xaxis, ax.yaxis):
            labels = [t for t in axis.get_ticklabels() if t.get_visible() and t.get_text()]
            boxes = [t.get_window_extent(renderer) for t in labels]
            found += [f"{ax.get_title()}: {labels[i].get_text()} / {labels[j].get_text()}"
                      for i in range(len(boxes)) for j in range(i + 1, len(boxes)) if boxes[i].overlaps(boxes[j])]
    return found


def test_uncertainty_tick_labels_do_not_overlap_on_a_pressure_panel():
    """The default run's pressure panel printed 50000 100000 150000 ... into each other."""
    figure = plots.uncertainty_figure(*_sheet_predictions(), SHEET, model="resmlp_seeds")
    assert _overlapping_ticks(figure) == []
    assert_readable(figure, "uncertainty")


def test_regression_figures_name_their_model():
    y, mean, lower, upper = _sheet_predictions()
    for figure in (plots.parity_figure(y, mean, SHEET, model="resmlp_seeds"),
                   plots.residual_figure(y, mean, SHEET, model="resmlp_seeds"),
                   plots.uncertainty_figure(y, mean, lower, upper, SHEET, model="resmlp_seeds")):
        assert figure.get_suptitle().startswith("resmlp_seeds: "), figure.get_suptitle()
        matplotlib.pyplot.close(figure)


@pytest.mark.parametrize("samples", ["rows", "windows"])
def test_the_confusion_colour_bar_counts_what_was_classified(samples):
    figure = plots.confusion_figure(np.array([[5, 1], [0, 4]]), ["left", "right"], "test accuracy 0.9",
                                    samples=samples)
    (bar,) = [ax for ax in figure.axes if ax.get_label() == "<colorbar>"]
    assert bar.get_ylabel() == f"share of the true class's {samples} (–)"
    matplotlib.pyplot.close(figure)
