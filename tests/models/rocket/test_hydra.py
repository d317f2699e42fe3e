"""model=hydra_minirocket (models/rocket/hydra.py): the Hydra counts against an explicit loop over
kernels and time steps, the sparse scaler against its formula, seed determinism, refusals, the
exported graph against the eager pipeline (and the fitted-state file), and a run through train.py."""
import numpy as np
import onnxruntime as ort
import pytest
import torch
from sklearn.base import clone

from common.errors import InputError
from export.pipelines import export_pipeline
from models.deployable import TimeSeriesPipeline, load_pipeline, save_pipeline
from models.rocket.classifier import RocketClassifier
from models.rocket.hydra import Hydra, hydra_dilations
from runs.run import run
from tests.models.nets.test_nets import ten_tones_npz

SMALL = {"n_features": 840, "member": "hydra_minirocket"}


def explicit_counts(module: Hydra, x: np.ndarray) -> np.ndarray:
    """Hydra's counts the slow way, in float64: per dilation, source (input, then its first
    difference), group and time step, each kernel's zero-padded dilated dot product on the sum of
    the group's channels; the largest adds its value to its kernel's soft count, the smallest (first
    on ties) one to its hard count."""
    difference = np.diff(x, axis=-1)
    features = []
    for block in module.dilations:
        d, k = block.dilation, block.kernels_per_group
        for source, series in enumerate((x, difference)):
            weights = block.weights[source, :, 0].double().numpy().reshape(block.half, k, 9)
            soft, hard = np.zeros((len(x), block.half, k)), np.zeros((len(x), block.half, k))
            length = series.shape[-1]
            for g in range(block.half):
                combined = np.einsum("c,nct->nt", block.mix[source, g].double().numpy(), series)
                padded = np.pad(combined, ((0, 0), (4 * d, 4 * d)))
                for t in range(length):
                    window = padded[:, t:t + 8 * d + 1:d]                       # [n, 9]
                    outputs = window @ weights[g].T                             # [n, k]
                    for n in range(len(x)):
                        soft[n, g, outputs[n].argmax()] += outputs[n].max()
                        hard[n, g, outputs[n].argmin()] += 1
            features += [soft.reshape(len(x), -1), hard.reshape(len(x), -1)]
    return np.concatenate(features, axis=1)


@pytest.mark.parametrize("n_channels, length", [(1, 9), (1, 40), (5, 23)])
def test_hydra_counts_equal_an_explicit_loop_over_kernels_and_time(n_channels, length):
    rng = np.random.default_rng(length)
    x = rng.standard_normal((3, n_channels, length))
    module = Hydra(n_channels, length, np.random.default_rng(0), n_groups=4, kernels_per_group=3)
    assert [b.dilation for b in module.dilations] == hydra_dilations(length)
    with torch.no_grad():
        counts = module.counts(torch.from_numpy(x.astype(np.float32))).numpy()
    assert counts.shape == (3, module.n_features)
    np.testing.assert_allclose(counts, explicit_counts(module, x), atol=1e-4)


def test_kernels_are_normalised_and_dilations_follow_the_paper():
    assert hydra_dilations(9) == [1] and hydra_dilations(150) == [1, 2, 4, 8, 16] and hydra_dilations(1460) == [
        2 ** e for e in range(8)]
    module = Hydra(12, 60, np.random.default_rng(0))
    weights = module.dilations[0].weights.double()
    np.testing.assert_allclose(weights.mean(-1), 0, atol=1e-6)
    np.testing.assert_allclose(weights.abs().sum(-1), 1, atol=1e-6)
    np.testing.assert_array_equal(module.dilations[0].mix.sum(-1), 6)      # clip(12 / 2, 2, 8) channels a group
    assert module.n_features == len(hydra_dilations(60)) * 1024


def test_the_sparse_scaler_follows_its_formula():
    x = torch.from_numpy(np.random.default_rng(1).standard_normal((30, 1, 20)).astype(np.float32))
    module = Hydra(1, 20, np.random.default_rng(0), n_groups=4, kernels_per_group=8)
    with torch.no_grad():
        counts = module.counts(x).double().numpy()
        module.fit_scaler(torch.from_numpy(counts))
        scaled = module(x).numpy()
    root = np.sqrt(np.clip(counts, 0, None))
    zero = (root == 0).mean(0)
    assert zero.max() > 0.3                                   # features zero in many windows: the mask and epsilon matter
    expected = (root - root.mean(0)) * (root != 0) / (root.std(0, ddof=1) + zero ** 4 + 1e-8)
    np.testing.assert_allclose(scaled, expected, atol=1e-4)


def tones(n=36, length=50, n_channels=2, seed=0):
    rng = np.random.default_rng(seed)
    y = np.arange(n) % 3
    t = np.arange(length)
    X = rng.standard_normal((n, n_channels, length)) * 0.5
    X[:, 0] += np.sin(2 * np.pi * (y[:, None] + 1) * t / 25 + rng.uniform(0, 6, (n, 1)))
    return X, y


def test_same_seed_same_result_and_minirocket_features_unchanged():
    X, y = tones()
    model = RocketClassifier(seed=3, **SMALL).fit(X, y)
    again = RocketClassifier(seed=3, **SMALL).fit(X, y)
    np.testing.assert_array_equal(model.predict_proba(X), again.predict_proba(X))
    other = RocketClassifier(seed=4, **SMALL).fit(X, y)
    assert not np.array_equal(model.transform(X), other.transform(X))
    plain = RocketClassifier(seed=3, n_features=840).fit(X, y)
    features = model.transform(X)
    np.testing.assert_array_equal(features[:, :model.module_.prescaled_from], plain.transform(X))
    assert features.shape[1] == model.module_.prescaled_from + model.module_.hydra.n_features
    assert (model.predict(X) == y).mean() == 1.0


@pytest.mark.parametrize("X, message", [
    (np.full((4, 1, 20), np.nan), "finite"),
    (np.zeros((4, 1, 8)), "at least 9 steps"),
])
def test_non_finite_and_short_windows_are_refused(X, message):
    with pytest.raises(InputError, match=message) as raised:
        RocketClassifier(**SMALL).fit(X, np.arange(4) % 2)
    assert "\n" not in str(raised.value)


def test_an_unknown_member_is_refused():
    X, y = tones(n=6)
    with pytest.raises(InputError, match="model.member must be one of minirocket, hydra_minirocket"):
        RocketClassifier(member="multirocket").fit(X, y)


def test_the_exported_graph_equals_the_eager_pipeline_and_survives_the_fitted_state_file(tmp_path):
    X, y = tones(length=40)
    model = RocketClassifier(**SMALL).fit(X, y)
    raw = 50.0 + 20.0 * X
    pipeline = TimeSeriesPipeline(["a", "b"], ["low", "mid", "high"], None, 1, 40,
                                  np.full((1, 2, 1), 50.0), np.full((1, 2, 1), 20.0), model)
    saved = load_pipeline(save_pipeline(pipeline, tmp_path / "pipeline.npz"))
    eager = pipeline.predict_raw(raw)
    np.testing.assert_array_equal(saved.predict_raw(raw), eager)
    np.testing.assert_array_equal(clone(saved.model).fit(X, y).predict_proba(X), model.predict_proba(X))
    proto = export_pipeline(pipeline, 17, "test")
    assert not proto.graph.initializer[0].data_location      # weights inside the file
    session = ort.InferenceSession(proto.SerializeToString(), providers=["CPUExecutionProvider"])
    onnx_proba = session.run(None, {"window": raw.astype(np.float32)})[0]
    np.testing.assert_allclose(onnx_proba, eager, atol=1e-4)


def test_hydra_minirocket_trains_through_train_py_and_its_export_matches(compose_config, tmp_path):
    npz = ten_tones_npz(tmp_path / "tones.npz")
    cfg = compose_config(["data=recordings_npz", f"data.path={npz}", "data.label=y", "model=hydra_minirocket",
                          "model.n_features=840", "extras=quick", "trainer.progress=false"])
    metrics = run(cfg, tmp_path / "run")
    assert metrics["val"]["accuracy"] > 0.5 and metrics["test"]["accuracy"] > 0.5      # chance: 0.1
    pipeline = load_pipeline(tmp_path / "run" / "pipeline.npz")
    assert pipeline.model.member == "hydra_minirocket"
    X = np.load(npz)["X"]
    session = ort.InferenceSession(str(tmp_path / "run" / "model.onnx"), providers=["CPUExecutionProvider"])
    np.testing.assert_allclose(session.run(None, {"window": X.astype(np.float32)})[0], pipeline.predict_raw(X),
                               atol=1e-4)
