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
Appends one record per net to results/ddp_step_time.jsonl.
"""
import argparse
import functools
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from common.result_records import recording  # noqa: E402
from common.spread import format_mean_sd  # noqa: E402
from models.distributed import fit_in_processes  # noqa: E402
from models.nets.lstm_fcn import LSTMFCN  # noqa: E402
from models.nets.prcnn import PRCNN  # noqa: E402
from models.resmlp_regressor import ResMLPRegressor  # noqa: E402
from models.timeseries_classifier import TimeSeriesClassifier  # noqa: E402
from runs.reference_tasks import generate, split  # noqa: E402

# What the step time and the loss differences measure: the process group, the two estimators'
# training loops, the nets, and the task the windows come from.
MEASURED_CODE = ["models/distributed.py", "common/distributed.py", "models/resmlp_regressor.py",
                 "models/timeseries_classifier.py", "models/nets/", "models/torch_runtime.py",
                 "runs/reference_tasks.py"]


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
    """(record name, name, data, whether it draws per rank, estimator for a seed)"""
    yield "resmlp", "resmlp (no dropout, no noise)", regression, False, lambda seed: ResMLPRegressor(
        widths=(256, 128, 96, 64), dropouts=(0, 0, 0, 0), noise_std=0.0, batch_size=64, max_epochs=epochs,
        early_stopping_patience=None, progress=False, seed=seed)
    tsc = dict(optimizer="adam", lr=1e-3, lr_schedule="plateau", batch_size=32, max_epochs=epochs,
               recalibrate_batchnorm=True, progress=False)
    yield "prcnn", "prcnn (BatchNorm synchronised)", windows, False, lambda seed: TimeSeriesClassifier(
        network=functools.partial(PRCNN, branch_width=32, fusion_width=64), seed=seed, **tsc)
    if dropout:
        yield "lstm_fcn", "lstm_fcn (dropout 0.8)", windows, True, lambda seed: TimeSeriesClassifier(
            network=functools.partial(LSTMFCN, hidden=32, widths=(32, 32, 32), dropout=0.8), seed=seed, **tsc)


def case_rows(name: str, per_rank: bool, runs: dict, test) -> list[dict]:
    """Print one net's rows (1 and 2 processes); return their raw numbers, one entry per repeat."""
    rows = []
    for n in (1, 2):
        fitted = runs[n]
        steps = len(fitted[0].step_losses_)
        step_ms = [1000 * f.fit_wall_s_ / len(f.step_losses_) for f in fitted]
        reference = runs[1][0].step_losses_
        differences = None if per_rank else [float(np.abs(np.subtract(f.step_losses_, reference)).max())
                                             for f in fitted]
        identical = None if per_rank else all(f.step_losses_ == fitted[0].step_losses_ for f in fitted)
        accuracy = [100 * float((f.predict(test[0]) == test[1]).mean()) for f in fitted] if test is not None else None
        difference = "— (dropout per rank)" if per_rank else f"{max(differences):.1e}"
        print(f"| {name} | {n} | {steps} | {format_mean_sd(step_ms, '.1f')} | {difference} | "
              f"{'—' if per_rank else identical} | "
              f"{format_mean_sd(accuracy, '.1f') + ' %' if accuracy is not None else '—'} |")
        rows.append({"processes": n, "steps": steps, "step_ms": step_ms,
                     "max_abs_loss_difference": differences, "repeats_identical": identical,
                     "test_accuracy_pct": accuracy})
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--epochs", type=int, default=3)
    parser.add_argument("--dropout", action="store_true", help="also LSTM-FCN with dropout (accuracy over seeds)")
    args = parser.parse_args()
    print("| net | processes | steps | step time (ms) | max abs loss difference to 1 process, any step | "
          "repeats identical | test accuracy |")
    print("|---|---|---|---|---|---|---|")
    # One record per net: --dropout adds LSTM-FCN's without touching the other two.
    with recording("ddp_step_time", MEASURED_CODE) as record:
        for key, name, data, per_rank, make in cases(args.epochs, args.dropout):
            fit_data, test = data()
            runs = {n: [] for n in (1, 2)}
            # with dropout drawn per rank: accuracy over seeds
            seeds = [repeat if per_rank else 0 for repeat in range(args.repeats)]
            for seed in seeds:
                for n in (1, 2):
                    runs[n].append(fit_in_processes(make(seed), n, *fit_data))
            rows = case_rows(name, per_rank, runs, test)
            record.add(key, {"net": name, "epochs": args.epochs, "repeats": args.repeats, "dropout_per_rank": per_rank,
                             "rows": rows}, seeds=sorted(set(seeds)))


if __name__ == "__main__":
    main()
