"""Nothing a user points at is unpickled: every reader of a user-named file refuses a crafted
file that would run code when loaded (one line, exit 2 or InputError) and the code never runs
(its marker file never appears); and the deployable pipeline's own format (models/fitted_state.py)
gives back every model kind exactly."""
import functools
import json
import os
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch
from hydra.errors import InstantiationException
from sklearn.base import clone

from common.errors import InputError
from data.preprocessing.minmax_scaling import MinMaxScaling
from data.readers.contact_streams import load_frames
from data.readers.recording_reader import load_npz
from data.readers.table_reader import read_table_file
from export.run_export import export_run
from models import storable
from models.classic_regressors import ClassicRegressor
from models.deployable import PIPELINE_FILE, RegressionPipeline, TimeSeriesPipeline, load_pipeline, save_pipeline
from models.fitted_state import FORMAT, VERSION, load_fitted, save_fitted
from models.kfold_blend import KFoldBlend
from models.nets.inceptiontime import InceptionTime
from models.nets.lstm_fcn import LSTMFCN
from models.nets.prcnn import PRCNN
from models.nets.rescnn import ResCNN
from models.resmlp_regressor import ResMLPRegressor
from models.timeseries_classifier import TimeSeriesClassifier
from models.trees import TreeRegressor
from models.weighted_blend import ValidationWeightedBlend
from runs.reference_tasks import generate
from runs.run import run

ROOT = Path(__file__).resolve().parents[2]


# -- crafted files ---------------------------------------------------------------------------
class Payload:
    """Unpickling this creates `marker`: a stand-in for any code a pickle can run."""

    def __init__(self, marker):
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, "w"))


def fitted_document(path, root, **arrays) -> Path:
    """A file in the fitted-state layout whose structure is `root` (crafted by hand)."""
    document = json.dumps({"format": FORMAT, "version": VERSION, "root": root}).encode()
    with open(path, "wb") as handle:
        np.savez(handle, structure=np.frombuffer(document, dtype=np.uint8), **arrays)
    return Path(path)


def crafted_pipelines(folder: Path, marker: Path) -> dict[str, bytes]:
    """Files a user could hand over as a run's pipeline.npz, each of which would create `marker`
    if it were loaded by a reader that runs what a file names."""
    folder.mkdir(parents=True, exist_ok=True)
    evil = pickle.dumps(Payload(marker))
    system = {"object": "os.system", "args": {"tuple": [f"touch {marker}"], "id": 1}, "id": 0}
    evaluate = {"object": "models.deployable.RegressionPipeline", "id": 0, "state": {"id": 1, "dict": [
        ["model", {"object": "builtins.eval", "args": {"tuple": [f"open({str(marker)!r}, 'w')"], "id": 3}, "id": 2}]]}}
    factory = {"factory": "builtins.open", "args": {"tuple": [str(marker), "w"], "id": 1},
               "keywords": {"dict": [], "id": 2}, "id": 0}
    object_array = np.empty(1, dtype=object)
    object_array[0] = Payload(marker)
    files = {"pickle": folder / "pickle.npz", "os.system": folder / "system.npz", "builtins.eval": folder / "eval.npz",
             "factory": folder / "factory.npz", "object array": folder / "objects.npz"}
    files["pickle"].write_bytes(evil)
    fitted_document(files["os.system"], system)
    fitted_document(files["builtins.eval"], evaluate)
    fitted_document(files["factory"], factory)
    np.savez(files["object array"], structure=np.frombuffer(b"{}", dtype=np.uint8), blob_0=object_array)
    return {name: path.read_bytes() for name, path in files.items()}


def one_line(message: str) -> bool:
    return "\n" not in message.strip() and message.strip() != ""


@pytest.fixture
def marker(tmp_path):
    return tmp_path / "RAN_CODE"


def test_the_crafted_files_would_run_code_if_unpickled_or_allowed(tmp_path, marker, monkeypatch):
    """Controls: the payloads below do run code when read by pickle, or by this format with
    os.system put on its lists, so the refusals in the other tests are what stops them."""
    files = crafted_pipelines(tmp_path / "files", marker)
    pickle.loads(files["pickle"])
    assert marker.exists()
    marker.unlink()
    torch.save({"module": Payload(marker)}, tmp_path / "last.pt")
    torch.load(tmp_path / "last.pt", weights_only=False)
    assert marker.exists()
    marker.unlink()
    monkeypatch.setitem(storable.STORABLE, "os.system", os.system)
    storable.CALLED.add("os.system")
    try:
        (tmp_path / "system.npz").write_bytes(files["os.system"])
        load_fitted(tmp_path / "system.npz")
    finally:
        storable.CALLED.discard("os.system")
    assert marker.exists()


# -- the run folder's pipeline: loading, export ---------------------------------------------
@pytest.mark.parametrize("kind", ["pickle", "os.system", "builtins.eval", "factory", "object array"])
def test_crafted_pipeline_files_are_refused_by_every_reader(tmp_path, marker, kind):
    content = crafted_pipelines(tmp_path / "files", marker)[kind]
    run_dir = tmp_path / "run"
    run_dir.mkdir()
    (run_dir / PIPELINE_FILE).write_bytes(content)
    # (latency is measured on the run's in-memory pipeline: it reads no file)
    readers = {"load_pipeline": lambda: load_pipeline(run_dir / PIPELINE_FILE), "export_run": lambda: export_run(run_dir)}
    for name, read in readers.items():
        with pytest.raises(InputError) as error:
            read()
        message = str(error.value)
        assert str(run_dir / PIPELINE_FILE) in message and one_line(message), (name, message)
        named = {"os.system": "'os.system'", "builtins.eval": "'builtins.eval'", "factory": "'builtins.open'"}
        if kind in named:
            assert named[kind] in message and "not on the list" in message, message
    assert not marker.exists() and not (run_dir / "model.onnx").exists()


def test_export_cli_refuses_a_crafted_pipeline_in_one_line(tmp_path, marker):
    run_dir = tmp_path / "run"
    run_dir.mkdir()
    (run_dir / PIPELINE_FILE).write_bytes(crafted_pipelines(tmp_path / "files", marker)["os.system"])
    result = subprocess.run([sys.executable, "-m", "export.run_export", str(run_dir)], capture_output=True, text=True,
                            cwd=ROOT)
    assert result.returncode == 2 and result.stderr.startswith("error: ") and one_line(result.stderr), result.stderr
    assert "'os.system'" in result.stderr and not marker.exists() and not (run_dir / "model.onnx").exists()


@pytest.mark.parametrize("damage, words", [
    (lambda p: p.write_bytes(b"not a zip at all"), "not a readable fitted-state file"),
    (lambda p: p.write_bytes(p.read_bytes()[: len(p.read_bytes()) // 2]), "not a readable fitted-state file"),
    (lambda p: np.savez(p, other=np.zeros(3)), "no 'structure' member"),
    (lambda p: np.savez(p, structure=np.frombuffer(b"{not json", dtype=np.uint8)), "JSONDecodeError"),
    (lambda p: np.savez(p, structure=np.frombuffer(b'{"format": "x"}', dtype=np.uint8)), "not a Touchstone"),
    (lambda p: fitted_document(p, {"array": 0, "offset": 5, "shape": [10], "order": "C", "id": 0},
                               blob_0=np.zeros(8)), "outside its blob"),
    (lambda p: fitted_document(p, {"list": [{"ref": 7}], "id": 0}), "KeyError"),
    (lambda p: fitted_document(p, {"generator": "os", "state": 1, "id": 0}), "unknown bit generator"),
    (lambda p: fitted_document(p, {"factory": "models.trees.TreeRegressor", "args": [], "keywords": [], "id": 0}),
     "not a network"),
    (lambda p: fitted_document(p, {"object": "torch.nn.modules.linear.Linear", "args": {"tuple": [10 ** 6, 10 ** 6]}}),
     "not built by calling it"),  # a listed class, but only sklearn's Tree is ever called
    (lambda p: fitted_document(p, {"dict": {}}), "holds a dict, not a deployable pipeline"),
])
def test_a_file_that_is_not_a_saved_pipeline_is_one_line(tmp_path, damage, words):
    path = tmp_path / PIPELINE_FILE
    save_fitted({"weights": np.arange(100.0)}, path)
    damage(path)
    with pytest.raises(InputError) as error:
        load_pipeline(path)
    assert words in str(error.value) and str(path) in str(error.value) and one_line(str(error.value))


@pytest.mark.parametrize("name", ["models.capabilities.Capabilities", "models.no_such_module.Model",
                                  "models..deployable.RegressionPipeline", "sklearn.svm._classes.NuSVR"])
def test_a_class_that_did_not_register_as_storable_is_refused(tmp_path, name):
    """Only registered classes are built: one of our modules that holds no registered class of
    that name, a module that does not exist, a malformed name, a library class nobody registered."""
    path = fitted_document(tmp_path / PIPELINE_FILE, {"object": name, "state": {"dict": {}}})
    with pytest.raises(InputError, match="not on the list of classes .*storable-class registry"):
        load_pipeline(path)


def test_saving_refuses_code_and_unlisted_classes_naming_where_they_sit(tmp_path):
    pipeline = regression_pipeline(TreeRegressor("decision_tree", max_depth=3).fit(*regression_data()))
    pipeline.description["hook"] = lambda x: x
    with pytest.raises(TypeError, match=r"RegressionPipeline\.description\.hook: .*is code, not data"):
        save_pipeline(pipeline, tmp_path / PIPELINE_FILE)
    pipeline.description["hook"] = Path("/tmp")  # data, but of a class nobody listed
    with pytest.raises(TypeError, match=r"description\.hook: class pathlib\.\w*Path is not in the storable-class registry"):
        save_pipeline(pipeline, tmp_path / PIPELINE_FILE)
    assert not (tmp_path / PIPELINE_FILE).exists()


# -- the capacitive study's force_model ------------------------------------------------------
CAPACITIVE = ["experiment=capacitive_tracking", "scene.sessions=[hold]", "scene.session_s=0.5", "scene.gap_s=0.2",
              "scene.n_rest_frames=30", "study.animation.max_frames=2", "study.animation.n_panels=1"]


def test_the_capacitive_force_model_refuses_a_crafted_file(compose_config, tmp_path, marker):
    folder = tmp_path / "force_run"
    folder.mkdir()
    (folder / "model.onnx").write_bytes(pickle.dumps(Payload(marker)))
    (folder / "pipeline.pkl").write_bytes(pickle.dumps(Payload(marker)))  # an old run's pickle is never read
    for given in (folder, folder / "model.onnx", folder / "pipeline.pkl"):
        with pytest.raises(InstantiationException) as error:
            run(compose_config(CAPACITIVE + [f"study.force_model={given}"]), tmp_path / "out")
        cause = error.value.__cause__
        assert isinstance(cause, InputError) and one_line(str(cause)), cause
        assert "not a loadable ONNX model" in str(cause) or "does not read the 3x3 window" in str(cause), cause
    assert not marker.exists()


# -- trainer.resume_from ---------------------------------------------------------------------
def crafted_checkpoints(folder: Path, marker: Path) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    torch.save({"fingerprint": {}, "module": Payload(marker)}, folder / "torch.pt")  # a torch file with a payload
    (folder / "pickle.pt").write_bytes(pickle.dumps(Payload(marker)))                 # a bare pickle
    torch.save({"epoch": 3}, folder / "foreign.pt")                                   # plain, but not ours
    return [folder / "torch.pt", folder / "pickle.pt", folder / "foreign.pt"]


@pytest.mark.filterwarnings("ignore:Detected pickle protocol")  # torch on the bare pickle, before refusing it
def test_resume_from_refuses_a_crafted_checkpoint(tmp_path, marker):
    X, y = generate("phase", 20, seed=0)
    for path in crafted_checkpoints(tmp_path / "checkpoints", marker):
        classifier = TimeSeriesClassifier(functools.partial(PRCNN, branch_width=4, fusion_width=4), max_epochs=1,
                                          progress=False, resume_from=str(path))
        with pytest.raises(InputError, match="trainer.resume_from: .*checkpoint") as error:
            classifier.fit(X, y)
        assert str(path) in str(error.value) and one_line(str(error.value))
    assert not marker.exists()


def test_train_py_refuses_a_crafted_checkpoint_end_to_end(tmp_path, marker):
    X, y = generate("frequency", 20, seed=0)
    np.savez(tmp_path / "rig.npz", X=X, y=y)
    folder = tmp_path / "interrupted"
    (folder / "checkpoint").mkdir(parents=True)
    torch.save({"fingerprint": {}, "module": Payload(marker)}, folder / "checkpoint" / "last.pt")
    result = subprocess.run(
        [sys.executable, "train.py", "data=recordings_npz", f"data.path={tmp_path / 'rig.npz'}", "model=prcnn",
         "trainer.max_epochs=1", "trainer.progress=false", "model.network.branch_width=4",
         "model.network.fusion_width=4", f"trainer.resume_from={folder}", f"hydra.run.dir={tmp_path / 'run'}"],
        capture_output=True, text=True, cwd=ROOT, env={**os.environ, "CI": "true"})
    assert result.returncode == 2, result.stderr[-2000:]
    errors = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "trainer.resume_from" in errors[0] and "Traceback" not in result.stderr, result.stderr
    assert not marker.exists()


# -- predict.py's model= and the data readers -------------------------------------------------
def test_predict_refuses_a_model_that_is_a_pickle(tmp_path, marker):
    (tmp_path / "model.onnx").write_bytes(pickle.dumps(Payload(marker)))
    (tmp_path / "rig.csv").write_text("a,b\n1,2\n")
    result = subprocess.run([sys.executable, str(ROOT / "predict.py"), f"model={tmp_path / 'model.onnx'}",
                             f"input={tmp_path / 'rig.csv'}", f"output={tmp_path / 'out.csv'}"],
                            capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode == 2 and result.stderr.startswith("error: ") and one_line(result.stderr), result.stderr
    assert not marker.exists() and not (tmp_path / "out.csv").exists()


def test_data_readers_refuse_pickles(tmp_path, marker):
    evil = pickle.dumps(Payload(marker))
    objects = np.empty(2, dtype=object)
    objects[:] = [Payload(marker), Payload(marker)]
    np.savez(tmp_path / "recordings.npz", X=objects, y=np.array(["a", "b"]))
    np.save(tmp_path / "frames.npy", objects)
    for name in ("table.csv", "table.parquet", "frames.csv", "pickle.npz"):
        (tmp_path / name).write_bytes(evil)
    readers = {"recordings.npz": load_npz, "pickle.npz": load_npz, "table.csv": read_table_file,
               "table.parquet": read_table_file,
               "frames.npy": lambda p: load_frames(p, rows=1, cols=2), "frames.csv": lambda p: load_frames(p, 1, 2)}
    for name, read in readers.items():
        with pytest.raises(InputError) as error:
            read(tmp_path / name)
        assert name in str(error.value) and one_line(str(error.value)), (name, str(error.value))
    assert not marker.exists()


# -- round trips: every model kind comes back exactly -----------------------------------------
def regression_data(n=60, seed=0):
    rng = np.random.default_rng(seed)
    X = rng.uniform(1.0, 2.0, (n, 4))
    return X, np.c_[X[:, 0] * X[:, 1], X[:, 2] - X[:, 3] ** 2]


def regression_pipeline(model) -> RegressionPipeline:
    """A pipeline around `model`, fitted here on the features the pipeline computes from raw
    readings (min-max normalised first); blends are calibrated, so they give intervals."""
    readings, y = regression_data()
    raw = readings * 1e3 + 17.0
    normalisation = MinMaxScaling.fit(raw, [f"r_{k}" for k in range(4)])
    pipeline = RegressionPipeline(channel_names=normalisation.raw_channels, target_names=["a_mm", "b_mm"],
                                  feature_groups=["raw"], feature_names=["r_0", "r_1", "r_2", "r_3"],
                                  scaler_mean=np.zeros(4), scaler_scale=np.ones(4), model=model,
                                  description={"source": "test"}, examples=raw[:8], normalisation=normalisation)
    X = pipeline.features(raw)
    model.fit(X, y)
    if hasattr(model, "calibrate"):
        model.calibrate(X[:40], y[:40], alpha=0.1)
    return pipeline


SMALL_RESMLP = {"widths": (8, 8), "dropouts": (0.1, 0.1), "max_epochs": 3, "progress": False}


def kfold(estimator):
    return KFoldBlend(estimator, n_folds=2, progress=False)


REGRESSORS = {
    "resmlp": lambda: ResMLPRegressor(**SMALL_RESMLP),
    "random_forest": lambda: TreeRegressor("random_forest", n_estimators=3, max_depth=4, per_output=True),
    "extra_trees": lambda: TreeRegressor("extra_trees", n_estimators=3, max_depth=4),
    "decision_tree": lambda: TreeRegressor("decision_tree", max_depth=4),
    "linear_regression": lambda: ClassicRegressor("linear_regression"),
    "svr": lambda: ClassicRegressor("svr"),
    "gaussian_process": lambda: ClassicRegressor("gaussian_process"),
    "kfold": lambda: kfold(ResMLPRegressor(**SMALL_RESMLP)),
    "blend": lambda: ValidationWeightedBlend({"resmlp": kfold(ResMLPRegressor(**SMALL_RESMLP)),
                                              "extra_trees": kfold(TreeRegressor("extra_trees", n_estimators=3))},
                                             weights="stacking"),
}


@pytest.mark.filterwarnings("ignore::sklearn.exceptions.ConvergenceWarning")
@pytest.mark.parametrize("kind", list(REGRESSORS))
def test_every_regression_model_comes_back_exactly(tmp_path, kind):
    pipeline = regression_pipeline(REGRESSORS[kind]())
    save_pipeline(pipeline, tmp_path / PIPELINE_FILE)
    loaded = load_pipeline(tmp_path / PIPELINE_FILE)
    assert type(loaded.model) is type(pipeline.model) and loaded.channel_names == pipeline.channel_names
    readings = np.random.default_rng(1).uniform(1000.0, 2100.0, (50, 4))
    (mean, half), (mean_back, half_back) = pipeline.predict_raw(readings), loaded.predict_raw(readings)
    np.testing.assert_array_equal(mean_back, mean)
    assert (half is None) == (half_back is None) == (kind not in ("kfold", "blend"))
    if half is not None:
        np.testing.assert_array_equal(half_back, half)
    np.testing.assert_array_equal(loaded.examples, pipeline.examples)


TIME_SERIES_NETS = {
    "prcnn": functools.partial(PRCNN, branch_width=4, fusion_width=4),
    "rescnn": functools.partial(ResCNN, widths=(4, 4, 4)),
    "inceptiontime": functools.partial(InceptionTime, depth=3, filters=4, bottleneck=4, kernels=(9, 5, 3)),
    "lstm_fcn": functools.partial(LSTMFCN, hidden=4, widths=(4, 4, 4), dropout=0.5),
}


@pytest.mark.parametrize("kind", list(TIME_SERIES_NETS))
def test_every_time_series_net_comes_back_exactly(tmp_path, kind):
    X, y = generate("phase", 24, seed=1)
    classifier = TimeSeriesClassifier(TIME_SERIES_NETS[kind], max_epochs=1, batch_size=8, progress=False).fit(X, y)
    calibration = {"channel": "fsr", "index": 1}
    pipeline = TimeSeriesPipeline(["tribo", "fsr"], ["a", "b"], calibration, 1, X.shape[-1],
                                  np.zeros((1, 2, 1)), np.ones((1, 2, 1)), classifier, {"label": "y"}, X[:4])
    save_pipeline(pipeline, tmp_path / PIPELINE_FILE)
    loaded = load_pipeline(tmp_path / PIPELINE_FILE)
    windows = np.random.default_rng(2).uniform(0.5, 2.5, size=(9,) + X.shape[1:])  # volts
    proba = pipeline.predict_raw(windows)
    assert np.isfinite(proba).all()
    np.testing.assert_array_equal(loaded.predict_raw(windows), proba)
    assert loaded.force_calibration == calibration and loaded.classes == ["a", "b"]
    for key, value in classifier.module_.state_dict().items():
        assert torch.equal(loaded.model.module_.state_dict()[key], value), key
    # the factory comes back as a plain partial of the same class: the loaded estimator refits
    assert loaded.model.network.func is TIME_SERIES_NETS[kind].func
    assert loaded.model.network.keywords == TIME_SERIES_NETS[kind].keywords
    clone(loaded.model).fit(X, y)
    if kind == "lstm_fcn":  # shared objects stay shared: the LSTM's flat weights are its parameters
        lstm = loaded.model.module_.lstm
        assert lstm._flat_weights[0] is lstm.weight_ih_l0


def test_shared_arrays_random_states_and_plain_values_survive(tmp_path):
    weights = np.arange(6.0).reshape(2, 3, order="F")
    generator = np.random.default_rng(5)
    state = {"a": weights, "b": weights, "numbers": (1, 2.5, float("inf"), None, True, "text", b"bytes"),
             "scalar": np.float32(1.5), "legacy": np.random.RandomState(3), "generator": generator,
             3: {1, 2}, "strings": np.array(["x", "yz"]), "empty": np.zeros((0, 4), dtype=np.int16)}
    save_fitted(state, tmp_path / "state.npz")
    back = load_fitted(tmp_path / "state.npz")
    assert back["a"] is back["b"] and back["a"].flags.f_contiguous
    np.testing.assert_array_equal(back["a"], weights)
    assert back["numbers"] == state["numbers"] and back[3] == {1, 2} and back["scalar"].dtype == np.float32
    assert back["legacy"].random() == np.random.RandomState(3).random()
    assert back["generator"].random() == np.random.default_rng(5).random()
    assert back["strings"].tolist() == ["x", "yz"] and back["empty"].shape == (0, 4)
