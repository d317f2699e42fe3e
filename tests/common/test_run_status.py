"""Run folders that cannot lie: status.json says running, finished or failed (interrupted when its
process is gone), a folder never mixes two runs, and the exported model carries its run's config
hash. The kill tests stop real train.py runs with SIGKILL at seeded random moments and check that
no folder reads as finished unless it is complete, and that every complete one (finished, or killed
after its last artefact moved in) loads and predicts what the uninterrupted run's model predicts."""
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import onnx
import pandas as pd
import pytest
from omegaconf import OmegaConf

from common.errors import InputError
from common.run_status import (
    ERROR_FILE,
    STATUS_FILE,
    config_hash,
    mark_failed,
    mark_finished,
    mark_running,
    prepare_folder,
    run_status,
)
from export.onnx_predictor import OnnxPredictor

ROOT = Path(__file__).resolve().parents[2]
# a whole run in a few seconds, most of it start-up: fit, report, figures, export, final moves
FAST = ["model=extra_trees", "model.n_estimators=10", "scene.n_samples=120", "scene.grid_nodes=21",
        "scene.progress=false"]


def train_command(*overrides) -> list[str]:
    return [sys.executable, str(ROOT / "train.py"), *overrides]


def train(*overrides, cwd):
    return subprocess.run(train_command(*overrides), capture_output=True, text=True, cwd=cwd, timeout=600,
                          env=dict(os.environ, CI="true"))


def snapshot(folder: Path) -> dict[str, bytes | None]:
    """Every path under `folder` with its content (None for a folder)."""
    return {str(p.relative_to(folder)): (p.read_bytes() if p.is_file() else None) for p in folder.rglob("*")}


@pytest.fixture(scope="module")
def whole_run(tmp_path_factory):
    """One uninterrupted run: the reference a killed run's folder is compared with. Returns its
    folder and how long it took (start-up to exit), which the kill moments are spread over."""
    folder = tmp_path_factory.mktemp("whole") / "run"
    start = time.perf_counter()
    result = train(*FAST, f"hydra.run.dir={folder}", cwd=folder.parent)
    assert result.returncode == 0, result.stderr[-2000:]
    return folder, time.perf_counter() - start


# -- the status record ------------------------------------------------------------------------

def test_a_run_records_running_then_finished_or_failed(tmp_path):
    running = mark_running(tmp_path / "a", "0123456789abcdef")
    assert running["pid"] == os.getpid() and running["config_hash"] == "0123456789abcdef"
    assert run_status(tmp_path / "a").state == "running"  # this process is alive
    mark_finished(tmp_path / "a", running)
    assert run_status(tmp_path / "a").state == "finished"
    running = mark_running(tmp_path / "b", "0123456789abcdef")
    mark_failed(tmp_path / "b", running, "scene.n_samples must be a positive integer, got -5")
    status = run_status(tmp_path / "b")
    assert (status.state, status.reason) == ("failed", "scene.n_samples must be a positive integer, got -5")
    assert (tmp_path / "b" / ERROR_FILE).read_text() == "scene.n_samples must be a positive integer, got -5\n"
    assert run_status(tmp_path / "nothing").state == "unknown"


def test_a_run_whose_process_is_gone_reads_interrupted(tmp_path):
    # a process that records `running` and ends without a last record, as kill -9 would leave it
    code = f"from common.run_status import mark_running; mark_running({str(tmp_path)!r}, 'x')"
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    status = run_status(tmp_path)
    assert status.state == "interrupted" and "killed" in status.reason


def test_a_reused_pid_is_not_mistaken_for_the_run(tmp_path):
    record = mark_running(tmp_path, "x")  # this live process's pid, but another process's start time
    assert record["process_start"] is not None  # Linux: /proc gives the start time
    (tmp_path / STATUS_FILE).write_text(json.dumps({**record, "process_start": record["process_start"] + "0"}))
    assert run_status(tmp_path).state == "interrupted"
    (tmp_path / STATUS_FILE).write_text(json.dumps({**record, "host": "elsewhere"}))
    status = run_status(tmp_path)
    assert status.state == "running" and "cannot check another host" in status.reason


# -- the config hash --------------------------------------------------------------------------

def test_the_config_hash_follows_the_configuration_not_its_formatting(compose_config, tmp_path):
    a, b = compose_config(FAST), compose_config(FAST + ["seed=1"])
    assert config_hash(a) != config_hash(b)
    assert config_hash(a) == config_hash(compose_config(list(reversed(FAST))))
    OmegaConf.save(a, tmp_path / "config.yaml")  # what Hydra writes to .hydra/, read back
    assert config_hash(OmegaConf.load(tmp_path / "config.yaml")) == config_hash(a)
    assert len(config_hash(a)) == 16


def test_a_runs_model_carries_the_hash_of_its_configuration(whole_run, tmp_path):
    folder, _ = whole_run
    expected = config_hash(OmegaConf.load(folder / ".hydra" / "config.yaml"))
    metadata = {p.key: p.value for p in onnx.load(folder / "model.onnx").metadata_props}
    assert metadata["config_hash"] == expected
    assert json.loads((folder / STATUS_FILE).read_text())["config_hash"] == expected
    # exporting the run folder again by hand computes the same hash from its .hydra/config.yaml
    again = tmp_path / "again"
    shutil.copytree(folder, again, ignore=shutil.ignore_patterns("model.onnx"))
    result = subprocess.run([sys.executable, "-m", "export.run_export", str(again)], capture_output=True, text=True,
                            cwd=ROOT)
    assert result.returncode == 0, result.stderr
    assert {p.key: p.value for p in onnx.load(again / "model.onnx").metadata_props}["config_hash"] == expected


# -- one folder, one run ----------------------------------------------------------------------

def earlier_run(folder: Path) -> Path:
    """A folder as an earlier finished run leaves it (the files that matter here)."""
    (folder / ".hydra").mkdir(parents=True)
    (folder / ".hydra" / "config.yaml").write_text("seed: 0\n")
    (folder / "metrics.json").write_text("{}\n")
    (folder / "model.onnx").write_bytes(b"earlier")
    mark_finished(folder, mark_running(folder, "earlier"))
    return folder


def test_a_folder_is_refused_or_cleared_only_when_safe(tmp_path, monkeypatch):
    prepare_folder(tmp_path / "new", "hydra.run.dir", overwrite=False)  # absent or empty: used as it is
    (tmp_path / "empty").mkdir()
    prepare_folder(tmp_path / "empty", "hydra.run.dir", overwrite=False)
    run = earlier_run(tmp_path / "run")
    with pytest.raises(InputError, match=r"already holds an earlier run \(finished\).*overwrite=true"):
        prepare_folder(run, "hydra.run.dir", overwrite=False)
    prepare_folder(run, "hydra.run.dir", overwrite=True)
    assert not run.exists()
    # overwrite=true never deletes what is not a run, holds the working directory, or still runs
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("my notes\n")
    with pytest.raises(InputError, match="no run or sweep"):
        prepare_folder(mine, "hydra.run.dir", overwrite=True)
    live = tmp_path / "live"
    mark_running(live, "x")
    with pytest.raises(InputError, match="still running"):
        prepare_folder(live, "hydra.run.dir", overwrite=True)
    here = earlier_run(tmp_path / "here")
    monkeypatch.chdir(here / ".hydra")
    with pytest.raises(InputError, match="holds the working directory"):
        prepare_folder(Path(".."), "hydra.run.dir", overwrite=True)
    assert (mine / "notes.txt").is_file() and (live / STATUS_FILE).is_file() and (here / "metrics.json").is_file()


def test_reusing_a_run_folder_is_refused_in_one_line_and_changes_nothing(whole_run, tmp_path):
    folder, _ = whole_run
    before = snapshot(folder)
    result = train(*FAST, "seed=1", f"hydra.run.dir={folder}", cwd=tmp_path)
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0 and "Traceback" not in result.stderr
    assert f"hydra.run.dir={folder} already holds an earlier run (finished)" in result.stderr
    assert snapshot(folder) == before


def test_reusing_a_sweep_folder_is_refused_in_one_line_and_changes_nothing(tmp_path):
    sweep = tmp_path / "sweep"
    earlier_run(sweep / "0")
    (sweep / "multirun.yaml").write_text("hydra: {}\n")
    before = snapshot(sweep)
    result = train("-m", "model=decision_tree,extra_trees", f"hydra.sweep.dir={sweep}", cwd=tmp_path)
    assert result.returncode == 2 and result.stderr.strip().count("\n") == 0, result.stderr
    assert f"hydra.sweep.dir={sweep} already holds an earlier sweep" in result.stderr
    assert snapshot(sweep) == before


def test_overwrite_clears_the_folder_and_a_failed_run_says_why(tmp_path):
    folder = earlier_run(tmp_path / "run")
    result = train("model=decision_tree", "scene.n_samples=-5", f"hydra.run.dir={folder}", "overwrite=true",
                   cwd=tmp_path)
    assert result.returncode == 2 and "scene.n_samples must be a positive integer, got -5" in result.stderr
    status = run_status(folder)
    assert (status.state, status.reason) == ("failed", "scene.n_samples must be a positive integer, got -5")
    assert (folder / ERROR_FILE).read_text().strip() == status.reason
    # nothing of the earlier run is left beside the new one
    assert not (folder / "metrics.json").exists() and not (folder / "model.onnx").exists()
    assert OmegaConf.load(folder / ".hydra" / "config.yaml").scene.n_samples == -5


def test_overwrite_clears_a_sweep_folder(tmp_path):
    sweep = tmp_path / "sweep"
    for job in ("0", "1"):
        earlier_run(sweep / job)
    (sweep / "multirun.yaml").write_text("hydra: {}\n")
    result = train("-m", "model=decision_tree", "scene.n_samples=-5", f"hydra.sweep.dir={sweep}", "overwrite=true",
                   cwd=tmp_path)
    assert result.returncode == 0, result.stderr[-2000:]  # a failed job does not end the sweep
    assert not (sweep / "1").exists()  # the earlier sweep's second job is gone
    assert run_status(sweep / "0").state == "failed" and not (sweep / "0" / "metrics.json").exists()
    jobs = pd.read_csv(sweep / "jobs.csv")
    assert jobs["status"].tolist() == ["failed"]


def test_the_sweep_report_counts_only_finished_jobs(tmp_path):
    from runs.report.pareto import collect_jobs
    metrics = {"val": {"average": {"r2": 0.9}}, "test": {"average": {"r2": 0.8}}, "cost": {"fit_time_s": 1.0}}
    for job in ("0", "1"):
        (tmp_path / job / ".hydra").mkdir(parents=True)
        (tmp_path / job / ".hydra" / "overrides.yaml").write_text(f"- seed={job}\n")
        (tmp_path / job / "metrics.json").write_text(json.dumps(metrics))
    mark_finished(tmp_path / "0", mark_running(tmp_path / "0", "x"))
    # job 1 was killed while its artefacts were moving in: metrics.json is there, its last record is not
    code = f"from common.run_status import mark_running; mark_running({str(tmp_path / '1')!r}, 'x')"
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    jobs = collect_jobs(tmp_path).set_index("job")
    assert jobs.loc["0", "status"] == "ok" and jobs.loc["0", "val_score"] == 0.9
    assert jobs.loc["1", "status"] == "interrupted" and "killed" in jobs.loc["1", "error"]
    assert np.isnan(jobs.loc["1", "val_score"])


# -- killed at random moments -----------------------------------------------------------------

def is_complete(folder: Path, reference: Path) -> bool:
    """Every file and folder the uninterrupted run has, none staged, metrics readable."""
    names = {p.name for p in folder.iterdir()} if folder.is_dir() else set()
    wanted = {p.name for p in reference.iterdir()}
    if not wanted <= names or ".staging" in names:
        return False
    try:
        json.loads((folder / "metrics.json").read_text())
    except ValueError:
        return False
    return True


def predictions(folder: Path) -> np.ndarray:
    """The folder's model.onnx, through onnxruntime, on the raw readings its predictions.csv holds."""
    predictor = OnnxPredictor(folder / "model.onnx")
    return predictor.predict_table(pd.read_csv(folder / "predictions.csv")).to_numpy()


def kill_run(folder: Path, moment: float | None) -> tuple[str, str]:
    """Start a run into `folder` and SIGKILL it (with anything it started) `moment` seconds later,
    or, for None, as soon as the export's model.onnx appears (the final moves follow at once).
    Returns the state the folder read just before the kill and the last phase its log names."""
    process = subprocess.Popen(train_command(*FAST, f"hydra.run.dir={folder}"), cwd=folder.parent,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
                               env=dict(os.environ, CI="true"))
    if moment is None:
        while process.poll() is None and not any((folder / where / "model.onnx").exists() for where in (".staging", ".")):
            time.sleep(0.001)
    else:
        time.sleep(moment)
    before = run_status(folder).state
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except ProcessLookupError:  # it had already ended
        pass
    process.wait(timeout=60)
    log = folder / "train.log"
    lines = log.read_text().strip().splitlines() if log.is_file() else []
    return before, lines[-1].split(" - ", 1)[-1][:60] if lines else "(no log)"


def kill_at_random_moments(whole_run, tmp_path, n_random: int, n_at_export: int, seed: int) -> list[dict]:
    reference, duration = whole_run
    rng = random.Random(seed)
    moments = [rng.uniform(0.0, duration) for _ in range(n_random)] + [None] * n_at_export
    killed = []
    for i, moment in enumerate(moments):
        folder = tmp_path / f"killed{i:02d}"
        before, last_line = kill_run(folder, moment)
        status = run_status(folder)
        killed.append({"folder": folder.name, "moment_s": moment, "before_kill": before, "state": status.state,
                       "complete": is_complete(folder, reference), "last_log_line": last_line})
    print(f"\nwhole run {duration:.1f} s; each killed run:")
    print(pd.DataFrame(killed).to_string(index=False))

    expected = predictions(reference)
    for row in killed:
        folder = tmp_path / row["folder"]
        # SIGKILL leaves no last record: a folder reads finished (the kill came after it), or
        # interrupted (its process gone), or unknown (killed before the run wrote its first record)
        # (never running: its process is gone, whatever the record says)
        assert row["state"] in ("finished", "interrupted", "unknown"), row
        assert row["state"] != "unknown" or not (folder / STATUS_FILE).exists(), row
        if row["state"] == "finished":
            assert row["complete"], row
        if row["complete"]:  # finished, or killed after its last artefact moved in: its model works
            np.testing.assert_array_equal(predictions(folder), expected)  # same config and seed, same model
    return killed


def test_the_completeness_check_can_fail(whole_run, tmp_path):
    reference, _ = whole_run
    assert is_complete(reference, reference) and run_status(reference).state == "finished"
    for missing in ("model.onnx", "metrics.json", "predictions.csv"):
        partial = tmp_path / missing
        shutil.copytree(reference, partial, ignore=shutil.ignore_patterns(missing))
        assert not is_complete(partial, reference), missing
    staged = tmp_path / "staged"
    shutil.copytree(reference, staged)
    (staged / ".staging").mkdir()
    assert not is_complete(staged, reference)


def test_a_run_killed_at_random_moments_never_reads_finished_unless_complete(whole_run, tmp_path):
    killed = kill_at_random_moments(whole_run, tmp_path, n_random=2, n_at_export=1, seed=0)
    assert len(killed) == 3


@pytest.mark.slow
def test_twenty_kills_at_random_moments_never_read_finished_unless_complete(whole_run, tmp_path):
    killed = kill_at_random_moments(whole_run, tmp_path, n_random=16, n_at_export=4, seed=1)
    states = {row["state"] for row in killed}
    assert "interrupted" in states, killed  # the kills did land inside runs


def test_a_run_sent_sigterm_reads_failed_with_the_reason(tmp_path):
    """SIGTERM (a scheduler's time limit) ends the run as failed, with that reason, not interrupted."""
    folder = tmp_path / "run"
    process = subprocess.Popen(train_command(*FAST, f"hydra.run.dir={folder}"), cwd=tmp_path,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=dict(os.environ, CI="true"))
    deadline = time.monotonic() + 120
    while run_status(folder).state != "running" and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    assert run_status(folder).state == "running"
    process.send_signal(signal.SIGTERM)
    assert process.wait(timeout=120) != 0
    status = run_status(folder)
    assert (status.state, status.reason) == ("failed", "terminated by SIGTERM (a scheduler's time limit or a kill)")
    assert not (folder / "metrics.json").exists() and not (folder / "model.onnx").exists()
