"""The sweep report carries each regression job's spread over repeated splits (spread.splits)."""
import json

import numpy as np
import yaml

from common.run_status import mark_finished, mark_running
from runs.report.pareto import job_table, markdown, summarise


def job(folder, overrides, val, test, splits=None):
    (folder / ".hydra").mkdir(parents=True)
    (folder / ".hydra" / "overrides.yaml").write_text(yaml.safe_dump(overrides))
    metrics = {"val": {"average": {"r2": val}}, "test": {"average": {"r2": test}}, "cost": {"fit_time_s": 1.0}}
    if splits is not None:
        values = np.asarray(splits)
        metrics["spread"] = {"test": {"average": {"r2": {"mean": values.mean(), "sd": values.std(ddof=1),
                                                         "n": len(values)}}}}
    (folder / "metrics.json").write_text(json.dumps(metrics))
    mark_finished(folder, mark_running(folder, "hash"))
    return folder


def test_each_configuration_shows_its_test_score_over_splits_beside_its_seeds(tmp_path):
    jobs = {"0": job(tmp_path / "0", ["model=linear", "seed=0"], 0.5, 0.6, [0.2, 0.6, 0.7]),
            "1": job(tmp_path / "1", ["model=linear", "seed=1"], 0.4, 0.5, [0.3, 0.5, 0.7]),
            "2": job(tmp_path / "2", ["model=trees", "seed=0"], 0.8, 0.8)}
    table = job_table(jobs)
    summary = summarise(table)
    linear = summary[summary["label"] == "model=linear"].iloc[0]
    assert np.isclose(linear["test_splits_mean"], np.mean([0.5, 0.5]))
    assert np.isclose(linear["test_splits_sd"], np.sqrt((np.std([0.2, 0.6, 0.7], ddof=1) ** 2 + 0.04) / 2))
    text = markdown(summary, table, parallel_warning=False)
    assert "test over splits" in text and "(3 splits)" in text
    assert "| model=trees | 1 | 0.8000 | 0.8000 | — |" in text   # a job without splits says so
