"""The live summary's latency histogram: fixed memory, percentiles within its bins' width."""
import numpy as np

from export.live.summary import LatencyHistogram, Summary


def test_percentiles_match_the_exact_ones_within_half_a_percent():
    values = np.random.default_rng(0).lognormal(np.log(40), 0.5, 20_000)
    histogram = LatencyHistogram()
    for value in values:
        histogram.add(float(value))
    for q in (50, 99):
        exact = np.percentile(values, q, method="inverted_cdf")
        assert abs(histogram.percentile(q) / exact - 1) < 0.006, q
    assert len(histogram.counts) == len(LatencyHistogram().counts)   # memory does not grow with values


def test_p99_of_a_few_values_is_the_largest():
    histogram = LatencyHistogram()
    for value in (50, 70, 400):
        histogram.add(value)
    assert abs(histogram.percentile(99) / 400 - 1) < 0.006 and abs(histogram.percentile(50) / 70 - 1) < 0.006


def test_the_summary_line_counts_everything():
    summary = Summary()
    summary.read, summary.predicted, summary.skipped = 10, 8, 2
    summary.latency.add(30.0)
    text = summary.text()
    assert text.startswith("stream ended: 10 lines read, 8 predicted, 2 skipped (bad)") and "p50 30 µs" in text
    assert Summary().text().endswith("no latency (nothing predicted) in 0.0 s")


def test_the_model_time_keeps_wall_and_cpu_time():
    from export.live.summary import ModelTime
    clock = ModelTime()
    assert clock.call(sum, range(100_000)) == sum(range(100_000))
    assert clock.n == 1 and clock.cpu_us > 0 and clock.total_us >= clock.cpu_us * 0.5
