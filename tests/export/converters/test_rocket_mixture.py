"""The ROCKET-family mixture's ONNX graph (export/converters/rocket_mixture.py): one graph whose
probabilities onnxruntime computes as the eager pipeline does, with one transform (not one per
member), and the mixture trained through train.py exports a model.onnx that matches it."""
import numpy as np
import onnxruntime as ort

from export.converters.registry import converter_for
from export.converters.window_classifiers import window_classifier_graph
from export.pipelines import export_pipeline
from models.deployable import TimeSeriesPipeline, load_pipeline, save_pipeline
from models.rocket.classifier import RocketClassifier
from models.rocket.mixture import MixedRocketClassifier
from runs.run import run
from tests.models.nets.test_nets import ten_tones_npz
from tests.models.rocket.test_mixture import noisy_tones


def pipeline_of(model, length=40):
    return TimeSeriesPipeline(["a", "b"], ["low", "mid", "high"], None, 1, length,
                              np.full((1, 2, 1), 50.0), np.full((1, 2, 1), 20.0), model)


def onnx_proba(proto, raw):
    session = ort.InferenceSession(proto.SerializeToString(), providers=["CPUExecutionProvider"])
    return session.run(None, {"window": raw.astype(np.float32)})[0]


def test_the_mixture_exports_as_one_graph_matching_predict_proba_and_the_fitted_state_file(tmp_path):
    X, y = noisy_tones()
    X_new, _ = noisy_tones(seed=3)
    model = MixedRocketClassifier(n_features=840, seed=1).fit(X, y)
    assert converter_for(model) is window_classifier_graph
    assert len(set(model.member_weights_.values())) > 1          # unequal weights: the mix, not an average, is checked
    pipeline = pipeline_of(model)
    raw = 50.0 + 20.0 * X_new
    eager = pipeline.predict_raw(raw)
    np.testing.assert_allclose(eager, model.predict_proba(X_new), atol=1e-5)
    saved = load_pipeline(save_pipeline(pipeline, tmp_path / "pipeline.npz"))
    np.testing.assert_array_equal(saved.predict_raw(raw), eager)
    proto = export_pipeline(pipeline, 17, "test")
    np.testing.assert_allclose(onnx_proba(proto, raw), eager, atol=1e-5)
    # one transform: the mixture's graph is Hydra + MiniRocket's plus a few nodes for the heads' mix
    single = export_pipeline(pipeline_of(RocketClassifier(n_features=840, seed=1, member="hydra_minirocket").fit(X, y)),
                             17, "test")
    assert len(single.graph.node) < len(proto.graph.node) <= len(single.graph.node) + 12


def test_the_mixture_trains_through_train_py_and_its_model_onnx_matches(compose_config, tmp_path):
    npz = ten_tones_npz(tmp_path / "tones.npz")
    cfg = compose_config(["data=recordings_npz", f"data.path={npz}", "data.label=y", "model=rocket_mixture",
                          "model.n_features=840", "extras=quick", "trainer.progress=false"])
    metrics = run(cfg, tmp_path / "run")
    assert metrics["test"]["accuracy"] > 0.5                                    # chance: 0.1
    pipeline = load_pipeline(tmp_path / "run" / "pipeline.npz")
    assert isinstance(pipeline.model, MixedRocketClassifier)
    X = np.load(npz)["X"]
    session = ort.InferenceSession(str(tmp_path / "run" / "model.onnx"), providers=["CPUExecutionProvider"])
    np.testing.assert_allclose(session.run(None, {"window": X.astype(np.float32)})[0], pipeline.predict_raw(X),
                               atol=1e-4)
