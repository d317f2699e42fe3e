"""ERT skin benchmark (2 cores shared; OMP_NUM_THREADS=1): simulation frames/s with all 276
injections, the time to build the full pattern's Jacobian, and the ONNX reconstruction per frame.

    OMP_NUM_THREADS=1 .venv/bin/python bench/ert.py
    OMP_NUM_THREADS=1 .venv/bin/python bench/ert.py --scenes ert_internal --frames 2000

Simulation: `random` presses through the scene's full effect list (and ert_minimal's), the
sensor's solver already built (it is cached per process; its one-off build is reported apart).
Jacobian: TikhonovReconstruction.jacobian() from scratch (the dense baseline inverse, the adjoint
sensitivities, the four-terminal map). Reconstruction: onnxruntime, batch 1, one thread, median
of --calls calls; the fit uses a small calibration (its size does not change the graph).
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from data.scenes import ert
from export.reconstruction_graphs import tikhonov_to_onnx
from models.tikhonov_reconstruction import TikhonovReconstruction


def scene(name: str, **overrides):
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("config", overrides=[f"scene={name}", "seed=0"] + [f"scene.{k}={v}" for k, v in overrides.items()])
    return instantiate(cfg.scene)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scenes", nargs="*", default=["ert_boundary", "ert_internal", "ert_minimal"])
    parser.add_argument("--frames", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--calls", type=int, default=2000)
    args = parser.parse_args(argv)
    import onnxruntime as ort

    print("| scene | solver build (s, once) | frames/s (276 injections x 24) | Jacobian (s) | ONNX reconstruction per frame (ms, p50) |")
    print("|---|---|---|---|---|")
    for name in args.scenes:
        ert.sheet_solver.cache_clear()
        s = scene(name, protocol="random", n_samples=args.frames)
        start = time.perf_counter()
        s._solver(s.sensor())
        build_s = time.perf_counter() - start
        best = float("inf")
        for _ in range(args.repeats):
            start = time.perf_counter()
            s.generate()
            best = min(best, time.perf_counter() - start)
        fps = args.frames / best

        model = TikhonovReconstruction(geometry=s.geometry(), alpha_relative=(1e-3,))
        start = time.perf_counter()
        jacobian = model.jacobian()
        jacobian_s = time.perf_counter() - start
        cal = scene(name, protocol="calibration", grid_points_per_side=6, n_force_levels=2).generate()
        model.fit(cal.channels, cal.targets)
        options = ort.SessionOptions()
        options.intra_op_num_threads = 1
        session = ort.InferenceSession(tikhonov_to_onnx(model).SerializeToString(), options,
                                       providers=["CPUExecutionProvider"])
        frame = cal.channels[:1].astype(np.float32)
        for _ in range(50):
            session.run(["prediction"], {"voltages": frame})
        times = []
        for _ in range(args.calls):
            start = time.perf_counter()
            session.run(["prediction"], {"voltages": frame})
            times.append(time.perf_counter() - start)
        print(f"| {name} | {build_s:.2f} | {fps:.0f} | {jacobian_s:.2f} ({jacobian.shape[0]} x {jacobian.shape[1]}) "
              f"| {1e3 * np.median(times):.3f} |")


if __name__ == "__main__":
    main()
