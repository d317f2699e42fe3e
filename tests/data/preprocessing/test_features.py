import numpy as np
import pytest
from scipy import stats

from common.errors import InputError
from data.preprocessing.features import FEATURE_GROUPS, compute_features, feature_names

CHANNELS = [f"r_{k:02d}_ohm" for k in range(1, 13)]
ALL = {g: True for g in FEATURE_GROUPS}


def test_full_list_has_74_features_with_named_columns():
    names = feature_names(CHANNELS, ALL)
    assert len(names) == 74 == 4 * 12 + 4 + 2 * 11
    assert len(set(names)) == 74
    assert names[:2] == ["raw:r_01_ohm", "raw:r_02_ohm"]
    assert "ratio:r_11_ohm/r_12_ohm" in names and "stats:kurtosis" in names
    assert compute_features(np.ones((3, 12)), ALL).shape == (3, 74)


@pytest.mark.parametrize("group, width", [("raw", 12), ("log1p", 12), ("sqrt", 12), ("zscore", 12),
                                          ("stats", 4), ("pair_products", 11), ("pair_ratios", 11)])
def test_each_group_switches_on_alone(group, width):
    only = {g: g == group for g in FEATURE_GROUPS}
    assert len(feature_names(CHANNELS, only)) == width
    assert compute_features(np.random.default_rng(0).uniform(1, 2, (5, 12)), only).shape == (5, width)


@pytest.mark.parametrize("readings", [
    np.zeros((1, 12)),
    np.full((1, 12), 1234.5),                        # all channels equal: std = 0
    np.full((1, 12), 1e12),
    np.r_[np.zeros(11), 1e12][None],                 # one live channel among dead ones
    np.r_[np.full(11, 1e12), 0.0][None],             # one dead channel
    np.full((1, 12), 5e-324),                        # denormals
    np.random.default_rng(1).uniform(0, 1e12, (200, 12)),
    10.0 ** np.random.default_rng(2).uniform(-12, 12, (200, 12)),
])
def test_features_are_finite_for_finite_non_negative_input(readings):
    for dtype in (np.float64, np.float32):
        assert np.isfinite(compute_features(readings.astype(dtype), ALL)).all()


def test_constant_sample_has_zero_zscore_skew_and_kurtosis():
    out = compute_features(np.full((2, 12), 7.0), {"zscore": True, "stats": True})
    np.testing.assert_array_equal(out[:, :12], 0.0)
    np.testing.assert_array_equal(out[:, 12:], [[7.0, 0.0, 0.0, 0.0]] * 2)


def test_closed_form_moments_match_scipy():
    r = np.random.default_rng(3).lognormal(8, 1, (50, 12))
    mean, std, skew, kurt = compute_features(r, {"stats": True}).T
    np.testing.assert_allclose(mean, r.mean(axis=1))
    np.testing.assert_allclose(std, r.std(axis=1))
    np.testing.assert_allclose(skew, stats.skew(r, axis=1), rtol=1e-9)
    np.testing.assert_allclose(kurt, stats.kurtosis(r, axis=1), rtol=1e-9)


def test_pair_operators_use_neighbouring_channels():
    r = np.arange(1.0, 13.0)[None]
    products = compute_features(r, {"pair_products": True})
    ratios = compute_features(r, {"pair_ratios": True})
    np.testing.assert_allclose(products[0], r[0, :-1] * r[0, 1:])
    # the guard is 1e-4 of the sample's total reading (78 here)
    np.testing.assert_allclose(ratios[0], r[0, :-1] / (r[0, 1:] + 1e-4 * r.sum()), rtol=1e-15)


def test_ratios_of_normalised_channels_stay_bounded_at_exact_zeros():
    """Min-max normalised channels are exactly 0 at their minimum: a fixed 1e-8 guard gave 7.9e7."""
    r = np.array([[0.79, 0.0, 0.5, 0.0, 1.0, 0.3, 0.0, 0.0, 0.2, 0.9, 0.4, 0.6],
                  [1.0] + [0.0] * 11,                                    # the worst case: 1 / (1e-4 * 1)
                  [0.0] * 12])
    ratios = compute_features(r, {"pair_ratios": True})
    assert np.isfinite(ratios).all() and np.abs(ratios).max() <= 1e4 * (1 + 1e-12)
    np.testing.assert_allclose(ratios[0, 0], 0.79 / (1e-4 * r[0].sum()))
    np.testing.assert_allclose(ratios[1, 0], 1e4)
    np.testing.assert_array_equal(ratios[2], 0.0)
    # a normalised reading slightly below 0 (raw ohms under the training minimum) cannot cancel the guard
    assert np.isfinite(compute_features(np.array([[0.5, -1e-4, 0.5] + [0.0] * 9]), {"pair_ratios": True})).all()


def test_bad_feature_config_is_a_clear_error():
    with pytest.raises(InputError, match="unknown feature group"):
        feature_names(CHANNELS, {"raw": True, "fourier": True})
    with pytest.raises(InputError, match="no feature group"):
        compute_features(np.ones((1, 12)), {g: False for g in FEATURE_GROUPS})
    with pytest.raises(InputError, match="2-D"):
        compute_features(np.ones(12), ALL)
