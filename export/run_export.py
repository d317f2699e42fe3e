"""Export a finished run to ONNX: `python -m export.run_export <run_dir> [--opset 18]`.

Reads the run's pipeline.pkl (and its .hydra/config.yaml for the config hash) and writes one
self-contained <run_dir>/model.onnx, atomically. train.py calls it at the end of every run
when `export.enabled` is true (the default).
"""
import argparse
import logging
import sys
import time
from pathlib import Path

from data.atomic import atomic_write
from data.errors import InputError
from export.pipelines import export_pipeline
from models.deployable import load_pipeline

log = logging.getLogger(__name__)


def export_run(run_dir, opset: int = 18, file_name: str = "model.onnx") -> Path:
    run_dir = Path(run_dir)
    pipeline_path = run_dir / "pipeline.pkl"
    if not pipeline_path.is_file():
        raise InputError(f"{run_dir}: no pipeline.pkl; is this a Touchstone run folder?")
    config = run_dir / ".hydra" / "config.yaml"
    start = time.perf_counter()
    model = export_pipeline(load_pipeline(pipeline_path), opset, config.read_text() if config.is_file() else "")
    path = atomic_write(run_dir / file_name, lambda tmp: tmp.write_bytes(model.SerializeToString()))
    log.info("exported %s (%.1f MB) in %.1f s", path, path.stat().st_size / 1e6, time.perf_counter() - start)
    return path


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run_dir")
    parser.add_argument("--opset", type=int, default=18)
    args = parser.parse_args(argv)
    try:
        print(export_run(args.run_dir, args.opset))
    except InputError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
