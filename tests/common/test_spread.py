"""The one mean ± sd every report writes: sample sd (ddof 1), 0 for a single value."""
import numpy as np

from common.spread import format_mean_and_sd, format_mean_sd, mean_and_sd


def test_sample_standard_deviation_and_a_single_value():
    assert mean_and_sd([1.0, 2.0, 3.0]) == (2.0, 1.0)
    assert mean_and_sd([4.5]) == (4.5, 0.0)
    values = np.random.default_rng(0).normal(size=7)
    assert np.isclose(mean_and_sd(values)[1], np.std(values, ddof=1))


def test_format_takes_one_spec_for_both_numbers():
    assert format_mean_sd([1000, 2000, 3500], ",.0f") == "2,167 ± 1,258"
    assert format_mean_sd([1, 2], ".2f", " +- ") == "1.50 +- 0.71"


def test_a_single_value_by_its_template_and_missing_values_left_out():
    assert format_mean_sd(np.array([2.25]), ".1f", one_value="{}") == "2.2"
    assert format_mean_sd([0.5, None], ".3f", one_value="{} (1 seed)", missing="—") == "0.500 (1 seed)"
    assert format_mean_sd([None], ".3f", missing="—") == "—"
    assert format_mean_sd([1.0, 3.0], ".1f", one_value="{}", missing="—") == "2.0 ± 1.4"


def test_a_format_that_follows_the_magnitude():
    magnitude = lambda mean: ".2f" if mean < 10 else ".0f"  # noqa: E731
    assert format_mean_sd([1.0, 2.0], magnitude, " +- ") == "1.50 +- 0.71"
    assert format_mean_sd([1000.0, 1500.0], magnitude, " +- ") == "1250 +- 354"


def test_a_computed_mean_and_sd_with_what_is_missing():
    assert format_mean_and_sd(0.81234, 0.0123, ".4f") == "0.8123 ± 0.0123"
    assert format_mean_and_sd(1234.5, float("nan"), ",.0f", missing="—") == "1,234"   # one seed: no sd
    assert format_mean_and_sd(float("nan"), 1.0, ".2f", missing="—") == "—"
