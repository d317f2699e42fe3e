"""Hints that help (issue 45): `train.py --help` is one page of the settings a user changes first,
read from the configs; a misspelt setting gets the closest valid names, never Hydra's advice to
append it with `+`; a wrong data path is one line before torch is imported, with no run folder."""
import os
import subprocess
import sys
from pathlib import Path

import pytest
from omegaconf import OmegaConf

from runs.help_page import first_clause, key_comment
from runs.setting_hints import closest_settings, setting_keys

ROOT = Path(__file__).resolve().parents[2]


def train(*arguments, cwd):
    return subprocess.run([sys.executable, str(ROOT / "train.py"), *arguments], capture_output=True, text=True,
                          cwd=cwd, timeout=300, env=dict(os.environ, CI="true"))


def test_help_is_one_page_of_the_settings_a_user_changes_first(tmp_path):
    """Before: Hydra's 435-line dump, without data.path or data.target_columns and no descriptions."""
    result = train("data=table", "--help", cwd=tmp_path)
    assert result.returncode == 0 and result.stderr == ""
    page = result.stdout.splitlines()
    assert len(page) <= 60
    text = result.stdout
    for key in ("data.path", "data.target_columns", "data.group_columns", "model", "seed", "threads", "trainer",
                "scene"):
        assert f"\n  {key} " in text, key
    # descriptions are the configs' own comments, and values what this command composes
    assert "what to learn: quantities (regression) or one class label (classification)" in text
    assert "[??? (needed)]" in text and "--help-all" in text
    assert not (tmp_path / "outputs").exists()


def test_help_piped_into_a_reader_that_stops_early_is_no_error(tmp_path):
    """`python train.py --help | head`: a reader that closes the pipe early (here at once) printed a
    BrokenPipe traceback and exit 1."""
    command = f"{sys.executable} {ROOT / 'train.py'} --help | true"
    result = subprocess.run(["bash", "-o", "pipefail", "-c", command], capture_output=True, text=True, cwd=tmp_path,
                            timeout=300)
    assert result.returncode == 0 and result.stderr == ""


def test_help_all_is_hydras_full_page(tmp_path):
    result = train("--help-all", cwd=tmp_path)
    assert result.returncode == 0 and "== Config ==" in result.stdout


@pytest.mark.parametrize("overrides, hint", [
    (["data=table", "data.target_colums=[x_mm]"], "error: data.target_colums is not a setting; did you mean "
                                                   "data.target_columns?"),
    (["scene.n_sampels=50"], "error: scene.n_sampels is not a setting; did you mean scene.n_samples?"),
    (["seeds=3"], "error: seeds is not a setting; did you mean seed?"),
])
def test_a_misspelt_setting_gets_the_closest_valid_one_not_the_append_hint(tmp_path, overrides, hint):
    result = train(*overrides, f"hydra.run.dir={tmp_path / 'run'}", cwd=tmp_path)
    assert result.returncode == 2 and result.stderr.strip() == hint
    assert "+" not in result.stderr and not (tmp_path / "run").exists()


def test_a_wrong_data_path_is_one_line_before_torch_with_no_run_folder(tmp_path):
    """Before: reported after the pre-flight had loaded scikit-learn (1.75 s CPU, 12 s wall at load 10),
    and after ~5 s of imports when it was left to the data module, leaving a failed run's folder."""
    probe = ("import sys; sys.argv[0] = 'train.py'; import train\n"
             "try:\n    train.preflight(sys.argv[1:])\nexcept SystemExit as stop:\n"
             "    print('exit', stop.code, 'torch' in sys.modules, 'sklearn' in sys.modules)\n")
    result = subprocess.run([sys.executable, "-c", probe, "data=table", f"data.path={tmp_path / 'rig.csv'}",
                             "data.target_columns=[force_n]", f"hydra.run.dir={tmp_path / 'run'}"],
                            capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert result.stdout.strip() == "exit 2 False False"   # neither torch nor scikit-learn loaded
    assert result.stderr.strip() == f"error: {tmp_path / 'rig.csv'}: no such file (data.path)"
    assert not (tmp_path / "run").exists()


def test_closest_settings_prefer_the_same_parent_and_ignore_hydras_own_keys():
    cfg = OmegaConf.create({"seed": 0, "data": {"target_columns": "???", "path": "???", "source": None},
                            "hydra": {"run": {"dir": "x"}}, "_target_": "x"})
    keys = setting_keys(cfg)
    assert "hydra.run.dir" not in keys and "_target_" not in keys and "data.path" in keys
    assert closest_settings("data.target_colums", keys) == ["data.target_columns"]
    assert closest_settings("seeds", keys) == ["seed"]
    assert closest_settings("sparkle", keys) == []


def test_a_key_comment_is_read_with_its_continuation_and_cut_at_its_first_clause(tmp_path):
    config = tmp_path / "c.yaml"
    config.write_text("a: 1   # first part\n       # second part\nb: 2\nc: 3   # " + "word " * 30 + "; more\n")
    assert key_comment(config, "x.a") == "first part second part"
    assert key_comment(config, "b") is None
    assert key_comment(config, "c").endswith("word") and "more" not in key_comment(config, "c")
    assert first_clause("size (e.g. " + "x" * 120 + "); rest") == "size (e.g. " + "x" * 120 + ")"
