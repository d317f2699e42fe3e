"""The live view for a person at the rig (predict.py --plot): the last few seconds of readings
above, the predictions below, redrawn a few times a second from the live loop's own thread
(a plot never slows the model more than its redraws). plot_file=PNG saves the last view when the
stream ends, also without a screen.
"""
import time
from collections import deque

import numpy as np

HISTORY = 500            # lines kept on screen
REDRAW_S = 0.2           # at most five redraws a second
MOST_READINGS = 8        # channels drawn (a contact grid would be hundreds of lines)


class LivePlot:
    def __init__(self, input_columns: list[str], output_columns: list[str], title: str, show: bool,
                 file: str | None = None):
        import matplotlib
        if not show:
            matplotlib.use("Agg")  # no screen needed to save the view
        import matplotlib.pyplot as plt
        self.plt, self.show, self.file = plt, show, file
        self.readings_names = input_columns[:MOST_READINGS]
        self.numeric = None    # which output values are numbers, found on the first prediction
        self.output_columns = output_columns
        self.lines_x, self.readings = deque(maxlen=HISTORY), deque(maxlen=HISTORY)
        self.pred_x, self.predictions = deque(maxlen=HISTORY), deque(maxlen=HISTORY)
        if show:
            plt.ion()
        self.figure, (self.top, self.bottom) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
        self.figure.suptitle(title)
        self.top.set_ylabel("readings")
        self.bottom.set_ylabel("predictions")
        self.bottom.set_xlabel("input line")
        self.drawn = 0.0

    def update(self, parsed, rows) -> None:
        """parsed: (line, time_s, readings) per line; rows: [line, time_s, *values, latency_us]."""
        for number, _, readings in parsed:
            self.lines_x.append(number)
            self.readings.append(np.asarray(readings[:MOST_READINGS], dtype=float))
        for row in rows:
            values = row[2:-1]
            if self.numeric is None:
                self.numeric = [k for k, v in enumerate(values) if isinstance(v, (int, float))][:MOST_READINGS]
            self.pred_x.append(row[0])
            self.predictions.append([float(values[k]) for k in self.numeric])
        if time.perf_counter() - self.drawn >= REDRAW_S:
            self.draw()

    def draw(self) -> None:
        self.drawn = time.perf_counter()
        for axis, x, y, names in ((self.top, self.lines_x, self.readings, self.readings_names),
                                  (self.bottom, self.pred_x, self.predictions,
                                   [self.output_columns[k] for k in (self.numeric or [])])):
            axis.clear()
            if y:
                values = np.array(y)
                for k, name in enumerate(names[:values.shape[1]]):
                    axis.plot(np.array(x), values[:, k], lw=1, label=name)
                axis.legend(loc="upper left", fontsize=7, ncol=4)
        self.top.set_ylabel("readings")
        self.bottom.set_ylabel("predictions")
        self.bottom.set_xlabel("input line")
        if self.show:
            self.figure.canvas.draw_idle()
            self.plt.pause(0.001)

    def finish(self) -> None:
        self.draw()
        if self.file:
            self.figure.savefig(self.file, dpi=100)
        self.plt.close(self.figure)
