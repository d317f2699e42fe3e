"""Trials whose worker died (SIGKILL, a pre-empted SLURM job, power loss) must not stay RUNNING
for ever: the study's budget counts them and its report would wait for them.

Every trial records its job folder and worker (host, pid, process start; common/run_status.py)
as the user attribute `job` (`trial_job`). Before each trial it asks for, a worker fails the
RUNNING trials of workers that are gone from its own host and re-queues each, up to
`lost_trial_retries` times (Optuna's RetryHeartbeatStaleTrialCallback: the same parameters as a
WAITING trial, which the next `ask` of any worker takes). That works on every storage and at
once. A worker on another host cannot be checked that way: RDB storages (PostgreSQL) also keep
Optuna's heartbeat, recorded for each running trial every `heartbeat_interval` seconds by
`Heartbeat`, and Optuna's `fail_stale_trials` fails and re-queues a trial silent for twice that
long. The journal file has no heartbeat: there a trial lost on another host waits until a worker
starts on that host. A worker being stopped (SIGTERM, Ctrl-C) gives its trials back itself.
"""
import threading
import warnings

import optuna
from optuna.trial import TrialState

from common.run_status import process_state, this_process

JOB = "job"  # user attribute: {folder, host, pid, process_start, trial}


def record_job(trial: optuna.Trial, folder: str) -> None:
    """Mark `trial` as run by this process, its results in the job folder `folder`."""
    trial.set_user_attr(JOB, {"folder": folder, **this_process(), "trial": trial.number})


def trial_job(trial: optuna.trial.FrozenTrial) -> dict | None:
    """The job record of `trial`, or None before its worker wrote one: a re-queued trial carries
    its predecessor's attributes (another trial number) until its new worker records itself."""
    job = trial.user_attrs.get(JOB)
    return job if job and job.get("trial") == trial.number else None


def lost_by_a_gone_worker(trial: optuna.trial.FrozenTrial) -> bool:
    """A RUNNING trial whose worker process is gone from this host."""
    job = trial_job(trial)
    return job is not None and process_state(job) == "gone"


def requeuing(max_retry: int):
    """The callback that re-queues a lost trial up to `max_retry` times (Optuna's)."""
    with warnings.catch_warnings():  # "experimental" since Optuna 2.8
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        return optuna.storages.RetryHeartbeatStaleTrialCallback(max_retry=max_retry)


def fail_and_requeue(study: optuna.Study, trial_number: int, retry) -> bool:
    """Fail a running trial and re-queue it through `retry`; False when it had finished already.
    Two workers may fail one trial together: the storage lets only one of them do it."""
    try:
        study.tell(trial_number, state=TrialState.FAIL)
    except (RuntimeError, ValueError):  # UpdateFinishedTrialError is a RuntimeError
        return False
    retry(study, next(t for t in study.get_trials(deepcopy=False) if t.number == trial_number))
    return True


def fail_lost_trials(study: optuna.Study, trials: list[optuna.trial.FrozenTrial], retry,
                     heartbeats: bool) -> list[int]:
    """Fail and re-queue the trials lost by gone workers among `trials` (the study's, as just read)
    and, with `heartbeats`, the trials whose heartbeat went stale; returns their numbers."""
    failed = [trial.number for trial in trials if trial.state == TrialState.RUNNING
              and lost_by_a_gone_worker(trial) and fail_and_requeue(study, trial.number, retry)]
    if heartbeats:
        with warnings.catch_warnings():  # fail_stale_trials is "experimental"
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            before = {t.number for t in study.get_trials(deepcopy=False, states=(TrialState.FAIL,))}
            optuna.storages.fail_stale_trials(study)
            failed += sorted({t.number for t in study.get_trials(deepcopy=False, states=(TrialState.FAIL,))} - before)
    return failed


def give_back(study: optuna.Study, trials: list[optuna.Trial], retry) -> None:
    """This worker is being stopped (Ctrl-C, SIGTERM from a scheduler's time limit or pre-emption)
    mid-batch: its trials are failed and re-queued now, for the other workers, rather than found
    lost later."""
    for trial in trials:
        fail_and_requeue(study, trial.number, retry)


def has_heartbeat(storage) -> bool:
    return isinstance(storage, optuna.storages.RDBStorage) and storage.get_heartbeat_interval() is not None


class Heartbeat:
    """While open, records a heartbeat for each of `trials` every `interval` seconds (RDB storages;
    nothing on the journal file). Optuna does this only inside study.optimize(); the sweeper asks
    and tells."""

    def __init__(self, storage, trials: list[optuna.Trial], interval: int) -> None:
        self.record = storage.record_heartbeat if has_heartbeat(storage) else None
        self.trials, self.interval, self.stop = trials, interval, threading.Event()
        self.thread = threading.Thread(target=self._beat, daemon=True)

    def _beat(self) -> None:
        while True:
            for trial in self.trials:
                self.record(trial._trial_id)
            if self.stop.wait(self.interval):
                return

    def __enter__(self):
        if self.record is not None:
            self.thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self.stop.set()
        if self.thread.is_alive():
            self.thread.join()
