"""The sweeper's config, registered as hydra/sweeper=optuna_tpe. Hydra imports every module under
the `hydra_plugins` namespace package at start-up (the repo root is on sys.path), which runs
this registration and finds the Sweeper subclass in optuna_sweeper.py."""
from dataclasses import dataclass, field
from typing import Any

from hydra.core.config_store import ConfigStore


@dataclass
class OptunaTPESweeperConf:
    _target_: str = "hydra_plugins.touchstone_optuna_sweeper.optuna_sweeper.OptunaTPESweeper"
    n_trials: int = 20              # the study's trial budget, shared by all its workers
    n_jobs: int = 1                 # trials this worker asks for and launches together (the launcher may run them in parallel)
    direction: str = "maximize"     # train.py returns the validation score (R² or accuracy)
    seed: int = 0                   # TPE's random streams: one per trial, from (seed, trial number)
    n_startup_trials: int = 10      # random trials before TPE models the good and bad regions
    study_name: str | None = None   # a name: the study every worker started with it joins; null: this sweep's own
    storage: str | None = None      # null: journal file multirun/studies/<study_name>.log (or <sweep dir>/study.log
                                    # when unnamed); journal:///path.log, path.log, or a SQLAlchemy URL (docs/cluster.md)
    heartbeat_interval: int = 60    # RDB storages: seconds between a running trial's heartbeats (stale after twice that)
    lost_trial_retries: int = 1     # a trial whose worker died runs again this many times (same parameters)
    params: dict[str, Any] = field(default_factory=dict)  # key: choice(...) | range(...) | interval(...) | tag(log, interval(...))


ConfigStore.instance().store(group="hydra/sweeper", name="optuna_tpe", node=OptunaTPESweeperConf, provider="touchstone")
