"""A search shared by several workers: trials per minute with 1, 2 and 4 `train.py -m` workers on
one study (journal file and PostgreSQL), the storage's overhead per trial, and a loop of
two-worker studies, some with a worker SIGKILLed mid-trial, counting lost and duplicated trials.

    .venv/bin/python bench/search_scaling.py                          # ~30 min on 2 cores
    .venv/bin/python bench/search_scaling.py --repeats 1 --kill-runs 4  # a quick look
    .venv/bin/python bench/search_scaling.py --storages postgresql --workers 1 2 --kill-runs 0

Every worker is a real `python train.py -m hparams_search=resmlp_optuna` process (threads=1, the
default) with tiny trials (120 presses, 3 epochs), all on one study of `--trials` trials.
Trials per minute: the sum over workers of each worker's steady rate, its trials after its first
over the time from its first trial's end to its last one's (a worker's start-up and its first
trial's imports, ~5 s of CPU per process, are a fixed cost per process, outside it; the gaps
between trials, where the storage works, are inside). Overhead: the time each
worker's sweeper spends on the study between its jobs (lost-trial check, ask and TPE sampling,
records, tell; `storage_ms_per_trial` in its optimization_results.yaml), averaged over workers.
PostgreSQL: a throwaway server per study (runs/throwaway_postgres.py) with the server's default
durability (every commit flushed to disk, as on a real server), so every study also meets the
schema race of an empty database.
Lost: a counted trial that did not complete; duplicated: a trial number, job folder or
parameter set run twice (a re-queued trial aside).
Appends its per-study numbers to results/search_scaling.jsonl (common/result_records.py).
"""
import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time
from contextlib import nullcontext
from pathlib import Path

import numpy as np
import optuna
import yaml
from optuna.trial import TrialState

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402
from common.run_status import run_status  # noqa: E402
from common.spread import format_mean_sd  # noqa: E402
from hydra_plugins.touchstone_optuna_sweeper.lost_trials import trial_job  # noqa: E402
from hydra_plugins.touchstone_optuna_sweeper.study_budget import counted  # noqa: E402
from runs.throwaway_postgres import missing, throwaway_postgres  # noqa: E402

SEARCH = ["hparams_search=resmlp_optuna", "hydra.sweeper.n_startup_trials=4", "hydra.sweeper.study_name=bench",
          "scene.n_samples=120", "scene.grid_nodes=21", "scene.progress=false", "trainer.max_epochs=3"]
SEED = 0   # the sweeper's sampler seed: hydra.sweeper.seed=${seed}, the config's default seed
KILL_TRIALS = 6   # trials per two-worker study of the kill loop
# What the rates and counts measure: the sweeper (ask/tell, lost trials, storage), the search it
# runs, and the throwaway server whose durability sets PostgreSQL's commit cost.
MEASURED_CODE = ["hydra_plugins/touchstone_optuna_sweeper/", "configs/hparams_search/resmlp_optuna.yaml",
                 "runs/throwaway_postgres.py"]


def study_run(folder: Path, storage: str, workers: int, n_trials: int, kill: bool) -> dict:
    """One study run by `workers` train.py processes; its numbers."""
    env = {**os.environ, "CI": "true", "OMP_NUM_THREADS": "1"}
    processes = [subprocess.Popen([sys.executable, "train.py", "-m", *SEARCH, f"hydra.sweeper.n_trials={n_trials}",
                                   f"hydra.sweeper.storage='{storage}'", f"hydra.sweep.dir={folder / f'w{i}'}"],
                                  cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                 for i in range(workers)]
    if kill:  # the first worker, as soon as one of its trials runs
        while not any(run_status(job).state == "running" for job in folder.glob("w0/[0-9]*")):
            time.sleep(0.05)
        processes[0].send_signal(signal.SIGKILL)
    codes = [p.wait() for p in processes]
    if any(code != 0 for code in codes[1 if kill else 0:]):
        raise SystemExit(f"a worker failed in {folder}: exit codes {codes}")
    study = optuna.load_study(study_name="bench", storage=storage_object(storage))
    trials = study.get_trials()
    kept = counted(trials)
    done = [t for t in kept if t.state == TrialState.COMPLETE]
    by_worker = {}
    for trial in done:
        by_worker.setdefault(trial_job(trial)["pid"], []).append(trial.datetime_complete)
    steady = [(len(ends) - 1) / (max(ends) - min(ends)).total_seconds() for ends in by_worker.values() if len(ends) > 1]
    retried = {n for t in trials for n in t.system_attrs.get("retry_history", ())}
    fresh = [t for t in kept if "retry_history" not in t.system_attrs]  # a re-queued trial repeats on purpose
    folders = [trial_job(t)["folder"] for t in kept if trial_job(t)]
    reports = [yaml.safe_load(p.read_text()) for p in folder.glob("w*/optimization_results.yaml")]
    return {"trials_per_min": 60 * sum(steady),
            "overhead_ms": float(np.mean([r["this_worker"]["storage_ms_per_trial"] for r in reports])),
            "lost": n_trials - len(done) + sum(t.state in (TrialState.RUNNING, TrialState.WAITING) for t in trials),
            "duplicated": (len(kept) - len({t.number for t in kept})) + (len(folders) - len(set(folders)))
            + (len(fresh) - len({tuple(sorted(t.params.items())) for t in fresh})),
            "requeued": len(retried), "workers_contributed": len(by_worker)}


def storage_object(storage: str):
    if storage.endswith(".log"):
        from optuna.storages.journal import JournalFileBackend, JournalStorage
        return JournalStorage(JournalFileBackend(storage))
    return storage


def one_study(engine: str, workers: int, n_trials: int, kill: bool = False) -> dict:
    with tempfile.TemporaryDirectory(prefix="search-scaling-") as tmp:
        folder = Path(tmp)
        server = throwaway_postgres(durable=True) if engine == "postgresql" else nullcontext(str(folder / "study.log"))
        with server as storage:
            return study_run(folder, storage, workers, n_trials, kill)


def scaling(engines, args) -> list[dict]:
    """The trials-per-minute table, printed row by row; its rows with the per-study numbers."""
    print(f"{os.cpu_count()} cores; {args.trials} trials per study; load average: the 1-minute figure before and after")
    print("| storage | workers | trials/min | speed-up vs 1 worker | storage overhead (ms/trial) | load average |")
    print("|---|---|---|---|---|---|")
    rows = []
    for engine in engines:
        rates = {}
        for workers in args.workers:
            load_before = os.getloadavg()[0]
            runs = [one_study(engine, workers, args.trials) for _ in range(args.repeats)]
            load_after = os.getloadavg()[0]
            rates[workers] = rate = np.array([r["trials_per_min"] for r in runs])
            overhead = np.array([r["overhead_ms"] for r in runs])
            speedup = f"{rate.mean() / rates[1].mean():.2f}×" if 1 in rates else "—"
            print(f"| {engine} | {workers} | {format_mean_sd(rate, '.1f')} | {speedup} | "
                  f"{format_mean_sd(overhead, '.1f')} | {load_before:.1f}–{load_after:.1f} |", flush=True)
            rows.append({"storage": engine, "workers": workers, "trials_per_min": rate, "overhead_ms": overhead,
                         "load_before": load_before, "load_after": load_after})
    return rows


def kills(engines, n_runs: int) -> list[dict]:
    """The kill loop's table (every other study with a worker killed); its rows, per study."""
    print("\n| storage | two-worker studies | with a worker killed | lost | duplicated | re-queued | both contributed |")
    print("|---|---|---|---|---|---|---|")
    rows = []
    for engine in engines:
        killed = [i % 2 == 1 for i in range(n_runs)]
        runs = [one_study(engine, 2, KILL_TRIALS, kill=kill) for kill in killed]
        print(f"| {engine} | {len(runs)} | {n_runs // 2} | {sum(r['lost'] for r in runs)} "
              f"| {sum(r['duplicated'] for r in runs)} | {sum(r['requeued'] for r in runs)} "
              f"| {sum(r['workers_contributed'] == 2 for r in runs)} |", flush=True)
        counts = ("lost", "duplicated", "requeued", "workers_contributed")
        rows.append({"storage": engine, "killed": killed, **{key: [r[key] for r in runs] for key in counts}})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--trials", type=int, default=24, help="trials per study")
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2, 4])
    parser.add_argument("--kill-runs", type=int, default=20, help="two-worker studies, every other one with a kill")
    parser.add_argument("--storages", nargs="+", choices=["journal", "postgresql"], default=["journal", "postgresql"])
    args = parser.parse_args()
    engines = [e for e in args.storages if e == "journal" or missing() is None]
    skipped = missing() if "postgresql" in args.storages else None
    if skipped:
        print(f"PostgreSQL skipped: {skipped}")
    with recording("search_scaling", MEASURED_CODE) as record:
        record.add("scaling", {"trials_per_study": args.trials, "repeats": args.repeats, "cores": os.cpu_count(),
                               "postgresql_skipped": skipped, "rows": scaling(engines, args)}, seeds=[SEED])
        if args.kill_runs:
            record.add("kills", {"studies": args.kill_runs, "trials_per_study": KILL_TRIALS,
                                 "postgresql_skipped": skipped, "rows": kills(engines, args.kill_runs)}, seeds=[SEED])


if __name__ == "__main__":
    main()
