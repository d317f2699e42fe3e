"""Generated time-series classification tasks whose optimal accuracy is known (1.00), and the
networks fitted on them exactly as `python train.py model=<name> trainer=<trainer>` builds them:
do the nets reach the optimum with the reference recipe? (bench/tsc_reference.py prints the
table; tests/runs/test_reference_tasks.py asserts it on small budgets.) The tasks are described in
bench/tsc_reference.py."""
import time
from pathlib import Path

import numpy as np
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate

ROOT = Path(__file__).resolve().parents[1]

LENGTH = 100
NOISE_SD = 1.0
TASKS = ("frequency", "phase", "imu6")
MODELS = ("prcnn", "rescnn", "inceptiontime", "lstm_fcn")
OPTIMUM = 1.0


def generate(task: str, n: int, seed: int, length: int = LENGTH, noise_sd: float = NOISE_SD):
    """(X (n, channels, length) float32, y (n,) int64), classes balanced and shuffled."""
    rng = np.random.default_rng(seed)
    y = rng.permutation(np.arange(n) % 2)
    t = np.arange(length) / length
    phase = rng.uniform(0, 2 * np.pi, n)[:, None]
    if task == "frequency":
        cycles = np.where(y == 1, 5.0, 3.0)[:, None]
        X = np.sin(2 * np.pi * cycles * t + phase)[:, None, :]
    elif task in ("phase", "imu6"):
        cycles = rng.uniform(2.0, 6.0, n)[:, None]
        shift = np.where(y == 1, np.pi / 2, -np.pi / 2)[:, None]
        first, second = np.sin(2 * np.pi * cycles * t + phase), np.sin(2 * np.pi * cycles * t + phase + shift)
        if task == "phase":
            X = np.stack([first, second], axis=1)
        else:
            X = np.zeros((n, 6, length))
            X[:, 0], X[:, 3] = first, second
    else:
        raise ValueError(f"unknown task {task!r}; choose from {', '.join(TASKS)}")
    X = X + noise_sd * rng.standard_normal(X.shape)
    return X.astype(np.float32), y.astype(np.int64)


def split(y: np.ndarray, seed: int, fractions=(0.6, 0.2)):
    """Stratified train / validation / test row indices."""
    rng = np.random.default_rng(seed + 1)
    parts = ([], [], [])
    for label in np.unique(y):
        rows = rng.permutation(np.flatnonzero(y == label))
        a, b = int(len(rows) * fractions[0]), int(len(rows) * (fractions[0] + fractions[1]))
        for part, chunk in zip(parts, (rows[:a], rows[a:b], rows[b:])):
            part.extend(chunk)
    return tuple(np.sort(np.array(p)) for p in parts)


def reference_model(model: str, epochs: int, seed: int, overrides=(), trainer: str = "reference"):
    """The estimator exactly as `python train.py model=<model> trainer=<trainer>` builds it."""
    args = [f"model={model}", f"trainer={trainer}", f"trainer.max_epochs={epochs}", "trainer.progress=false",
            "trainer.device=cpu", "trainer.checkpoint=false", f"seed={seed}", *overrides]
    if trainer == "reference":  # the same budget for every network: LSTM-FCN's own 2000 epochs replaced
        args.append(f"trainer.per_model.lstm_fcn.max_epochs={epochs}")
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("config", overrides=args)
    return instantiate(cfg.model)


def fit_one(task: str, model: str, epochs: int, n: int, seed: int, overrides=(), trainer: str = "reference") -> dict:
    X, y = generate(task, n, seed)
    train, val, test = split(y, seed)
    estimator = reference_model(model, epochs, seed, overrides, trainer)
    start = time.perf_counter()
    estimator.fit(X[train], y[train], X[val], y[val])
    fit_s = time.perf_counter() - start
    return {"task": task, "model": model, "trainer": trainer, "seed": seed, "n_channels": X.shape[1], "batch": estimator.batch_size_,
            "epochs_run": estimator.n_epochs_, "best_epoch": estimator.best_epoch_,
            "val_accuracy": float((estimator.predict(X[val]) == y[val]).mean()),
            "test_accuracy": float((estimator.predict(X[test]) == y[test]).mean()), "fit_s": fit_s}
