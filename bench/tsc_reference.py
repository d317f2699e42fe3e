"""Do the time-series networks reach a known optimum with the reference training recipe?

    OMP_NUM_THREADS=1 .venv/bin/python bench/tsc_reference.py [--tasks phase frequency imu6]
        [--models prcnn rescnn inceptiontime lstm_fcn] [--epochs 150] [--n 300] [--seeds 0] [--trainer tsc]
    OMP_NUM_THREADS=1 .venv/bin/python bench/tsc_reference.py --batchnorm-check --seeds 0 1 2

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


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tasks", nargs="*", default=list(TASKS), choices=TASKS)
    parser.add_argument("--models", nargs="*", default=list(MODELS), choices=MODELS)
    parser.add_argument("--epochs", type=int, default=150, help="the same epoch budget for every network")
    parser.add_argument("--n", type=int, default=300, help="series per task (60/20/20 split)")
    parser.add_argument("--seeds", nargs="*", type=int, default=[0])
    parser.add_argument("--trainer", default="reference", choices=("reference", "tsc"),
                        help="tsc: the fingertip paper's SGD schedule, for comparison")
    parser.add_argument("--batchnorm-check", action="store_true",
                        help="only the eval-mode vs batch-statistics measurement (paper recipe, 1 step per epoch)")
    args = parser.parse_args(argv)
    if args.batchnorm_check:
        return batchnorm_check(args.seeds)
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
