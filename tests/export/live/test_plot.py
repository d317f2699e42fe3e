"""The live view: drawn from the loop's rows without a screen, saved as PNG when asked."""
import numpy as np

from export.live.plot import LivePlot


def test_the_view_is_saved_with_readings_and_numeric_predictions(tmp_path):
    png = tmp_path / "live.png"
    plot = LivePlot(["a_ohm", "b_ohm"], ["predicted", "p_soft", "p_hard"], "test", show=False, file=str(png))
    parsed = [(k, None, np.array([k, 2.0 * k])) for k in range(1, 30)]
    rows = [[k, 0.0, "soft", 0.7, 0.3, 12.0] for k in range(1, 30)]
    plot.update(parsed, rows)
    assert plot.numeric == [1, 2]          # the class name is not drawn, its probabilities are
    plot.finish()
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
