"""The live view for a person at the rig (predict.py --plot): the last few hundred lines of
readings on top, then one panel per predicted quantity (each on its own scale: a pressure in Pa
beside a position in mm would flatten the position), redrawn a few times a second from the live
loop's own thread. plot_file=PNG saves the last view when the stream ends, also without a screen.
"""
import time
from collections import deque

import numpy as np

HISTORY = 500            # lines kept on screen
REDRAW_S = 0.2           # at most five redraws a second
MOST_READINGS = 8        # channels drawn (a contact grid would be hundreds of lines)
MOST_PANELS = 4          # predicted quantities drawn, one panel each


class LivePlot:
    def __init__(self, input_columns: list[str], output_columns: list[str], title: str, show: bool,
                 file: str | None = None):
        import matplotlib
        if not show:
            matplotlib.use("Agg")  # no screen needed to save the view
        import matplotlib.pyplot as plt
        self.plt, self.show, self.file, self.title = plt, show, file, title
        self.readings_names = input_columns[:MOST_READINGS]
        self.output_columns = output_columns
        self.numeric = None    # which output values are numbers, found on the first prediction
        self.lines_x, self.readings = deque(maxlen=HISTORY), deque(maxlen=HISTORY)
        self.pred_x, self.predictions = deque(maxlen=HISTORY), deque(maxlen=HISTORY)
        self.figure, self.axes = None, []
        if show:
            plt.ion()
        self.drawn = 0.0

    def update(self, parsed, rows) -> None:
        """parsed: (line, time_s, readings) per line; rows: [line, time_s, *values, latency_us]."""
        for number, _, readings in parsed:
            self.lines_x.append(number)
            self.readings.append(np.asarray(readings[:MOST_READINGS], dtype=float))
        for row in rows:
            values = row[2:-1]
            if self.numeric is None:
                self.numeric = [k for k, v in enumerate(values) if isinstance(v, (int, float))][:MOST_PANELS]
            self.pred_x.append(row[0])
            self.predictions.append([float(values[k]) for k in self.numeric])
        if time.perf_counter() - self.drawn >= REDRAW_S:
            self.draw()

    def _figure(self) -> None:
        """The panels, made once the predicted quantities are known."""
        panels = 1 + len(self.numeric or [])
        self.figure, axes = self.plt.subplots(panels, 1, figsize=(9, 2.2 + 1.6 * panels), sharex=True, squeeze=False)
        self.axes = list(axes[:, 0])
        self.figure.suptitle(self.title)

    def draw(self) -> None:
        self.drawn = time.perf_counter()
        if self.figure is None or (self.numeric and len(self.axes) == 1):
            if self.figure is not None:
                self.plt.close(self.figure)
            self._figure()
        top, panels = self.axes[0], self.axes[1:]
        top.clear()
        if self.readings:
            values = np.array(self.readings)
            for k, name in enumerate(self.readings_names[:values.shape[1]]):
                top.plot(np.array(self.lines_x), values[:, k], lw=1, label=name)
            top.legend(loc="upper left", fontsize=7, ncol=4)
        top.set_ylabel("readings")
        if self.predictions:
            values = np.array(self.predictions)
            for axis, k, name in zip(panels, range(values.shape[1]), (self.output_columns[j] for j in self.numeric)):
                axis.clear()
                axis.plot(np.array(self.pred_x), values[:, k], lw=1, color=f"C{k}")
                axis.set_ylabel(name, fontsize=8)
        self.axes[-1].set_xlabel("input line")
        self.figure.tight_layout()
        if self.show:
            self.figure.canvas.draw_idle()
            self.plt.pause(0.001)

    def finish(self) -> None:
        self.draw()
        if self.file:
            self.figure.savefig(self.file, dpi=100)
        self.plt.close(self.figure)
