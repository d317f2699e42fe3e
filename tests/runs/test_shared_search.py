"""A search many workers share: one study, its budget, its lost trials and its report, on the
real engines (Optuna's journal file, a throwaway PostgreSQL server, train.py processes)."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import optuna
import pytest
import yaml
from optuna.storages.journal import JournalFileBackend, JournalStorage
from optuna.trial import TrialState

from common.errors import InputError
from common.run_status import mark_finished, mark_running, run_status, this_process
from hydra_plugins.touchstone_optuna_sweeper.lost_trials import (
    JOB,
    Heartbeat,
    fail_lost_trials,
    give_back,
    record_job,
    requeuing,
    trial_job,
)
from hydra_plugins.touchstone_optuna_sweeper.study_budget import budget_left, counted, is_surplus, mark_surplus
from hydra_plugins.touchstone_optuna_sweeper.study_report import study_results, write_study_report
from hydra_plugins.touchstone_optuna_sweeper.study_storage import join_study, open_storage, shown, storage_location
from hydra_plugins.touchstone_optuna_sweeper.trial_seeded_sampler import TrialSeededTPESampler, trial_seed
from runs.throwaway_postgres import missing, throwaway_postgres

from tests import slurm_support

ROOT = Path(__file__).resolve().parents[2]
SPACE = {"x": optuna.distributions.FloatDistribution(0.0, 1.0), "k": optuna.distributions.IntDistribution(1, 9)}
SEARCH = ["hparams_search=resmlp_optuna", "hydra.sweeper.n_startup_trials=2", "scene.n_samples=120",
          "scene.grid_nodes=21", "scene.progress=false", "trainer.max_epochs=2"]


def journal_study(path: Path, name="s", seed=0, n_trials=4) -> optuna.Study:
    """A study as one worker opens it: journal storage, per-trial seeded TPE."""
    storage = open_storage(storage_location(str(path), name, path.parent), 60, retry)
    return join_study(storage, name, TrialSeededTPESampler(seed, 2), "maximize", {"n_trials": n_trials, "seed": seed})


retry = requeuing(max_retry=1)


def test_storage_setting_names_a_journal_file_or_a_url(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    sweep = tmp_path / "sweep"
    assert storage_location(None, None, sweep) == f"journal://{sweep}/study.log"  # the sweep's own study
    assert storage_location(None, "lr", sweep) == f"journal://{tmp_path}/multirun/studies/lr.log"  # shared by name
    assert storage_location("shared/s.log", "lr", sweep) == f"journal://{tmp_path}/shared/s.log"
    assert storage_location("journal:///nfs/s.log", "lr", sweep) == "journal:///nfs/s.log"
    url = "postgresql+psycopg2://u@db/optuna"
    assert storage_location(url, "lr", sweep) == url
    assert shown("postgresql+psycopg2://u:secret@db/optuna") == "postgresql+psycopg2://u:***@db/optuna"
    with pytest.raises(InputError, match="neither a journal file"):
        storage_location("studies/s.db", "lr", sweep)
    with pytest.raises(InputError, match="study_name"):
        storage_location(None, "../escape", sweep)


def test_a_trials_random_stream_is_its_own(tmp_path):
    """Two workers on one study, same seed: no two trials alike; one worker again: the same trials."""
    first, second = journal_study(tmp_path / "a.log"), journal_study(tmp_path / "a.log")
    trials = []
    for study in (first, second, first, second):  # interleaved, as two workers would
        trial = study.ask(SPACE)
        study.tell(trial, trial.params["x"])
        trials.append(trial.params)
    assert len({(t["x"], t["k"]) for t in trials}) == 4
    alone = journal_study(tmp_path / "b.log")
    again = []
    for _ in range(4):
        trial = alone.ask(SPACE)
        alone.tell(trial, trial.params["x"])
        again.append(trial.params)
    assert again == trials  # by trial number: the same stream and the same history


def test_a_trials_parameters_are_drawn_from_one_reading_of_the_study(tmp_path):
    """TPE with constant_liar reads the study again for every parameter (a round of SQL statements
    each on PostgreSQL); the sampler reads it once per trial, however many parameters, or not at
    all when handed the sweeper's reading, and draws exactly what TPE draws from that reading."""
    wide = {f"p{i}": optuna.distributions.FloatDistribution(0.0, 1.0) for i in range(6)}

    def modelled(name: str, space: dict) -> optuna.Study:  # past the 2 random start-up trials: TPE from here on
        study = journal_study(tmp_path / f"{name}.log")
        for _ in range(3):
            trial = study.ask(space)
            study.tell(trial, sum(trial.params.values()))
        return study

    readings = {}
    for name, space in (("narrow", SPACE), ("wide", wide)):
        study = modelled(name, space)
        calls, read = [], study._storage.get_all_trials
        study._storage.get_all_trials = lambda *a, **k: calls.append(1) or read(*a, **k)
        drawn = study.ask(space)
        readings[name] = len(calls)
    assert readings["wide"] == readings["narrow"]
    handed = modelled("handed", wide)
    handed.sampler.draw_next_from(handed.get_trials(deepcopy=False))  # as the sweeper hands its budget check's
    assert handed.ask(wide).params == drawn.params
    study.tell(drawn, state=TrialState.FAIL)  # out of TPE's sight: the next trial sees trial 3's history
    plain = optuna.load_study(study_name="s", storage=JournalStorage(JournalFileBackend(str(tmp_path / "wide.log"))),
                              sampler=optuna.samplers.TPESampler(seed=trial_seed(0, 3), n_startup_trials=2,
                                                                 constant_liar=True, multivariate=False))
    assert plain.ask(wide).params == drawn.params  # TPE's own draw, from trial 3's seed and history


def test_a_study_started_with_other_settings_is_refused(tmp_path):
    journal_study(tmp_path / "s.log", n_trials=4)
    with pytest.raises(InputError, match="n_trials differ"):
        journal_study(tmp_path / "s.log", n_trials=5)


def test_the_budget_is_the_studys_and_a_trial_beyond_it_is_surplus(tmp_path):
    one, two = journal_study(tmp_path / "s.log", n_trials=2), journal_study(tmp_path / "s.log", n_trials=2)
    a, b = one.ask(SPACE), two.ask(SPACE)
    assert budget_left(one.get_trials(), 2) is False  # two trials running: nothing left for either worker
    late = one.ask(SPACE)  # a worker that checked before the others asked
    assert is_surplus(late.number, one.get_trials(), 2) and not is_surplus(b.number, one.get_trials(), 2)
    mark_surplus(one, late)
    assert [t.number for t in counted(two.get_trials())] == [a.number, b.number]


def test_a_trial_whose_worker_is_gone_is_failed_and_requeued_once(tmp_path):
    study, other = journal_study(tmp_path / "s.log"), journal_study(tmp_path / "s.log")
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    lost, alive = study.ask(SPACE), study.ask(SPACE)
    lost.set_user_attr(JOB, {**this_process(), "pid": gone.pid, "process_start": "another process",
                             "folder": str(tmp_path / "0"), "trial": lost.number})
    record_job(alive, str(tmp_path / "1"))  # this process: alive
    assert fail_lost_trials(other, other.get_trials(), retry, heartbeats=False) == [lost.number]
    assert fail_lost_trials(study, study.get_trials(), retry, heartbeats=False) == []  # once only
    trials = study.get_trials()
    assert trials[lost.number].state == TrialState.FAIL and trials[alive.number].state == TrialState.RUNNING
    requeued = study.ask(SPACE)  # the next ask of any worker takes the re-queued copy
    assert requeued.number == 2 and requeued.params == lost.params
    assert trial_job(study.get_trials()[2]) is None  # the predecessor's record is not this trial's
    assert [t.number for t in counted(study.get_trials())] == [1, 2]  # the budget counts it once


def finished_job(folder: Path, overrides: list[str], val_r2: float) -> None:
    """A job folder as a finished regression run leaves it, no cost measured."""
    (folder / ".hydra").mkdir(parents=True)
    (folder / ".hydra" / "overrides.yaml").write_text(yaml.safe_dump(overrides))
    (folder / "metrics.json").write_text(json.dumps({"val": {"average": {"r2": val_r2}}}))
    mark_finished(folder, mark_running(folder, "0" * 16))


def test_a_report_written_while_trials_run_elsewhere_says_partial(tmp_path):
    study = journal_study(tmp_path / "s.log", n_trials=3)
    done, running = study.ask(SPACE), study.ask(SPACE)
    for trial in (done, running):
        record_job(trial, str(tmp_path / "sweep" / str(trial.number)))
    finished_job(tmp_path / "sweep" / "0", [f"x={done.params['x']}"], 0.5)
    study.tell(done, 0.5)
    results = study_results(study, 3, "journal:///s.log")
    assert results["partial"] and (results["complete"], results["running"]) == (1, 1)
    assert results["best_job_folder"] == str(tmp_path / "sweep" / "0")
    write_study_report(tmp_path / "report", results, parallel=False)
    written = yaml.safe_load((tmp_path / "report" / "optimization_results.yaml").read_text())
    assert written["partial"] and "1 complete, 0 failed, 1 running" in written["note"]
    assert (tmp_path / "report" / "pareto.md").read_text().splitlines()[2].startswith("> Partial report")
    assert not (tmp_path / "report" / "pareto.png").exists()  # no cost measured: no figure of empty panels
    assert [p.name for p in (tmp_path / "report" / "tensorboard").iterdir()] == ["trial_0000"]
    by_hand = subprocess.run([sys.executable, "-m", "hydra_plugins.touchstone_optuna_sweeper.study_report",
                              str(tmp_path / "s.log"), "s", str(tmp_path / "by_hand")], cwd=ROOT, capture_output=True,
                             text=True, timeout=120)
    assert by_hand.returncode == 0 and "1 of 3 trials complete, 1 running, 0 waiting (partial)" in by_hand.stdout
    assert yaml.safe_load((tmp_path / "by_hand" / "optimization_results.yaml").read_text())["trials"] == written["trials"]


def test_a_trial_whose_heartbeat_stops_is_failed_and_requeued(tmp_path):
    """RDB storages (here SQLite): a worker on another host cannot be checked by its pid, but its
    trial's heartbeat stops; after twice the interval any worker fails and re-queues the trial."""
    storage = open_storage(f"sqlite:///{tmp_path / 's.db'}", 1, retry)
    study = join_study(storage, "s", TrialSeededTPESampler(0, 2), "maximize", {})
    with pytest.warns(UserWarning, match="Heartbeat"):  # Optuna expects study.optimize(); the sweeper asks
        trial = study.ask(SPACE)
    with Heartbeat(storage, [trial], interval=1):
        assert fail_lost_trials(study, study.get_trials(), retry, heartbeats=True) == []  # beating
    # silent for longer than the grace period (2 intervals); SQLite's clock counts whole seconds, so
    # 2.5 s could read as 2 (not stale); 3.5 s reads as at least 3
    time.sleep(3.5)
    assert fail_lost_trials(study, study.get_trials(), retry, heartbeats=True) == [trial.number]
    trials = study.get_trials()
    assert trials[1].state == TrialState.WAITING and trials[1].params == trial.params


def test_a_stopped_worker_gives_its_trials_back(tmp_path):
    study = journal_study(tmp_path / "s.log")
    mine = study.ask(SPACE)
    give_back(study, [mine], retry)
    trials = study.get_trials()
    assert trials[0].state == TrialState.FAIL
    assert trials[1].state == TrialState.WAITING and trials[1].params == mine.params


def workers(tmp_path: Path, storage: str, n_trials: int, *overrides: str, env: dict | None = None,
            indices=(0, 1)) -> list:
    """`train.py -m` search workers on study `shared`, sweep<i>/ their folders, worker<i>.log their output."""
    env = {**(env or os.environ), "CI": "true", "OMP_NUM_THREADS": "1"}
    started = []
    for index in indices:
        out = open(tmp_path / f"worker{index}.log", "w")
        command = [sys.executable, "train.py", "-m", *SEARCH, *overrides, f"hydra.sweeper.n_trials={n_trials}",
                   "hydra.sweeper.study_name=shared", f"hydra.sweeper.storage='{storage}'",  # quoted: a URL holds '='
                   f"hydra.sweep.dir={tmp_path / f'sweep{index}'}"]
        started.append(subprocess.Popen(command, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT, env=env))
    return started


def finished(tmp_path: Path, processes: list, timeout: float = 600) -> None:
    for index, process in enumerate(processes):
        assert process.wait(timeout=timeout) == 0, (tmp_path / f"worker{index}.log").read_text()[-3000:]


def assert_one_study(study: optuna.Study, n_trials: int, tmp_path: Path) -> dict:
    """Every counted trial number once, all complete, none running; returns {pid: trials}."""
    trials = study.get_trials()
    assert not [t.number for t in trials if t.state in (TrialState.RUNNING, TrialState.WAITING)]
    kept = counted(trials)
    assert len(kept) == n_trials and len({t.number for t in kept}) == n_trials
    assert all(t.state == TrialState.COMPLETE for t in kept)
    by_worker = {}
    for trial in kept:
        job = trial_job(trial)
        assert run_status(job["folder"]).state == "finished" and Path(job["folder"]).name == str(trial.number)
        by_worker.setdefault(job["pid"], []).append(trial.number)
    reports = [yaml.safe_load((tmp_path / f"sweep{i}" / "optimization_results.yaml").read_text()) for i in range(2)]
    whole = [r for r in reports if not r["partial"]]
    assert whole, "the worker that ended last wrote the whole study"
    assert sorted(t["number"] for t in whole[0]["trials"] if t["state"] == "COMPLETE") == sorted(t.number for t in kept)
    assert whole[0]["best_value"] == max(t.value for t in kept)
    return by_worker


@pytest.mark.slow
def test_two_workers_share_a_study_on_the_journal_file(tmp_path):
    log = tmp_path / "study.log"
    finished(tmp_path, workers(tmp_path, str(log), n_trials=6))
    study = optuna.load_study(study_name="shared", storage=JournalStorage(JournalFileBackend(str(log))))
    assert len(assert_one_study(study, 6, tmp_path)) == 2  # both workers contributed
    late = workers(tmp_path, str(log), 6, indices=(2,))  # the study is done: nothing to run, the whole report
    assert late[0].wait(timeout=300) == 0
    report = yaml.safe_load((tmp_path / "sweep2" / "optimization_results.yaml").read_text())
    assert report["this_worker"]["trials_run"] == 0 and not report["partial"] and report["complete"] == 6


@pytest.mark.slow
@pytest.mark.skipif(missing() is not None, reason=missing() or "")
def test_two_workers_share_a_study_on_postgresql(tmp_path):
    with throwaway_postgres() as url:  # empty: the two workers create its tables together
        finished(tmp_path, workers(tmp_path, url, n_trials=6))
        study = optuna.load_study(study_name="shared", storage=url)
        assert len(assert_one_study(study, 6, tmp_path)) == 2
        optuna.storages.RDBStorage(url).engine.dispose()


@pytest.mark.slow
@pytest.mark.parametrize("kill, job_state", [(signal.SIGKILL, "interrupted"), (signal.SIGTERM, "failed")])
def test_a_worker_killed_mid_trial_leaves_its_trial_to_the_survivor(tmp_path, kill, job_state):
    """SIGKILL: the survivor finds the trial lost (its worker's pid is gone); SIGTERM (a scheduler's
    time limit): the stopped worker gives its trial back itself. Either way it runs again."""
    log = tmp_path / "study.log"
    victim, survivor = workers(tmp_path, str(log), n_trials=6)
    deadline = time.monotonic() + 300
    while not any(run_status(job).state == "running" for job in tmp_path.glob("sweep0/[0-9]*")):  # mid-trial
        assert time.monotonic() < deadline and victim.poll() is None
        time.sleep(0.05)
    victim.send_signal(kill)
    victim.wait()
    finished(tmp_path, [survivor])
    study = optuna.load_study(study_name="shared", storage=JournalStorage(JournalFileBackend(str(log))))
    trials = study.get_trials()
    lost = [t for t in trials if t.state == TrialState.FAIL]
    assert len(lost) == 1 and not [t for t in trials if t.state == TrialState.RUNNING]
    requeued = [t for t in trials if t.system_attrs.get("retry_history") == [lost[0].number]]
    assert len(requeued) == 1 and requeued[0].params == lost[0].params and requeued[0].state == TrialState.COMPLETE
    assert run_status(trial_job(lost[0])["folder"]).state == job_state
    found_lost = f"trial {lost[0].number}: its worker is gone" in (tmp_path / "worker1.log").read_text()
    assert found_lost == (kill == signal.SIGKILL)  # SIGTERM: given back before the survivor could find it
    kept = counted(trials)
    assert len(kept) == 6 and all(t.state == TrialState.COMPLETE for t in kept)
    report = yaml.safe_load((tmp_path / "sweep1" / "optimization_results.yaml").read_text())
    assert not report["partial"] and report["complete"] == 6
    assert [t["requeued_as"] for t in report["trials"] if t["number"] == lost[0].number] == [requeued[0].number]


@pytest.mark.slow
@pytest.mark.skipif(slurm_support.missing() is not None, reason=slurm_support.missing() or "")
def test_two_workers_send_their_trials_to_slurm_through_submitit(tmp_path):
    """Each worker's batch of two trials is one SLURM job array (hydra/launcher=slurm) on a one-node cluster."""
    log = tmp_path / "study.log"
    with slurm_support.throwaway_slurm() as env:
        finished(tmp_path, workers(tmp_path, str(log), 4, "hydra/launcher=slurm", "hydra.launcher.partition=debug",
                                   "hydra.launcher.cpus_per_task=1", "hydra.launcher.mem_gb=null",
                                   "hydra.launcher.timeout_min=10", "hydra.sweeper.n_jobs=2", env=env))
    study = optuna.load_study(study_name="shared", storage=JournalStorage(JournalFileBackend(str(log))))
    assert len(assert_one_study(study, 4, tmp_path)) == 2
    assert list(tmp_path.glob("sweep*/.submitit/*/*_submission.sh"))  # sbatch scripts: the jobs went through SLURM
