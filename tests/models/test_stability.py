"""Hard cases in training and simulation: finite results or a clear one-line error."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from common.errors import InputError
from data.scenes.rubber12 import Rubber12Scene
from models.nets.prcnn import PRCNN
from models.resmlp_regressor import ResMLPRegressor
from models.timeseries_classifier import TimeSeriesClassifier

ROOT = Path(__file__).resolve().parents[2]


def regression_data(scale, n=200, seed=0):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, 8)) * scale
    y = np.column_stack([X[:, 0] / scale * 3 + 10, (X[:, 1] / scale) ** 2])
    return X, y


@pytest.mark.parametrize("scale", [1e-6, 1e6])
def test_resmlp_converges_on_badly_scaled_inputs(scale):
    X, y = regression_data(scale)
    model = ResMLPRegressor(max_epochs=60, progress=False).fit(X[:160], y[:160], X[160:], y[160:])
    assert np.isfinite(model.predict(X[160:])).all()
    assert model.score(X[160:], y[160:]) > 0.5  # BatchNorm after the first layer absorbs the scale


def windows(scale, n=96, seed=0):
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 1, 64)
    y = np.repeat([0, 1, 2], n // 3)
    X = np.stack([np.stack([np.sin(2 * np.pi * (2 + 3 * c) * t), rng.normal(size=64)]) for c in y]) * scale
    return X.astype(np.float32), y


@pytest.mark.parametrize("scale", [1e-6, 1e6])
def test_prcnn_trains_or_stops_clearly_on_badly_scaled_inputs(scale):
    X, y = windows(scale)
    model = TimeSeriesClassifier(network=lambda **kw: PRCNN(**kw, branch_width=16, fusion_width=16),
                                 modalities={"a": [0], "b": [1]}, max_epochs=10, milestones=[8], lr=0.01,
                                 batch_size=16, progress=False)
    try:
        model.fit(X, y, X, y)
    except InputError as error:
        assert "diverged at epoch" in str(error) and "\n" not in str(error)
        return
    assert np.isfinite(model.predict_proba(X)).all()
    assert (model.predict(X) == y).mean() > 0.6


def test_nan_loss_stops_at_once_with_the_epoch_and_writes_no_model(tmp_path):
    X, y = regression_data(1.0)
    with pytest.raises(InputError, match=r"^resmlp: training diverged at epoch 1 "):
        ResMLPRegressor(max_epochs=5, lr=1e12, progress=False).fit(X, y, X[:10], y[:10])
    rows = np.column_stack([np.full((120, 12), 1.7e4), np.tile([[10.0, 10.0, 1.0, np.inf]], (120, 1))])
    import pandas as pd
    columns = [f"r_{k:02d}_ohm" for k in range(1, 13)] + ["x_mm", "y_mm", "depth_mm", "pressure_pa"]
    pd.DataFrame(rows, columns=columns).to_csv(tmp_path / "rig.csv", index=False)
    result = subprocess.run([sys.executable, str(ROOT / "train.py"), "data=table", f"data.path={tmp_path / 'rig.csv'}",
                             "data.target_columns=[x_mm,y_mm,depth_mm,pressure_pa]", "model=resmlp", f"hydra.run.dir={tmp_path / 'run'}"], capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode == 2 and "'pressure_pa' has a missing or infinite value in line 2" in result.stderr
    assert result.stderr.strip().count("\n") == 0
    run_folder = tmp_path / "run"
    assert json.loads((run_folder / "status.json").read_text())["state"] == "failed"
    assert not (run_folder / "metrics.json").exists() and not (run_folder / "pipeline.npz").exists()


@pytest.mark.parametrize("kwargs", [
    {"effects": {"contact": {}, "percolation": {"filler_fraction": 0.040 + 1e-9, "percolation_threshold": 0.040}}},
    {"depth_range_mm": (0.0, 0.0)},
    {"depth_range_mm": (6.0, 6.0)},
    {"effects": {"contact": {}, "percolation": {}, "adc": {"bits": 1}}},
    {"effects": {"contact": {"strain_transfer": 0.99}, "percolation": {}, "tunneling": {"gap_nm": 5.0}}},
])
def test_extreme_scene_parameters_give_finite_data_or_a_clear_error(kwargs):
    settings = {"n_samples": 40, "protocol": "random", "progress": False,
                "effects": {"contact": {}, "percolation": {}, "tunneling": {}, "adc": {}}, **kwargs}
    try:
        table = Rubber12Scene(**settings).generate()
    except InputError as error:
        assert "\n" not in str(error)
        return
    assert np.isfinite(table.channels).all() and (table.channels >= 0).all()


def test_percolation_threshold_must_stay_below_the_filler_fraction():
    with pytest.raises(InputError, match="percolation_threshold < filler_fraction"):
        Rubber12Scene(n_samples=5, progress=False,
                      effects={"contact": {}, "percolation": {"filler_fraction": 0.03}}).generate()
