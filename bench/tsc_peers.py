"""Touchstone's classifiers against aeon's ROCKET family on the UCR/UEA sets inside aeon's wheel.

    .venv/bin/python bench/tsc_peers.py --quick            # GunPoint, BasicMotions, seed 0: aeon's MiniRocket
                                                           # and MultiRocket-Hydra, the default (< 10 min)
    .venv/bin/python bench/tsc_peers.py                    # every set and method (about 3 h on 2 cores)
    .venv/bin/python bench/tsc_peers.py --sets GunPoint --methods aeon:minirocket prcnn --seeds 0 1 2
    .venv/bin/python bench/tsc_peers.py --report           # the table and figure from the results so far

The peer runs in its own venv, bench/.venv-aeon (bench/requirements-aeon.txt: aeon 1.6.0 pins numpy
and pandas below the project's versions through numba, so it never enters .venv), created here
when missing (python -m venv + pip install from the package registry; if that fails, one line
says so and only Touchstone runs). The sets are the equal-length classification sets aeon ships
(ACSF1, ArrowHead, BasicMotions, GunPoint, ItalyPowerDemand, OSULeaf and the equal-length
JapaneseVowels and PickupGestureWiimoteZ), read from the installed package's files with their
official train/test splits (bench/tsc_peers_aeon.py export) and written once as Touchstone
recordings NPZ files (X, y, split).

Methods:
  aeon:minirocket, aeon:multirocket_hydra, aeon:quant   aeon 1.6.0, n_jobs=1, numba warmed up before timing
                                                       (bench/tsc_peers_aeon.py run)
  every Touchstone classifier, run as a user would:    python train.py data=recordings_npz data.path=<set>.npz
                                                       model=<m> seed=<s> threads=1 (the ROCKET family found in
                                                       configs/model/ at run time, the nets, and `default`:
                                                       no model= at all; `default_most_accurate`: the
                                                       same with model.prefer=most_accurate)
Three seeds for aeon, the ROCKET family and the default. A net runs seed 0 first under a 15-minute
limit; seeds 1 and 2 follow only when that fit finished within it, else the table says why.
Accuracy is on the official test split; fit s is the fit alone (metrics.json fit_time_s, aeon:
fit()); latency is per recording at batch 1 (Touchstone: onnxruntime p50, one thread, from
metrics.json; aeon: the median of 20 single-recording predict() calls, and in brackets predict()
on the whole test set divided by its size). Every row records the 1-minute load average before
it ran: the peer and Touchstone are measured in the same script run, under the same load.

Results accumulate in --out (default bench/results/tsc_peers/): results.jsonl (one line per run;
a rerun skips what is there, so a long run can be continued), table.md (set x method, beside the
published ResNet and InceptionTime accuracies) and pareto.png (the classification Pareto front
over all families: mean test accuracy over the sets against mean fit time). When a run completes,
its grid's per-seed rows (Touchstone's and aeon's, those resumed from --out included) are appended to
results/tsc_peers.jsonl (common/result_records.py), one record per set and method.
"""
import argparse
import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402
from common.spread import format_mean_sd  # noqa: E402
from runs.report.pareto import pareto_mask  # noqa: E402

PEER_VENV = ROOT / "bench" / ".venv-aeon"
PEER_REQUIREMENTS = ROOT / "bench" / "requirements-aeon.txt"
PEER_SCRIPT = ROOT / "bench" / "tsc_peers_aeon.py"
SETS = ("ACSF1", "ArrowHead", "BasicMotions", "GunPoint", "ItalyPowerDemand", "OSULeaf", "JapaneseVowels_eq",
        "PickupGestureWiimoteZ_eq")
QUICK_SETS = ("GunPoint", "BasicMotions")   # one channel and six
QUICK_METHODS = ("aeon:minirocket", "aeon:multirocket_hydra", "default")
QUICK_SEEDS = (0,)
AEON_METHODS = ("aeon:minirocket", "aeon:multirocket_hydra", "aeon:quant")
NETS = ("prcnn", "rescnn", "inceptiontime", "lstm_fcn")
DEFAULT = "default"   # train.py with no model=
# the default under another setting of its choice: method name -> train.py overrides (no model= either)
DEFAULT_VARIANTS = {DEFAULT: [], "default_most_accurate": ["model.prefer=most_accurate"]}
NET_LIMIT_S = 15 * 60
# What the rows measure: Touchstone's whole run as train.py makes it, and the peer's side (its
# pinned aeon version and how bench/tsc_peers_aeon.py fits and times it).
MEASURED_CODE = ["train.py", "common/", "data/", "models/", "export/", "runs/", "configs/",
                 "bench/tsc_peers_aeon.py", "bench/requirements-aeon.txt"]
SINGLE_THREAD = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
                 "OPENBLAS_NUM_THREADS": "1", "TOUCHSTONE_THREADS": "1", "CI": "true"}

# Published test accuracies on the same official splits. Each is the mean over the runs the
# authors report (5 iterations for ResNet on the 2018 archive, 10 on the MTS archive); InceptionTime
# is the paper's 5-network ensemble. None: not in that publication.
PUBLISHED_SOURCES = {
    "ResNet": "H. Ismail Fawaz, G. Forestier, J. Weber, L. Idoumghar, P.-A. Muller, \"Deep learning for time "
              "series classification: a review\", Data Min. Knowl. Disc. 33, 2019; results files of "
              "github.com/hfawaz/dl-4-tsc: results/results-ucr-128.csv (UCR 2018 archive, mean of 5 iterations) "
              "and results/results-mts.csv (Baydogan's MTS archive, mean of 10)",
    "InceptionTime": "H. Ismail Fawaz, B. Lucas, G. Forestier, C. Pelletier, D. F. Schmidt, J. Weber, G. I. Webb, "
                     "L. Idoumghar, P.-A. Muller, F. Petitjean, \"InceptionTime: finding AlexNet for time series "
                     "classification\", Data Min. Knowl. Disc. 34, 2020; github.com/hfawaz/InceptionTime "
                     "results-InceptionTime-128.csv (UCR 2018 archive, the 5-network ensemble)",
}
PUBLISHED = {  # set: {method: accuracy}
    "ACSF1": {"ResNet": 0.916, "InceptionTime": 0.920},
    "ArrowHead": {"ResNet": 0.838, "InceptionTime": 0.846},
    "BasicMotions": {"ResNet": None, "InceptionTime": None},
    "GunPoint": {"ResNet": 0.991, "InceptionTime": 1.000},
    "ItalyPowerDemand": {"ResNet": 0.962, "InceptionTime": 0.965},
    "OSULeaf": {"ResNet": 0.980, "InceptionTime": 0.942},
    # The MTS archive's JapaneseVowels pads its variable lengths; aeon's _eq version truncates or pads
    # differently, so the figure is a guide, not a like-for-like number.
    "JapaneseVowels_eq": {"ResNet": 0.992, "InceptionTime": None},
    "PickupGestureWiimoteZ_eq": {"ResNet": 0.704, "InceptionTime": 0.760},
}


def load_average() -> float:
    return os.getloadavg()[0]


# -- the peer's venv and the sets --------------------------------------------------------------
def peer_python() -> Path | None:
    """bench/.venv-aeon's python, created when missing; None (and one line said) when it cannot be."""
    python = PEER_VENV / "bin" / "python"
    if python.exists():
        return python
    print(f"creating {PEER_VENV.relative_to(ROOT)} (aeon 1.6.0 from {PEER_REQUIREMENTS.name}; a few minutes)", flush=True)
    steps = ([sys.executable, "-m", "venv", str(PEER_VENV)],
             [str(python), "-m", "pip", "install", "-q", "-r", str(PEER_REQUIREMENTS)])
    for step in steps:
        done = subprocess.run(step, capture_output=True, text=True)
        if done.returncode != 0:
            reason = (done.stderr.strip().splitlines() or ["no message"])[-1]
            print(f"aeon skipped: could not set up {PEER_VENV.relative_to(ROOT)} ({reason})", flush=True)
            return None
    return python


def write_sets(python: Path | None, folder: Path, names) -> dict[str, Path]:
    """Each set once as a Touchstone recordings NPZ (X, y, split), from aeon's installed files."""
    missing = [n for n in names if not (folder / f"{n}.npz").exists()]
    if missing:
        if python is None:
            print(f"sets {', '.join(missing)} skipped: they are read from aeon's package, which is not installed")
        else:
            subprocess.run([str(python), str(PEER_SCRIPT), "export", str(folder), *missing], check=True,
                           stdout=subprocess.DEVNULL)
    return {n: folder / f"{n}.npz" for n in names if (folder / f"{n}.npz").exists()}


# -- runs ------------------------------------------------------------------------------------------
def rocket_models() -> list[str]:
    """The ROCKET family's model configs present now (configs/model/*.yaml whose target is models.rocket)."""
    return sorted(p.stem for p in (ROOT / "configs" / "model").glob("*.yaml")
                  if "models.rocket" in p.read_text())


def run_aeon(python: Path, path: Path, method: str, seeds) -> list[dict]:
    load = load_average()
    done = subprocess.run([str(python), str(PEER_SCRIPT), "run", str(path), method.split(":")[1],
                           *map(str, seeds)], capture_output=True, text=True, env={**os.environ, **SINGLE_THREAD})
    if done.returncode != 0:
        reason = (done.stderr.strip().splitlines() or ["no message"])[-1]
        return [{"seed": s, "error": reason, "load": load} for s in seeds]
    rows = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    return [{"seed": r["seed"], "accuracy": r["accuracy"], "fit_s": r["fit_s"],
             "latency_ms": r["predict_ms_batch1"], "latency_bulk_ms": r["predict_ms_bulk"], "load": load}
            for r in rows]


def run_touchstone(path: Path, method: str, seed: int, run_dir: Path, limit_s: float | None) -> dict:
    """`python train.py data=recordings_npz data.path=... [model=...] seed=... threads=1`."""
    command = [sys.executable, "train.py", "data=recordings_npz", f"data.path={path}", f"seed={seed}", "threads=1",
               f"hydra.run.dir={run_dir}", "overwrite=true"]
    if method in DEFAULT_VARIANTS:
        command += DEFAULT_VARIANTS[method]
    else:
        command.insert(3, f"model={method}")
    load, start = load_average(), time.perf_counter()
    try:
        done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=limit_s,
                              env={**os.environ, **SINGLE_THREAD})
    except subprocess.TimeoutExpired:
        return {"seed": seed, "error": f"timeout: the run took more than {limit_s / 60:.0f} min here",
                "timeout": True, "load": load}
    wall = time.perf_counter() - start
    metrics_path = run_dir / "metrics.json"
    if done.returncode != 0 or not metrics_path.exists():
        reason = next((line for line in reversed(done.stderr.strip().splitlines()) if line.startswith("error")),
                      (done.stderr.strip().splitlines() or ["no message"])[-1])
        return {"seed": seed, "error": reason, "load": load}
    metrics = json.loads(metrics_path.read_text())
    latency = metrics.get("cost", {}).get("latency_batch1_us", {}).get("onnx_1_thread", {}).get("p50")
    training = metrics.get("training", {})
    return {"seed": seed, "accuracy": metrics["test"]["accuracy"], "fit_s": metrics["fit_time_s"],
            "latency_ms": None if latency is None else latency / 1e3, "wall_s": wall, "model": metrics.get("model"),
            "chosen": metrics.get("choice", {}).get("chosen"), "reason": metrics.get("choice", {}).get("reason"),
            "scored_on": metrics.get("choice", {}).get("scored_on"),
            "skipped": list(metrics.get("choice", {}).get("skipped", {})),
            "chosen_fit_s": metrics.get("cost", {}).get("chosen_fit_time_s"),
            "trade": metrics.get("choice", {}).get("trade"),
            "best_epoch": training.get("best_epoch"), "fold_best_epochs": training.get("fold_best_epochs"),
            "load": load}


# -- report ----------------------------------------------------------------------------------------
def read_results(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines()] if path.exists() else []


def summary(rows: list[dict]) -> dict:
    """(set, method) -> accuracies, fit s, latencies, loads, errors."""
    cells = {}
    for r in rows:
        cell = cells.setdefault((r["set"], r["method"]), {"accuracy": [], "fit_s": [], "latency_ms": [],
                                                         "latency_bulk_ms": [], "load": [], "errors": [], "notes": []})
        if "error" in r:
            cell["errors"].append(r["error"])
            continue
        if r.get("chosen"):    # what the default chose, on what, and what the budget skipped
            scored = r.get("scored_on") or {}   # validation, or how the chosen one held training rows out
            on = scored.get("by", {}).get(r["chosen"], scored.get("rows"))
            cell["notes"].append(f"{r['chosen']} ({on}, {scored['n']})" if scored else r["chosen"])
        elif r.get("best_epoch") is not None:   # the epochs a net was refitted for
            cell["notes"].append(f"{r['best_epoch']} epochs")
        for key in ("accuracy", "fit_s", "latency_ms", "latency_bulk_ms", "load"):
            if r.get(key) is not None:
                cell[key].append(r[key])
    return cells


def table(rows: list[dict]) -> str:
    cells = summary(rows)
    sets = [s for s in SETS if any(k[0] == s for k in cells)]
    methods = sorted({k[1] for k in cells}, key=lambda m: (not m.startswith("aeon:"), m))
    lines = ["| set | method | test accuracy | fit s | latency ms / recording | load (1 min) | chose / epochs |",
             "|---|---|---|---|---|---|---|"]
    for s in sets:
        for m in methods:
            cell = cells.get((s, m))
            if cell is None:
                continue
            if not cell["accuracy"]:
                lines.append(f"| {s} | {m} | {cell['errors'][0] if cell['errors'] else '—'} | | | | |")
                continue
            # over the seeds that ran: a seed that failed is left out, a single one says so
            accuracy, fit_s, latency = (format_mean_sd(cell[key], spec, one_value="{} (1 seed)", missing="—")
                                        for key, spec in (("accuracy", ".3f"), ("fit_s", ".2f"), ("latency_ms", ".2f")))
            if cell["latency_bulk_ms"]:
                latency += f" ({np.mean(cell['latency_bulk_ms']):.2f} bulk)"
            note = f"; {len(cell['errors'])} failed: {cell['errors'][0]}" if cell["errors"] else ""
            lines.append(f"| {s} | {m} | {accuracy}{note} | {fit_s} | "
                         f"{latency} | {min(cell['load']):.1f}–{max(cell['load']):.1f} | {', '.join(cell['notes'])} |")
        published = PUBLISHED.get(s, {})
        text = ", ".join(f"{k} {v:.3f}" for k, v in published.items() if v is not None)
        lines.append(f"| {s} | published | {text or '—'} | | | | |")
    return "\n".join(lines)


def pareto_figure(rows: list[dict], path: Path) -> str:
    """Mean test accuracy over the sets, against mean fit time, for the methods that ran on the most
    sets (a net run on one set would otherwise shrink the comparison to that set); the front marked."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    cells = summary(rows)
    methods = sorted({k[1] for k in cells})
    counts = {m: sum(bool(cells.get((s, m), {}).get("accuracy")) for s in SETS) for m in methods}
    methods = [m for m in methods if counts[m] == max(counts.values())]
    common = [s for s in SETS if all(cells.get((s, m), {}).get("accuracy") for m in methods)]
    accuracy = np.array([np.mean([np.mean(cells[(s, m)]["accuracy"]) for s in common]) for m in methods])
    fit = np.array([np.mean([np.mean(cells[(s, m)]["fit_s"]) for s in common]) for m in methods])
    front = pareto_mask(accuracy, fit)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.scatter(fit[~front], accuracy[~front], color="0.6")
    ax.scatter(fit[front], accuracy[front], color="C3")
    order = np.argsort(fit[front])
    ax.plot(fit[front][order], accuracy[front][order], color="C3", linestyle="--", label="Pareto front")
    for m, x, a in zip(methods, fit, accuracy):
        ax.annotate(m, (x, a), textcoords="offset points", xytext=(4, 3), fontsize=8)
    ax.set_xscale("log")
    ax.set_xlabel("mean fit time (s, one thread, log scale)")
    ax.set_ylabel("mean test accuracy")
    ax.set_title(textwrap.fill(f"over {len(common)} sets: {', '.join(common)}", 90), fontsize=8)
    ax.margins(x=0.2, y=0.1)
    ax.legend(loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return ", ".join(m for m, f in zip(methods, front) if f)


def append_row(results_path: Path, row: dict) -> None:
    """One run's row into --out's results.jsonl (what a rerun resumes from), and shown."""
    with results_path.open("a") as f:
        f.write(json.dumps(row) + "\n")
    shown = {k: (round(v, 4) if isinstance(v, float) else v) for k, v in row.items()}
    print(json.dumps(shown), flush=True)


def run_grid(args, paths: dict, methods, python: Path | None, done: set, results_path: Path) -> None:
    """Every set x method x seed not in --out yet, each row appended to results_path as it ends."""
    for name, path in paths.items():
        for method in methods:
            seeds = [s for s in args.seeds if (name, method, s) not in done]
            if not seeds:
                continue
            if method.startswith("aeon:"):
                if python is None:
                    continue
                for row in run_aeon(python, path, method, seeds):
                    append_row(results_path, {"set": name, "method": method, **row})
                continue
            net = method in NETS or method.startswith("inceptiontime")
            for seed in seeds:
                run_dir = args.out / "runs" / name / method / f"seed{seed}"
                row = run_touchstone(path, method, seed, run_dir, args.net_limit_min * 60 if net else None)
                append_row(results_path, {"set": name, "method": method, **row})
                if net and row.get("timeout"):  # one fit beyond the limit: the other seeds are not run
                    for rest in seeds[seeds.index(seed) + 1:]:
                        append_row(results_path, {"set": name, "method": method, "seed": rest, "load": load_average(),
                                                  "error": f"skipped: seed {seed} took more than "
                                                           f"{args.net_limit_min:.0f} min"})
                    break


def record_cells(record, rows: list[dict], grid: set, resumed: set, prefix: str) -> None:
    """One record per set and method of this run's grid: per seed its accuracy, fit s and latency
    (None where it failed) and the whole row; `resumed` rows came from an earlier run in --out."""
    cells = {}
    for r in rows:   # a later line for the same set, method and seed replaces an earlier one
        key = (r["set"], r["method"], r["seed"])
        if key in grid:
            cells.setdefault(key[:2], {})[r["seed"]] = {**r, "resumed": key in resumed}
    headline = ("accuracy", "fit_s", "latency_ms", "latency_bulk_ms")
    for (name, method), by_seed in cells.items():
        runs = [by_seed[seed] for seed in sorted(by_seed)]
        record.add(f"{prefix}{name}/{method}",
                   {"set": name, "method": method, "side": "aeon" if method.startswith("aeon:") else "touchstone",
                    "threads": 1, "published": PUBLISHED.get(name, {}),
                    **{key: [r.get(key) for r in runs] for key in headline}, "runs": runs}, seeds=sorted(by_seed))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help=f"sets {', '.join(QUICK_SETS)}, methods "
                        f"{', '.join(QUICK_METHODS)}, seed 0 (a smoke run, not a result: one seed)")
    parser.add_argument("--sets", nargs="+", choices=SETS)
    parser.add_argument("--methods", nargs="+", help="aeon:minirocket, ..., a model name, default or "
                        "default_most_accurate")
    parser.add_argument("--seeds", nargs="+", type=int)
    parser.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "tsc_peers")
    parser.add_argument("--report", action="store_true", help="run nothing: the table and figure from --out's results")
    parser.add_argument("--net-limit-min", type=float, default=NET_LIMIT_S / 60,
                        help="a net's seed 0 must finish within this; else its other seeds are skipped")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    if args.report:  # --sets: the Pareto figure over those sets only (the table keeps every set)
        rows = read_results(args.out / "results.jsonl")
        return report(rows, args.out, [r for r in rows if r["set"] in args.sets] if args.sets else rows)
    sets = args.sets or (QUICK_SETS if args.quick else SETS)
    methods = args.methods or (list(QUICK_METHODS) if args.quick else [*AEON_METHODS, *rocket_models(), DEFAULT, *NETS])
    args.seeds = args.seeds or list(QUICK_SEEDS if args.quick else (0, 1, 2))
    python = peer_python() if any(m.startswith("aeon:") for m in methods) or not (args.out / "sets").exists() else None
    if python is None and not all((args.out / "sets" / f"{s}.npz").exists() for s in sets):
        python = peer_python()
    paths = write_sets(python, args.out / "sets", sets)
    results_path = args.out / "results.jsonl"
    done = {(r["set"], r["method"], r["seed"]) for r in read_results(results_path)}
    print(f"{len(paths)} sets x {len(methods)} methods, seeds {args.seeds}; results in {results_path}", flush=True)

    with recording("tsc_peers", MEASURED_CODE) as record:
        run_grid(args, paths, methods, python, done, results_path)
        grid = {(name, method, seed) for name in paths for method in methods for seed in args.seeds}
        # --quick is a smoke run (one seed), recorded apart from the results.
        record_cells(record, read_results(results_path), grid, done, "quick/" if args.quick else "")
    report(read_results(results_path), args.out)


def report(rows: list[dict], out: Path, front_rows: list[dict] | None = None) -> None:
    text = table(rows)
    (out / "table.md").write_text(text + "\n")
    front = pareto_figure(rows if front_rows is None else front_rows, out / "pareto.png")
    print(text)
    print(f"Pareto front (mean accuracy vs mean fit s): {front}; figure {out / 'pareto.png'}")


if __name__ == "__main__":
    main()
