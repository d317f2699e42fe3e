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

Every mode appends its per-seed numbers to results/tsc_reference.jsonl (common/result_records.py);
--epoch-curve only with the recipe's own budget (no --epochs), the one docs/training_recipes.md shows.
"""
import argparse
import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402
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

# What the accuracies and epochs measure: the nets and their training loop, the recipes composed
# from configs/, and the generated tasks.
MEASURED_CODE = ["models/", "configs/model/", "configs/trainer/", "runs/reference_tasks.py"]


def batchnorm_check(seeds, n: int = 100, epochs: int = 15) -> dict:
    """The issue's BatchNorm measurement: PR-CNN with the paper's recipe (trainer=tsc, batch 128 >
    the 60 training series: one optimiser step per epoch), accuracy on its own training windows in
    eval mode vs with batch statistics, without and with the recalibrated statistics."""
    import torch
    print("| recalibrate | seed | steps per epoch | train acc, eval mode | train acc, batch statistics | test acc |")
    print("|---|---|---|---|---|---|")
    rows = []
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
            test_acc = (model.predict(X[test]) == y[test]).mean()
            print(f"| {recalibrate} | {seed} | {steps} | {eval_mode:.3f} | {batch_stats:.3f} | {test_acc:.3f} |")
            rows.append({"recalibrate": recalibrate, "seed": seed, "steps_per_epoch": steps,
                         "train_accuracy_eval_mode": eval_mode, "train_accuracy_batch_statistics": batch_stats,
                         "test_accuracy": test_acc})
    return {"task": "frequency", "model": "prcnn", "trainer": "tsc", "n": n, "epochs": epochs, "rows": rows}


def refit_curve(model: str, seed: int, curve_epochs: int, every: int, data) -> list | None:
    """Test accuracy every `every` epochs of one fit as the refit trains; None for an ensemble."""
    X, y, X_test, y_test = data
    estimator = reference_model(model, curve_epochs, seed, ["trainer.epoch_selection=train_loss",
                                                            "trainer.early_stopping_patience=null"])
    if estimator.ensemble_size > 1:
        print(f"{model}: no curve (an ensemble has no network to score until every member is trained; "
              "its members' curves are --models inceptiontime at seeds seed, seed+1, ...)")
        return None
    curve = []

    def logged(record):
        if record["epoch"] % every == 0:
            curve.append((record["epoch"], float((estimator.predict(X_test) == y_test).mean())))
    estimator.fit(X, y, epoch_callback=logged)
    print(f"{model} seed {seed}, test accuracy of the refit for E epochs: "
          + " ".join(f"{e}:{a:.3f}" for e, a in curve), flush=True)
    return curve


def recipe_fit(name: str, model: str, seed: int, epochs: int, data) -> dict:
    """The whole trainer=reference fit: the folds' choice, the refit's test accuracy, fit times;
    printed in words and as one JSON line, returned with each fold's choice and the pooled accuracy."""
    from models.fold_epoch_choice import FOLD_CURVE_WINDOW
    X, y, X_test, y_test = data
    chosen = reference_model(model, epochs, seed)
    load_before, start, cpu_start = os.getloadavg()[0], time.perf_counter(), time.process_time()
    chosen.fit(X, y)
    fit_s, fit_cpu_s = time.perf_counter() - start, time.process_time() - cpu_start
    accuracy = float((chosen.predict(X_test) == y_test).mean())
    # An ensemble (model.ensemble_size > 1): its members' choices, one list each.
    pooled = None if isinstance(chosen.best_epoch_, list) else chosen.fold_curve_["accuracy"][chosen.best_epoch_ - 1]
    pooled_text = "" if pooled is None else \
        f" (pooled held-out accuracy over {FOLD_CURVE_WINDOW} epochs {pooled:.3f})"
    print(f"{model} seed {seed}, trainer=reference: folds ran {chosen.fold_epochs_run_} epochs, chose "
          f"{chosen.best_epoch_}{pooled_text}; each fold alone {chosen.fold_best_epochs_}; refit test accuracy "
          f"{accuracy:.3f}, fit {fit_s:.0f} s wall, {fit_cpu_s:.0f} s CPU, at load "
          f"{load_before:.1f}-{os.getloadavg()[0]:.1f}", flush=True)
    row = {"set": name, "model": model, "seed": seed, "test_accuracy": accuracy,
           "epochs": chosen.best_epoch_, "fold_epochs_run": chosen.fold_epochs_run_,
           "fit_s": round(fit_s, 1), "fit_cpu_s": round(fit_cpu_s, 1),
           "load": [round(load_before, 1), round(os.getloadavg()[0], 1)]}
    print(json.dumps(row), flush=True)
    return {**row, "fold_best_epochs": chosen.fold_best_epochs_, "pooled_held_out_accuracy": pooled,
            "pooled_window": FOLD_CURVE_WINDOW}


def epoch_curve(path: str, models, seeds, epochs: int, every: int, folds: bool, curve_epochs: int) -> dict:
    """Per model, its settings and per seed the refit's curve and the recipe's fit (see the docstring)."""
    import numpy as np

    data = np.load(path, allow_pickle=False)   # a user's file: never unpickled
    classes, y_all = np.unique(data["y"], return_inverse=True)
    train, test = data["split"] == "train", data["split"] == "test"
    split_data = data["X"][train], y_all[train], data["X"][test], y_all[test]
    name = Path(path).stem
    print(f"{name}: {train.sum()} training / {test.sum()} test recordings, {split_data[0].shape[2]} steps, "
          f"{len(classes)} classes; 1-minute load average {os.getloadavg()[0]:.1f}")
    settings = {"set": name, "n_train": int(train.sum()), "n_test": int(test.sum()), "steps": split_data[0].shape[2],
                "classes": len(classes), "epochs": epochs, "curve_epochs": curve_epochs, "every": every}
    results = {}
    for model in models:
        runs = results.setdefault(model, {**settings, "model": model, "runs": []})["runs"]
        for seed in seeds:
            curve = refit_curve(model, seed, curve_epochs, every, split_data) if curve_epochs else None
            recipe = recipe_fit(name, model, seed, epochs, split_data) if folds else None
            runs.append({"seed": seed, "curve": curve, "recipe": recipe})
    for model, result in results.items():
        accuracies = [run["recipe"]["test_accuracy"] for run in result["runs"] if run["recipe"]]
        if accuracies:
            print(f"{name} {model}: refit test accuracy {np.mean(accuracies):.3f} +- "
                  f"{np.std(accuracies, ddof=1 if len(accuracies) > 1 else 0):.3f} over seeds {list(seeds)}", flush=True)
    return results


def tasks(args) -> dict:
    """Every network on every generated task and seed: the table, and its rows with the settings."""
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
    return {"trainer": args.trainer, "epochs": args.epochs, "n": args.n, "length": LENGTH, "optimum": OPTIMUM,
            "rows": rows}


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
    with recording("tsc_reference", MEASURED_CODE) as record:
        if args.batchnorm_check:
            record.add("batchnorm_check", batchnorm_check(args.seeds), seeds=args.seeds)
        elif args.epoch_curve:
            results = epoch_curve(args.epoch_curve, args.models, args.seeds, args.epochs or 1500, args.every,
                                  not args.skip_folds, args.curve_epochs)
            # Another budget than the recipe's own is a check (tests/bench/test_tsc_reference.py runs
            # one), not the measurement docs/training_recipes.md shows: it prints only.
            if args.epochs is None:
                for model, values in results.items():
                    record.add(f"epoch_curve/{values['set']}/{model}", values, seeds=args.seeds)
        else:
            record.add(f"tasks/{args.trainer}", tasks(args), seeds=args.seeds)


if __name__ == "__main__":
    main()
