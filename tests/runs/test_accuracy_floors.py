"""Accuracy floors with margin on a moderately sized simulated set (random positions and depths)."""
import pytest

from runs.run import run


def test_extra_trees_locates_presses_on_unseen_points(compose_config, tmp_path):
    cfg = compose_config(["scene.protocol=random", "scene.n_samples=3000", "scene.progress=false",
                          "model=extra_trees", "analysis.ablation=false"])
    test = run(cfg, tmp_path)["test"]
    print({t: round(test[t]["r2"], 4) for t in test})
    # Measured R^2 0.900 (x), 0.911 (y), 0.898 (depth), 0.848 (pressure) at seed 0 (issue 11's
    # scene: the film strain spreads over the gel's thickness and the default readout pairs
    # electrodes across the sheet, so depth is far better observed than the ~0.5 before, while
    # x and y fell from ~0.94; bench/fidelity.py --patterns: x 0.91 +/- 0.04, y 0.93 +/- 0.01
    # over seeds 0-2 on 1,500 presses). Pressure is now its own target (stiffening, relaxation,
    # the specimen's thickness map, load-cell noise), a little below depth.
    assert test["x_mm"]["r2"] > 0.85 and test["y_mm"]["r2"] > 0.85
    assert test["depth_mm"]["r2"] > 0.75 and test["pressure_pa"]["r2"] > 0.7


@pytest.mark.slow
def test_resmlp_learns_depth_on_unseen_presses(compose_config, tmp_path):
    cfg = compose_config(["scene.protocol=random", "scene.n_samples=3000", "scene.progress=false",
                          "model=resmlp", "trainer.progress=false", "trainer.max_epochs=150", "analysis.ablation=false"])
    test = run(cfg, tmp_path)["test"]
    print({t: round(test[t]["r2"], 4) for t in test})
    # Measured 0.930 (x), 0.946 (y), 0.845 (depth), 0.774 (pressure) at seed 0 since the film's
    # response varies from cycle to cycle as much as the paper's repeats do (cycle_response, issue
    # 42; 0.978, 0.977, 0.894, 0.845 without it): the net still untangles depth from position.
    assert test["x_mm"]["r2"] > 0.9 and test["y_mm"]["r2"] > 0.9
    assert test["depth_mm"]["r2"] > 0.75 and test["pressure_pa"]["r2"] > 0.7
