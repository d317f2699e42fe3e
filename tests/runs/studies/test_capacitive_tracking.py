"""The capacitive_tracking study end to end, tiny: a short simulated stream (and the same frames
as a user's CSV recording), ours beside the paper's tracker, every artefact written."""
import io
import json

import numpy as np
import pandas as pd
import pytest
from hydra.errors import InstantiationException
from PIL import Image

from common.errors import InputError
from data.readers.contact_streams import save_frames_csv
from export.run_export import export_run
from runs.run import run
from runs.studies.capacitive_tracking import load_stream

TINY = ["experiment=capacitive_tracking", "scene.sessions=[hold,cross]", "scene.session_s=1.0", "scene.gap_s=0.2",
        "scene.n_rest_frames=30", "study.force_repetitions=3", "study.animation.max_frames=4",
        "study.animation.n_panels=2"]


def test_simulated_stream_is_tracked_evaluated_and_animated(compose_config, tmp_path):
    cfg = compose_config(TINY)
    metrics = run(cfg, tmp_path)
    names = {p.name for p in tmp_path.iterdir()}
    assert {"metrics.json", "contacts.csv", "contacts_paper.csv", "contacts.gif", "contacts.png", "tensorboard"} <= names
    written = json.loads((tmp_path / "metrics.json").read_text())
    assert set(written["trackers"]) == {"ours", "paper"}
    ours, paper = (written["trackers"][name]["overall"] for name in ("ours", "paper"))
    # measured on this tiny stream (seed 0, a hold and a crossing): ours F1 0.868, the paper's 0.781
    assert ours["f1"] >= 0.85 and ours["precision"] >= 0.95 and paper["f1"] >= 0.75
    assert ours["f1"] > paper["f1"] and ours["recall"] > paper["recall"]
    for name in ("ours", "paper"):
        assert set(written["trackers"][name]["by_scenario"]) >= {"hold", "cross"}
        timing = written["trackers"][name]["timing"]
        assert timing["frames"] == written["stream"]["frames"] - 30 and timing["p99_us"] >= timing["p50_us"] > 0
    assert metrics["trackers"]["ours"]["overall"]["tp"] > 0
    force_model = written["force_model"]     # the pipeline's model, fitted on windows of the presses
    assert force_model["model"] == "ClassicRegressor" and force_model["test"]["force_n"]["r2"] > 0.95
    contacts = pd.read_csv(tmp_path / "contacts.csv")
    assert list(contacts.columns) == ["frame", "id", "x_mm", "y_mm", "cells", "mean_load", "peak_load", "force_n"]
    assert contacts.frame.min() >= 30 and contacts.force_n.notna().all()
    assert not contacts.duplicated(["frame", "id"]).any()
    with Image.open(tmp_path / "contacts.gif") as gif:
        assert gif.n_frames == 4
    assert any((tmp_path / "tensorboard").iterdir())


def test_a_recording_without_truth_writes_contacts_and_animation_only(compose_config, tmp_path):
    cfg = compose_config(TINY)
    stream, _ = load_stream(cfg, None)
    path = save_frames_csv(stream, tmp_path / "frames.csv")
    out = tmp_path / "run"
    cfg = compose_config(TINY + [f"study.recording.path={path}", "study.recording.n_rest_frames=30"])
    metrics = run(cfg, out)
    assert metrics["evaluation"] is None and "overall" not in metrics["trackers"]["ours"]
    assert {"contacts.csv", "contacts.gif", "contacts.png", "metrics.json"} <= {p.name for p in out.iterdir()}
    simulated = pd.read_csv(out / "contacts.csv")
    assert len(simulated) > 0 and np.isnan(simulated.force_n).all()   # no scene: no force model


@pytest.mark.parametrize("override, words", [
    ("study.recording.rows=5", "cells per frame"),          # grid does not match the data
    ("study.recording.n_rest_frames=5000", "rest frames"),  # fewer frames than the rest period
])
def test_bad_recordings_are_one_line_errors_and_write_nothing(compose_config, tmp_path, override, words):
    cfg = compose_config(TINY)
    stream, _ = load_stream(cfg, None)
    path = save_frames_csv(stream, tmp_path / "frames.csv")
    out = tmp_path / "run"
    cfg = compose_config(TINY + [f"study.recording.path={path}", "study.recording.n_rest_frames=30", override])
    with pytest.raises(InstantiationException) as error:  # train.py unwraps it: one line, exit 2
        run(cfg, out)
    cause = error.value.__cause__
    assert isinstance(cause, InputError) and words in str(cause) and "\n" not in str(cause)
    assert not out.exists() or not any(out.iterdir())


def test_a_saved_window_force_model_serves_the_tracker(compose_config, tmp_path):
    """A capacitive_force run on window channels exports a model the tracker reads force with;
    a model of other channels is a one-line error. The window run presses anywhere on a cell
    (press_offset_mm 3, as docs/capacitive.md's saved run): a line through nine cells fitted on
    centre presses alone learns the centre's pattern and reads an off-centre touch wrongly."""
    force_run = tmp_path / "force"
    run(compose_config(["experiment=capacitive_force", "hydra.mode=RUN", "model=linear_regression",
                        "scene.characterisation_channels=window", "scene.press_offset_mm=3", "scene.n_repetitions=3",
                        "extras=quick"]), force_run)
    export_run(force_run)
    out = tmp_path / "track"
    metrics = run(compose_config(TINY + [f"study.force_model={force_run}"]), out)
    assert metrics["force_model"]["loaded_from"].endswith("model.onnx")  # the exported model, not a pickle
    contacts = pd.read_csv(out / "contacts.csv")
    # touches of at most 3 N, two of them in one region while they cross
    assert contacts.force_n.notna().all() and contacts.force_n.between(-0.5, 6.0).all()
    cells_run = tmp_path / "cells"
    run(compose_config(["experiment=capacitive_force", "hydra.mode=RUN", "model=linear_regression",
                        "scene.n_repetitions=3", "extras=quick"]), cells_run)
    export_run(cells_run)
    with pytest.raises(InstantiationException, match="3x3 window"):
        run(compose_config(TINY + [f"study.force_model={cells_run}"]), tmp_path / "bad")


def test_standard_input_is_tracked_line_by_line(compose_config, tmp_path, monkeypatch, capsys):
    """`study.recording.path=-`: contacts are printed as the frames arrive; the files at the end
    are those of the same frames given as a file."""
    cfg = compose_config(TINY)
    stream, _ = load_stream(cfg, None)
    path = save_frames_csv(stream, tmp_path / "frames.csv")
    monkeypatch.setattr("sys.stdin", io.StringIO(path.read_text()))
    run(compose_config(TINY + ["study.recording.path=-", "study.recording.n_rest_frames=30"]), tmp_path / "live")
    printed = [line for line in capsys.readouterr().out.splitlines() if line and line[0].isdigit()]
    from_file = run(compose_config(TINY + [f"study.recording.path={path}", "study.recording.n_rest_frames=30"]),
                    tmp_path / "file")
    written = pd.read_csv(tmp_path / "file" / "contacts.csv")
    assert len(printed) == len(written) == from_file["trackers"]["ours"]["contacts_reported"] > 0
    assert [int(line.split(",")[1]) for line in printed] == written.id.tolist()
    assert pd.read_csv(tmp_path / "live" / "contacts.csv").equals(written)


def test_a_bad_line_on_standard_input_names_it(compose_config, tmp_path, monkeypatch):
    monkeypatch.setattr("sys.stdin", io.StringIO("1,2,3\n"))
    with pytest.raises(InstantiationException, match="stdin: line 1 has 3 cells, expected rows x cols = 36"):
        run(compose_config(TINY + ["study.recording.path=-"]), tmp_path / "bad")
