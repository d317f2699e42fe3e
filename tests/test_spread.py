"""The one mean ± sd every report writes: sample sd (ddof 1), 0 for a single value."""
import numpy as np

from common.spread import format_mean_sd, mean_and_sd


def test_sample_standard_deviation_and_a_single_value():
    assert mean_and_sd([1.0, 2.0, 3.0]) == (2.0, 1.0)
    assert mean_and_sd([4.5]) == (4.5, 0.0)
    values = np.random.default_rng(0).normal(size=7)
    assert np.isclose(mean_and_sd(values)[1], np.std(values, ddof=1))


def test_format_takes_one_spec_for_both_numbers():
    assert format_mean_sd([1000, 2000, 3500], ",.0f") == "2,167 ± 1,258"
    assert format_mean_sd([1, 2], ".2f", " +- ") == "1.50 +- 0.71"
