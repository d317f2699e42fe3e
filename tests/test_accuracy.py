"""Accuracy floors with margin on a moderately sized simulated set (random positions and depths)."""
import pytest

from models.run_regression import run


def test_extra_trees_locates_presses_on_unseen_points(compose_config, tmp_path):
    cfg = compose_config(["scene.protocol=random", "scene.n_samples=3000", "scene.progress=false",
                          "model=extra_trees"])
    test = run(cfg, tmp_path)["test"]
    print({t: round(test[t]["r2"], 4) for t in test})
    # Measured R^2 0.939 (x) and 0.944 (y) at seed 0 (0.92-0.95 over seeds 0-2). Depth and
    # pressure reach only ~0.5 on random positions: a press changes the sheet only near the
    # probe, so its depth is confounded with its position and with the lab's +/- 1 C drift.
    assert test["x_mm"]["r2"] > 0.9 and test["y_mm"]["r2"] > 0.9
    assert test["depth_mm"]["r2"] > 0.3 and test["pressure_pa"]["r2"] > 0.3


@pytest.mark.slow
def test_resmlp_matches_the_trees_on_a_larger_set(compose_config, tmp_path):
    cfg = compose_config(["scene.protocol=random", "scene.n_samples=3000", "scene.progress=false",
                          "model=resmlp", "trainer.progress=false", "trainer.max_epochs=150"])
    test = run(cfg, tmp_path)["test"]
    print({t: round(test[t]["r2"], 4) for t in test})
    assert min(test[t]["r2"] for t in ("x_mm", "y_mm", "depth_mm", "pressure_pa")) > 0.9
