"""A TPE search as a Hydra sweeper: `python train.py -m hparams_search=<name>`, by one process or
by many workers sharing a study (`hydra.sweeper.study_name=<name>`; docs/cluster.md).

The search space is declared with Hydra's own sweep syntax in `hydra.sweeper.params` (or on the
command line): `choice(a, b)` -> categorical, `range(lo, hi[, step])` -> integers lo..hi-1,
`interval(lo, hi)` -> a float, `tag(log, interval(lo, hi))` -> a float on a log scale; anything
else is a fixed override passed to every trial. Each trial is one ordinary job of the launcher,
in the folder <this worker's sweep dir>/<trial number> (numbers are the study's, unique across
its workers); the value told to Optuna is what the task returns (train.py: the validation score;
a failed trial is marked failed, never scored). The study lives in the storage of
study_storage.py; its budget (study_budget.py), lost trials (lost_trials.py) and report
(study_report.py) are the study's, not this process's. The best configuration is logged and
written to <sweep dir>/optimization_results.yaml with its job folder, wherever that lies.

TPE: Bergstra et al., "Algorithms for hyper-parameter optimization", NeurIPS 2011; Optuna:
Akiba et al., KDD 2019. Written over Optuna's ask-and-tell interface (study.ask(distributions),
study.tell(trial, value)), as the Hydra plugin docs describe a Sweeper: setup() gets the launcher,
sweep(arguments) launches batches of override lists.
"""
import logging
import math
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import optuna
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import (
    ChoiceSweep,
    IntervalSweep,
    Override,
    RangeSweep,
)
from hydra.core.plugins import Plugins
from hydra.errors import HydraException
from hydra.plugins.sweeper import Sweeper
from hydra.types import HydraContext, TaskFunction
from omegaconf import DictConfig, OmegaConf

from common.errors import InputError
from hydra_plugins.touchstone_optuna_sweeper.lost_trials import (
    Heartbeat,
    fail_lost_trials,
    give_back,
    has_heartbeat,
    record_job,
    requeuing,
)
from hydra_plugins.touchstone_optuna_sweeper.study_budget import (
    budget_left,
    is_surplus,
    mark_surplus,
    may_be_surplus,
    progress,
)
from hydra_plugins.touchstone_optuna_sweeper.study_report import RESULTS, study_results, write_study_report
from hydra_plugins.touchstone_optuna_sweeper.study_storage import join_study, open_storage, shown, storage_location
from hydra_plugins.touchstone_optuna_sweeper.trial_seeded_sampler import TrialSeededTPESampler

log = logging.getLogger(__name__)


def distribution(override: Override) -> optuna.distributions.BaseDistribution:
    """Hydra sweep syntax -> an Optuna distribution."""
    sweep = override.value()
    key = override.get_key_element()
    if isinstance(sweep, ChoiceSweep):  # categorical over the overrides' own text (lists included)
        return optuna.distributions.CategoricalDistribution(
            [Override._get_value_element_as_str(value) for value in sweep.list])
    if isinstance(sweep, RangeSweep):
        if all(isinstance(v, int) for v in (sweep.start, sweep.stop, sweep.step)):
            return optuna.distributions.IntDistribution(sweep.start, sweep.stop - sweep.step, step=sweep.step)
        raise HydraException(f"{key}: range() searches integers; use interval() for floats")
    if isinstance(sweep, IntervalSweep):
        return optuna.distributions.FloatDistribution(float(sweep.start), float(sweep.end), log="log" in sweep.tags)
    raise HydraException(f"{key}: cannot search {override.input_line!r}")


def split_space(overrides: list[Override]):
    """(fixed overrides as text, {key: distribution})."""
    fixed, space = [], {}
    for override in overrides:
        key = override.get_key_element()
        if override.is_sweep_override():
            space[key] = distribution(override)
        else:
            fixed.append(f"{key}={override.get_value_element_as_str()}")
    return fixed, space


class OptunaTPESweeper(Sweeper):
    def __init__(self, n_trials: int, n_jobs: int, direction: str, seed: int, n_startup_trials: int,
                 study_name: str | None, storage: str | None, heartbeat_interval: int, lost_trial_retries: int,
                 params: dict | None = None) -> None:
        self.n_trials, self.n_jobs, self.direction, self.seed = n_trials, n_jobs, direction, seed
        self.n_startup_trials, self.study_name, self.storage = n_startup_trials, study_name, storage
        self.heartbeat_interval, self.lost_trial_retries = heartbeat_interval, lost_trial_retries
        self.retry_lost = requeuing(lost_trial_retries)
        self.params = dict(params or {})
        self.hydra_context: HydraContext | None = None
        self.config: DictConfig | None = None
        self.launcher = None

    def setup(self, *, hydra_context: HydraContext, task_function: TaskFunction, config: DictConfig) -> None:
        self.hydra_context, self.config = hydra_context, config
        self.launcher = Plugins.instance().instantiate_launcher(
            hydra_context=hydra_context, task_function=task_function, config=config)

    def sweep(self, arguments: list[str]) -> Any:
        try:
            fixed, space, study, storage, location = self._join(arguments)
        except InputError as error:  # a wrong setting or an unreachable storage: one line, exit 2, nothing written
            print(f"error: {error}", file=sys.stderr)
            sys.exit(2)
        sweep_dir = Path(self.config.hydra.sweep.dir)
        sweep_dir.mkdir(parents=True, exist_ok=True)
        OmegaConf.save(self.config, sweep_dir / "multirun.yaml")
        log.info("Optuna TPE search: study %r (%s), %d trials in the study over %s; this worker's jobs in %s",
                 study.study_name, shown(location), self.n_trials, ", ".join(space), sweep_dir)
        # storage_s: time spent on the study between jobs (tell, lost-trial check, ask and sampling,
        # records), the storage's overhead per trial in optimization_results.yaml; it runs from a
        # batch's tell to the next batch's launch
        returns, ran, storage_s = [], 0, 0.0
        stale_checked = -math.inf  # heartbeats go stale in minutes: look for stale trials once an interval
        started = time.perf_counter()
        # The study's trials, read once per round: after a batch's tell they give its progress line,
        # then the next round's lost-trial and budget checks, which follow at once (each reading is
        # a round of SQL statements on an RDB storage)
        study_trials = study.get_trials(deepcopy=False)
        while True:
            check_stale = has_heartbeat(storage) and started - stale_checked >= self.heartbeat_interval
            stale_checked = started if check_stale else stale_checked
            lost = fail_lost_trials(study, study_trials, self.retry_lost, check_stale)
            for number in lost:
                log.warning("trial %d: its worker is gone (killed?); marked failed%s", number,
                            ", re-queued" if self.lost_trial_retries else "")
            trials = self._ask(study, space, sweep_dir, study.get_trials(deepcopy=False) if lost else study_trials)
            storage_s += time.perf_counter() - started
            if not trials:
                break
            batch = [fixed + [f"{key}={trial.params[key]}" for key in space] + [f"hydra.sweep.subdir={trial.number}"]
                     for trial in trials]
            if not returns:  # every batch overrides the same keys: composing the first one proves them all
                self.validate_batch_is_legal(batch)
            try:
                with Heartbeat(storage, trials, self.heartbeat_interval):
                    results = self.launcher.launch(batch, initial_job_idx=trials[0].number)
            except BaseException:
                give_back(study, trials, self.retry_lost)
                raise
            started = time.perf_counter()  # counted at the next launch, with that round's checks and ask
            values = [self._tell(study, trial, result) for trial, result in zip(trials, results)]
            study_trials = study.get_trials(deepcopy=False)
            counts = progress(study_trials)
            for trial, value in zip(trials, values):
                log.info("trial %d: %s -> %s (study %r: %d of %d trials taken, %d complete, %d failed, %d running)",
                         trial.number, trial.params, value, study.study_name, counts["counted"], self.n_trials,
                         counts["complete"], counts["failed"], counts["running"])
            ran += len(trials)
            returns.append(results)
        fail_lost_trials(study, study.get_trials(deepcopy=False), self.retry_lost, has_heartbeat(storage))
        self._report(study, fixed, location, sweep_dir, ran, storage_s)
        return returns

    def _join(self, arguments: list[str]):
        """(fixed overrides, search space, study, storage, its location): the study joined or created."""
        if self.n_trials < 1 or self.n_jobs < 1 or self.heartbeat_interval < 1 or self.lost_trial_retries < 0:
            raise InputError(f"hydra.sweeper: n_trials, n_jobs and heartbeat_interval must be positive, "
                             f"lost_trial_retries >= 0; got {self.n_trials}, {self.n_jobs}, "
                             f"{self.heartbeat_interval}, {self.lost_trial_retries}")
        parser = OverridesParser.create(config_loader=self.hydra_context.config_loader)
        declared = [f"{key}={value}" for key, value in self.params.items()]
        try:
            fixed, space = split_space(parser.parse_overrides(declared + list(arguments)))
        except HydraException as error:
            raise InputError(str(error).splitlines()[0]) from None
        if not space:
            raise InputError("nothing to search: declare hydra.sweeper.params (choice/range/interval)")
        location = storage_location(self.storage, self.study_name, Path(self.config.hydra.sweep.dir))
        storage = open_storage(location, self.heartbeat_interval, self.retry_lost)
        optuna.logging.set_verbosity(optuna.logging.WARNING)
        definition = {"direction": self.direction, "n_trials": self.n_trials, "seed": self.seed,
                      "n_startup_trials": self.n_startup_trials, "fixed": sorted(fixed),
                      "space": {k: optuna.distributions.distribution_to_json(d) for k, d in sorted(space.items())}}
        study = join_study(storage, self.study_name or "search", TrialSeededTPESampler(self.seed, self.n_startup_trials),
                           self.direction, definition)
        return fixed, space, study, storage, location

    def _ask(self, study: optuna.Study, space: dict, sweep_dir: Path,
             study_trials: list[optuna.trial.FrozenTrial]) -> list[optuna.Trial]:
        """Up to n_jobs trials while the study's budget lasts, each marked with its job folder and
        worker. `study_trials`: the study's trials as just read, for the budget check and the
        sampler; after a first ask, read again."""
        trials = []
        while len(trials) < self.n_jobs:
            reading = study.get_trials(deepcopy=False) if trials else study_trials
            if not budget_left(reading, self.n_trials):
                break
            study.sampler.draw_next_from(reading)
            with warnings.catch_warnings():  # Optuna warns that its heartbeat expects study.optimize()
                warnings.simplefilter("ignore", UserWarning)
                trial = study.ask(space)
            if may_be_surplus(trial.number, self.n_trials) and is_surplus(
                    trial.number, study.get_trials(deepcopy=False), self.n_trials):
                mark_surplus(study, trial)  # other workers took the last trials at the same moment
                break
            record_job(trial, str((sweep_dir / str(trial.number)).absolute()))
            trials.append(trial)
        return trials

    def _tell(self, study: optuna.Study, trial: optuna.Trial, result) -> float:
        """Record the job's result on its trial; returns the value (NaN: failed)."""
        try:
            value = float(result.return_value)
        except Exception as error:  # noqa: BLE001 - any job failure is recorded as a failed trial
            log.warning("trial %d failed: %s", trial.number, str(error).splitlines()[0] if str(error) else error)
            value = math.nan
        # Study.tell less its last step, a re-read of the told trial to return it (6 SQL statements on
        # PostgreSQL); Optuna-internal, so imported here: were it renamed, searches fail, not every run
        from optuna.study._tell import _tell_with_warning
        try:
            if math.isfinite(value):
                _tell_with_warning(study, trial, value)
            else:
                _tell_with_warning(study, trial, state=optuna.trial.TrialState.FAIL)
        except (RuntimeError, ValueError) as error:  # UpdateFinishedTrialError: another worker failed it
            log.warning("trial %d: not recorded, another worker marked it failed while it ran (%s)", trial.number,
                        str(error).splitlines()[0])
        return value

    def _report(self, study: optuna.Study, fixed: list[str], location: str, sweep_dir: Path, ran: int,
                storage_s: float) -> None:
        results = study_results(study, self.n_trials, shown(location))
        results["this_worker"] = {"sweep_dir": str(sweep_dir.absolute()), "trials_run": ran,
                                  "storage_ms_per_trial": round(1e3 * storage_s / max(ran, 1), 2)}
        if "best_trial" in results:
            # a plain run of the winner: the search config's choices without the search itself
            choices = self.config.hydra.runtime.choices
            plain = [f"{group}={choices[group]}" for group in ("model",) if choices.get(group)]
            plain += [o for o in fixed if "hparams_search" not in o.split("=", 1)[0]]
            results["best_overrides"] = plain + [f"{key}={value}" for key, value in results["best_params"].items()]
            log.info("best trial %d of study %r (job folder %s): validation score %.6g; rerun it with: python train.py %s",
                     results["best_trial"], study.study_name, results["best_job_folder"], results["best_value"],
                     " ".join(results["best_overrides"]))
        else:
            log.warning("no trial of the study completed; see the job folders' error.txt")
        launcher = str(self.config.hydra.launcher.get("_target_", ""))
        write_study_report(sweep_dir, results, parallel=results["workers"] > 1 or "joblib" in launcher.lower())
        log.info("study report in %s%s", sweep_dir / RESULTS, (
            f" (partial: {results['running']} trials running, {results['waiting']} waiting in other workers)"
            if results["partial"] else ""))
