"""bench/tsc_reference.py --epoch-curve: the refit the recipe chooses is the curve's network at the
chosen epoch (the mode's premise), and the recipe's result comes as one JSON line per fit."""
import json
import re
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.tsc_reference import main  # noqa: E402
from runs.reference_tasks import generate  # noqa: E402


def test_the_recipes_refit_is_the_curves_network_at_the_chosen_epoch(tmp_path, capsys):
    X, y = generate("frequency", 36, seed=0, length=40)
    split = np.where(np.arange(len(y)) < 24, "train", "test")
    path = tmp_path / "tones.npz"
    np.savez(path, X=X, y=np.array([f"class{c}" for c in y]), split=split)
    main(["--epoch-curve", str(path), "--models", "rescnn", "--seeds", "0", "--epochs", "3", "--curve-epochs", "3",
          "--every", "1"])
    out = capsys.readouterr().out
    curve = dict(re.findall(r"(\d+):([0-9.]+)", out.split("refit for E epochs:")[1].splitlines()[0]))
    result = json.loads(next(line for line in out.splitlines() if line.startswith("{")))
    assert len(curve) == 3 and result["fold_epochs_run"] == [3, 3, 3]      # the folds' budget is --epochs
    assert f"{result['test_accuracy']:.3f}" == curve[str(result["epochs"])]
    assert result["fit_cpu_s"] > 0 and "over seeds [0]" in out
