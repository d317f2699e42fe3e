"""Do the time-series networks reach a known optimum with the reference training recipe?

    OMP_NUM_THREADS=1 .venv/bin/python bench/tsc_reference.py [--tasks phase frequency imu6]
        [--models prcnn rescnn inceptiontime lstm_fcn] [--epochs 150] [--n 300] [--seeds 0] [--trainer tsc]
    OMP_NUM_THREADS=1 .venv/bin/python bench/tsc_reference.py --batchnorm-check --seeds 0 1 2
    OMP_NUM_THREADS=1 .venv/bin/python bench/tsc_reference.py --epoch-curve ArrowHead.npz --models rescnn
        [inceptiontime inceptiontime_ensemble] [--epochs 1500] [--curve-epochs 300] [--every 5] [--seeds 0 1 2]
        [--skip-folds]

--epoch-curve: on a recordings NPZ with a declared train/test split (X, y, split; bench/tsc_peers.py
writes the UCR/UEA sets so), how test accuracy depends on the epoch count the refit trains for,
and which count the reference recipe's folds choose. One fit on every training recording as the
refit trains (the plateau on the training loss, no early stopping), its test accuracy logged every
--every epochs, for --curve-epochs epochs (0: no curve): the refit for E epochs IS this fit's network
at epoch E (same seed, same schedule). Then (unless --skip-folds) the whole `trainer=reference` fit,
as `python train.py data=recordings_npz data.path=<NPZ> model=<m> trainer=reference` fits it (the
folds' budget --epochs, default the trainer's 1500): the folds' choice, their pooled held-out
accuracy there, the refit's test accuracy, fit wall and CPU time (one JSON line per fit; the mean
and sd over the seeds at the end).

Generated data whose optimal accuracy is known (no public archive can be downloaded here):
  frequency  1 channel: a sine of 3 or 5 cycles per series at a random phase, plus noise.
  phase      2 channels carrying the same sine (random frequency and phase); the second channel
             leads the first by +90 degrees in one class and lags it by 90 degrees in the other.
             Each channel alone is the same in both classes: only the relation between channels
             separates them (a pattern shifted in phase).
  imu6       6 channels (an accelerometer + gyroscope stand-in): channels 0 and 3 as `phase`, the
             other four independent noise of the same spread.
With unit amplitude and noise sd 1.0 per step over 100 steps, the matched-filter signal-to-noise
ratio is about 7 (amplitude x sqrt(steps / 2) / sd): the Bayes error is of order 1e-12 and the
optimal accuracy 1.00 for every task (the networks must find the frequency or the phase relation
under noise as strong as the signal).

Every network trains with `trainer=reference` (configs/trainer/reference.yaml) composed through
Hydra, with the same epoch budget for all (--epochs, LSTM-FCN's own 2000 replaced by it), on
a stratified 60/20/20 train/validation/test split; the table gives the epochs run (early
stopping), the best validation epoch, validation and test accuracy, and the fit time.
"""
import argparse
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from runs.reference_tasks import (  # noqa: E402
    LENGTH,
    MODELS,
    OPTIMUM,
    TASKS,
    fit_one,
    generate,
    reference_model,
    split,
)


def batchnorm_check(seeds, n: int = 100, epochs: int = 15) -> None:
    """The issue's BatchNorm measurement: PR-CNN with the paper's recipe (trainer=tsc, batch 128 >
    the 60 training series: one optimiser step per epoch), accuracy on its own training windows in
    eval mode vs with batch statistics, without and with the recalibrated statistics."""
    import torch
    print("| recalibrate | seed | steps per epoch | train acc, eval mode | train acc, batch statistics | test acc |")
    print("|---|---|---|---|---|---|")
    for recalibrate in (False, True):
        for seed in seeds:
            X, y = generate("frequency", n, seed)
            train, val, test = split(y, seed)
            model = reference_model("prcnn", epochs, seed, [f"trainer.recalibrate_batchnorm={recalibrate}"], "tsc")
            model.fit(X[train], y[train], X[val], y[val])
            eval_mode = (model.predict(X[train]) == y[train]).mean()
            model.module_.train()
            with torch.no_grad():
                logits = model.module_(torch.as_tensor(model._scaled(X[train])))
            model.module_.eval()
            batch_stats = (logits.argmax(1).numpy() == y[train]).mean()
            steps = -(-len(train) // model.batch_size_)
            print(f"| {recalibrate} | {seed} | {steps} | {eval_mode:.3f} | {batch_stats:.3f} "
                  f"| {(model.predict(X[test]) == y[test]).mean():.3f} |")


def epoch_curve(path: str, models, seeds, epochs: int, every: int, folds: bool, curve_epochs: int) -> None:
    import json

    import numpy as np

    from models.fold_epoch_choice import FOLD_CURVE_WINDOW
    data = np.load(path, allow_pickle=False)   # a user's file: never unpickled
    classes, y_all = np.unique(data["y"], return_inverse=True)
    train, test = data["split"] == "train", data["split"] == "test"
    X, y, X_test, y_test = data["X"][train], y_all[train], data["X"][test], y_all[test]
    print(f"{Path(path).stem}: {train.sum()} training / {test.sum()} test recordings, {X.shape[2]} steps, "
          f"{len(classes)} classes; 1-minute load average {os.getloadavg()[0]:.1f}")
    results = {}
    for model in models:
        for seed in seeds:
            if curve_epochs:
                estimator = reference_model(model, curve_epochs, seed, ["trainer.epoch_selection=train_loss",
                                                                        "trainer.early_stopping_patience=null"])
            if curve_epochs and estimator.ensemble_size > 1:
                print(f"{model}: no curve (an ensemble has no network to score until every member is trained; "
                      "its members' curves are --models inceptiontime at seeds seed, seed+1, ...)")
            elif curve_epochs:
                curve = []

                def logged(record, estimator=estimator, curve=curve):
                    if record["epoch"] % every == 0:
                        curve.append((record["epoch"], float((estimator.predict(X_test) == y_test).mean())))
                estimator.fit(X, y, epoch_callback=logged)
                print(f"{model} seed {seed}, test accuracy of the refit for E epochs: "
                      + " ".join(f"{e}:{a:.3f}" for e, a in curve), flush=True)
            if folds:
                chosen = reference_model(model, epochs, seed)
                load_before, start, cpu_start = os.getloadavg()[0], time.perf_counter(), time.process_time()
                chosen.fit(X, y)
                fit_s, fit_cpu_s = time.perf_counter() - start, time.process_time() - cpu_start
                accuracy = float((chosen.predict(X_test) == y_test).mean())
                results.setdefault(model, []).append(accuracy)
                # An ensemble (model.ensemble_size > 1): its members' choices, one list each.
                ensemble = isinstance(chosen.best_epoch_, list)
                pooled = "" if ensemble else \
                    f" (pooled held-out accuracy over {FOLD_CURVE_WINDOW} epochs {chosen.fold_curve_['accuracy'][chosen.best_epoch_ - 1]:.3f})"
                print(f"{model} seed {seed}, trainer=reference: folds ran {chosen.fold_epochs_run_} epochs, chose "
                      f"{chosen.best_epoch_}{pooled}; each fold alone {chosen.fold_best_epochs_}; refit test accuracy "
                      f"{accuracy:.3f}, fit {fit_s:.0f} s wall, {fit_cpu_s:.0f} s CPU, at load "
                      f"{load_before:.1f}-{os.getloadavg()[0]:.1f}", flush=True)
                print(json.dumps({"set": Path(path).stem, "model": model, "seed": seed, "test_accuracy": accuracy,
                                  "epochs": chosen.best_epoch_, "fold_epochs_run": chosen.fold_epochs_run_,
                                  "fit_s": round(fit_s, 1), "fit_cpu_s": round(fit_cpu_s, 1),
                                  "load": [round(load_before, 1), round(os.getloadavg()[0], 1)]}), flush=True)
    for model, accuracies in results.items():
        print(f"{Path(path).stem} {model}: refit test accuracy {np.mean(accuracies):.3f} +- {np.std(accuracies, ddof=1 if len(accuracies) > 1 else 0):.3f} "
              f"over seeds {list(seeds)}", flush=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tasks", nargs="*", default=list(TASKS), choices=TASKS)
    parser.add_argument("--models", nargs="*", default=list(MODELS), choices=(*MODELS, "inceptiontime_ensemble"))
    parser.add_argument("--epochs", type=int, help="the same epoch budget for every network (default: 150; "
                        "--epoch-curve: trainer=reference's own 1500, as train.py runs it)")
    parser.add_argument("--n", type=int, default=300, help="series per task (60/20/20 split)")
    parser.add_argument("--seeds", nargs="*", type=int, default=[0])
    parser.add_argument("--trainer", default="reference", choices=("reference", "tsc"),
                        help="tsc: the fingertip paper's SGD schedule, for comparison")
    parser.add_argument("--batchnorm-check", action="store_true",
                        help="only the eval-mode vs batch-statistics measurement (paper recipe, 1 step per epoch)")
    parser.add_argument("--epoch-curve", metavar="NPZ",
                        help="test accuracy against the refit's epoch count on a recordings NPZ (see above)")
    parser.add_argument("--every", type=int, default=5, help="--epoch-curve: test accuracy every this many epochs")
    parser.add_argument("--skip-folds", action="store_true", help="--epoch-curve: the curve alone")
    parser.add_argument("--curve-epochs", type=int, default=300,
                        help="--epoch-curve: the curve's length (every epoch runs); 0: the recipe alone")
    args = parser.parse_args(argv)
    if args.batchnorm_check:
        return batchnorm_check(args.seeds)
    if args.epoch_curve:
        return epoch_curve(args.epoch_curve, args.models, args.seeds, args.epochs or 1500, args.every,
                           not args.skip_folds, args.curve_epochs)
    args.epochs = args.epochs or 150
    rows = []
    for task in args.tasks:
        for model in args.models:
            for seed in args.seeds:
                rows.append(fit_one(task, model, args.epochs, args.n, seed, trainer=args.trainer))
                r = rows[-1]
                print(f"{task} {model} seed {seed}: test {r['test_accuracy']:.3f} in {r['fit_s']:.0f} s",
                      file=sys.stderr)
    print(f"\ntrainer={args.trainer}, epoch budget {args.epochs}, {args.n} series of {LENGTH} steps per task, "
          f"optimum {OPTIMUM:.2f}; {os.cpu_count()} cores, OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', '-')}\n")
    print("| task | channels | network | seed | batch | epochs run | best epoch | val acc | test acc | optimum | fit (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['task']} | {r['n_channels']} | {r['model']} | {r['seed']} | {r['batch']} | {r['epochs_run']} "
              f"| {r['best_epoch']} | {r['val_accuracy']:.3f} | {r['test_accuracy']:.3f} | {OPTIMUM:.2f} | {r['fit_s']:.1f} |")


if __name__ == "__main__":
    main()
