"""The shared regression pipeline on the ERT skin: `python train.py scene=ert_internal
scene.protocol=random model=...` fits, reports, exports, and the ONNX graph answers like the
fitted pipeline in onnxruntime (tiny sizes: 21-node grid, the 24 adjacent injections)."""
import json

import numpy as np
import pytest
from hydra.utils import instantiate

from export.onnx_predictor import OnnxPredictor
from export.run_export import export_run
from models.deployable import load_pipeline
from runs.run import run

TINY_ERT = ["scene=ert_internal", "scene.protocol=random", "scene.grid_nodes=21", "scene.injection=adjacent",
            "scene.n_samples=160", "analysis.ablation=false"]
SIZES = {"extra_trees": ["model.n_estimators=10"],
         "blend": ["data.n_folds=2", "analysis.progress=false", "trainer.max_epochs=3", "trainer.progress=false",
                   "model.candidates.random_forest.estimator.n_estimators=5",
                   "model.candidates.extra_trees.estimator.n_estimators=5"]}


@pytest.mark.parametrize("model", ["extra_trees", "blend"])
def test_random_presses_train_report_and_export_through_the_pipeline(compose_config, tmp_path, model):
    cfg = compose_config([*TINY_ERT, f"model={model}", *SIZES[model]])
    metrics = run(cfg, tmp_path)
    saved = json.loads((tmp_path / "metrics.json").read_text())
    assert set(saved["test"]) == {"x_mm", "y_mm", "force_n", "average"}
    assert saved["data"]["source"]["protocol"] == "random"
    assert saved["data"]["channels"][0] == "dv_a01_b02_m01_v" and len(saved["data"]["channels"]) == 24 * 24
    assert (tmp_path / "parity.png").stat().st_size > 0 and saved == json.loads(json.dumps(metrics))

    # fresh presses of the same sensor, read as the deployed model would read them
    presses = instantiate(cfg.scene, n_samples=16, session=1).generate().channels
    predictor, pipeline = OnnxPredictor(export_run(tmp_path)), load_pipeline(tmp_path / "pipeline.npz")
    onnx_out = predictor.predict_array(presses)
    reference, half = pipeline.predict_raw(presses)
    assert onnx_out["prediction"].shape == (16, 3) and np.isfinite(onnx_out["prediction"]).all()
    scale = np.abs(reference).max(axis=0) + 1e-9
    relative = np.abs(onnx_out["prediction"] - reference) / scale
    # float32 graph: a tree feature exactly on a split threshold may take the other branch
    assert np.median(relative) < 1e-4 and (relative.max(axis=1) > 1e-3).mean() <= 1 / 16
    if model == "blend":
        assert np.allclose(onnx_out["interval_half_width"], half, rtol=1e-3, atol=1e-6 * np.abs(half).max())
