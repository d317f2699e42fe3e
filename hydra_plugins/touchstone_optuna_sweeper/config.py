"""The sweeper's config, registered as hydra/sweeper=optuna_tpe. Hydra imports every module under
the `hydra_plugins` namespace package at start-up (the repo root is on sys.path), which runs
this registration and finds the Sweeper subclass in optuna_sweeper.py."""
from dataclasses import dataclass, field
from typing import Any

from hydra.core.config_store import ConfigStore


@dataclass
class OptunaTPESweeperConf:
    _target_: str = "hydra_plugins.touchstone_optuna_sweeper.optuna_sweeper.OptunaTPESweeper"
    n_trials: int = 20              # the trial budget
    n_jobs: int = 1                 # trials asked for and launched together (the launcher may run them in parallel)
    direction: str = "maximize"     # train.py returns the validation score (R² or accuracy)
    seed: int = 0                   # TPE's own random stream
    n_startup_trials: int = 10      # random trials before TPE models the good and bad regions
    study_name: str = "search"
    storage: str | None = None   # null: sqlite:///<sweep dir>/study.db
    params: dict[str, Any] = field(default_factory=dict)  # key: choice(...) | range(...) | interval(...) | tag(log, interval(...))


ConfigStore.instance().store(group="hydra/sweeper", name="optuna_tpe", node=OptunaTPESweeperConf, provider="touchstone")
