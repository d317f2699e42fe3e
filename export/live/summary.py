"""What a live stream did, counted as it runs in fixed memory, said once at its end.

Latencies go into a log-spaced histogram (0.1 µs to 100 s, bins 0.5 % wide) rather than a list:
a stream of hours keeps the same few kilobytes, and a percentile read from it is within half a
percent of the exact one.
"""
import json
import math
import time

LOWEST_US, HIGHEST_US = 0.1, 1e8
BINS_PER_E = 200          # e-fold per 200 bins: each bin 0.5 % wide
N_BINS = int(math.log(HIGHEST_US / LOWEST_US) * BINS_PER_E) + 1
LOG_LOWEST = math.log(LOWEST_US)


class LatencyHistogram:
    def __init__(self):
        self.counts = [0] * N_BINS
        self.n = 0
        self.total_us = 0.0

    def add(self, us: float) -> None:
        k = int((math.log(us) - LOG_LOWEST) * BINS_PER_E) if us > LOWEST_US else 0
        self.counts[k if k < N_BINS else N_BINS - 1] += 1
        self.n += 1
        self.total_us += us

    def percentile(self, q: float) -> float | None:
        """The q-th percentile in µs (a bin's centre); None before any value."""
        if not self.n:
            return None
        rank, seen = max(math.ceil(q / 100 * self.n), 1), 0   # nearest rank: p99 of 3 values is the largest
        for k, count in enumerate(self.counts):
            seen += count
            if seen >= rank:
                return LOWEST_US * math.exp((k + 0.5) / BINS_PER_E)
        return HIGHEST_US

    def mean(self) -> float | None:
        return self.total_us / self.n if self.n else None


class ModelTime(LatencyHistogram):
    """The model's own time per call: wall time into the histogram, and its CPU time summed (on a
    busy machine the wall time includes waiting for a core; the CPU time does not)."""

    def __init__(self):
        super().__init__()
        self.cpu_us = 0.0

    def call(self, function, *args):
        wall, cpu = time.perf_counter(), time.thread_time()
        result = function(*args)
        self.cpu_us += (time.thread_time() - cpu) * 1e6
        self.add((time.perf_counter() - wall) * 1e6)
        return result


class Summary:
    """Counts of lines and predictions, latency per prediction (line taken -> its output line
    ready) and the model's own time per call (onnxruntime, or the tracker's update)."""

    def __init__(self):
        self.read = self.predicted = self.skipped = self.dropped = self.waiting_for_window = 0
        self.latency = LatencyHistogram()
        self.model = ModelTime()
        self.seconds = self.cpu_seconds = 0.0

    def as_dict(self) -> dict:
        def rounded(value):
            return None if value is None else round(value, 2)
        return {"lines_read": self.read, "predicted": self.predicted, "skipped": self.skipped,
                "dropped": self.dropped, "not_predicted": self.waiting_for_window,
                "latency_us": {"p50": rounded(self.latency.percentile(50)), "p99": rounded(self.latency.percentile(99)),
                               "mean": rounded(self.latency.mean())},
                "model_us": {"p50": rounded(self.model.percentile(50)), "p99": rounded(self.model.percentile(99)),
                             "mean": rounded(self.model.mean()), "calls": self.model.n,
                             "cpu_mean": rounded(self.model.cpu_us / self.model.n if self.model.n else None)},
                "seconds": round(self.seconds, 3), "cpu_seconds": round(self.cpu_seconds, 3),
                "wall_us_per_prediction": rounded(self.seconds * 1e6 / self.predicted if self.predicted else None),
                "cpu_us_per_prediction": rounded(self.cpu_seconds * 1e6 / self.predicted if self.predicted else None)}

    def text(self, unit: str = "lines") -> str:
        """One line for stderr at the end of the stream."""
        d = self.as_dict()
        parts = [f"{self.read} {unit} read", f"{self.predicted} predicted", f"{self.skipped} skipped (bad)"]
        if self.dropped:
            parts.append(f"{self.dropped} dropped (backlog=drop)")
        if self.waiting_for_window:
            parts.append(f"{self.waiting_for_window} not predicted (a window filling, between hops, or the tracker's rest frames)")
        latency = (f"latency p50 {d['latency_us']['p50']:,.0f} µs, p99 {d['latency_us']['p99']:,.0f} µs"
                   if self.latency.n else "no latency (nothing predicted)")
        return f"stream ended: {', '.join(parts)}; {latency} in {self.seconds:.1f} s"

    def json(self) -> str:
        return json.dumps(self.as_dict())
