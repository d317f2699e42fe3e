"""The ROCKET family (models/rocket/): the transform against an explicit convolution with the 84
kernels, the ridge head's leave-one-out against refits, the estimator contract, and the exported
graph against the eager pipeline."""
import itertools

import numpy as np
import onnxruntime as ort
import pytest
import torch
from sklearn.base import clone
from sklearn.utils.estimator_checks import check_no_attributes_set_in_init, check_parameters_default_constructible

from common.errors import InputError
from export.pipelines import export_pipeline
from models.deployable import TimeSeriesPipeline, load_pipeline, save_pipeline
from models.rocket.classifier import RocketClassifier
from models.rocket.minirocket import (SORT_FROM_COUNT, MiniRocket, dilations_and_features, linear_quantiles,
                                      quantiles)
from models.rocket.ridge_loo import ALPHAS, class_indicators, ridge_loo


def explicit_kernels() -> torch.Tensor:
    """The paper's 84 kernels as weights: -1 everywhere, +2 at each choice of three of nine positions."""
    weights = -torch.ones(84, 1, 9, dtype=torch.float64)
    for k, positions in enumerate(itertools.combinations(range(9), 3)):
        weights[k, 0, list(positions)] = 2.0
    return weights


def explicit_features(module: MiniRocket, x: np.ndarray):
    """PPV features computed the slow way: a dilated conv1d per channel with the explicit kernels,
    summed over each kernel's channel combination, pooled over the whole output or its inner part
    (alternating from the first dilation), one feature per bias, in the module's order; and where
    an output lies so close to a bias that float32 rounding may put it on either side (a constant
    window's outputs are all zero: exactly in float64, within rounding in float32)."""
    x64 = torch.from_numpy(x.astype(np.float64))
    features, ties, index = [], [], 0
    for group in module.groups:
        for j in range(group.biases.shape[0]):
            i, d = index + j, module.dilations[index + j]
            per_channel = torch.stack([torch.nn.functional.conv1d(x64[:, c:c + 1], explicit_kernels(), dilation=d,
                                                                  padding=4 * d) for c in range(x.shape[1])], 1)
            mask = group.channel_mask[:, j, :, 0].double()                    # [channels, 84]
            outputs = (per_channel * mask[None, :, :, None]).sum(1)            # [n, 84, length]
            for k in range(84):
                values = outputs[:, k] if (i + k) % 2 == 0 else outputs[:, k, 4 * d:outputs.shape[-1] - 4 * d]
                for b in group.biases[j, k, :, 0].double():
                    features.append((values > b).double().mean(-1))
                    ties.append(((values - b).abs() <= 1e-5 * (1 + outputs.abs().max())).any(-1))
        index += group.biases.shape[0]
    return torch.stack(features, 1).numpy(), torch.stack(ties, 1).numpy()


def fitted(X, y, **settings) -> RocketClassifier:
    return RocketClassifier(**settings).fit(X, y)


@pytest.mark.parametrize("n_channels, length, scale", [(1, 9, 1.0), (1, 40, 1e-6), (3, 31, 1e6), (2, 64, 1.0),
                                                       (1, 1800, 1e-3)])  # long: groups of one dilation
def test_shifted_sums_equal_an_explicit_convolution_with_the_84_kernels(n_channels, length, scale):
    rng = np.random.default_rng(length)
    X = scale * rng.standard_normal((6, n_channels, length)).cumsum(-1)
    X[0] = 3.0 * scale                                   # a constant window
    model = fitted(X, np.arange(6) % 2, n_features=840)
    x = model._scaled(X)
    with torch.no_grad():
        for group in model.module_.groups:
            shared = group.convolutions(torch.from_numpy(x)).numpy()
            for j, d in enumerate(group.dilations):
                explicit = torch.stack([torch.nn.functional.conv1d(torch.from_numpy(x[:, c:c + 1]).double(),
                                                                   explicit_kernels(), dilation=d, padding=4 * d)
                                        for c in range(n_channels)], 1)
                mask = group.channel_mask[:, j, :, 0].double()              # [channels, 84]
                expected = (explicit * mask[None, :, :, None]).sum(1).numpy()
                np.testing.assert_allclose(shared[:, j], expected, atol=1e-4 * np.abs(expected).max() + 1e-5)
    features = model.transform(X)
    assert features.shape == (6, model.module_.n_features)
    expected, ties = explicit_features(model.module_, x)
    np.testing.assert_allclose(features[~ties], expected[~ties], atol=1e-6)
    assert np.mean(np.abs(features - expected)[1:] > 1e-6) < 0.01   # and flip rarely off the constant window
    if length < 1_000:     # over many steps some output lies within the (loose) tie distance of most biases
        assert ties[1:].mean() < 0.01          # ties are rare off the constant window


@pytest.mark.parametrize("length, n_features", [(80, 2_000), (700, 10_000)])
def test_biases_own_outputs_and_inner_pooling_agree_with_the_whole_transform(length, n_features):
    """A kernel's output on its own window (what its biases are quantiles of) is that row of the
    batched product; eager torch, comparing inner-pooled kernels on the inner part only, counts
    what the graph counts: with -inf padding (short windows, several dilations per step) or
    comparing them on their inner part only, the kernels reordered and put back (long windows)."""
    rng = np.random.default_rng(3)
    x = rng.standard_normal((7, 2, length)).cumsum(-1).astype(np.float32)
    x[2, :, 30:] = 0.5                                            # a flat stretch: outputs tie biases
    module = MiniRocket(2, length, n_features)
    module.fit_biases(x, np.random.default_rng(0), 4)
    with torch.no_grad():
        for group in module.groups:
            drawn = rng.integers(len(x), size=(len(group.dilations), 84))
            own = group.own_outputs(torch.from_numpy(x[drawn])).numpy()
            rows = group.convolutions(torch.from_numpy(x)).numpy()[drawn, np.arange(len(group.dilations))[:, None],
                                                                    np.arange(84)]
            np.testing.assert_allclose(own, rows, rtol=0, atol=1e-5 * np.abs(rows).max())
            padded_count = group._traced_features(torch.from_numpy(x))
            np.testing.assert_array_equal(group(torch.from_numpy(x)).numpy(), padded_count.numpy())


def plain_counts(module: MiniRocket, x: np.ndarray) -> np.ndarray:
    """Each feature's count of outputs above its bias, the plain way: the group's batched product
    of all 84 kernels, each (dilation, kernel)'s output pooled over the whole or its inner part
    (alternating from the first dilation), compared with each bias one at a time."""
    counts = []
    with torch.no_grad():
        for group in module.groups:
            outputs = group.convolutions(torch.from_numpy(x))                      # [n, D, 84, length]
            for j, d in enumerate(group.dilations):
                for k in range(84):
                    values = outputs[:, j, k]
                    if (group.first_index + j + k) % 2 == 1:
                        values = values[:, 4 * d:x.shape[-1] - 4 * d]
                    counts += [(values > b).sum(-1) for b in group.biases[j, k, :, 0]]
    return torch.stack(counts, 1).numpy()


@pytest.mark.parametrize("n_channels, length, n_windows", [(1, 80, 7), (3, 60, 23), (1, 1800, 3)])
def test_the_eager_transform_counts_what_plain_comparisons_count(n_channels, length, n_windows):
    """The eager transform (parts of a few windows, one dilation at a time; each output sorted
    and searched where a kernel has SORT_FROM_COUNT biases or more, compared and summed where
    fewer) counts exactly what comparing each output with each bias counts, ties included: a
    constant window (inner outputs 0), a flat stretch and integer values
    (outputs equal to biases), and a last part smaller than the others."""
    rng = np.random.default_rng(length)
    x = rng.standard_normal((n_windows, n_channels, length)).cumsum(-1).astype(np.float32)
    x[0] = 1.5                                                                   # a constant window
    x[1, :, length // 3:] = -0.25                                                # a flat stretch
    x[2] = np.round(x[2])                                                        # integer steps: many ties
    module = MiniRocket(n_channels, length, 10_000)
    module.fit_biases(x, np.random.default_rng(1), 4)
    counts = {g.count for g in module.groups}
    assert min(counts) < SORT_FROM_COUNT <= max(counts) or length > 1_000   # both ways of counting are tested
    with torch.no_grad():
        features = module.transform(torch.from_numpy(x)).numpy()
        pooled = np.concatenate([g.pool_scale.expand(len(g.dilations), 84, g.count).flatten() for g in module.groups])
        for group in module.groups:   # the biases' own outputs are the batched product's rows, bit for bit
            drawn = rng.integers(len(x), size=(len(group.dilations), 84))
            own = group.own_outputs(torch.from_numpy(x[drawn])).numpy()
            rows = group.convolutions(torch.from_numpy(x)).numpy()[drawn, np.arange(len(group.dilations))[:, None],
                                                                    np.arange(84)]
            np.testing.assert_array_equal(own, rows)
    expected = plain_counts(module, x)
    assert 0.1 < (expected * pooled).mean() < 0.9
    np.testing.assert_array_equal(np.rint(features / pooled), expected)
    np.testing.assert_array_equal(features, (expected * pooled).astype(np.float32))


def test_long_windows_split_dilations_into_cache_sized_groups():
    short, long = MiniRocket(1, 150, 10_000), MiniRocket(2, 1800, 10_000)
    assert max(len(g.dilations) for g in short.groups) > 1
    assert [d for g in long.groups for d in g.dilations] == long.dilations
    assert all(len(g.dilations) == 1 for g in long.groups)


def test_dilations_follow_the_paper():
    dilations, counts = dilations_and_features(1460, 10_000)
    assert dilations[0] == 1 and dilations[-1] == 182 and sum(counts) == 119 and len(dilations) <= 32
    assert dilations == sorted(set(dilations))
    assert dilations_and_features(9, 10_000) == ([1], [119])
    np.testing.assert_allclose(quantiles(3), [0.6180339887, 0.2360679775, 0.8541019662], atol=1e-9)
    rows, levels = np.random.default_rng(0).standard_normal((5, 7, 30)), np.random.default_rng(1).uniform(size=(5, 7, 4))
    expected = [[np.quantile(rows[i, j], levels[i, j]) for j in range(7)] for i in range(5)]
    np.testing.assert_allclose(linear_quantiles(rows, levels), expected, rtol=1e-12, atol=1e-12)


def test_non_finite_and_short_windows_are_refused():
    X = np.random.default_rng(0).standard_normal((4, 1, 20))
    X[1, 0, 3] = np.nan
    with pytest.raises(InputError, match="finite"):
        fitted(X, np.arange(4) % 2)
    with pytest.raises(InputError, match="at least 9 steps"):
        fitted(np.ones((4, 1, 8)), np.arange(4) % 2)
    with pytest.raises(InputError, match="n_features"):
        fitted(np.ones((4, 1, 20)), np.arange(4) % 2, n_features=10)


def brute_force_loo(X, Y, alpha):
    """Each sample predicted by ridge (unpenalised intercept) refitted without it."""
    predictions = []
    for i in range(len(X)):
        keep = np.arange(len(X)) != i
        x_mean, y_mean = X[keep].mean(0), Y[keep].mean(0)
        Xc = X[keep] - x_mean
        coef = np.linalg.solve(Xc.T @ Xc + alpha * np.eye(X.shape[1]), Xc.T @ (Y[keep] - y_mean))
        predictions.append(y_mean + (X[i] - x_mean) @ coef)
    return np.array(predictions)


@pytest.mark.parametrize("n, n_features", [(12, 30), (25, 6)])
def test_ridge_leave_one_out_equals_refits_without_each_sample(n, n_features):
    rng = np.random.default_rng(n)
    X = rng.standard_normal((n, n_features))
    Y = class_indicators(rng.integers(0, 3, n), 3)
    fit = ridge_loo(X, Y)
    brute = [((Y - brute_force_loo(X, Y, a)) ** 2).sum() for a in ALPHAS]
    np.testing.assert_allclose(fit.loo_errors, brute, rtol=1e-8)
    np.testing.assert_allclose(fit.loo_predictions, brute_force_loo(X, Y, fit.alpha), rtol=1e-8, atol=1e-10)
    assert fit.alpha == ALPHAS[int(np.argmin(brute))]
    Xc = X - X.mean(0)
    coef = np.linalg.solve(Xc.T @ Xc + fit.alpha * np.eye(n_features), Xc.T @ (Y - Y.mean(0)))
    np.testing.assert_allclose(fit.coef, coef, rtol=1e-7, atol=1e-10)
    np.testing.assert_allclose(fit.intercept, Y.mean(0) - X.mean(0) @ coef, rtol=1e-7, atol=1e-10)


def tones(n_per_class=10, length=60, n_channels=2, seed=0):
    """Three classes told apart by a tone's frequency in the first channel (the others noise)."""
    rng = np.random.default_rng(seed)
    t = np.arange(length) / 20
    y = np.repeat(np.arange(3), n_per_class)
    X = rng.standard_normal((len(y), n_channels, length))
    X[:, 0] += np.sin(2 * np.pi * (1 + y[:, None]) * t + rng.uniform(0, 6, (len(y), 1)))
    return X, y


@pytest.mark.parametrize("head", ["ridge", "logistic"])
def test_both_heads_learn_and_give_probabilities(head):
    X, y = tones()
    X_test, y_test = tones(seed=1)
    model = fitted(X, y, head=head, n_features=2000)
    proba = model.predict_proba(X_test)
    np.testing.assert_allclose(proba.sum(1), 1.0, rtol=1e-5)
    assert (proba.argmax(1) == y_test).mean() >= 0.8
    assert model.head_ == head
    binary = fitted(X[y < 2], y[y < 2], head=head, n_features=2000)
    assert binary.predict_proba(X_test).shape == (len(X_test), 2)
    assert (binary.predict(X_test[y_test < 2]) == y_test[y_test < 2]).mean() >= 0.8


def test_auto_head_switches_by_the_number_of_training_windows():
    X, y = tones()
    assert fitted(X, y, n_features=168, ridge_max_samples=len(X)).head_ == "ridge"
    assert fitted(X, y, n_features=168, ridge_max_samples=len(X) - 1).head_ == "logistic"


def test_parameter_count_holds_every_bias_and_the_folded_head():
    X, y = tones()
    model = fitted(X, y, n_features=840)
    n_features = model.transform(X).shape[1]              # one bias per MiniRocket feature
    head = sum(p.numel() for p in model.module_.head.parameters())
    assert model.n_parameters_ == n_features + head


def test_estimator_contract_and_seed():
    check_no_attributes_set_in_init("RocketClassifier", RocketClassifier())
    check_parameters_default_constructible("RocketClassifier", RocketClassifier())
    X, y = tones()
    model = RocketClassifier(n_features=840, seed=3)
    assert model.fit(X, y) is model
    again = clone(model).fit(X, y)
    np.testing.assert_array_equal(model.transform(X), again.transform(X))
    np.testing.assert_array_equal(model.predict_proba(X), again.predict_proba(X))
    other = RocketClassifier(n_features=840, seed=4).fit(X, y)
    assert not np.array_equal(model.transform(X), other.transform(X))


def test_the_exported_graph_equals_the_eager_pipeline_and_survives_the_fitted_state_file(tmp_path):
    X, y = tones(length=80)
    model = fitted(X, y, n_features=1000)
    raw = 50.0 + 20.0 * X.repeat(2, axis=-1)                   # raw windows at twice the rate, offset and scaled
    pipeline = TimeSeriesPipeline(["a", "b"], ["low", "mid", "high"], None, 2, 80,
                                  np.full((1, 2, 1), 50.0), np.full((1, 2, 1), 20.0), model)
    saved = load_pipeline(save_pipeline(pipeline, tmp_path / "pipeline.npz"))
    eager = pipeline.predict_raw(raw)
    np.testing.assert_array_equal(saved.predict_raw(raw), eager)
    np.testing.assert_array_equal(clone(saved.model).fit(X, y).predict_proba(X), model.predict_proba(X))  # refits alike
    proto = export_pipeline(pipeline, 17, "test")
    assert {n.op_type for n in proto.graph.node}.isdisjoint({"Conv", "ConvTranspose"})
    session = ort.InferenceSession(proto.SerializeToString(), providers=["CPUExecutionProvider"])
    onnx_proba = session.run(None, {"window": raw.astype(np.float32)})[0]
    np.testing.assert_allclose(onnx_proba, eager, atol=1e-4)
    assert (onnx_proba.argmax(1) == y).mean() == (eager.argmax(1) == y).mean()


@pytest.mark.parametrize("length", [150, 700])
def test_the_exported_minirocket_counts_what_eager_counts_and_long_windows_add_no_mask(length):
    """The traced graph in onnxruntime gives eager torch's features: short windows through the
    -inf mask, long ones (one dilation per comparison step) with inner-pooled kernels compared on
    their inner steps only, so no -inf constant reaches their graph."""
    import onnx
    from export.torch_graphs import to_onnx

    class Features(torch.nn.Module):
        def __init__(self, minirocket):
            super().__init__()
            self.minirocket = minirocket

        def forward(self, x):
            return self.minirocket.transform(x)

    rng = np.random.default_rng(length)
    x = rng.standard_normal((5, 2, length)).cumsum(-1).astype(np.float32)
    x[1, :, length // 2:] = 0.25                                       # a flat stretch
    module = MiniRocket(2, length, 10_000)
    module.fit_biases(x, np.random.default_rng(0), 4)
    one_per_step = [g for g in module.groups if (1 << 18) // (84 * g.count * length) <= 1]
    assert (len(one_per_step) == len(module.groups)) == (length > 500)     # both forms are tested
    proto = to_onnx(Features(module), torch.from_numpy(x[:2]), "window", "features", 17)
    session = ort.InferenceSession(proto.SerializeToString(), providers=["CPUExecutionProvider"])
    with torch.no_grad():
        eager = module.transform(torch.from_numpy(x)).numpy()
    graph = session.run(None, {"window": x})[0]
    assert np.mean(graph != eager) < 1e-3      # a flat stretch's ties may round either way (module docstring)
    np.testing.assert_allclose(graph, eager, atol=0.02)
    masks = [t for t in proto.graph.initializer if np.isneginf(onnx.numpy_helper.to_array(t)).any()]
    masks += [n for n in proto.graph.node if n.op_type == "Constant" and any(
        a.t.dims and np.isneginf(onnx.numpy_helper.to_array(a.t)).any() for a in n.attribute)]
    assert bool(masks) == (len(one_per_step) < len(module.groups))    # only groups of several dilations per step
