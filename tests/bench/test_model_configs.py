"""Same code, same seed, same numbers: every model config and study at seed 0 reproduces the scores
and ONNX predictions its committed record holds (results/model_configs.jsonl, 6 decimals). A change
meant to move no number (a refactor) passes this unchanged; one that moves numbers re-measures
them (`python bench/model_configs.py`) and says why in its commit."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RECORDS = ROOT / "results" / "model_configs.jsonl"
CASES = list(dict.fromkeys(json.loads(line)["name"] for line in RECORDS.read_text().splitlines())) if RECORDS.exists() else []


def test_every_case_has_a_record():
    assert len(CASES) >= 25, f"results/model_configs.jsonl holds {len(CASES)} cases: run bench/model_configs.py"


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_a_model_config_reproduces_its_record(case):
    done = subprocess.run([sys.executable, "bench/model_configs.py", "--check", "--only", case], cwd=ROOT,
                          env={**os.environ, "CI": "true"}, capture_output=True, text=True)
    assert done.returncode == 0, (done.stdout + done.stderr)[-3000:]
