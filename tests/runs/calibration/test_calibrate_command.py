"""`python train.py experiment=calibrate scene=... data=table data.path=...` end to end on a small
stand-in rig's table: the fit's report, the calibrated scene (which `scene=` accepts through a
search path), the choice and its reason, model.onnx that predict.py runs; and a bad calibration
table stops with one line, exit 2, and no outputs."""
import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate

from data.calibration.rig_standin import hidden_parameters, rig_presses
from tests.conftest import CONFIG_DIR
from tests.predict_support import ROOT, predict_main

SMALL = ["calibration.n_simulated=150", "calibration.max_evaluations=12", "model.n_estimators=8",
         "cost.onnx_latency_calls=0", "scene.progress=false"]


def train(*overrides):
    return subprocess.run([sys.executable, "train.py", "experiment=calibrate", *SMALL, *overrides],
                          capture_output=True, text=True, cwd=ROOT)


@pytest.fixture
def presses(compose_config, tmp_path):
    scene = instantiate(compose_config(["scene=taxels"]).scene)
    frame = rig_presses(scene, hidden_parameters(scene, np.random.default_rng(5)), 5, 30)
    path = tmp_path / "presses.csv"
    frame.to_csv(path, index=False)
    return path, frame


@pytest.mark.slow
def test_the_one_command_fits_pretrains_chooses_and_exports(presses, tmp_path):
    path, frame = presses
    run_dir = tmp_path / "run"
    result = train("scene=taxels", "data=table", f"data.path={path}", f"hydra.run.dir={run_dir}")
    assert result.returncode == 0, result.stderr[-3000:]
    log = result.stdout + result.stderr
    assert "scene fit: taxels, 3 parameters" in log and "calibration choice:" in log
    metrics = json.loads((run_dir / "metrics.json").read_text())
    assert metrics["choice"]["chosen"] in ("scratch", "default_scene", "fitted_scene")
    assert "validation presses no candidate was fitted on" in metrics["choice"]["reason"]
    fitted = metrics["calibration"]["parameters"]
    assert set(fitted) == {"cover_thickness_um", "effects.amplifier.gain", "effects.plate_averaging.side_um"}
    assert all(row["sd"] > 0 for row in fitted.values())
    for name in ("fit_report.md", "measured_vs_simulated.png", "model.onnx", "predictions.csv"):
        assert (run_dir / name).is_file(), name
    assert "| `cover_thickness_um`" in (run_dir / "fit_report.md").read_text()

    # scene= accepts the calibrated scene, with the fitted values in place
    with initialize_config_dir(config_dir=CONFIG_DIR, version_base="1.3"):
        cfg = compose("config", overrides=[f"hydra.searchpath=[file://{run_dir}]", "scene=calibrated"])
    scene = instantiate(cfg.scene)
    assert scene.cover_thickness_um == pytest.approx(fitted["cover_thickness_um"]["value"], rel=1e-5)
    assert scene.effects["amplifier"]["gain"] == pytest.approx(fitted["effects.amplifier.gain"]["value"], rel=1e-5)

    # predict.py runs the exported model on the run's own predictions file
    output = tmp_path / "pred.csv"
    predict_main([f"model={run_dir / 'model.onnx'}", f"input={run_dir / 'predictions.csv'}", f"output={output}"])
    predicted = pd.read_csv(output)
    assert {"x_mm", "normal_n"} <= set(predicted.columns) and len(predicted) == metrics["data"]["n_test"]


@pytest.mark.parametrize("change, words", [
    (lambda f: f.drop(columns=["v_t2_up_mv"]), "channels do not match scene taxels: expected v_t0_left_mv"),
    (lambda f: f.assign(v_t1_left_mv=np.where(np.arange(len(f)) == 3, np.nan, f["v_t1_left_mv"])),
     "'v_t1_left_mv' has a missing or infinite value in line 5"),
    (lambda f: f.iloc[:2], "2 presses; calibrating scene taxels needs at least 3"),
    (lambda f: f.assign(**{c: -f[c] for c in f.columns if c.endswith("_mv")}),
     "x the change scene taxels simulates at its best-fitting parameters in range; check the channel's unit and sign"),
])
def test_a_bad_calibration_table_is_one_line_exit_2_and_no_outputs(presses, tmp_path, change, words):
    path, frame = presses
    change(frame).to_csv(path, index=False)
    run_dir = tmp_path / "bad"
    result = train("scene=taxels", "data=table", f"data.path={path}", f"hydra.run.dir={run_dir}")
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and words in lines[-1], result.stderr[-2000:]
    assert lines[-1].startswith("error: ")
    assert not (run_dir / "model.onnx").exists() and not (run_dir / "fit_report.md").exists()
