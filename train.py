"""Train and evaluate one Touchstone model: `python train.py model=resmlp scene.n_samples=2000 seed=3`.

Thin on purpose: Hydra composes the config, models/run.py does the work, export/ writes the
ONNX file, and a user-input problem ends in one line on stderr and exit code 2 instead of a
traceback.
"""
import sys

import hydra
from hydra.core.hydra_config import HydraConfig
from hydra.types import RunMode
from omegaconf import DictConfig

from data.atomic import atomic_write_text
from data.errors import InputError
from export.costs import record_costs
from export.run_export import export_run
from models.run import run


@hydra.main(version_base="1.3", config_path="configs", config_name="config")
def main(cfg: DictConfig) -> float:
    output_dir = HydraConfig.get().runtime.output_dir
    try:
        metrics = run(cfg, output_dir)
        if cfg.export.enabled:
            export_run(output_dir, cfg.export.opset, cfg.export.file)
        if cfg.cost.measure_latency:
            metrics = record_costs(output_dir, cfg.export.file, cfg.cost.budget_s)
    except InputError as error:
        print(f"error: {error}", file=sys.stderr)
        if HydraConfig.get().mode == RunMode.MULTIRUN:  # one bad job must not end the sweep
            atomic_write_text(f"{output_dir}/error.txt", f"{error}\n")
            return float("nan")
        sys.exit(2)
    val = metrics["val"]  # the value a Hydra sweeper would optimise
    return val["average"]["r2"] if "average" in val else val["accuracy"]


if __name__ == "__main__":
    main()
