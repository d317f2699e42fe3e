"""Pretraining on a scene, then the user's presses: three candidates, one chosen on validation.

- `scratch`: the model on the user's training presses alone (what `data=table` does);
- `default_scene`: the scene as configured simulates presses over the range the user's labels
  cover; the model learns from them and the user's training presses together;
- `fitted_scene`: the same from the scene fitted to the user's training presses
  (data/calibration/system_identification.py).

The user's presses and the simulated ones are augmented with a domain weight: the real rows are
repeated so that they carry `real_weight` of the training set's total weight (0.5: as much as
the whole simulated set). Repetition, not sample weights, so every model (trees, nets, blends)
takes it through the same fit. A net is not fine-tuned in a second stage here: it learns from
the mixed set like a tree.

The choice is the best mean R² over the targets on the user's validation presses, which no
candidate and no scene fit has seen; the test presses are never consulted.
"""
import logging
import time

import numpy as np
from hydra.utils import instantiate

from common.progress import phase
from data.calibration.identifiable import calibration_for
from data.calibration.press_simulation import draw_labels, simulate_at
from data.calibration.system_identification import identify
from data.preprocessing.features import compute_features
from data.units import clip_columns
from models.capabilities import fit
from runs.report.metrics import regression_metrics

log = logging.getLogger(__name__)
CANDIDATES = ("scratch", "default_scene", "fitted_scene")


def scene_features(datamodule, table) -> np.ndarray:
    """A simulated table's features through the user's own feature groups and scaler."""
    return datamodule.scaler.transform(compute_features(table.channels, datamodule.features))


def pretraining_sets(datamodule, scenes: dict, n_simulated: int, seed: int) -> dict:
    """{candidate: (X, y)} of `n_simulated` presses from each scene, at labels drawn over the
    user's training labels (the same labels for every scene)."""
    frame = datamodule.table.frame.iloc[datamodule.train_idx]
    inputs = calibration_for(next(iter(scenes.values()))).inputs
    labels = draw_labels(frame, inputs, n_simulated, np.random.default_rng(seed))
    sets = {}
    for name, scene in scenes.items():
        with phase(f"simulating {n_simulated:,} presses on the {name.replace('_', ' ')}"):
            table = simulate_at(scene, labels)
        sets[name] = (scene_features(datamodule, table), table.frame[datamodule.target_names].to_numpy(float))
    return sets


def fit_candidates(model_node, datamodule, sets: dict, real_weight: float) -> dict:
    """{candidate: (fitted model, fit wall and CPU seconds)}: scratch, then each scene's augmented set."""
    (X_train, y_train), (X_val, y_val) = datamodule.train, datamodule.val
    fitted = {}
    for name in CANDIDATES:
        X, y = X_train, y_train
        if name in sets:
            X_sim, y_sim = sets[name]
            repeats = max(1, int(round(real_weight / (1.0 - real_weight) * len(X_sim) / len(X_train))))
            X = np.concatenate([X_sim, np.repeat(X_train, repeats, axis=0)])
            y = np.concatenate([y_sim, np.repeat(y_train, repeats, axis=0)])
        model = instantiate(model_node)
        with phase(f"fitting {name.replace('_', ' ')} on {len(X):,} rows", enabled=name in sets):
            start, cpu_start = time.perf_counter(), time.process_time()
            fit(model, X, y, X_val, y_val)
        fitted[name] = (model, time.perf_counter() - start, time.process_time() - cpu_start)
    return fitted


def predict(model, X, targets) -> np.ndarray:
    return clip_columns(model.predict(X), targets)


def choose(fitted: dict, datamodule) -> tuple[str, dict]:
    """The candidate with the best mean validation R² (scratch on a tie), and why."""
    X_val, y_val = datamodule.val
    targets = datamodule.target_names
    scores = {name: regression_metrics(y_val, predict(model, X_val, targets), targets)
              for name, (model, *_) in fitted.items()}
    r2 = {name: score["average"]["r2"] for name, score in scores.items()}
    chosen = "scratch"
    for name in CANDIDATES[1:]:
        if r2[name] is not None and (r2[chosen] is None or r2[name] > r2[chosen]):
            chosen = name
    others = ", ".join(f"{r2[n]:.3f} ({n})" for n in CANDIDATES if n != chosen and r2[n] is not None)
    reason = (f"{chosen}: mean validation R² {r2[chosen]:.3f} over {', '.join(targets)} against {others}, "
              f"on {len(y_val)} validation presses no candidate was fitted on")
    return chosen, {"chosen": chosen, "reason": reason, "validation_r2": r2, "validation": scores,
                    "fit_time_s": {name: seconds for name, (_, seconds, _) in fitted.items()}}


def calibrate_and_pretrain(cfg, datamodule, scene) -> dict:
    """The scene fitted on the training presses, the pretraining sets, the candidates and the
    choice: everything a calibration run (or the bench) needs, nothing written."""
    settings = cfg.calibration
    train = datamodule.table.frame.iloc[datamodule.train_idx]
    with phase(f"fitting scene {scene.name} to {len(train)} training presses"):
        fitted_fit, fitted_scene = identify(scene, train, int(settings.max_evaluations))
    scenes = {"default_scene": scene, "fitted_scene": fitted_scene}
    sets = pretraining_sets(datamodule, scenes, int(settings.n_simulated), int(cfg.seed))
    fitted = fit_candidates(cfg.model, datamodule, sets, float(settings.real_weight))
    chosen, choice = choose(fitted, datamodule)
    log.info("calibration choice: %s", choice["reason"])
    return {"fit": fitted_fit, "fitted_scene": fitted_scene, "candidates": fitted, "chosen": chosen,
            "choice": choice}
