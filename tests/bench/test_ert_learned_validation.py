"""bench/ert_learned_validation.py: learned_mlp's configuration is scored on validation sensors
that are neither its training sensors nor the bench's test sensors, one row per sensor, ensemble
size and force. Run as a script: tests do not import bench/ (tests/test_house.py)."""
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SMALL_SCENE = ["scene.grid_points_per_side=4", "scene.grid_nodes=21", "scene.injection=adjacent"]
TINY_MODEL = ["n_training_sensors=2", "presses_per_sensor=150", "noise_weights=[1e-5,1e-4]", "width=16",
              "epochs=2", "half_width_patches=1"]


def run_validation(*args):
    return subprocess.run([sys.executable, str(ROOT / "bench" / "ert_learned_validation.py"), *args],
                          cwd=ROOT, capture_output=True, text=True, env={"OMP_NUM_THREADS": "1", "PATH": ""})


def test_validation_refuses_the_benchs_test_sensors():
    done = run_validation("--seeds", "30000", "1")
    assert done.returncode == 2 and done.stderr.startswith("error:") and "test sensors" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1        # one line, no traceback


@pytest.mark.slow
def test_validation_scores_every_ensemble_size_on_other_sensors(tmp_path):
    out = tmp_path / "rows.json"
    done = run_validation("--seeds", "30000", "30001", "--members", "2", "--scene-overrides", *SMALL_SCENE,
                          "--set", *TINY_MODEL, "--json", str(out))
    assert done.returncode == 0, done.stderr[-2000:]
    rows = json.loads(out.read_text())
    assert sorted((r["seed"], r["n_nets"], r["force_n"]) for r in rows) == [
        (seed, k, force) for seed in (30000, 30001) for k in (1, 2) for force in (4.0, 10.0)]
    assert all(r["noise_weight"] in (1e-5, 1e-4) and r["localisation_mm"] > 0 for r in rows)
    one = {(r["seed"], r["force_n"]): r["localisation_mm"] for r in rows if r["n_nets"] == 1}
    two = {(r["seed"], r["force_n"]): r["localisation_mm"] for r in rows if r["n_nets"] == 2}
    assert one != two          # the second net changes the prediction: the sizes are scored apart
