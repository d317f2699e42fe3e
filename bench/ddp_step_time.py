"""Training across processes: step time with 1 and 2 processes, and how far 2 processes' losses
are from 1 process's at every optimiser step (same global batch, same seed).

    .venv/bin/python bench/ddp_step_time.py --repeats 3

Each fit runs in forked children (models/distributed.py fit_in_processes: gloo on this machine, as
`torchrun --standalone` runs it; one thread per process). The step time is a fit's wall time
divided by its optimiser steps (the epochs' validation included), mean ± sd over the repeats.
Nets: the residual MLP without dropout and input noise (both draw per rank) on a generated
regression, and PR-CNN (BatchNorm, synchronised across the processes) on the `phase` task of
runs/reference_tasks.py. `--dropout` adds LSTM-FCN with its dropout, where the two differ by
seed noise: its test accuracy over the repeats' seeds is printed instead of a step difference.
"""
import argparse
import functools
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from common.spread import format_mean_sd  # noqa: E402
from models.distributed import fit_in_processes  # noqa: E402
from models.nets.lstm_fcn import LSTMFCN  # noqa: E402
from models.nets.prcnn import PRCNN  # noqa: E402
from models.resmlp_regressor import ResMLPRegressor  # noqa: E402
from models.timeseries_classifier import TimeSeriesClassifier  # noqa: E402
from runs.reference_tasks import generate, split  # noqa: E402


def regression(n=2000, features=12, seed=0):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, features))
    y = np.c_[np.sin(X[:, 0]) * X[:, 1], X[:, 2] ** 2] + 0.05 * rng.normal(size=(n, 2))
    cut = int(0.8 * n)
    return (X[:cut], y[:cut], X[cut:], y[cut:]), None


def windows(n=400, seed=0):
    X, y = generate("phase", n, seed=seed)
    train, val, test = split(y, seed)
    return (X[train], y[train], X[val], y[val]), (X[test], y[test])


def cases(epochs: int, dropout: bool):
    """(name, data, estimator for a seed, whether it draws per rank)"""
    yield "resmlp (no dropout, no noise)", regression, False, lambda seed: ResMLPRegressor(
        widths=(256, 128, 96, 64), dropouts=(0, 0, 0, 0), noise_std=0.0, batch_size=64, max_epochs=epochs,
        early_stopping_patience=None, progress=False, seed=seed)
    tsc = dict(optimizer="adam", lr=1e-3, lr_schedule="plateau", batch_size=32, max_epochs=epochs,
               recalibrate_batchnorm=True, progress=False)
    yield "prcnn (BatchNorm synchronised)", windows, False, lambda seed: TimeSeriesClassifier(
        network=functools.partial(PRCNN, branch_width=32, fusion_width=64), seed=seed, **tsc)
    if dropout:
        yield "lstm_fcn (dropout 0.8)", windows, True, lambda seed: TimeSeriesClassifier(
            network=functools.partial(LSTMFCN, hidden=32, widths=(32, 32, 32), dropout=0.8), seed=seed, **tsc)


def mean_sd(values) -> str:
    return format_mean_sd(values, ".1f")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--epochs", type=int, default=3)
    parser.add_argument("--dropout", action="store_true", help="also LSTM-FCN with dropout (accuracy over seeds)")
    args = parser.parse_args()
    print("| net | processes | steps | step time (ms) | max abs loss difference to 1 process, any step | "
          "repeats identical | test accuracy |")
    print("|---|---|---|---|---|---|---|")
    for name, data, per_rank, make in cases(args.epochs, args.dropout):
        fit_data, test = data()
        runs = {n: [] for n in (1, 2)}
        for repeat in range(args.repeats):
            seed = repeat if per_rank else 0  # with dropout drawn per rank: accuracy over seeds
            for n in (1, 2):
                runs[n].append(fit_in_processes(make(seed), n, *fit_data))
        for n in (1, 2):
            fitted = runs[n]
            steps = len(fitted[0].step_losses_)
            step_ms = [1000 * f.fit_wall_s_ / len(f.step_losses_) for f in fitted]
            if per_rank:
                difference, identical = "— (dropout per rank)", "—"
            else:
                reference = runs[1][0].step_losses_
                difference = f"{max(np.abs(np.subtract(f.step_losses_, reference)).max() for f in fitted):.1e}"
                identical = all(f.step_losses_ == fitted[0].step_losses_ for f in fitted)
            accuracy = (mean_sd([100 * float((f.predict(test[0]) == test[1]).mean()) for f in fitted]) + " %"
                        if test is not None else "—")
            print(f"| {name} | {n} | {steps} | {mean_sd(step_ms)} | {difference} | {identical} | {accuracy} |")


if __name__ == "__main__":
    main()
