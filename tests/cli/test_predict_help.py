"""predict.py --help answers without the heavy imports (issue 45: it took 7 s): without a model it
imports neither numpy, pandas nor onnxruntime; with model= only what reading the model needs
(not scikit-learn, torch or the recording readers)."""
import subprocess
import sys
from pathlib import Path

from tests.predict_support import regression_model, save

ROOT = Path(__file__).resolve().parents[2]
PROBE = """
import runpy, sys
main = runpy.run_path("predict.py", run_name="predict_script")["main"]
code = main(sys.argv[1:])
heavy = sorted(m for m in ("numpy", "pandas", "onnxruntime", "sklearn", "torch", "data.readers.recording_reader")
               if m in sys.modules)
print("HEAVY=" + ",".join(heavy))
sys.exit(code)
"""


def imported(*args) -> tuple[str, list[str]]:
    done = subprocess.run([sys.executable, "-c", PROBE, *map(str, args)], capture_output=True, text=True,
                          timeout=120, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    line = [line for line in done.stdout.splitlines() if line.startswith("HEAVY=")][0]
    return done.stdout, [m for m in line.removeprefix("HEAVY=").split(",") if m]


def test_help_alone_imports_nothing_heavy():
    out, heavy = imported("--help")
    assert "usage: python predict.py" in out and heavy == []


def test_help_with_a_model_reads_it_without_training_code(tmp_path):
    out, heavy = imported("--help", f"model={save(regression_model(), tmp_path / 'reg.onnx')}")
    assert "channels (2, in this order)" in out
    assert "sklearn" not in heavy and "torch" not in heavy and "data.readers.recording_reader" not in heavy
