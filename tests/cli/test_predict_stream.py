"""predict.py on a live stream, end to end as a rig would run it: lines through a pipe (standard
input) and through a pseudo-terminal (a serial port's stand-in, opened with pyserial), for every
kind of model (table regression, table classification, recordings classifier over a sliding
window, the contact tracker per frame), with bad lines mixed in. The predictions must be the
ones the batch predict.py writes for the same good lines (or, for the tracker, the ones the
tracker gives frame by frame), every bad line reported with its number, the summary counting
them all."""
import io
import json
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from tests.predict_support import (
    CHANNELS,
    WINDOW_STEPS,
    classification_model,
    contact_frames,
    force_model,
    predict_main,
    regression_model,
    row_classification_model,
    save,
)

ROOT = Path(__file__).resolve().parents[2]
BAD_LINES = ["abc,1", "1,nan", "1e308,2", "5", "1,2,3,4", "-1,2"]   # text, NaN, beyond float32, counts, a negative ohm
WHY = ["'abc' is not a number", "is nan, not finite", "beyond float32", "1 values, expected 2",
       "4 values, expected 2", "outside its physical range"]


def good_lines(n: int, seed: int = 0) -> list[str]:
    rng = np.random.default_rng(seed)
    return [",".join(repr(float(v)) for v in row) for row in rng.uniform(0.1, 5.0, (n, len(CHANNELS)))]


def mixed(good: list[str]) -> tuple[list[str], list[int]]:
    """The good lines with the bad ones spread among them; the bad lines' 1-based numbers."""
    lines, bad_numbers = list(good), []
    for k, bad in enumerate(BAD_LINES):
        at = 2 + 3 * k
        lines.insert(at, bad)
        bad_numbers.append(at + 1)
    return lines, bad_numbers


def command(model, *args) -> list[str]:
    return [sys.executable, str(ROOT / "predict.py"), f"model={model}", *map(str, args)]


def through_pipe(model, lines, *args) -> tuple[int, str, str]:
    done = subprocess.run(command(model, "input=-", *args), input="\n".join(lines) + "\n", capture_output=True,
                          text=True, timeout=120, cwd=ROOT)
    return done.returncode, done.stdout, done.stderr


def started(argv) -> tuple[subprocess.Popen, threading.Timer]:
    """predict.py started with pipes, and a watchdog that kills it should a test hang."""
    process = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT)
    watchdog = threading.Timer(120, process.kill)
    watchdog.start()
    return process, watchdog


def through_pty(model, lines, *args) -> tuple[int, str, str]:
    """The lines written into a pseudo-terminal's master while predict.py reads its serial end;
    the master closes once predict.py said it reads (the end of the stream, as a cable pulled)."""
    master, slave = os.openpty()   # predict.py opens the slave end with pyserial (requirements.lock pins it)
    process, watchdog = started(command(model, f"input={os.ttyname(slave)}", *args))
    try:
        first = process.stderr.readline()
        assert first.startswith("reading "), first
        # a port is quiet until the rig sends: predict.py's first read waits on an empty port (a read
        # that returned at once there ended the stream before its first line, as pyserial's VMIN = 0 did)
        time.sleep(0.3)
        os.write(master, ("\n".join(lines) + "\n").encode())
        out_lines = [process.stdout.readline()]   # the header, then one line per prediction
        expected = predictions_expected(model, lines)
        while len(out_lines) < 1 + expected:
            out_lines.append(process.stdout.readline())
        os.close(master)
        # read the rest through the same buffered files: communicate() reads the raw pipes and would
        # lose what readline() had already buffered
        process.wait()
        out, err = process.stdout.read(), process.stderr.read()
    finally:
        watchdog.cancel()
        os.close(slave)
    return process.returncode, "".join(out_lines) + out, first + err


def predictions_expected(model, lines) -> int:
    good = [line for line in lines if line not in BAD_LINES]
    name = Path(model).name
    if name == "cls.onnx":
        return len(good) // WINDOW_STEPS
    if name == "force.onnx":   # a frame is 36 finite cells; the tracker's test mixes in its own bad frames
        return len([line for line in good if len(line.split(",")) == 36 and "nan" not in line]) - N_REST
    return len(good)


def batch(tmp_path, model, good: list[str]) -> pd.DataFrame:
    """What predict.py writes for the same lines as a file."""
    source, output = tmp_path / "batch_in.csv", tmp_path / "batch_out.csv"
    source.write_text(",".join(CHANNELS) + "\n" + "\n".join(good) + "\n")
    assert predict_main([f"model={model}", f"input={source}", f"output={output}"]) == 0
    return pd.read_csv(output)


@pytest.fixture
def models(tmp_path):
    return {"regression": save(regression_model(), tmp_path / "reg.onnx"),
            "row_classification": save(row_classification_model(), tmp_path / "rowcls.onnx"),
            "classification": save(classification_model(), tmp_path / "cls.onnx"),
            "tracker": save(force_model(), tmp_path / "force.onnx")}


@pytest.mark.parametrize("via", [through_pipe, through_pty], ids=["pipe", "pty"])
@pytest.mark.parametrize("kind", ["regression", "row_classification", "classification"])
def test_a_stream_predicts_what_the_batch_predicts(tmp_path, models, kind, via):
    good = good_lines(4 * WINDOW_STEPS + 1)
    lines, bad_numbers = mixed(good)
    code, out, err = via(models[kind], lines)
    assert code == 0, err
    streamed = pd.read_csv(io.StringIO(out))
    expected = batch(tmp_path, models[kind], good)
    if kind == "classification":
        expected = expected.drop(columns="start_step")
        assert len(streamed) == len(good) // WINDOW_STEPS
    columns = list(expected.columns)
    assert list(streamed.columns) == ["line", "time_s"] + (["start_line"] if kind == "classification" else []) \
        + columns + ["latency_us"]
    probabilities = [c for c in columns if c.startswith("p_")]   # float32: the batch CSV writes float32's digits
    streamed[probabilities] = streamed[probabilities].astype(np.float32)
    expected[probabilities] = expected[probabilities].astype(np.float32)
    pd.testing.assert_frame_equal(streamed[columns], expected, check_exact=True)
    good_numbers = [k + 1 for k in range(len(lines)) if k + 1 not in bad_numbers]
    step = WINDOW_STEPS if kind == "classification" else 1
    assert streamed["line"].tolist() == good_numbers[step - 1::step][:len(streamed)]
    for number, why in zip(bad_numbers, WHY):
        assert f"line {number}: " in err and why in err.split(f"line {number}: ")[1].splitlines()[0], (why, err)
    summary = err.strip().splitlines()[-1]
    assert summary.startswith(f"stream ended: {len(lines)} lines read, {len(streamed)} predicted, "
                              f"{len(BAD_LINES)} skipped (bad)"), summary
    assert "latency p50" in summary and "p99" in summary


N_REST = 20


@pytest.mark.parametrize("via", [through_pipe, through_pty], ids=["pipe", "pty"])
def test_the_tracker_streams_frame_by_frame_as_it_tracks_a_recording(models, via):
    from models.contact_tracking import ContactTracker
    frames = contact_frames(n_rest=N_REST, n_press=12)
    lines = [",".join(f"{v:.3f}" for v in frame) for frame in frames]
    lines.insert(N_REST + 3, "1,2,3")                       # a frame with 3 cells of 36
    lines.insert(N_REST + 6, ",".join(["nan"] * 36))
    code, out, err = via(models["tracker"], lines, "rows=6", "cols=6", f"n_rest_frames={N_REST}")
    assert code == 0, err
    streamed = pd.read_csv(io.StringIO(out), dtype={"id": str, "x_mm": str, "force_n": str})
    assert len(streamed) == len(frames) - N_REST
    assert f"line {N_REST + 4}: 3 values, expected 36" in err and f"line {N_REST + 7}: column 'cell_r0_c0' is nan" in err
    # the same frames (as the stream parsed them) through the tracker itself, force from the same graph
    from export.onnx_predictor import OnnxPredictor
    predictor = OnnxPredictor(models["tracker"], threads=1)
    parsed = np.array([[float(f"{v:.3f}") for v in frame] for frame in frames])
    tracker = ContactTracker(rows=6, cols=6, pitch_mm=10.0, force_feature="window",
                             force_model=lambda w: predictor.predict_array(w)["prediction"][:, 0])
    tracker.fit(parsed[:N_REST].reshape(-1, 6, 6))
    for row, frame in zip(streamed.itertuples(), parsed[N_REST:]):
        contacts = tracker.update(frame.reshape(6, 6))
        assert row.contacts == len(contacts.ids) and row.contacts >= 1
        assert [int(i) for i in row.id.split(";")] == contacts.ids.tolist()
        assert [float(x) for x in row.x_mm.split(";")] == np.round(contacts.x_mm, 3).tolist()
        assert [float(f) for f in row.force_n.split(";")] == np.round(contacts.force_n, 4).tolist()
    assert err.strip().splitlines()[-1].startswith(f"stream ended: {len(lines)} frames read, {len(frames) - N_REST} "
                                                   f"predicted, 2 skipped (bad), {N_REST} not predicted")


def test_on_bad_line_stop_exits_2_with_the_line_and_leaves_no_output(models, tmp_path):
    output = tmp_path / "live.csv"
    code, out, err = through_pipe(models["regression"], ["1,2", "3,4", "1,x", "5,6"], "on_bad_line=stop",
                                  f"output={output}")
    assert code == 2
    assert err.strip().splitlines()[-1] == "error: stdin: line 3: 'x' is not a number (on_bad_line=stop)"
    assert not output.exists() and not list(tmp_path.glob("live.csv*"))


def test_a_file_output_and_json_lines_and_a_summary_file(models, tmp_path):
    output, summary = tmp_path / "live.jsonl", tmp_path / "summary.json"
    lines = ["time_s,a_ohm,b_ohm", "0.5,1,2", "0.6,3,4"]
    code, out, err = through_pipe(models["regression"], lines, f"output={output}", f"summary={summary}")
    assert code == 0, err
    rows = [json.loads(line) for line in output.read_text().splitlines()]
    assert [row["time_s"] for row in rows] == [0.5, 0.6] and [row["x_mm"] for row in rows] == [3.0, 7.0]
    assert [row["line"] for row in rows] == [2, 3]
    counts = json.loads(summary.read_text())
    assert counts["lines_read"] == 2 and counts["predicted"] == 2 and counts["skipped"] == 0


def test_a_socket_source_listens_on_localhost_only(models):
    process, watchdog = started(command(models["regression"], "input=tcp://:0"))
    try:
        said = process.stderr.readline()
        assert said.startswith("listening on 127.0.0.1:"), said
        port = int(said.split(":")[1].split()[0])
        with socket.create_connection(("127.0.0.1", port)) as connection:
            connection.sendall(b"1,2\n3,4\n")
        out, err = process.communicate()
    finally:
        watchdog.cancel()
    assert process.returncode == 0, err
    assert pd.read_csv(io.StringIO(out))["x_mm"].tolist() == [3.0, 7.0]


def test_a_recordings_stream_at_another_rate_is_refused(models):
    lines = [f"{k * 0.02},{k},{k}" for k in range(2 * WINDOW_STEPS)]   # 50 Hz; the model's windows are 100 Hz
    code, out, err = through_pipe(models["classification"], lines)
    assert code == 2 and "give 50 Hz, but the model's windows are 100 Hz" in err


def test_hop_slides_the_window(models):
    good = good_lines(2 * WINDOW_STEPS)
    code, out, err = through_pipe(models["classification"], good, "hop=1")
    assert code == 0, err
    streamed = pd.read_csv(io.StringIO(out))
    assert streamed["start_line"].tolist() == list(range(1, WINDOW_STEPS + 2))
    assert streamed["line"].tolist() == list(range(WINDOW_STEPS, 2 * WINDOW_STEPS + 1))


def test_help_names_the_stream_settings_without_a_model():
    done = subprocess.run([sys.executable, str(ROOT / "predict.py"), "--help"], capture_output=True, text=True,
                          timeout=60, cwd=ROOT)
    assert done.returncode == 0
    for key in ("backlog=", "on_bad_line=", "hop=", "rows=", "baud=", "--plot"):
        assert key in done.stdout, key
