"""Accuracy floors with margin on a moderately sized simulated set (random positions and depths)."""
import pytest

from models.runs.run import run


def test_extra_trees_locates_presses_on_unseen_points(compose_config, tmp_path):
    cfg = compose_config(["scene.protocol=random", "scene.n_samples=3000", "scene.progress=false",
                          "model=extra_trees", "analysis.ablation=false"])
    test = run(cfg, tmp_path)["test"]
    print({t: round(test[t]["r2"], 4) for t in test})
    # Measured R^2 0.939 (x) and 0.944 (y) at seed 0 (0.92-0.95 over seeds 0-2). Depth and
    # pressure reach only ~0.5 on random positions: a press changes the sheet only near the
    # probe, so its depth is confounded with its position and with the lab's +/- 1 C drift.
    assert test["x_mm"]["r2"] > 0.9 and test["y_mm"]["r2"] > 0.9
    assert test["depth_mm"]["r2"] > 0.3 and test["pressure_pa"]["r2"] > 0.3


@pytest.mark.slow
def test_resmlp_learns_depth_on_unseen_presses(compose_config, tmp_path):
    cfg = compose_config(["scene.protocol=random", "scene.n_samples=3000", "scene.progress=false",
                          "model=resmlp", "trainer.progress=false", "trainer.max_epochs=150", "analysis.ablation=false"])
    test = run(cfg, tmp_path)["test"]
    print({t: round(test[t]["r2"], 4) for t in test})
    # Measured 0.996 (x), 0.996 (y), 0.866 (depth, pressure) at seed 0: the net untangles depth
    # from position where the trees (~0.5) cannot.
    assert test["x_mm"]["r2"] > 0.97 and test["y_mm"]["r2"] > 0.97
    assert test["depth_mm"]["r2"] > 0.75 and test["pressure_pa"]["r2"] > 0.75
