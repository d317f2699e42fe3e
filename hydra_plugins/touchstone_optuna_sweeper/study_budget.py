"""The study's trial budget, shared by all its workers: `n_trials` trials in the study, whichever
worker runs them, not n_trials per worker.

Counted: every trial but two kinds. A trial failed because its worker died and re-queued
(lost_trials.py) counts through its re-queued copy, not twice. A trial that a worker asked for
after the others had used the budget up (two workers asking at the same moment both see one
trial left) is `surplus`: trial numbers are handed out by the storage in one order for all
workers, so the trial with more than n_trials counted trials before it is the one too many. Its
worker marks it failed and surplus without running it; every count and report leaves it out.
"""
import optuna
from optuna.trial import FrozenTrial, TrialState

SURPLUS = "surplus"  # user attribute of a trial asked for beyond the budget, never run


def retried_numbers(trials: list[FrozenTrial]) -> set[int]:
    """Trials that were re-queued: each re-queued copy lists its predecessors (Optuna's retry_history)."""
    return {number for t in trials for number in t.system_attrs.get("retry_history", ())}


def counted(trials: list[FrozenTrial]) -> list[FrozenTrial]:
    retried = retried_numbers(trials)
    return [t for t in trials if not t.user_attrs.get(SURPLUS) and t.number not in retried]


def budget_left(trials: list[FrozenTrial], n_trials: int) -> bool:
    """Whether a worker may ask for a trial: budget left, or a re-queued trial waiting to run."""
    trials = counted(trials)
    return len(trials) < n_trials or any(t.state == TrialState.WAITING for t in trials)


def is_surplus(trial_number: int, trials: list[FrozenTrial], n_trials: int) -> bool:
    return sum(t.number < trial_number for t in counted(trials)) >= n_trials


def may_be_surplus(trial_number: int, n_trials: int) -> bool:
    """Fewer trials than its number come before a trial: below n_trials it cannot be surplus
    (spares a storage query per trial)."""
    return trial_number >= n_trials


def mark_surplus(study: optuna.Study, trial: optuna.Trial) -> None:
    trial.set_user_attr(SURPLUS, True)
    study.tell(trial, state=TrialState.FAIL)


def progress(trials: list[FrozenTrial]) -> dict:
    """The study's counted trials by state."""
    trials = counted(trials)
    states = [t.state for t in trials]
    return {"complete": states.count(TrialState.COMPLETE), "failed": states.count(TrialState.FAIL),
            "running": states.count(TrialState.RUNNING), "waiting": states.count(TrialState.WAITING),
            "counted": len(trials)}
