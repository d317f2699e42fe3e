"""The fresh-clone walk-through, as a new user types it: their own CSV of presses (a measured
target, then a string-labelled region), their own NPZ of recordings, each trained with default
settings (only the file's path and the target's name given) and predicted with predict.py on the
file they trained on and on the run's predictions.csv where that is a ready input.

The files are small and generated with a known relation, so each trained model must actually have
learned it: scores are checked against what a model that learned nothing would get."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[2]
CLASS_COLUMNS = ["p_left", "p_middle", "p_right"]


def command(script, *args, cwd):
    """`python <script> args` from `cwd`, as a user runs it (CI=true: log lines, no bars)."""
    return subprocess.run([sys.executable, str(ROOT / script), *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=600, env=dict(os.environ, CI="true"))


def train(tmp_path, *overrides) -> Path:
    run = tmp_path / "run"
    result = command("train.py", *overrides, f"hydra.run.dir={run}", cwd=tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    assert json.loads((run / "status.json").read_text())["state"] == "finished"
    return run


def predict(tmp_path, run: Path, source, output="pred.csv") -> pd.DataFrame:
    result = command("predict.py", f"model={run / 'model.onnx'}", f"input={source}", f"output={output}", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("wrote ") and result.stderr == ""
    return pd.read_csv(tmp_path / output)


def presses(n=200, seed=0) -> pd.DataFrame:
    """A two-electrode pad pressed at a position along it to a depth: each electrode reads the
    depth shared by its distance from the press, plus a channel that is noise."""
    rng = np.random.default_rng(seed)
    position, depth = rng.uniform(0, 1, n), rng.uniform(0.5, 3.0, n)
    return pd.DataFrame({"left_v": depth * (1 - position) + rng.normal(0, 0.05, n),
                         "right_v": depth * position + rng.normal(0, 0.05, n),
                         "ref_v": rng.normal(0, 1, n), "depth_mm": depth,
                         "region": np.select([position < 1 / 3, position < 2 / 3], ["left", "middle"], "right")})


@pytest.mark.slow  # the default pipeline (a K-fold blend of three candidates): 38 s here beside other work
def test_a_csv_of_presses_with_a_measured_target(tmp_path):
    """`python train.py data=table data.path=pads.csv data.target_columns=[depth_mm]`, then
    predict.py on the pads and on the run's predictions.csv."""
    pads = presses().drop(columns="region")
    pads.to_csv(tmp_path / "pads.csv", index=False)
    run = train(tmp_path, "data=table", "data.path=pads.csv", "data.target_columns=[depth_mm]")
    predicted = predict(tmp_path, run, "pads.csv")
    assert len(predicted) == len(pads) and np.isfinite(predicted.to_numpy()).all()
    error = np.abs(predicted["depth_mm"] - pads["depth_mm"]).mean()
    assert error < 0.5 * np.abs(pads["depth_mm"] - pads["depth_mm"].mean()).mean()  # beats the mean by 2x
    ours = pd.read_csv(run / "predictions.csv")
    again = predict(tmp_path, run, run / "predictions.csv", "again.csv")
    np.testing.assert_allclose(again.to_numpy(), ours[list(again.columns)].to_numpy(), rtol=1e-4, atol=1e-4)


def test_a_csv_of_presses_with_a_string_target(tmp_path):
    """`python train.py data=table data.path=regions.csv data.target_columns=[region]`: a
    classifier of rows, whose predictions.csv is a ready predict.py input."""
    regions = presses().drop(columns="depth_mm")
    regions.to_csv(tmp_path / "regions.csv", index=False)
    run = train(tmp_path, "data=table", "data.path=regions.csv", "data.target_columns=[region]")
    predicted = predict(tmp_path, run, "regions.csv")
    assert list(predicted.columns) == ["predicted"] + CLASS_COLUMNS
    assert (predicted["predicted"] == regions["region"]).mean() >= 0.8  # chance: 1/3
    ours = pd.read_csv(run / "predictions.csv")
    again = predict(tmp_path, run, run / "predictions.csv", "again.csv")
    assert again["predicted"].tolist() == ours["predicted"].tolist()
    np.testing.assert_allclose(again[CLASS_COLUMNS].to_numpy(), ours[CLASS_COLUMNS].to_numpy(), rtol=1e-4, atol=1e-6)


def recordings(n=30, steps=50, seed=0):
    """Recordings of a press and a slip channel (volts) at 100 Hz; the class raises one of them."""
    rng = np.random.default_rng(seed)
    y = np.array(["soft", "hard", "medium"] * (n // 3))
    X = rng.normal(size=(n, 2, steps))
    X[y == "hard", 0] += 2.0
    X[y == "medium", 1] += 2.0
    return X, y


def save_recordings(tmp_path):
    X, y = recordings()
    np.savez(tmp_path / "rig.npz", X=X, y=y, channel_names=np.array(["press_v", "slip_v"]),
             sample_rate_hz=np.array(100.0))
    return X, y


def test_an_npz_of_recordings_without_a_model_trains_the_default_choice(tmp_path):
    """No model named: the default chooses a recordings model on validation (a budget that leaves
    room for MiniRocket only: its first candidate, the cheapest), and predict.py reads the NPZ; model=blend, which regresses tables,
    is refused in one line that says what to do instead."""
    X, y = save_recordings(tmp_path)
    run = train(tmp_path, "data=recordings_npz", "data.path=rig.npz", "model.budget_s=0.001")
    choice = json.loads((run / "metrics.json").read_text())["choice"]
    assert choice["chosen"] == "minirocket"
    assert set(choice["skipped"]) == {"hydra_minirocket", "rocket_mixture", "prcnn", "rescnn", "inceptiontime"}
    assert (predict(tmp_path, run, "rig.npz")["predicted"] == y).mean() >= 0.8  # chance: 1/3
    result = command("train.py", "data=recordings_npz", "data.path=rig.npz", "model=blend",
                     f"hydra.run.dir={tmp_path / 'refused'}", cwd=tmp_path)
    assert result.returncode == 2 and result.stderr.count("\n") == 1 and "leave model= out" in result.stderr
    assert not (tmp_path / "refused").exists()


# PR-CNN (a network, 15 epochs) takes ~55 s of the default suite's 8 min: slow; MiniRocket runs the
# same reading and predicting path in a few seconds
@pytest.mark.parametrize("model", ["minirocket", pytest.param("prcnn", marks=pytest.mark.slow)])
def test_an_npz_of_recordings(tmp_path, model):
    """`python train.py data=recordings_npz data.path=rig.npz model=<model>` (the README's command
    with a model named), then predict.py on the NPZ (one row per recording) and on the same recordings as a long table
    with shuffled rows."""
    X, y = save_recordings(tmp_path)
    run = train(tmp_path, "data=recordings_npz", "data.path=rig.npz", f"model={model}")
    predicted = predict(tmp_path, run, "rig.npz")
    assert predicted["recording"].tolist() == list(range(len(X))) and (predicted["start_step"] == 0).all()
    assert (predicted["predicted"] == y).mean() >= 0.8  # chance: 1/3
    ours = pd.read_csv(run / "predictions.csv")  # its validation and test recordings, by index in the file
    classes = [c for c in ours.columns if c.startswith("p_")]
    np.testing.assert_allclose(predicted.loc[ours["recording"], classes].to_numpy(), ours[classes].to_numpy(),
                               rtol=1e-4, atol=1e-6)
    steps = np.arange(X.shape[2])
    table = pd.concat([pd.DataFrame({"recording": k, "time_s": steps / 100.0, "press_v": x[0], "slip_v": x[1]})
                       for k, x in enumerate(X)], ignore_index=True).sample(frac=1.0, random_state=0)
    table.to_csv(tmp_path / "rig.csv", index=False)
    pd.testing.assert_frame_equal(predict(tmp_path, run, "rig.csv", "from_table.csv"), predicted, rtol=1e-6)
