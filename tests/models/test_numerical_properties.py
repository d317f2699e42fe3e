"""Hard cases stay numerically stable: property-based tests with explicit strategies for the
regions where sensors near percolation live (0 to 1e12 ohm, exact zeros, denormals, equal or
dead channels) and min-max normalised channels (in [0, 1], exact zeros), in float32 and float64.

Example counts (profile "ci"): features 3000 + normalised ratios 1000 + ONNX parity 2000 +
virtual force levels 1500 + metrics 1500 + blend weights 1000 + conformal 1000 = 11,000 per CI
run. The "thorough" profile multiplies each by 20.
"""
import numpy as np
import pytest
import torch
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from common.errors import InputError
from data.preprocessing.features import FEATURE_GROUPS, compute_features
from data.preprocessing.virtual_force_levels import virtual_force_levels
from models.uncertainty import conformal_quantile, normalised_scores
from models.weighted_blend import validation_weights
from runs.report.metrics import nonzero_rows, regression_metrics

ALL = list(FEATURE_GROUPS)
def examples(n):
    """n examples under the "ci" profile (max_examples 100), proportionally more under "thorough"."""
    return settings(max_examples=n * settings().max_examples // 100)


# Resistances as sensors produce them: exact zeros, denormals, tiny, ordinary, huge, open circuits.
special = st.sampled_from([0.0, 5e-324, 1e-300, 1e-12, 1e-3, 1.0, 1.7e4, 1e9, 1e12])
ordinary = st.floats(min_value=0.0, max_value=1e12, allow_nan=False, allow_infinity=False)
readings_value = st.one_of(special, ordinary)


@st.composite
def readings(draw, n_channels=12):
    rows = draw(st.integers(1, 4))
    kind = draw(st.sampled_from(["free", "equal", "dead", "one_live"]))
    data = draw(arrays(np.float64, (rows, n_channels), elements=readings_value))
    if kind == "equal":
        data[:] = data[:, :1]
    elif kind == "dead":
        data[:, draw(st.integers(0, n_channels - 1))] = 0.0
    elif kind == "one_live":
        live = draw(st.integers(0, n_channels - 1))
        data[:, [c for c in range(n_channels) if c != live]] = 0.0
    return data


@examples(3000)
@given(readings(), st.sampled_from([np.float64, np.float32]))
@example(np.zeros((1, 12)), np.float64)
@example(np.full((1, 12), 1e12), np.float32)
@example(np.full((1, 12), 5e-324), np.float64)
@example(np.full((1, 12), 1.22167959e11), np.float64)  # found by Hypothesis: z-scores were +/-1
def test_features_are_finite_and_defined_everywhere(r, dtype):
    features = compute_features(r.astype(dtype), ALL)
    assert np.isfinite(features).all()
    equal = (r.astype(dtype).astype(np.float64) == r.astype(dtype).astype(np.float64)[:, :1]).all(axis=1)
    # all-equal channels: z-scores, skew and (excess) kurtosis are defined as 0
    assert (features[equal][:, 36:48] == 0).all() and (features[equal][:, 50:52] == 0).all()


# Min-max normalised channels (scene=rubber12_lab): unitless in [0, 1], exactly 0 at each
# channel's minimum and 1 at its maximum, so exact zeros are common in a sample.
unit_value = st.one_of(st.sampled_from([0.0, 0.0, 1.0, 5e-324, 1e-12, 1e-6]), st.floats(0.0, 1.0))


@st.composite
def normalised_readings(draw, n_channels=12):
    rows = draw(st.integers(1, 4))
    return draw(arrays(np.float64, (rows, n_channels), elements=unit_value))


RATIOS = slice(52, 63)  # 48 + 4 stats + 11 products, then the 11 ratios


@examples(1000)
@given(normalised_readings(), st.sampled_from([np.float64, np.float32]))
@example(np.array([[0.79, 0.0, 0.5, 0.0, 1.0, 0.3, 0.0, 0.0, 0.2, 0.9, 0.4, 0.6]]), np.float64)  # was 7.9e7
@example(np.r_[1.0, np.zeros(11)][None], np.float64)  # one live channel: the bound itself
def test_ratios_of_normalised_channels_stay_bounded(r, dtype):
    features = compute_features(r.astype(dtype), ALL)
    assert np.isfinite(features).all()
    assert np.abs(features[:, RATIOS]).max() <= 1e4 * (1 + 1e-12)


@pytest.fixture(scope="module")
def features_session():
    import onnxruntime as ort

    from export.torch_graphs import PhysicsFeatures, to_onnx
    model = to_onnx(PhysicsFeatures(ALL), torch.ones(2, 12, dtype=torch.float64), "channels", "features", 18)
    return ort.InferenceSession(model.SerializeToString())


@examples(2000)
@given(r=st.one_of(readings(), normalised_readings()))
@example(r=np.zeros((1, 12)))
@example(r=np.r_[1.0, np.zeros(11)][None])
@example(r=np.r_[np.full(11, 1e12), 0.0][None])
def test_exported_features_match_numpy(features_session, r):
    onnx_features = features_session.run(None, {"channels": r})[0]
    numpy_features = compute_features(r, ALL)
    assert np.isfinite(onnx_features).all()
    # both in float64; summation order differs, so agree to ~1e-12 of each feature's magnitude,
    # except shape statistics of nearly constant samples, which are pure rounding noise
    scale = np.maximum(np.abs(numpy_features), 1.0)
    close = np.abs(onnx_features - numpy_features) <= 1e-9 * scale
    close[:, 50:52] |= np.abs(onnx_features[:, 50:52] - numpy_features[:, 50:52]) < 1e-3 + 1e-6 * np.abs(numpy_features[:, 50:52])
    assert close.all(), np.argwhere(~close)[:5]


@st.composite
def window_sets(draw):
    levels = draw(st.lists(st.sampled_from([1.0, 5.0, 10.0, 15.0, 20.0, 25.0]), min_size=2, max_size=12))
    n = len(levels)
    windows = draw(arrays(np.float64, (n, 2, 6), elements=st.one_of(st.just(0.0), st.floats(-1e4, 1e4))))
    labels = np.asarray(draw(st.lists(st.integers(0, 2), min_size=n, max_size=n)))
    target = draw(st.sampled_from([0.5, 1.0, 3.0, 7.5, 12.0, 20.0, 25.0, 30.0]))
    return windows, labels, np.asarray(levels), target


DENORMAL_CASE = (np.concatenate([np.full((4, 2, 6), 5e-324), [[[5e-324] * 6, [1.0] + [5e-324] * 5]]]),
                 np.zeros(5, dtype=int), np.array([1.0, 5.0, 10.0, 15.0, 20.0]), 7.5)


@examples(1500)
@given(window_sets())
@example(DENORMAL_CASE)  # found by Hypothesis: f3 = 5e-324 gave eta_PR = inf and inf windows
def test_virtual_force_levels_never_make_nan_windows(case):
    windows, labels, levels, target = case
    try:
        virtual, virtual_labels, virtual_levels, report = virtual_force_levels(windows, labels, levels, [target])
    except InputError as error:
        assert "outside the recorded levels" in str(error) or "same f3" in str(error)
        return
    assert np.isfinite(virtual).all() and len(virtual) == len(virtual_labels) == len(virtual_levels)
    assert set(np.unique(virtual_levels)) <= {target}


targets = arrays(np.float64, st.tuples(st.integers(1, 30), st.just(2)),
                 elements=st.one_of(st.just(0.0), st.floats(-1e6, 1e6)))


@examples(1500)
@given(targets, st.sampled_from(["perfect", "constant", "noisy"]))
@example(np.array([[4.16e-157, 0.0], [0.0, 0.0]]), "constant")  # found by Hypothesis: R2 was -inf
def test_metrics_are_defined_for_constant_zero_single_and_perfect(y, kind):
    predicted = {"perfect": y, "constant": np.zeros_like(y) + 1.0, "noisy": y + 1.0}[kind]
    scores = regression_metrics(y, predicted, ["a_mm", "b_pa"])
    for column, target in enumerate(("a_mm", "b_pa")):
        row = scores[target]
        assert np.isfinite([row["rmse"], row["mae"]]).all()
        # a percentage error is defined on the rows whose true value is not zero: none, none reported
        assert (row["mape_pct"] is None) == (not nonzero_rows(y[:, column]).any())
        assert row["mape_pct"] is None or np.isfinite(row["mape_pct"])
        if len(y) < 2:
            assert row["r2"] is None  # undefined for one sample: reported as null
        else:
            assert np.isfinite(row["r2"])
        if kind == "perfect":
            assert row["rmse"] == 0 and row["mape_pct"] in (None, 0) and (row["r2"] in (None, 1.0))


@examples(1000)
@example(np.array([[5e-324], [1.0], [1.0]]), "weighted")  # a denormal R^2 underflowed in the division
@given(arrays(np.float64, st.tuples(st.integers(1, 5), st.integers(1, 4)),
              elements=st.one_of(st.just(0.0), st.just(np.nan), st.floats(-1e3, 1.0))),
       st.sampled_from(["weighted", "argmax"]))
def test_blend_weights_always_sum_to_one(scores, mode):
    with np.errstate(all="raise"):
        weights, fallback = validation_weights(scores, mode)
    assert np.isfinite(weights).all() and (weights >= 0).all()
    np.testing.assert_allclose(weights.sum(axis=0), 1.0)
    assert set(fallback.tolist()) == set(np.flatnonzero(~(np.nan_to_num(scores) > 0).any(axis=0)).tolist())


@examples(1000)
@given(arrays(np.float64, st.tuples(st.integers(1, 60), st.integers(1, 3)),
              elements=st.floats(-1e6, 1e6)),
       arrays(np.float64, st.tuples(st.integers(1, 60), st.integers(1, 3)),
              elements=st.one_of(st.just(0.0), st.floats(0, 1e3))))
def test_conformal_calibration_is_finite_or_a_clear_error(errors, sigma):
    n = min(len(errors), len(sigma))
    k = min(errors.shape[1], sigma.shape[1])
    scores = normalised_scores(errors[:n, :k], np.zeros((n, k)), sigma[:n, :k])
    assert np.isfinite(scores).all()
    if n < 19:
        with pytest.raises(InputError, match="calibration rows"):
            conformal_quantile(scores)
    else:
        assert np.isfinite(conformal_quantile(scores)).all()
