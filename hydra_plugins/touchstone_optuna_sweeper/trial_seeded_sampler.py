"""TPE whose random stream belongs to the trial, not to the process.

Workers that share a study and seed one sampler each with the same `seed` propose the same
parameters (the first trials of two workers were identical). Here every trial gets its own TPE
sampler seeded from (seed, trial number): trial numbers are unique in a study, so no two trials
draw from one stream however many workers there are, and one worker with the same seed repeats
its search exactly. TPE still models every finished trial of the study; with `constant_liar`
it treats trials running in other workers as bad ones, so concurrent workers spread out
(Optuna's recommendation for distributed TPE; with one worker and n_jobs=1 nothing else runs,
so it changes nothing there).
"""
import numpy as np
import optuna


def trial_seed(seed: int, trial_number: int) -> int:
    """A well-mixed 32-bit seed for one trial (numpy's SeedSequence over both numbers)."""
    return int(np.random.SeedSequence([seed, trial_number]).generate_state(1)[0])


class TrialSeededTPESampler(optuna.samplers.BaseSampler):
    def __init__(self, seed: int, n_startup_trials: int) -> None:
        self.seed, self.n_startup_trials = seed, n_startup_trials
        self._trial_number, self._tpe = None, None

    def _sampler_of(self, trial_number: int) -> optuna.samplers.TPESampler:
        if trial_number != self._trial_number:  # a trial's parameters are drawn one after another
            self._trial_number = trial_number
            self._tpe = optuna.samplers.TPESampler(seed=trial_seed(self.seed, trial_number),
                                                   n_startup_trials=self.n_startup_trials, constant_liar=True)
        return self._tpe

    def infer_relative_search_space(self, study, trial) -> dict:
        return {}  # independent TPE: every parameter is drawn on its own

    def sample_relative(self, study, trial, search_space) -> dict:
        return {}

    def sample_independent(self, study, trial, param_name, param_distribution):
        return self._sampler_of(trial.number).sample_independent(study, trial, param_name, param_distribution)
