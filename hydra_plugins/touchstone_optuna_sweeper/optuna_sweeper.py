"""A TPE search as a Hydra sweeper: `python train.py -m hparams_search=<name>`.

The search space is declared with Hydra's own sweep syntax in `hydra.sweeper.params` (or on the
command line): `choice(a, b)` -> categorical, `range(lo, hi[, step])` -> integers lo..hi-1,
`interval(lo, hi)` -> a float, `tag(log, interval(lo, hi))` -> a float on a log scale; anything
else is a fixed override passed to every trial. Each trial is one ordinary job of the launcher
(folder <sweep dir>/<trial number>, its metrics.json in the sweep's Pareto report); the value
told to Optuna is what the task returns (train.py: the validation score; a failed trial is
marked failed, never scored). The study lives in <sweep dir>/study.db (SQLite; reload it with
optuna.load_study(study_name="search", storage="sqlite:///<sweep dir>/study.db")), and the
best configuration is logged and written to <sweep dir>/optimization_results.yaml.

TPE: Bergstra et al., "Algorithms for hyper-parameter optimization", NeurIPS 2011; Optuna:
Akiba et al., KDD 2019. Written over Optuna's ask-and-tell interface (study.ask(distributions),
study.tell(trial, value)), as the Hydra plugin docs describe a Sweeper: setup() gets the launcher,
sweep(arguments) launches batches of override lists.
"""
import logging
import math
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
                 study_name: str, storage: str | None, params: dict | None = None) -> None:
        self.n_trials, self.n_jobs, self.direction, self.seed = n_trials, n_jobs, direction, seed
        self.n_startup_trials, self.study_name, self.storage = n_startup_trials, study_name, storage
        self.params = dict(params or {})
        self.hydra_context: HydraContext | None = None
        self.config: DictConfig | None = None
        self.launcher = None

    def setup(self, *, hydra_context: HydraContext, task_function: TaskFunction, config: DictConfig) -> None:
        self.hydra_context, self.config = hydra_context, config
        self.launcher = Plugins.instance().instantiate_launcher(
            hydra_context=hydra_context, task_function=task_function, config=config)

    def sweep(self, arguments: list[str]) -> Any:
        if self.n_trials < 1 or self.n_jobs < 1:
            raise HydraException(f"hydra.sweeper.n_trials and n_jobs must be positive, got {self.n_trials}, {self.n_jobs}")
        sweep_dir = Path(self.config.hydra.sweep.dir)
        sweep_dir.mkdir(parents=True, exist_ok=True)
        OmegaConf.save(self.config, sweep_dir / "multirun.yaml")
        parser = OverridesParser.create(config_loader=self.hydra_context.config_loader)
        declared = [f"{key}={value}" for key, value in self.params.items()]
        fixed, space = split_space(parser.parse_overrides(declared + list(arguments)))
        if not space:
            raise HydraException("nothing to search: declare hydra.sweeper.params (choice/range/interval)")
        storage = self.storage or f"sqlite:///{(sweep_dir / 'study.db').resolve()}"
        sampler = optuna.samplers.TPESampler(seed=self.seed, n_startup_trials=self.n_startup_trials)
        optuna.logging.set_verbosity(optuna.logging.WARNING)
        study = optuna.create_study(study_name=self.study_name, storage=storage, sampler=sampler,
                                    direction=self.direction, load_if_exists=True)
        log.info("Optuna TPE search: %d trials over %s (study in %s)", self.n_trials, ", ".join(space), storage)
        returns, launched = [], 0
        while launched < self.n_trials:
            trials = [study.ask(space) for _ in range(min(self.n_jobs, self.n_trials - launched))]
            batch = [fixed + [f"{key}={trial.params[key]}" for key in space] for trial in trials]
            self.validate_batch_is_legal(batch)
            results = self.launcher.launch(batch, initial_job_idx=launched)
            for trial, result in zip(trials, results):
                try:
                    value = float(result.return_value)
                except Exception as error:  # noqa: BLE001 - any job failure is recorded as a failed trial
                    log.warning("trial %d failed: %s", trial.number, str(error).splitlines()[0] if str(error) else error)
                    value = math.nan
                if math.isfinite(value):
                    study.tell(trial, value)
                else:
                    study.tell(trial, state=optuna.trial.TrialState.FAIL)
                log.info("trial %d/%d: %s -> %s", trial.number + 1, self.n_trials, trial.params, value)
            launched += len(trials)
            returns.append(results)
        self._report(study, fixed, sweep_dir)
        return returns

    def _report(self, study: optuna.Study, fixed: list[str], sweep_dir: Path) -> None:
        complete = [t for t in study.trials if t.state == optuna.trial.TrialState.COMPLETE]
        results = {"study_name": study.study_name, "direction": self.direction, "n_trials": len(study.trials),
                   "n_complete": len(complete), "trials": [
                       {"number": t.number, "state": t.state.name, "value": t.value, "params": dict(t.params)}
                       for t in study.trials]}
        if complete:
            best = study.best_trial
            # a plain run of the winner: the search config's choices without the search itself
            choices = self.config.hydra.runtime.choices
            plain = [f"{group}={choices[group]}" for group in ("model",) if choices.get(group)]
            plain += [o for o in fixed if "hparams_search" not in o.split("=", 1)[0]]
            overrides = plain + [f"{key}={value}" for key, value in best.params.items()]
            results.update(best_trial=best.number, best_value=best.value, best_params=dict(best.params),
                           best_overrides=overrides)
            log.info("best trial %d (job folder %s): validation score %.6g; rerun it with: python train.py %s",
                     best.number, sweep_dir / str(best.number), best.value, " ".join(overrides))
        else:
            log.warning("no trial completed; see the job folders' error.txt")
        OmegaConf.save(OmegaConf.create(results), sweep_dir / "optimization_results.yaml")
