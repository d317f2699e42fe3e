"""Hyper-parameter search from the command line: a TPE sweeper over Optuna as a Hydra plugin."""
import os
import subprocess
import sys
from pathlib import Path

import optuna
from optuna.storages.journal import JournalFileBackend, JournalStorage
import pandas as pd
import pytest
import yaml
from hydra.core.override_parser.overrides_parser import OverridesParser

from hydra_plugins.touchstone_optuna_sweeper.optuna_sweeper import split_space

ROOT = Path(__file__).resolve().parents[2]


def test_hydra_sweep_syntax_becomes_optuna_distributions():
    parser = OverridesParser.create()
    fixed, space = split_space(parser.parse_overrides([
        "model.lr=tag(log, interval(1e-4, 1e-2))", "model.noise_std=interval(0, 0.05)",
        "trainer.batch_size=choice(16, 32)", "model.depth=range(2, 8, 2)", "model.widths=choice([8,4],[16,8])",
        "seed=3"]))
    assert fixed == ["seed=3"]
    assert space["model.lr"] == optuna.distributions.FloatDistribution(1e-4, 1e-2, log=True)
    assert space["model.noise_std"] == optuna.distributions.FloatDistribution(0.0, 0.05)
    assert space["trainer.batch_size"] == optuna.distributions.CategoricalDistribution(["16", "32"])
    assert space["model.depth"] == optuna.distributions.IntDistribution(2, 6, step=2)  # range() excludes its end
    assert space["model.widths"].choices == ("[8,4]", "[16,8]")


def test_two_tiny_trials_from_the_command_line(tmp_path):
    sweep = tmp_path / "sweep"
    command = [sys.executable, "train.py", "-m", "hparams_search=resmlp_optuna", "hydra.sweeper.n_trials=2",
               "hydra.sweeper.n_startup_trials=1", "scene.n_samples=120", "scene.grid_nodes=21", "scene.progress=false",
               "trainer.max_epochs=3", f"hydra.sweep.dir={sweep}"]
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "CI": "true", "OMP_NUM_THREADS": "1"}, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "best trial" in done.stdout + done.stderr
    results = yaml.safe_load((sweep / "optimization_results.yaml").read_text())
    assert results["complete"] == 2 and len(results["trials"]) == 2
    values = [t["value"] for t in results["trials"]]
    assert results["best_value"] == max(values)  # maximised: the validation score
    assert results["best_overrides"][0] == "model=resmlp" and not any("hparams_search" in o for o in results["best_overrides"])
    lrs = [t["params"]["model.lr"] for t in results["trials"]]
    assert lrs[0] != lrs[1] and all(1e-4 <= lr <= 3e-3 for lr in lrs)
    study = optuna.load_study(study_name="search", storage=JournalStorage(JournalFileBackend(str(sweep / "study.log"))))
    assert [t.value for t in study.trials] == values
    jobs = pd.read_csv(sweep / "jobs.csv")  # the trials in the sweep's Pareto report
    assert sorted(jobs["job"].astype(str)) == ["0", "1"] and (jobs["status"] == "ok").all()
    assert sorted(jobs["val_score"]) == pytest.approx(sorted(values))
    assert "fit time" in (sweep / "pareto.md").read_text()
    assert results["best_job_folder"] == str(sweep / str(results["best_trial"])) and not results["partial"]
    board = sweep / "tensorboard"  # the study's HPARAMS view: one session per trial
    assert sorted(p.name for p in board.iterdir()) == ["trial_0000", "trial_0001"]


def test_a_storage_that_is_neither_journal_nor_url_is_one_line(tmp_path):
    done = subprocess.run([sys.executable, "train.py", "-m", "hparams_search=resmlp_optuna",
                           "hydra.sweeper.storage=studies/x.db", f"hydra.sweep.dir={tmp_path / 'sweep'}"],
                          cwd=ROOT, capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert done.stderr.startswith("error: hydra.sweeper.storage=studies/x.db: neither a journal file")
    assert not (tmp_path / "sweep").exists()


def test_trial_labels_are_short_but_never_merge_two_trials():
    from runs.report.pareto import _labels
    assert _labels([{"model.lr": "0.00064664227", "seed": "0"}, {"model.lr": "0.0012345678", "seed": "0"}]) == [
        "lr=0.0006466", "lr=0.001235"]
    close = _labels([{"model.lr": "0.00064664227"}, {"model.lr": "0.00064664991"}])
    assert len(set(close)) == 2  # rounded they would be one configuration
