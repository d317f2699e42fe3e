"""Accuracy floors with margin on a moderately sized simulated set (random positions and depths)."""
import pytest

from models.run_regression import run


def test_extra_trees_locates_presses_on_unseen_points(compose_config, tmp_path):
    cfg = compose_config(["scene.protocol=random", "scene.n_samples=1500", "scene.progress=false",
                          "model=extra_trees", "model.n_estimators=200"])
    test = run(cfg, tmp_path)["test"]
    print({t: round(test[t]["r2"], 4) for t in test})
    # Measured 0.987-0.988 for x and y, 0.992 for depth and pressure (seed 0); the floors leave margin.
    assert test["x_mm"]["r2"] > 0.9 and test["y_mm"]["r2"] > 0.9
    assert test["depth_mm"]["r2"] > 0.9 and test["pressure_pa"]["r2"] > 0.9


@pytest.mark.slow
def test_resmlp_matches_the_trees_on_a_larger_set(compose_config, tmp_path):
    cfg = compose_config(["scene.protocol=random", "scene.n_samples=3000", "scene.progress=false",
                          "model=resmlp", "trainer.progress=false", "trainer.max_epochs=150"])
    test = run(cfg, tmp_path)["test"]
    print({t: round(test[t]["r2"], 4) for t in test})
    assert min(test[t]["r2"] for t in ("x_mm", "y_mm", "depth_mm", "pressure_pa")) > 0.9
