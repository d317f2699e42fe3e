"""The ERT study runs end to end on tiny settings: they write their artefacts and metrics."""
import json

import pytest

from common.errors import InputError
from runs.run import run
from runs.studies.ert_learned import run_learned

TINY = ["study.seeds=[0,1]", "study.calibration.grid_points_per_side=4", "scene.grid_points_per_side=4",
        "scene.grid_nodes=21", "study.reconstruction.pixels_per_side=8", "scene.injection=adjacent"]


@pytest.mark.parametrize("experiment, files", [
    ("ert_localisation", ["localisation_map.png", "localisation.csv"]),
    ("ert_force", ["force.png", "force.csv"]),
])
def test_single_point_studies_write_their_tables(compose_config, tmp_path, experiment, files):
    no_comparison = ["study.compare.kinds=[]"] if experiment == "ert_localisation" else []
    cfg = compose_config([f"experiment={experiment}", "scene=ert_boundary", *TINY, "study.n_blank=10", *no_comparison])
    metrics = run(cfg, tmp_path)
    for name in files + ["metrics.json"]:
        assert (tmp_path / name).exists(), name
    written = json.loads((tmp_path / "metrics.json").read_text())
    assert written["scene"] == "ert_boundary" and written["study"] == f"run_{experiment.removeprefix('ert_')}"
    assert "val" in metrics
    key = "localisation_mm" if experiment == "ert_localisation" else "force_error_n"
    # labelled mean and spread over the two simulated sensors, as written
    assert set(written[key]) == {"mean", "sd", "n"} and written[key]["n"] == 2
    assert 0.0 < written[key]["mean"] < 200.0 and written[key]["sd"] >= 0.0
    assert list((tmp_path / "tensorboard").glob("*/events.out.tfevents.*"))


TINY_GREIT = {"pixels_per_side": 12, "desired_radius_mm": [15.0], "noise_weights": [1e-2], "n_training_sensors": 2,
              "presses_per_sensor": 120}


def test_localisation_reports_the_best_kind_chosen_on_validation_sensors_beside_tikhonov(compose_config, tmp_path,
                                                                                         monkeypatch):
    from runs.studies import ert_tests

    studied = []
    original = ert_tests.single_point_study

    def spy(cfg, seeds, calibration, reconstruction, *args):
        studied.append((tuple(seeds), (reconstruction or {}).get("kind", "tikhonov")))
        return original(cfg, seeds, calibration, reconstruction, *args)

    monkeypatch.setattr(ert_tests, "single_point_study", spy)
    cfg = compose_config(["experiment=ert_localisation", "scene=ert_boundary", *TINY, "study.n_blank=10",
                          "study.compare.validation_seeds=[30000,30001]", "study.compare.kinds=[greit,greit_learned]",
                          *[f"+study.reconstruction.greit.{k}={v}" for k, v in TINY_GREIT.items()],
                          *[f"+study.reconstruction.greit_learned.{k}={v}" for k, v in TINY_GREIT.items()],
                          "+study.reconstruction.greit_learned.n_estimators=10"])
    metrics = run(cfg, tmp_path)
    best = metrics["best"]
    # the reference row is Tikhonov's, on the test sensors; both candidates are scored on the
    # validation sensors only, and only the chosen one on the test sensors
    assert metrics["kind"] == "tikhonov" and studied[0] == ((0, 1), "tikhonov")
    assert sorted(studied[1:3]) == [((30000, 30001), "greit"), ((30000, 30001), "greit_learned")]
    assert studied[3:] == [((0, 1), best["kind"])]
    scores = {kind: row["localisation_mm"]["mean"] for kind, row in best["validation"].items()}
    assert best["kind"] == min(scores, key=scores.get)
    assert all(row["per_frame_ms"]["n"] == 2 and row["seconds"] > 0 for row in best["validation"].values())
    assert best["localisation_mm"]["n"] == 2 and best["localisation_mm"]["mean"] > 0
    cost = best["reconstruction_cost"]
    assert cost["fit_s"]["mean"] > 0 and cost["per_frame_ms"]["mean"] > 0 and cost["comparison_wall_s"] > 0
    assert metrics["reconstruction_cost"]["per_frame_ms"]["mean"] > 0
    written = json.loads((tmp_path / "metrics.json").read_text())
    assert written["best"]["kind"] == best["kind"]


def test_localisation_refuses_validation_sensors_among_the_test_sensors(compose_config, tmp_path, monkeypatch):
    from runs.studies import ert_tests

    monkeypatch.setattr(ert_tests, "single_point_study", lambda *args: pytest.fail("a sensor was run"))
    cfg = compose_config(["experiment=ert_localisation", "scene=ert_boundary", *TINY])
    with pytest.raises(InputError, match="validation_seeds"):
        ert_tests.run_localisation(cfg, tmp_path, None, seeds=(0, 1),
                                   compare={"kinds": ["greit"], "validation_seeds": [1, 30000]})
    with pytest.raises(InputError, match="not learned or GREIT"):
        ert_tests.run_localisation(cfg, tmp_path, None, seeds=(0, 1),
                                   compare={"kinds": ["tikhonov"], "validation_seeds": [30000]})


def test_two_point_study_gives_a_p_value_per_location_and_distance(compose_config, tmp_path):
    cfg = compose_config(["experiment=ert_two_point", "scene=ert_internal", *TINY, "study.n_repeats=3",
                          "scene.distances_mm=[20,60]"])
    metrics = run(cfg, tmp_path)
    table = metrics["p_table_seed0"]
    assert set(table) == {1, 2, 3} and all(set(row) == {20.0, 60.0} for row in table.values())
    assert all(0.0 <= p <= 1.0 for row in table.values() for p in row.values())


@pytest.mark.slow
def test_injection_study_sweeps_pair_counts(compose_config, tmp_path):
    cfg = compose_config(["experiment=ert_injection", "scene=ert_internal", *TINY[:-1], "study.pair_counts=[12,24]"])
    metrics = run(cfg, tmp_path)
    assert (tmp_path / "injection_selection.png").exists() and (tmp_path / "accuracy_vs_time.csv").exists()
    assert {row["order"] for row in metrics["accuracy_vs_time"]} == {"optimal", "random", "adjacent"}


@pytest.mark.slow
def test_learned_study_compares_with_tikhonov_on_the_same_presses(compose_config, tmp_path):
    # test recording: 4 x 4 points x 3 forces = 48 presses; 5 training recordings of 48
    cfg = compose_config(["experiment=ert_learned", "scene=ert_boundary", *TINY, "study.n_train=240",
                          "study.models.extra_trees.n_estimators=5", "study.models.resmlp.max_epochs=2",
                          "model.candidates.resmlp.estimator.max_epochs=2", "model.candidates.random_forest.estimator.n_estimators=3",
                          "model.candidates.extra_trees.estimator.n_estimators=3"])
    metrics = run(cfg, tmp_path)
    assert set(metrics["summary"]) == {"tikhonov", "extra_trees", "resmlp", "blend"}
    assert set(metrics["summary"]["tikhonov"]["localisation_mm"]) == {"mean", "sd", "n"}
    assert metrics["features"] == "tikhonov_peak_window"
    table = (tmp_path / "learned_vs_tikhonov.csv").read_text()
    assert "coverage_force" in table and "loo_coverage_force" in table   # 5 calibration recordings, left out in turn
    assert metrics["n_conformal_recordings"] == 5



@pytest.mark.parametrize("option, message", [({"features": "pixels"}, "features must be one of"),
                                             ({"conformal_on": "test"}, "conformal_on must be"),
                                             ({"models": {"svm": {}}}, "unknown model 'svm'")])
def test_learned_study_bad_options_are_one_line_before_any_work(compose_config, tmp_path, option, message):
    cfg = compose_config(["experiment=ert_learned", "scene=ert_boundary"])
    with pytest.raises(InputError, match=message):
        run_learned(cfg, tmp_path, None, **option)
    assert not any(tmp_path.iterdir())
