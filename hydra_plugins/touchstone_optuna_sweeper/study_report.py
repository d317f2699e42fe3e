"""The report of a whole study, written by any of its workers into its own sweep folder:
optimization_results.yaml (every trial, its job folder and worker, the best trial), the Pareto
report (runs/report/pareto.py over every trial's job folder, in whichever sweep folder it lies)
and TensorBoard's HPARAMS view of the study (`tensorboard --logdir <sweep dir>/tensorboard`: one
session per finished trial, its searched parameters and validation score).

A worker writes it when it ends. It is complete once no trial of the study is running or waiting;
a worker that ends while others still run trials writes it labelled partial, with the counts, and
the worker that ends last writes the whole study. By hand, from any machine that sees the study
(a killed last worker, a report wanted mid-search):
`python -m hydra_plugins.touchstone_optuna_sweeper.study_report <storage> <study name> <folder>`.
"""
import shutil
import sys
from pathlib import Path

import optuna
from omegaconf import OmegaConf

from common.atomic import atomic_write_text
from hydra_plugins.touchstone_optuna_sweeper.lost_trials import trial_job
from hydra_plugins.touchstone_optuna_sweeper.study_budget import SURPLUS, progress

RESULTS = "optimization_results.yaml"


def trial_record(trial, requeued_as: dict[int, int]) -> dict:
    job = trial_job(trial) or {}
    record = {"number": trial.number, "state": trial.state.name, "value": trial.value, "params": dict(trial.params),
              "job_folder": job.get("folder"), "host": job.get("host"), "pid": job.get("pid")}
    if trial.number in requeued_as:
        record["requeued_as"] = requeued_as[trial.number]  # its worker died; the same parameters ran again
    return record


def study_results(study: optuna.Study, n_trials: int, location: str) -> dict:
    """Everything optimization_results.yaml says about the study, the best trial included."""
    trials = [t for t in study.get_trials(deepcopy=False) if not t.user_attrs.get(SURPLUS)]
    requeued_as = {t.system_attrs["retry_history"][-1]: t.number for t in trials if t.system_attrs.get("retry_history")}
    counts = progress(trials)
    results = {"study_name": study.study_name, "storage": location, "direction": study.direction.name.lower(),
               "n_trials": n_trials, "partial": counts["running"] + counts["waiting"] > 0, **counts,
               "workers": len({(j["host"], j["pid"]) for j in map(trial_job, trials) if j}),
               "trials": [trial_record(t, requeued_as) for t in trials]}
    if counts["complete"]:
        best = study.best_trial
        results.update(best_trial=best.number, best_value=best.value, best_params=dict(best.params),
                       best_job_folder=(trial_job(best) or {}).get("folder"))
    return results


def write_study_report(sweep_dir: Path, results: dict, parallel: bool) -> None:
    """optimization_results.yaml, the Pareto report and the HPARAMS view of `results` (study_results)."""
    from runs.report.pareto import write_report
    from runs.report.tensorboard_logger import TensorBoardLogger

    if results["partial"]:
        results = {**results, "note": (
            f"Partial report of study '{results['study_name']}': of its {results['n_trials']} trials "
            f"{results['complete']} complete, {results['failed']} failed, {results['running']} running and "
            f"{results['waiting']} waiting in other workers; the worker that ends last writes the whole study.")}
    atomic_write_text(sweep_dir / RESULTS, OmegaConf.to_yaml(OmegaConf.create(results)))
    jobs = {str(t["number"]): Path(t["job_folder"]) for t in results["trials"] if t["job_folder"]}
    write_report(sweep_dir, jobs, parallel=parallel, note=results.get("note", ""))
    board = sweep_dir / "tensorboard"
    shutil.rmtree(board, ignore_errors=True)  # rewritten whole: one session per trial, never two
    for trial in results["trials"]:
        if trial["state"] == "COMPLETE":
            with TensorBoardLogger(str(board / f"trial_{trial['number']:04d}")) as logger:
                logger.log_hparams(trial["params"], {"hparam/validation_score": trial["value"]})


def main(argv: list[str]) -> None:
    from common.errors import InputError
    from hydra_plugins.touchstone_optuna_sweeper.study_storage import (
        JOURNAL_SCHEME,
        open_storage,
        shown,
        storage_location,
    )

    if len(argv) != 3:
        sys.exit("usage: python -m hydra_plugins.touchstone_optuna_sweeper.study_report <storage> <study name> <folder>")
    storage, name, folder = argv[0], argv[1], Path(argv[2])
    try:
        location = storage_location(storage, name, folder)
        journal = Path(location.removeprefix(JOURNAL_SCHEME))
        if location.startswith(JOURNAL_SCHEME) and not journal.is_file():
            raise InputError(f"{journal}: no such file")
        opened = open_storage(location, 60, None)
        if name not in optuna.get_all_study_names(opened):
            raise InputError(f"no study {name!r} in {shown(location)}")
    except InputError as error:
        print(f"error: {error}", file=sys.stderr)
        sys.exit(2)
    study = optuna.load_study(study_name=name, storage=opened)
    folder.mkdir(parents=True, exist_ok=True)
    results = study_results(study, study.user_attrs.get("definition", {}).get("n_trials", len(study.trials)),
                            shown(location))
    write_study_report(folder, results, parallel=results["workers"] > 1)
    print(f"{folder / RESULTS}: {results['complete']} of {results['n_trials']} trials complete"
          + (f", {results['running']} running, {results['waiting']} waiting (partial)" if results["partial"] else ""))


if __name__ == "__main__":
    main(sys.argv[1:])
