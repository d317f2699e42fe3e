"""ERT skin benchmark (2 cores shared; OMP_NUM_THREADS=1): simulation frames/s with all 276
injections and every effect the scene lists, the time to build the full pattern's Jacobian, and
the ONNX reconstruction per frame.

    OMP_NUM_THREADS=1 .venv/bin/python bench/ert.py
    OMP_NUM_THREADS=1 .venv/bin/python bench/ert.py --scenes ert_internal --frames 2000 --parts simulation

Simulation: `random` presses through the scene's full effect list, the sensor's press solver
already built (cached per process; its one-off build, the resting sheet's dense inverse, is
reported apart); frames/s is the mean +- sd of --repeats whole generate() calls (presses,
effects, readings, the checked SensorTable), in wall-clock time and per second of the process's
CPU time (what one core all its own would give when other jobs share the machine; cache and
memory contention still count).
Jacobian: TikhonovReconstruction.jacobian() from scratch (the electrode potentials by one sparse
LU, the adjoint sensitivities, the four-terminal map), mean +- sd of --repeats, and the
sensitivity of the transfer matrix's 276 unique entries alone (models/ert/readings.py, what
Gauss-Newton uses).
Reconstruction: onnxruntime, batch 1, one thread, median of --calls calls, for Tikhonov,
Gauss-Newton (20 x 20 pixels) and GREIT (48 x 48); the fits use a small calibration (its size
does not change the graphs). Each row ends with the 1-minute load average before and after it:
beside other jobs every time grows with the share of a core the bench does not get.
"""
import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate
from omegaconf import OmegaConf

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.spread import format_mean_sd
from data.scenes import ert
from export.reconstruction_graphs import linear_image_to_onnx, tikhonov_to_onnx
from models.ert.gauss_newton import GaussNewtonReconstruction
from models.ert.greit import GreitReconstruction
from models.ert.readings import pixel_sensitivity
from models.tikhonov_reconstruction import TikhonovReconstruction


def scene_node(name: str, **overrides) -> dict:
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("config", overrides=[f"scene={name}", "seed=0"] + [f"scene.{k}={v}" for k, v in overrides.items()])
    return OmegaConf.to_container(cfg.scene, resolve=True)


def scene(name: str, **overrides):
    return instantiate(scene_node(name, **overrides))


def mean_sd(values) -> str:
    return format_mean_sd(values, ".2f" if np.mean(values) < 10 else ".0f", " +- ")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scenes", nargs="*", default=["ert_boundary", "ert_internal", "ert_physical_boundary",
                                                       "ert_physical_internal", "ert_minimal"])
    parser.add_argument("--frames", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--parts", nargs="*", default=["simulation", "jacobian", "onnx"],
                        choices=["simulation", "jacobian", "onnx"])
    args = parser.parse_args(argv)
    import onnxruntime as ort

    print(f"| scene | solver build (s, once) | frames/s ({args.frames} presses, mean +- sd of {args.repeats}) "
          "| Jacobian (s) | Jacobian via Z (s, 20 x 20) | ONNX per frame (ms, p50): Tikhonov | Gauss-Newton "
          "| GREIT (48 x 48) | load before / after |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in args.scenes:
        load_before = os.getloadavg()[0]
        cells = {"build": "", "fps": "", "jacobian": "", "via_z": "", "tikhonov": "", "gauss_newton": "", "greit": ""}
        s = scene(name, protocol="random", n_samples=args.frames)
        if "simulation" in args.parts:
            ert.sheet_solver.cache_clear()
            start = time.perf_counter()
            s.transfer_resistance(np.zeros((1, 1, 3)))        # the first press builds the dense inverse
            cells["build"] = f"{time.perf_counter() - start:.2f}"
            fps, per_cpu = [], []
            for _ in range(args.repeats):
                start, cpu = time.perf_counter(), time.process_time()
                s.generate()
                fps.append(args.frames / (time.perf_counter() - start))
                per_cpu.append(args.frames / (time.process_time() - cpu))
            cells["fps"] = f"{mean_sd(fps)} ({mean_sd(per_cpu)} per CPU-s)"
        geometry = s.geometry()
        if "jacobian" in args.parts:
            seconds = []
            for _ in range(args.repeats):
                model = TikhonovReconstruction(geometry=geometry, alpha_relative=(1e-3,))
                start = time.perf_counter()
                jacobian = model.jacobian()
                seconds.append(time.perf_counter() - start)
            cells["jacobian"] = f"{mean_sd(seconds)} ({jacobian.shape[0]} x {jacobian.shape[1]})"
            start = time.perf_counter()
            pixel_sensitivity(geometry, 20)
            cells["via_z"] = f"{time.perf_counter() - start:.2f}"
        if "onnx" in args.parts:
            model = TikhonovReconstruction(geometry=geometry, alpha_relative=(1e-3,))
            cal = scene(name, protocol="calibration", grid_points_per_side=6, n_force_levels=2).generate()
            model.fit(cal.channels, cal.targets)
            options = ort.SessionOptions()
            options.intra_op_num_threads = 1
            frame = cal.channels[:1].astype(np.float32)

            def onnx_ms(proto):
                session = ort.InferenceSession(proto.SerializeToString(), options, providers=["CPUExecutionProvider"])
                for _ in range(50):
                    session.run(["prediction"], {"voltages": frame})
                times = []
                for _ in range(args.calls):
                    start = time.perf_counter()
                    session.run(["prediction"], {"voltages": frame})
                    times.append(time.perf_counter() - start)
                return f"{1e3 * np.median(times):.3f}"

            gauss_newton = GaussNewtonReconstruction(geometry=geometry, lambdas_relative=(1e-3,)).fit(cal.channels, cal.targets)
            # the graph's size does not depend on how many presses GREIT trained on
            greit = GreitReconstruction(geometry=geometry, training_scene=scene_node(name), n_training_sensors=1,
                                        presses_per_sensor=50, desired_radius_mm=(20.0,),
                                        noise_weights=(1e-3,)).fit(cal.channels, cal.targets)
            cells.update(tikhonov=onnx_ms(tikhonov_to_onnx(model)), gauss_newton=onnx_ms(linear_image_to_onnx(gauss_newton)),
                         greit=onnx_ms(linear_image_to_onnx(greit)))
        print(f"| {name} | {' | '.join(cells.values())} | {load_before:.1f} / {os.getloadavg()[0]:.1f} |", flush=True)


if __name__ == "__main__":
    main()
