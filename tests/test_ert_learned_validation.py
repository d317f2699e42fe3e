"""bench/ert_learned_validation.py: learned_mlp's configuration is scored on validation sensors
that are neither its training sensors nor the bench's test sensors, one row per sensor, ensemble
size and force."""
import json
import sys
from pathlib import Path

import pytest

from common.errors import InputError

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.ert_learned_validation import main  # noqa: E402

SMALL_SCENE = ["scene.grid_points_per_side=4", "scene.grid_nodes=21", "scene.injection=adjacent"]
TINY_MODEL = ["n_training_sensors=2", "presses_per_sensor=150", "noise_weights=[1e-5,1e-4]", "width=16",
              "epochs=2", "half_width_patches=1"]


def test_validation_refuses_the_benchs_test_sensors():
    with pytest.raises(InputError, match="test sensors"):
        main(["--seeds", "30000", "1"])


@pytest.mark.slow
def test_validation_scores_every_ensemble_size_on_other_sensors(tmp_path):
    out = tmp_path / "rows.json"
    assert main(["--seeds", "30000", "30001", "--members", "2", "--scene-overrides", *SMALL_SCENE,
                 "--set", *TINY_MODEL, "--json", str(out)]) == 0
    rows = json.loads(out.read_text())
    assert sorted((r["seed"], r["n_nets"], r["force_n"]) for r in rows) == [
        (seed, k, force) for seed in (30000, 30001) for k in (1, 2) for force in (4.0, 10.0)]
    assert all(r["noise_weight"] in (1e-5, 1e-4) and r["localisation_mm"] > 0 for r in rows)
    one = {(r["seed"], r["force_n"]): r["localisation_mm"] for r in rows if r["n_nets"] == 1}
    two = {(r["seed"], r["force_n"]): r["localisation_mm"] for r in rows if r["n_nets"] == 2}
    assert one != two          # the second net changes the prediction: the sizes are scored apart
