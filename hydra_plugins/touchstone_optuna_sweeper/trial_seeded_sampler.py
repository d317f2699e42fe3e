"""TPE whose random stream belongs to the trial, not to the process.

Workers that share a study and seed one sampler each with the same `seed` propose the same
parameters (the first trials of two workers were identical). Here every trial gets its own TPE
sampler seeded from (seed, trial number): trial numbers are unique in a study, so no two trials
draw from one stream however many workers there are, and one worker with the same seed repeats
its search exactly. TPE still models every finished trial of the study; with `constant_liar`
it treats trials running in other workers as bad ones, so concurrent workers spread out
(Optuna's recommendation for distributed TPE; with one worker and n_jobs=1 nothing else runs,
so it changes nothing there).

A trial's parameters are all drawn from one reading of the study's trials: the one its worker
took just before asking for it (`draw_next_from`; the sweeper's budget check), or else one taken
when the trial starts. TPE with `constant_liar` reads the study again for every parameter, each
reading a round of SQL statements on an RDB storage (about 7 on PostgreSQL), though the
parameters of one trial are drawn milliseconds apart; the trial itself, missing from a reading
taken before it, is one TPE leaves out anyway.
"""
import copy

import numpy as np
import optuna


def trial_seed(seed: int, trial_number: int) -> int:
    """A well-mixed 32-bit seed for one trial (numpy's SeedSequence over both numbers)."""
    return int(np.random.SeedSequence([seed, trial_number]).generate_state(1)[0])


class StudyAtTrialStart:
    """The study as TPE sees it while it draws one trial's parameters: its trials as read once
    when the trial started, everything else the study's own."""

    def __init__(self, study: optuna.Study, trials: list[optuna.trial.FrozenTrial]) -> None:
        self._study, self._trials = study, trials

    def __getattr__(self, name: str):
        return getattr(self._study, name)

    def _get_trials(self, deepcopy: bool = True, states=None, use_cache: bool = False) -> list:
        trials = [t for t in self._trials if states is None or t.state in states]
        return copy.deepcopy(trials) if deepcopy else trials

    def get_trials(self, deepcopy: bool = True, states=None) -> list:
        return self._get_trials(deepcopy, states)


class TrialSeededTPESampler(optuna.samplers.BaseSampler):
    def __init__(self, seed: int, n_startup_trials: int) -> None:
        self.seed, self.n_startup_trials = seed, n_startup_trials
        self._trial_number, self._tpe, self._study, self._reading = None, None, None, None

    def draw_next_from(self, trials: list[optuna.trial.FrozenTrial]) -> None:
        """The study's trials as just read: the next trial to start draws its parameters from them."""
        self._reading = trials

    def before_trial(self, study, trial) -> None:
        self._start(study, trial.number)

    def _start(self, study, trial_number: int) -> None:
        reading, self._reading = self._reading, None
        self._trial_number = trial_number
        self._tpe = optuna.samplers.TPESampler(seed=trial_seed(self.seed, trial_number),
                                               n_startup_trials=self.n_startup_trials, constant_liar=True)
        self._study = StudyAtTrialStart(study, study.get_trials(deepcopy=False) if reading is None else reading)

    def infer_relative_search_space(self, study, trial) -> dict:
        return {}  # independent TPE: every parameter is drawn on its own

    def sample_relative(self, study, trial, search_space) -> dict:
        return {}

    def sample_independent(self, study, trial, param_name, param_distribution):
        if trial.number != self._trial_number:  # a trial started without before_trial (Optuna calls it in Trial())
            self._start(study, trial.number)
        return self._tpe.sample_independent(self._study, trial, param_name, param_distribution)
