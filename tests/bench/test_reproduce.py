"""Same lock, same seed, same result: a small run of the README's tour (`python train.py
model=extra_trees seed=0`) reproduces the scores its committed record holds, to the digits a run
prints (R², RMSE, MAE, MAPE to 4 decimals). `python bench/reproduce.py` does the same for the
default run; the record must come from requirements.lock (a record of another lock is refused)."""
import json
import os
import subprocess
import sys
from pathlib import Path

from common.result_records import differences, latest

ROOT = Path(__file__).resolve().parents[2]


def test_a_tour_run_reproduces_its_committed_record(tmp_path):
    record = latest("quick_tour", "extra_trees")
    recorded = record["values"]["metrics_by_seed"][record["seeds"].index(0)]
    done = subprocess.run([sys.executable, "train.py", "model=extra_trees", "seed=0", f"hydra.run.dir={tmp_path}"],
                          cwd=ROOT, env={**os.environ, "CI": "true"}, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    fresh = json.loads((tmp_path / "metrics.json").read_text())
    assert differences(recorded, {part: fresh[part] for part in recorded}) == []


def test_the_comparison_sees_a_changed_digit():
    recorded = {"test": {"x_mm": {"r2": 0.84061}, "chosen": "resmlp_seeds"}}
    assert differences(recorded, {"test": {"x_mm": {"r2": 0.840612}, "chosen": "resmlp_seeds"}}) == []
    assert differences(recorded, {"test": {"x_mm": {"r2": 0.8408}, "chosen": "resmlp_seeds"}}) == [
        "/test/x_mm/r2: recorded 0.84061, now 0.8408"]
    assert differences(recorded, {"test": {"x_mm": {"r2": 0.84061}, "chosen": "kfold_blend"}})
