"""predict.py on bad input: every case is one line on stderr naming the culprit, exit code 2 and
no output file; nothing it writes holds a non-finite number. Models are the hand-built ones of
tests/predict_support.py (same names, dtypes and metadata keys as an export)."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from tests.predict_support import (
    CHANNELS,
    CLASSES,
    SAMPLE_RATE_HZ,
    WINDOW_STEPS,
    classification_metadata,
    classification_model,
    predict_main,
    regression_metadata,
    regression_model,
    row_classification_model,
    save,
)

from common.errors import InputError
from export.onnx_predictor import OnnxPredictor

ROOT = Path(__file__).resolve().parents[2]


def run_main(capsys, *args) -> tuple[int, str, str]:
    code = predict_main([str(a) for a in args])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def assert_one_line_error(code, err, *fragments):
    assert code == 2, err
    assert err.startswith("error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    for fragment in fragments:
        assert fragment in err, (fragment, err)


@pytest.fixture
def models(tmp_path):
    return {"regression": save(regression_model(), tmp_path / "reg.onnx"),
            "classification": save(classification_model(), tmp_path / "cls.onnx")}


def recording(steps=2 * WINDOW_STEPS, **cells) -> pd.DataFrame:
    """A recording of `steps` rows; cells={(row, column): value} overrides single values."""
    frame = pd.DataFrame(np.linspace(0.0, 1.0, steps * len(CHANNELS)).reshape(steps, len(CHANNELS)), columns=CHANNELS)
    for (row, column), value in cells.get("cells", {}).items():
        frame.loc[row, column] = value
    return frame


# -- values that are not finite in the model's dtype --------------------------------------
# A table's values are checked where the table is read (data/readers/table_reader.py: finite in float32,
# the dtype the models compute in) and again by the predictor against the graph's own input dtype;
# either names the file, the column, the line and the value.
@pytest.mark.parametrize("value", [1e308, -1e308, 3.5e38])
def test_a_value_beyond_float32_is_refused_naming_column_and_line(models, tmp_path, capsys, value):
    recording(cells={(5, "b_ohm"): value}).to_csv(tmp_path / "pass.csv", index=False)
    out = tmp_path / "classes.csv"
    code, _, err = run_main(capsys, f"model={models['classification']}", f"input={tmp_path / 'pass.csv'}",
                            f"output={out}")
    assert_one_line_error(code, err, "pass.csv: ", "'b_ohm'", "line 7", f"{value:g}", "float32")
    assert not out.exists()


def test_a_value_beyond_float32_in_parquet_names_the_row(models, tmp_path, capsys):
    recording(cells={(2, "a_ohm"): 1e308}).to_parquet(tmp_path / "pass.parquet", index=False)
    code, _, err = run_main(capsys, f"model={models['classification']}", f"input={tmp_path / 'pass.parquet'}",
                            f"output={tmp_path / 'c.csv'}")
    assert_one_line_error(code, err, "pass.parquet: ", "'a_ohm'", "row 3", "1e+308", "float32")


def test_arrays_are_checked_in_the_graphs_input_dtype(models):
    """The array API (what bench/ and latency measurements call) casts to the graph's input dtype
    and refuses what is not finite there, naming the index and the channel."""
    classifier = OnnxPredictor(models["classification"])
    windows = np.ones((2, len(CHANNELS), WINDOW_STEPS))
    windows[1, 0, 3] = -1e308
    with pytest.raises(InputError, match=r"^windows\[1, 0, 3\] \(channel 'a_ohm'\) has -1e\+308, beyond the "
                                         r"model's float32 range \(±3.403e\+38\)$"):
        classifier.predict_windows(windows)
    windows[1, 0, 3] = np.nan
    with pytest.raises(InputError, match=r"^windows\[1, 0, 3\] \(channel 'a_ohm'\) has nan \(not finite\)$"):
        classifier.predict_windows(windows)
    with pytest.raises(InputError, match="input values must be real numbers, got dtype complex128"):
        classifier.predict_windows(windows.astype(complex))
    # the regression graph takes float64: 1e308 is a valid input there, and its float32 part makes
    # the output inf, which is refused too
    regressor = OnnxPredictor(models["regression"])
    assert regressor.input_dtype == np.float64
    with pytest.raises(InputError, match=r"^readings row 1: the model's output 'prediction' is not finite"):
        regressor.predict_array(np.array([[1.0, 2.0], [1e308, 1.0]]))
    np.testing.assert_allclose(regressor.predict_array(np.array([[1.0, 2.0]]))["prediction"], [[3.0]])


def test_an_infinite_output_is_refused_not_written(models, tmp_path, capsys):
    """Two readings within float32 whose sum in the graph's float32 part is not: the prediction is
    inf, and is refused rather than written."""
    pd.DataFrame({"a_ohm": [1.0, 3e38, 2.0], "b_ohm": [1.0, 3e38, 1.0]}).to_csv(tmp_path / "rig.csv", index=False)
    out = tmp_path / "pred.csv"
    code, _, err = run_main(capsys, f"model={models['regression']}", f"input={tmp_path / 'rig.csv'}", f"output={out}")
    assert_one_line_error(code, err, "rig.csv: line 3: the model's output 'prediction' is not finite")
    assert not out.exists()


def test_finite_input_whose_probabilities_overflow_is_refused(models, tmp_path, capsys):
    """Every value fits float32, but the graph's sum over the window overflows: NaN
    probabilities are never written."""
    big = recording(steps=2 * WINDOW_STEPS)
    big.iloc[WINDOW_STEPS:] = 3e38  # the second window
    big.to_csv(tmp_path / "pass.csv", index=False)
    out = tmp_path / "classes.csv"
    code, _, err = run_main(capsys, f"model={models['classification']}", f"input={tmp_path / 'pass.csv'}",
                            f"output={out}")
    assert_one_line_error(code, err, f"pass.csv: the window starting at line {WINDOW_STEPS + 2}: the model's output "
                                     "'probabilities' is not finite")
    assert not out.exists()


def test_ordinary_input_is_predicted_and_written_finite(models, tmp_path, capsys):
    """The same models and files without the bad value: the predictions are written, all finite."""
    recording().to_csv(tmp_path / "pass.csv", index=False)
    code, out, err = run_main(capsys, f"model={models['classification']}", f"input={tmp_path / 'pass.csv'}",
                              f"output={tmp_path / 'classes.csv'}")
    assert code == 0 and "wrote 2 rows" in out, err
    classes = pd.read_csv(tmp_path / "classes.csv")
    assert list(classes.columns) == ["start_step", "predicted"] + [f"p_{c}" for c in CLASSES]
    probabilities = classes[[f"p_{c}" for c in CLASSES]].to_numpy()
    assert np.isfinite(probabilities).all() and np.allclose(probabilities.sum(axis=1), 1.0, atol=1e-6)
    pd.DataFrame({"a_ohm": [1.0, 2.5], "b_ohm": [2.0, 1.5]}).to_parquet(tmp_path / "rig.parquet")
    code, _, err = run_main(capsys, f"model={models['regression']}", f"input={tmp_path / 'rig.parquet'}",
                            f"output={tmp_path / 'pred.parquet'}")
    assert code == 0, err
    np.testing.assert_allclose(pd.read_parquet(tmp_path / "pred.parquet")["x_mm"], [3.0, 4.0])


# -- the output is the input, or cannot be written ----------------------------------------
@pytest.fixture
def sample(models, tmp_path):
    """A recording file and a function giving the arguments that would predict it into `output`."""
    recording().to_csv(tmp_path / "pass.csv", index=False)
    return lambda output: [f"model={models['classification']}", f"input={tmp_path / 'pass.csv'}", f"output={output}"]


def test_output_equal_to_input_is_refused_and_the_input_kept(sample, tmp_path, capsys, monkeypatch):
    before = (tmp_path / "pass.csv").read_bytes()
    (tmp_path / "sub").mkdir()
    (tmp_path / "link.csv").symlink_to(tmp_path / "pass.csv")
    os.link(tmp_path / "pass.csv", tmp_path / "hard.csv")
    monkeypatch.chdir(tmp_path / "sub")
    for output in (tmp_path / "pass.csv", "../pass.csv", "./../sub/../pass.csv", tmp_path / "link.csv",
                   tmp_path / "hard.csv"):
        code, _, err = run_main(capsys, *sample(output))
        assert_one_line_error(code, err, f"output={Path(output)} is the input file", "never overwrites its input")
    assert (tmp_path / "pass.csv").read_bytes() == before


def test_output_equal_to_the_model_is_refused(sample, models, capsys):
    before = models["classification"].read_bytes()
    code, _, err = run_main(capsys, *sample(models["classification"]))
    assert_one_line_error(code, err, "is the model file")
    assert models["classification"].read_bytes() == before


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc and /sys are Linux's")
@pytest.mark.parametrize("output, fragments", [
    ("{tmp}/pass.csv/pred.csv", ["pass.csv is a file, not a folder"]),  # parent is a file
    ("/proc/touchstone/pred.csv", ["cannot create folder /proc/touchstone"]),  # a parent nobody can create
    ("/sys/touchstone_pred.csv", ["/sys"]),  # a folder nobody may create files in, root included
    ("{tmp}", ["is a folder; name a file in it"]),
    ("{tmp}/", ["is a folder; name a file in it"]),
    ("", ["is a folder; name a file in it"]),
    ("{tmp}/pipe", ["exists and is not a regular file"]),  # a FIFO here: a device like /dev/null would be
])                                                        # replaced for everyone by a regression run as root
def test_unwritable_output_is_one_line(sample, tmp_path, capsys, output, fragments):
    os.mkfifo(tmp_path / "pipe")
    output = output.format(tmp=tmp_path)
    code, _, err = run_main(capsys, *sample(output))
    assert_one_line_error(code, err, f"output={Path(output)}", *fragments)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cls.onnx", "pass.csv", "pipe", "reg.onnx"]
    assert not (tmp_path / "pipe").is_file()


def test_missing_output_folders_are_created(sample, tmp_path, capsys):
    code, _, err = run_main(capsys, *sample(tmp_path / "new" / "deeper" / "classes.csv"))
    assert code == 0, err
    assert len(pd.read_csv(tmp_path / "new" / "deeper" / "classes.csv")) == 2


# -- malformed model files and metadata ---------------------------------------------------
def without(metadata, key):
    return {k: v for k, v in metadata.items() if k != key}


def replaced(metadata, key, value):
    return {**metadata, key: value}


REG, CLS = regression_metadata(), classification_metadata()
METADATA_CASES = [
    ("regression", {}, "not a Touchstone model (no metadata key 'kind')"),
    ("regression", without(REG, "kind"), "no metadata key 'kind'"),
    ("regression", replaced(REG, "kind", "clustering"), "metadata 'kind' must be one of regression, classification"),
    ("regression", without(REG, "channels"), "metadata key 'channels' is missing"),
    ("regression", without(REG, "targets"), "metadata key 'targets' is missing"),
    ("regression", without(REG, "outputs"), "metadata key 'outputs' is missing"),
    ("classification", without(CLS, "classes"), "metadata key 'classes' is missing"),
    ("classification", without(CLS, "window_steps"), "metadata key 'window_steps' is missing"),
    ("regression", replaced(REG, "channels", '["a_ohm", "b_ohm"'), "metadata 'channels' is not valid JSON"),
    ("regression", replaced(REG, "targets", "x_mm"), "metadata 'targets' is not valid JSON"),
    ("regression", replaced(REG, "channels", '"a_ohm"'), "metadata 'channels' must be a non-empty JSON list of names"),
    ("regression", replaced(REG, "channels", "[1, 2]"), "metadata 'channels' must be a non-empty JSON list of names"),
    ("regression", replaced(REG, "targets", "[]"), "metadata 'targets' must be a non-empty JSON list of names"),
    ("regression", replaced(REG, "targets", "null"), "metadata 'targets' must be a non-empty JSON list of names"),
    ("regression", replaced(REG, "outputs", '{"prediction": 1}'), "metadata 'outputs' must be a non-empty JSON list"),
    ("regression", replaced(REG, "channels", '["a_ohm", "a_ohm"]'), "metadata 'channels' lists 'a_ohm' more than once"),
    ("classification", replaced(CLS, "window_steps", "abc"), "metadata 'window_steps' must be a positive whole number"),
    ("classification", replaced(CLS, "window_steps", "0"), "metadata 'window_steps' must be a positive whole number"),
    ("classification", replaced(CLS, "window_steps", "-4"), "metadata 'window_steps' must be a positive whole number"),
    ("classification", replaced(CLS, "window_steps", "4.0"), "metadata 'window_steps' must be a positive whole number"),
    ("classification", replaced(CLS, "window_steps", "8"),
     "but metadata 'channels' and window_steps say (batch, 2, 8)"),
    ("regression", replaced(REG, "channels", json.dumps(CHANNELS + ["c_ohm"])), "metadata 'channels' say (batch, 3)"),
    ("regression", replaced(REG, "targets", '["x_mm", "y_mm"]'), "metadata 'targets' names 2"),
    ("classification", replaced(CLS, "classes", '["soft"]'), "metadata 'classes' names 1"),
    ("regression", replaced(REG, "outputs", '["probabilities"]'), "metadata 'outputs' says ['probabilities']"),
    ("regression", replaced(REG, "kind", "classification"), "metadata key 'classes' is missing"),
    ("classification", replaced(CLS, "kind", "regression"), "metadata key 'targets' is missing"),
    ("classification", replaced(CLS, "sample_rate_hz", "fast"),
     "metadata 'sample_rate_hz' must be a positive number of hertz or 'unknown', got 'fast'"),
    ("classification", replaced(CLS, "sample_rate_hz", "-250"), "metadata 'sample_rate_hz' must be a positive number"),
    ("regression", replaced(REG, "input", "window"), "metadata 'input' must be 'channels' for a regression model"),
    ("classification", replaced(CLS, "input", "frames"), "metadata 'input' must be 'channels' or 'window'"),
    ("classification", {**REG, "kind": "classification", "classes": json.dumps(CLASSES), "window_steps": "4"},
     "the graph takes ['window'], expected one input 'channels'"),
]


@pytest.mark.parametrize("kind, metadata, fragment", METADATA_CASES)
def test_malformed_metadata_is_one_line_naming_file_and_key(tmp_path, capsys, kind, metadata, fragment):
    build = regression_model if kind == "regression" else classification_model
    if "expected one input 'channels'" in fragment:  # a classification graph labelled regression
        metadata = replaced(metadata, "kind", "regression")
    model = save(build(metadata), tmp_path / "model.onnx")
    recording().to_csv(tmp_path / "in.csv", index=False)
    out = tmp_path / "out.csv"
    code, _, err = run_main(capsys, f"model={model}", f"input={tmp_path / 'in.csv'}", f"output={out}")
    assert_one_line_error(code, err, f"{model}: ", fragment)
    assert not out.exists()


def test_a_graph_that_fails_on_the_input_is_one_line(tmp_path):
    """A graph with a named (dynamic) channel axis cannot be checked against its metadata when it
    is opened; one whose metadata list three channels for weights that take two fails when it
    runs: onnxruntime's error is our one line naming the file (its own log line is silenced)."""
    model = regression_model(replaced(REG, "channels", json.dumps(CHANNELS + ["c_ohm"])))
    model.graph.input[0].type.tensor_type.shape.dim[1].dim_param = "n_channels"
    save(model, tmp_path / "model.onnx")
    pd.DataFrame({"a_ohm": [1.0], "b_ohm": [2.0], "c_ohm": [3.0]}).to_csv(tmp_path / "in.csv", index=False)
    result = subprocess.run([sys.executable, str(ROOT / "predict.py"), "model=model.onnx", "input=in.csv",
                             "output=o.csv"], capture_output=True, text=True, cwd=tmp_path)
    assert_one_line_error(result.returncode, result.stderr, "error: model.onnx: the model failed to run (Fail: ",
                          "MatMul dimension mismatch")
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.parametrize("content, fragment", [
    (b"", "model file is empty"),
    (b"a_ohm,b_ohm\n1,2\n", "not a loadable ONNX model"),
    (b"\x00\xff" * 50, "not a loadable ONNX model"),
    ("truncated", "not a loadable ONNX model"),
    ("not_utf8", "metadata or tensor names are not UTF-8 text"),
    ("folder", "no such model file"),
    ("missing", "no such model file"),
])
def test_a_file_that_is_not_a_model_is_one_line(tmp_path, capsys, content, fragment):
    model = tmp_path / "model.onnx"
    if content == "truncated":
        whole = regression_model().SerializeToString()
        model.write_bytes(whole[:len(whole) // 2])
    elif content == "not_utf8":  # one byte of the metadata value "regression" flipped, lengths intact
        model.write_bytes(regression_model().SerializeToString().replace(b"regression", b"regr\xffssion"))
    elif content == "folder":
        model.mkdir()
    elif content != "missing":
        model.write_bytes(content)
    recording().to_csv(tmp_path / "in.csv", index=False)
    code, _, err = run_main(capsys, f"model={model}", f"input={tmp_path / 'in.csv'}", f"output={tmp_path / 'o.csv'}")
    assert_one_line_error(code, err, f"{model}: {fragment}")


# -- the command itself --------------------------------------------------------------------
def test_the_command_prints_one_line_and_exits_2(models, tmp_path):
    """As a user runs it: no RuntimeWarning from the float32 cast, one line, exit 2, no file."""
    recording(cells={(1, "a_ohm"): 1e308}).to_csv(tmp_path / "pass.csv", index=False)
    result = subprocess.run([sys.executable, str(ROOT / "predict.py"), f"model={models['classification']}",
                             "input=pass.csv", "output=classes.csv"], capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode == 2
    assert result.stderr.startswith("error: pass.csv: ") and result.stderr.count("\n") == 1, result.stderr
    assert all(fragment in result.stderr for fragment in ("'a_ohm'", "line 3", "1e+308", "float32")), result.stderr
    assert not (tmp_path / "classes.csv").exists()


# -- recordings as training reads them: NPZ and long tables ---------------------------------
def signals(n_recordings, steps, seed=0) -> np.ndarray:
    """(n, channels, steps) values in [0, 1): every window's probabilities differ."""
    return np.random.default_rng(seed).random((n_recordings, len(CHANNELS), steps))


def windows_of(X, steps=WINDOW_STEPS) -> np.ndarray:
    """Back-to-back windows of each recording, in order, the trailing part dropped: (windows, channels, steps)."""
    n = X.shape[2] // steps
    return np.concatenate([x[:, :n * steps].reshape(len(CHANNELS), n, steps).transpose(1, 0, 2) for x in X])


def probabilities(frame) -> np.ndarray:
    return frame[[f"p_{c}" for c in CLASSES]].to_numpy()


def test_an_npz_is_predicted_per_recording_with_channels_by_name(models, tmp_path, capsys):
    """Three recordings of 9 steps: two windows each (the ninth step is left over, and said so),
    rows carry the recording's index in X and the step the window starts at; channel_names in
    another order than the model's are put in the model's order."""
    X = signals(3, 2 * WINDOW_STEPS + 1)
    np.savez(tmp_path / "rig.npz", X=X[:, ::-1], channel_names=np.array(CHANNELS[::-1]),
             sample_rate_hz=np.array(SAMPLE_RATE_HZ))
    code, out, err = run_main(capsys, f"model={models['classification']}", f"input={tmp_path / 'rig.npz'}",
                              f"output={tmp_path / 'classes.csv'}")
    assert code == 0, err
    assert "wrote 6 rows from 3 recordings" in out and "3 steps after the last whole window" in out
    classes = pd.read_csv(tmp_path / "classes.csv")
    assert list(classes.columns) == ["recording", "start_step", "predicted"] + [f"p_{c}" for c in CLASSES]
    assert classes["recording"].tolist() == [0, 0, 1, 1, 2, 2]
    assert classes["start_step"].tolist() == [0, WINDOW_STEPS] * 3
    expected = OnnxPredictor(models["classification"]).predict_windows(windows_of(X))
    np.testing.assert_allclose(probabilities(classes), expected, rtol=1e-6)
    assert classes["predicted"].tolist() == [CLASSES[k] for k in expected.argmax(axis=1)]


@pytest.mark.parametrize("arrays, fragments", [
    ({"X": signals(2, 8, seed=1)[:, :1]}, ["the model reads channels a_ohm, b_ohm; the NPZ has channel_0",
                                           "save the names as channel_names"]),
    ({"X": signals(2, 8), "channel_names": np.array(["a_ohm", "c_ohm"])}, ["the NPZ has a_ohm, c_ohm"]),
    ({"X": signals(2, 8), "channel_names": np.array(CHANNELS), "sample_rate_hz": np.array(250.0)},
     ["sample_rate_hz says 250 Hz, but the model's windows are 100 Hz; resample"]),
    ({"X": signals(2, WINDOW_STEPS - 1), "channel_names": np.array(CHANNELS)},
     ["recording 0, 3 steps is shorter than the model's window of 4 steps"]),
    ({"X": signals(2, 8).astype(object), "channel_names": np.array(CHANNELS)},
     ["array 'X' is an object (pickled) array, which is refused"]),
    ({"y": np.array(["soft", "hard"])}, ["missing array 'X'"]),
    ({"X": signals(2, 8)[0], "channel_names": np.array(CHANNELS)}, ["X must be (n, channels, length)"]),
])
def test_a_bad_npz_is_one_line(models, tmp_path, capsys, arrays, fragments):
    np.savez(tmp_path / "rig.npz", **arrays)
    code, _, err = run_main(capsys, f"model={models['classification']}", f"input={tmp_path / 'rig.npz'}",
                            f"output={tmp_path / 'classes.csv'}")
    assert_one_line_error(code, err, f"{tmp_path / 'rig.npz'}: ", *fragments)
    assert not (tmp_path / "classes.csv").exists()


def test_a_value_beyond_float32_in_an_npz_names_recording_channel_and_step(models, tmp_path, capsys):
    X = signals(2, 8)
    X[1, 1, 5] = 1e308
    np.savez(tmp_path / "rig.npz", X=X, channel_names=np.array(CHANNELS))
    code, _, err = run_main(capsys, f"model={models['classification']}", f"input={tmp_path / 'rig.npz'}",
                            f"output={tmp_path / 'classes.csv'}")
    assert_one_line_error(code, err, "rig.npz: recording 1, channel 'b_ohm', step 5 has 1e+308, beyond the model's "
                                     "float32 range")


def test_an_npz_given_to_a_row_model_is_one_line(models, tmp_path, capsys):
    np.savez(tmp_path / "rig.npz", X=signals(2, 8), channel_names=np.array(CHANNELS))
    code, _, err = run_main(capsys, f"model={models['regression']}", f"input={tmp_path / 'rig.npz'}",
                            f"output={tmp_path / 'pred.csv'}")
    assert_one_line_error(code, err, "rig.npz: an NPZ holds recordings; this regression model reads one row per press")


def long_table(X, ids=("trial_b", "trial_a"), rate_hz=SAMPLE_RATE_HZ) -> pd.DataFrame:
    """Recordings X as a long table (one row per step, a recording id and a time column), rows shuffled."""
    parts = [pd.DataFrame({"recording": name, "time_s": np.arange(x.shape[1]) / rate_hz,
                           **{c: x[k] for k, c in enumerate(CHANNELS)}}) for name, x in zip(ids, X)]
    return pd.concat(parts, ignore_index=True).sample(frac=1.0, random_state=0)


def test_a_long_table_gives_one_prediction_set_per_recording(models, tmp_path, capsys):
    """Two recordings of 6 steps in one file, rows shuffled: one window each, from that recording's
    first steps in time order; cut by row position, 12 rows would give 3 windows, the second across
    the boundary. Rows carry the recording id (ids in sorted order, as training reads them)."""
    X = signals(2, WINDOW_STEPS + 2)
    long_table(X).to_csv(tmp_path / "rig.csv", index=False)
    code, out, err = run_main(capsys, f"model={models['classification']}", f"input={tmp_path / 'rig.csv'}",
                              f"output={tmp_path / 'classes.csv'}")
    assert code == 0 and "wrote 2 rows from 2 recordings" in out, err
    classes = pd.read_csv(tmp_path / "classes.csv")
    assert classes["recording"].tolist() == ["trial_a", "trial_b"] and classes["start_step"].tolist() == [0, 0]
    expected = OnnxPredictor(models["classification"]).predict_windows(windows_of(X[::-1]))
    np.testing.assert_allclose(probabilities(classes), expected, rtol=1e-6)


def test_a_long_table_names_its_columns_on_the_command_line(models, tmp_path, capsys):
    """recording_column= and time_column= name other columns; the output's id column keeps its name."""
    X = signals(2, WINDOW_STEPS)
    long_table(X).rename(columns={"recording": "trial", "time_s": "t_s"}).to_parquet(tmp_path / "rig.parquet")
    code, _, err = run_main(capsys, f"model={models['classification']}", f"input={tmp_path / 'rig.parquet'}",
                            f"output={tmp_path / 'classes.csv'}", "recording_column=trial", "time_column=t_s")
    assert code == 0, err
    classes = pd.read_csv(tmp_path / "classes.csv")
    assert classes["trial"].tolist() == ["trial_a", "trial_b"]
    np.testing.assert_allclose(probabilities(classes),
                               OnnxPredictor(models["classification"]).predict_windows(X[::-1]), rtol=1e-6)


@pytest.mark.parametrize("change, args, fragments", [
    ("rate", [], ["rig.csv: time column 'time_s' gives 50 Hz, but the model's windows are 100 Hz"]),
    ("none", ["recording_column=trial"], ["rig.csv: missing recording column(s) trial"]),
    ("none", ["time_column=clock_s"], ["rig.csv: missing time column(s) clock_s"]),
    ("empty_id", [], ["rig.csv: recording column 'recording' is empty in line "]),
    ("repeated_time", [], ["rig.csv: time column 'time_s' gives no positive time step"]),
    ("short", [], ["rig.csv: recording trial_a, 3 steps is shorter than the model's window of 4 steps"]),
    ("huge", [], ["rig.csv: channel column 'b_ohm' has 1e+308 in line "]),
    ("text_time", [], ["rig.csv: time column 'time_s' has a non-numeric value 'noon' in line "]),
])
def test_a_bad_long_table_is_one_line(models, tmp_path, capsys, change, args, fragments):
    X = signals(2, 2 * WINDOW_STEPS)
    frame = long_table(X, rate_hz=SAMPLE_RATE_HZ / 2 if change == "rate" else SAMPLE_RATE_HZ)
    if change == "empty_id":
        frame.iloc[3, 0] = None
    if change == "repeated_time":
        frame["time_s"] = 0.0
    if change == "short":
        frame = frame[(frame["recording"] == "trial_b") | (frame["time_s"] < 3 / SAMPLE_RATE_HZ)]
    if change == "text_time":
        frame["time_s"] = frame["time_s"].astype(object)
        frame.iloc[2, frame.columns.get_loc("time_s")] = "noon"
    if change == "huge":
        frame.iloc[5, frame.columns.get_loc("b_ohm")] = 1e308
    frame.to_csv(tmp_path / "rig.csv", index=False)
    code, _, err = run_main(capsys, f"model={models['classification']}", f"input={tmp_path / 'rig.csv'}",
                            f"output={tmp_path / 'classes.csv'}", *args)
    assert_one_line_error(code, err, *fragments)
    assert not (tmp_path / "classes.csv").exists()


def test_an_infinite_output_names_the_recording_and_its_window(models, tmp_path, capsys):
    X = signals(2, 2 * WINDOW_STEPS)
    X[1, :, WINDOW_STEPS:] = 3e38  # trial_a's second window overflows in the graph's sum
    frame = long_table(X, ids=("trial_b", "trial_a"))
    frame.to_csv(tmp_path / "rig.csv", index=False)
    line = int(np.flatnonzero((frame["recording"] == "trial_a").to_numpy() & (frame["time_s"] == 0.04).to_numpy())[0]) + 2
    code, _, err = run_main(capsys, f"model={models['classification']}", f"input={tmp_path / 'rig.csv'}",
                            f"output={tmp_path / 'classes.csv'}")
    assert_one_line_error(code, err, f"rig.csv: recording trial_a, the window starting at line {line}: the model's "
                                     "output 'probabilities' is not finite")


def test_a_row_classifier_writes_classes_per_row_and_carries_the_id_column(tmp_path, capsys):
    """A classifier of table rows (input 'channels'): one output row per input row, the predicted
    class and its probabilities, with the recording column copied through."""
    model = save(row_classification_model(), tmp_path / "rows.onnx")
    pd.DataFrame({"recording": ["p1", "p2"], "a_ohm": [3.0, 0.0], "b_ohm": [0.0, 3.0]}).to_csv(tmp_path / "pads.csv",
                                                                                               index=False)
    code, _, err = run_main(capsys, f"model={model}", f"input={tmp_path / 'pads.csv'}", f"output={tmp_path / 'o.csv'}")
    assert code == 0, err
    out = pd.read_csv(tmp_path / "o.csv")
    assert list(out.columns) == ["recording", "predicted"] + [f"p_{c}" for c in CLASSES]
    assert out["recording"].tolist() == ["p1", "p2"] and out["predicted"].tolist() == ["soft", "hard"]
    np.testing.assert_allclose(out["p_soft"], [1 / (1 + np.exp(-6)), 1 / (1 + np.exp(6))], rtol=1e-6)


# -- --help -----------------------------------------------------------------------------------
@pytest.mark.parametrize("flag", ["--help", "-h"])
def test_help_lists_the_arguments_and_an_example(capsys, flag):
    code, out, err = run_main(capsys, flag)
    assert code == 0 and err == ""
    assert out.startswith("usage: python predict.py model=")
    for key in ("model=", "input=", "output=", "threads=", "recording_column=", "time_column="):
        assert f"\n  {key}" in out
    assert "python predict.py model=outputs/<run>/model.onnx input=" in out and "Add model=<file> to --help" in out


def test_help_with_a_model_lists_what_it_expects(models, tmp_path, capsys):
    code, out, _ = run_main(capsys, "--help", f"model={models['classification']}")
    assert code == 0
    described = out.split("This model:\n")[1]
    assert "channels (2, in this order): a_ohm (resistance, ohm), b_ohm (resistance, ohm)" in described
    assert "windows of 4 steps at 100 Hz (0.04 s)" in described and "classes (2): soft, hard" in described
    assert "output: recording (when the input names them), start_step, predicted, p_soft, p_hard" in described
    code, out, _ = run_main(capsys, f"model={models['regression']}", "-h")
    assert code == 0 and "output: x_mm (length, mm)" in out and "one row per press" in out
    unknown = save(classification_model(replaced(classification_metadata(), "sample_rate_hz", "unknown")),
                   tmp_path / "unknown_rate.onnx")
    code, out, _ = run_main(capsys, "--help", f"model={unknown}")
    assert code == 0 and "windows of 4 steps (sample rate unknown)" in out


def test_help_with_a_bad_model_or_argument_is_one_line(tmp_path, capsys):
    code, _, err = run_main(capsys, "--help", f"model={tmp_path / 'none.onnx'}")
    assert_one_line_error(code, err, "none.onnx: no such model file")
    code, _, err = run_main(capsys, "--help", "colour=red")
    assert_one_line_error(code, err, "unknown argument 'colour=red'", "--help lists them")


def test_the_help_command_exits_0():
    result = subprocess.run([sys.executable, str(ROOT / "predict.py"), "--help"], capture_output=True, text=True)
    assert result.returncode == 0 and result.stderr == "" and "usage: python predict.py" in result.stdout
