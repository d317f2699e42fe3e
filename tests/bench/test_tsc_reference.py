"""bench/tsc_reference.py --epoch-curve: the refit the recipe chooses is the curve's network at the
chosen epoch (the mode's premise), and the recipe's result comes as one JSON line per fit."""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

from runs.reference_tasks import generate

ROOT = Path(__file__).resolve().parents[2]


def test_the_recipes_refit_is_the_curves_network_at_the_chosen_epoch(tmp_path):
    X, y = generate("frequency", 36, seed=0, length=40)
    split = np.where(np.arange(len(y)) < 24, "train", "test")
    path = tmp_path / "tones.npz"
    np.savez(path, X=X, y=np.array([f"class{c}" for c in y]), split=split)
    # Run as a user runs it (tests do not import bench/: tests/test_house.py).
    out = subprocess.run([sys.executable, "bench/tsc_reference.py", "--epoch-curve", str(path), "--models", "rescnn",
                          "--seeds", "0", "--epochs", "3", "--curve-epochs", "3", "--every", "1"], cwd=ROOT,
                         capture_output=True, text=True, check=True, env={**os.environ, "OMP_NUM_THREADS": "1"}).stdout
    curve = dict(re.findall(r"(\d+):([0-9.]+)", out.split("refit for E epochs:")[1].splitlines()[0]))
    result = json.loads(next(line for line in out.splitlines() if line.startswith("{")))
    assert len(curve) == 3 and result["fold_epochs_run"] == [3, 3, 3]      # the folds' budget is --epochs
    assert f"{result['test_accuracy']:.3f}" == curve[str(result["epochs"])]
    assert result["fit_cpu_s"] > 0 and "over seeds [0]" in out
