"""Export a finished run to ONNX: `python -m export.run_export <run_dir> [--opset 18]`.

Reads the run's pipeline.npz (models/fitted_state.py: a format that cannot run code) and its
.hydra/config.yaml for the config hash, and writes one self-contained <run_dir>/model.onnx,
atomically: a finished run re-exported (another opset, a newer exporter). A run itself exports
its in-memory pipeline with `write_onnx` (export/pipelines.py; runs/run.py) when `export.enabled` is true.
"""
import argparse
import logging
import sys
import time
from pathlib import Path

from omegaconf import OmegaConf

from common.errors import InputError
from common.run_status import config_hash
from export.pipelines import write_onnx
from models.deployable import PIPELINE_FILE, load_pipeline

log = logging.getLogger(__name__)


def export_run(run_dir, opset: int = 18, file_name: str = "model.onnx", configuration_hash: str | None = None) -> Path:
    """`configuration_hash`: config_hash of the run's configuration (train.py passes it); by
    default computed from run_dir/.hydra/config.yaml, `unknown` in a folder without one."""
    run_dir = Path(run_dir)
    pipeline_path = run_dir / PIPELINE_FILE
    if not pipeline_path.is_file():
        raise InputError(f"{run_dir}: no {PIPELINE_FILE}; is this a Touchstone run folder?")
    start = time.perf_counter()
    pipeline = load_pipeline(pipeline_path)  # first: a file that is not a pipeline is the one line said
    if configuration_hash is None:
        config = run_dir / ".hydra" / "config.yaml"
        if config.is_file():
            configuration_hash = config_hash(OmegaConf.load(config))
        else:
            log.warning("%s: no .hydra/config.yaml, so the model's config_hash is 'unknown'", run_dir)
            configuration_hash = "unknown"
    return write_onnx(pipeline, run_dir / file_name, opset, configuration_hash, start)


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
