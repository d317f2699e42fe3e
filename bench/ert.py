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
sensitivity of the transfer matrix's 276 unique entries alone (data/ert/jacobian.py, what
Gauss-Newton uses).
Reconstruction: onnxruntime, batch 1, one thread, median of --calls calls, for Tikhonov,
Gauss-Newton (20 x 20 pixels) and GREIT (48 x 48); the fits use a small calibration (its size
does not change the graphs). Each row ends with the 1-minute load average before and after it:
beside other jobs every time grows with the share of a core the bench does not get.
Appends one record per scene and part to results/ert.jsonl.
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

from common.result_records import recording  # noqa: E402
from common.spread import format_mean_sd
from data.ert.forward import sheet_solver
from data.ert.jacobian import pixel_sensitivity
from export.reconstruction_graphs import linear_image_to_onnx, tikhonov_to_onnx
from models.ert.gauss_newton import GaussNewtonReconstruction
from models.ert.greit import GreitReconstruction
from models.ert.tikhonov import TikhonovReconstruction

# What the three parts time: the scene, its effects and its sheet solver (simulation), the
# sensitivities (jacobian), the reconstructions and their graphs (onnx), and the scenes' configs.
MEASURED_CODE = ["data/scenes/ert.py", "data/scenes/ert_effects.py", "data/physics/sheet_conduction.py",
                 "data/physics/press_update.py", "data/physics/textile_contact.py", "models/ert/",
                 "data/ert/", "export/reconstruction_graphs.py", "configs/scene/"]


def scene_node(name: str, **overrides) -> dict:
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("config", overrides=[f"scene={name}", "seed=0"] + [f"scene.{k}={v}" for k, v in overrides.items()])
    return OmegaConf.to_container(cfg.scene, resolve=True)


def scene(name: str, **overrides):
    return instantiate(scene_node(name, **overrides))


def magnitude_spec(mean: float) -> str:
    """Two decimals below 10, none from 10 up: seconds stay small, frames per second run to thousands."""
    return ".2f" if mean < 10 else ".0f"


def simulation(s, frames: int, repeats: int) -> dict:
    """The press solver's one-off build (s), then frames/s of whole generate() calls, wall and per CPU-s."""
    sheet_solver.cache_clear()
    start = time.perf_counter()
    s.transfer_resistance(np.zeros((1, 1, 3)))        # the first press builds the dense inverse
    build = time.perf_counter() - start
    fps, per_cpu = [], []
    for _ in range(repeats):
        start, cpu = time.perf_counter(), time.process_time()
        s.generate()
        fps.append(frames / (time.perf_counter() - start))
        per_cpu.append(frames / (time.process_time() - cpu))
    return {"frames": frames, "repeats": repeats, "solver_build_s": build, "frames_per_s": fps,
            "frames_per_cpu_s": per_cpu}


def jacobian_timing(geometry, repeats: int) -> dict:
    """Seconds of TikhonovReconstruction.jacobian() from scratch per repeat; of the 20 x 20 sensitivity via Z."""
    seconds = []
    for _ in range(repeats):
        model = TikhonovReconstruction(geometry=geometry, alpha_relative=(1e-3,))
        start = time.perf_counter()
        jacobian = model.jacobian()
        seconds.append(time.perf_counter() - start)
    start = time.perf_counter()
    pixel_sensitivity(geometry, 20)
    return {"repeats": repeats, "jacobian_s": seconds, "jacobian_shape": list(jacobian.shape),
            "via_z_s": time.perf_counter() - start, "via_z_pixels": 20}


def onnx_timing(name: str, geometry, calls: int) -> dict:
    """Median ms per frame (batch 1, one thread) of each reconstruction's ONNX graph."""
    import onnxruntime as ort

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
        for _ in range(calls):
            start = time.perf_counter()
            session.run(["prediction"], {"voltages": frame})
            times.append(time.perf_counter() - start)
        return 1e3 * float(np.median(times))

    gauss_newton = GaussNewtonReconstruction(geometry=geometry, lambdas_relative=(1e-3,)).fit(cal.channels, cal.targets)
    # the graph's size does not depend on how many presses GREIT trained on
    greit = GreitReconstruction(geometry=geometry, training_scene=scene_node(name), n_training_sensors=1,
                                presses_per_sensor=50, desired_radius_mm=(20.0,),
                                noise_weights=(1e-3,)).fit(cal.channels, cal.targets)
    p50 = {"tikhonov": onnx_ms(tikhonov_to_onnx(model)), "gauss_newton": onnx_ms(linear_image_to_onnx(gauss_newton)),
           "greit": onnx_ms(linear_image_to_onnx(greit))}
    return {"calls": calls, "batch": 1, "threads": 1, "greit_pixels": 48, "p50_ms": p50}


def row_cells(measured: dict) -> list[str]:
    """The table's cells for the parts measured ('' for a part left out)."""
    cells = {"build": "", "fps": "", "jacobian": "", "via_z": "", "tikhonov": "", "gauss_newton": "", "greit": ""}
    if "simulation" in measured:
        sim = measured["simulation"]
        cells.update(build=f"{sim['solver_build_s']:.2f}",
                     fps=f"{format_mean_sd(sim['frames_per_s'], magnitude_spec, ' +- ')} "
                         f"({format_mean_sd(sim['frames_per_cpu_s'], magnitude_spec, ' +- ')} per CPU-s)")
    if "jacobian" in measured:
        jac = measured["jacobian"]
        cells.update(jacobian=f"{format_mean_sd(jac['jacobian_s'], magnitude_spec, ' +- ')} "
                              f"({jac['jacobian_shape'][0]} x {jac['jacobian_shape'][1]})",
                     via_z=f"{jac['via_z_s']:.2f}")
    if "onnx" in measured:
        cells.update({method: f"{ms:.3f}" for method, ms in measured["onnx"]["p50_ms"].items()})
    return list(cells.values())


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
    print(f"| scene | solver build (s, once) | frames/s ({args.frames} presses, mean +- sd of {args.repeats}) "
          "| Jacobian (s) | Jacobian via Z (s, 20 x 20) | ONNX per frame (ms, p50): Tikhonov | Gauss-Newton "
          "| GREIT (48 x 48) | load before / after |")
    print("|---|---|---|---|---|---|---|---|---|")
    # One record per scene and part (e.g. ert_internal/simulation): --scenes and --parts runs add to the rest.
    with recording("ert", MEASURED_CODE) as record:
        for name in args.scenes:
            load_before = os.getloadavg()[0]
            s = scene(name, protocol="random", n_samples=args.frames)
            measured = {}
            if "simulation" in args.parts:
                measured["simulation"] = simulation(s, args.frames, args.repeats)
            geometry = s.geometry()
            if "jacobian" in args.parts:
                measured["jacobian"] = jacobian_timing(geometry, args.repeats)
            if "onnx" in args.parts:
                measured["onnx"] = onnx_timing(name, geometry, args.calls)
            load_after = os.getloadavg()[0]
            print(f"| {name} | {' | '.join(row_cells(measured))} | {load_before:.1f} / {load_after:.1f} |", flush=True)
            for part, values in measured.items():
                record.add(f"{name}/{part}", {"scene": name, **values, "load_before": load_before,
                                              "load_after": load_after}, seeds=[0])


if __name__ == "__main__":
    main()
