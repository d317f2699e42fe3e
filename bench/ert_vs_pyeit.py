"""Touchstone's ERT reconstructions against pyEIT (JAC and GREIT) on the same frames.

    OMP_NUM_THREADS=1 .venv/bin/python bench/ert_vs_pyeit.py                 # both layouts, seeds 0-2
    OMP_NUM_THREADS=1 .venv/bin/python bench/ert_vs_pyeit.py --layouts ert_internal --seeds 0

pyEIT (package `pyeit`, 1.2.4, requirements-dev.txt; it adds shapely and trimesh and pins
nothing the project pins) is optional: without it the bench says so in one line and stops.

Frames: Touchstone's own scene (its 41 x 41 finite-volume grid, 5 mm, with every effect the
scene lists; the adc noise set per run), one simulated sensor per seed. Per seed and noise
level, a `calibration` recording (324 points x 2, 8.5, 15 N) is the validation set every
method chooses its hyper-parameters on, and a `single_point` recording (324 points x 4 and
10 N) is the test; nothing is chosen on the test.

pyEIT as a practitioner who knows it would use it (docs/examples eit_dynamic_jac.py and
eit_dynamic_greit.py): a distmesh mesh of the 200 x 200 mm sheet (scaled to [-1, 1]^2, h0 =
0.1 = 10 mm elements, coarser than the 5 mm forward grid), the electrodes then the four corners
as fixed points (so electrode k is node k and the corners stay square), all injection pairs as
`ex_mat`, the successive measurement with the `meas_current` parser (the scene reads on
current-carrying electrodes too), unnormalised difference imaging (jac_normalized=False: the
normalised form divides by near-zero reference voltages with internal electrodes). JAC:
kotre prior, p = 0.5, lambda 1e-3, 1e-2 or 1e-1; GREIT: n = 32, p = 0.5, s = 20, ratio = 0.1,
lambda 1e-2 (each GREIT lambda costs minutes: its H inverts the 6,624-square J J^T). JAC's
lambda and both read-outs (the arg-max element / pixel, or the thresholded centroid at 0.3, 0.5,
0.7, Touchstone's read-out) are chosen on the calibration recording like Touchstone's.
Touchstone's voltage is V_c - V_{c+1} for current into a; pyEIT's is v_{m+1} - v_m, so the
frames enter pyEIT negated (same channel order).

Touchstone: `tikhonov` (calibrated, models/ert/tikhonov.py), `gauss_newton`
(models/ert/gauss_newton.py: prior, lambda, threshold chosen), `greit` (models/ert/greit.py:
trained on presses of 4 other simulated sensors at the run's noise), `greit_learned`
(models/ert/learned_inverse.py: extra trees on GREIT's image, trained on the same other
sensors' presses), `learned_mlp` (models/ert/learned_readings_inverse.py: a linear map to the
patch loads and an MLP on the 5 x 5 patches around the most loaded one and the window's place,
trained on 80 other simulated sensors x 1,000 presses at the run's noise; its noise weight chosen
on calibration, then five nets at that weight averaged). The information floor these errors sit above:
bench/ert_localisation_floor.py.

Costs: set-up (pyEIT: mesh + Jacobian + H; Touchstone: the fit, which for GREIT includes
simulating its training presses), per-frame reconstruction (batch 1, numpy, median of 200).
Output: a markdown table on stdout and --json; appends one record per layout, noise level and
method to results/ert_vs_pyeit.jsonl (only when the comparison ran: not without pyEIT, not --table-from).
"""
import argparse
import json
import os
import sys
import time
from importlib import metadata
from pathlib import Path

import numpy as np
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate
from omegaconf import OmegaConf

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

# the module, not its `recording`: here a recording is a sensor's (calibration, single_point)
from common import result_records  # noqa: E402
from data.ert.protocol import injection_pairs  # noqa: E402
from models.ert.image_readout import thresholded_centroid  # noqa: E402
from models.ert.registry import RECONSTRUCTIONS  # noqa: E402
from runs.studies.ert_tests import fit_reconstruction  # noqa: E402

THRESHOLDS = (0.3, 0.5, 0.7)
PYEIT_LAMBDAS = (1e-3, 1e-2, 1e-1)
# What the errors and costs measure: the scene that draws the frames (and the other sensors the
# learned methods train on), Touchstone's reconstructions and the study that fits them; pyEIT's
# version is in each record's values.
MEASURED_CODE = ["data/scenes/ert.py", "data/scenes/ert_effects.py", "data/physics/sheet_conduction.py",
                 "data/physics/press_update.py", "data/physics/textile_contact.py", "models/ert/",
                 "data/ert/", "runs/studies/ert_tests.py", "configs/scene/"]


def scene_cfg(layout: str, noise_v: float, overrides=()):
    """The run's config for `layout` at adc noise `noise_v`; `overrides`: further Hydra overrides
    (small scenes for tests)."""
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("config", overrides=[f"scene={layout}", "seed=0", f"scene.effects.adc_noise.noise_v={noise_v}",
                                           *overrides])
    return cfg


def recording(cfg, seed, protocol, forces):
    node = OmegaConf.to_container(cfg.scene, resolve=True)
    node.update(seed=seed, protocol=protocol, n_force_levels=len(forces), force_range_n=[forces[0], forces[-1]])
    return instantiate(node).generate()


def load():
    return os.getloadavg()[0]


class PyEIT:
    """pyEIT's JAC and GREIT on the scene's electrodes; lambda and read-out chosen on validation."""

    def __init__(self, geometry, method):
        from pyeit.eit import greit, jac, protocol
        from pyeit.mesh import create, shape

        start = time.perf_counter()
        side = geometry["side_mm"]
        self.to_unit = lambda xy_mm: np.asarray(xy_mm) / (side / 2.0) - 1.0
        self.to_mm = lambda xy: (np.asarray(xy) + 1.0) * side / 2.0
        electrodes = self.to_unit(geometry["electrodes_mm"])
        corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
        on_corner = (np.abs(electrodes[:, None] - corners[None]).sum(-1) < 1e-9).any(axis=0)
        fixed = np.vstack([electrodes, corners[~on_corner]])
        mesh = create(n_el=len(electrodes), fd=lambda p: shape.rectangle0(p, p1=[-1, -1], p2=[1, 1]),
                      h0=0.1, p_fix=fixed, bbox=[[-1, -1], [1, 1]])
        ex_mat = injection_pairs(geometry["injection"], len(electrodes))
        proto = protocol.PyEITProtocol(ex_mat, *protocol.build_meas_pattern_std(ex_mat, len(electrodes), 1,
                                                                                   "meas_current"))
        self.method = method
        if method == "jac":
            self.solver = jac.JAC(mesh, proto)
            self.solver.setup(p=0.5, lamb=PYEIT_LAMBDAS[0], method="kotre", perm=1.0, jac_normalized=False)
            self.centres_mm = self.to_mm(mesh.elem_centers[:, :2])
            jacobian = self.solver.J
            self.maps = {lam: self.solver._compute_h(jacobian, 0.5, lam, "kotre") for lam in PYEIT_LAMBDAS}
        else:
            self.solver = greit.GREIT(mesh, proto)
            # one lambda, the documented 1e-2: GREIT's H inverts J J^T (6,624 square), minutes per lambda here
            self.solver.setup(p=0.5, lamb=1e-2, n=32, s=20.0, ratio=0.1, perm=1.0, jac_normalized=False)
            xg, yg, mask = self.solver.get_grid()
            self.centres_mm = self.to_mm(np.column_stack([xg.ravel(), yg.ravel()]))
            self.mask = mask.ravel()
            self.maps = {1e-2: self.solver.H}
        self.n_elements = mesh.n_elems
        self.setup_s = time.perf_counter() - start

    def images(self, frames, lam):
        ds = -(self.maps[lam] @ (-frames).T).T     # pyEIT's solve: ds = -H (v1 - v0); its v is -ours
        if self.method == "greit":
            ds = np.where(self.mask[None], 0.0, ds)
        return np.real(ds)

    def read(self, images, readout):
        if readout == "argmax":
            return self.centres_mm[images.argmax(axis=1)]
        return thresholded_centroid(images, self.centres_mm, readout)[0]

    def fit(self, frames, targets):
        usable = targets[:, 2] >= 2.0
        best = None
        for lam in self.maps:
            images = self.images(frames[usable], lam)
            for readout in ("argmax", *THRESHOLDS):
                error = np.hypot(*(self.read(images, readout) - targets[usable, :2]).T).mean()
                if best is None or error < best[0]:
                    best = (error, lam, readout)
        _, self.lam, self.readout = best
        return self

    def predict(self, frames):
        return self.read(self.images(frames, self.lam), self.readout)

    def chosen(self):
        return {"lambda": self.lam, "readout": self.readout}


class Touchstone:
    def __init__(self, kind, cfg, seed, params):
        self.kind, self.cfg, self.seed, self.params = kind, cfg, seed, params

    def fit(self, frames, targets):
        start = time.perf_counter()
        self.model = fit_reconstruction(self.kind, self.cfg, self.seed, frames, targets, self.params)
        self.setup_s = time.perf_counter() - start
        return self

    def predict(self, frames):
        return self.model.predict(frames)[:, :2]

    def chosen(self):
        return self.model.chosen_hyperparameters()


def per_frame_ms(method, frames, calls=200):
    times = []
    for k in range(calls):
        frame = frames[k % len(frames)][None]
        start = time.perf_counter()
        method.predict(frame)
        times.append(time.perf_counter() - start)
    return 1e3 * float(np.median(times))


def compare(args) -> list[dict]:
    """Every method on every layout, noise level and sensor: one row per force, printed as it comes."""
    rows = []
    print(f"load average at start: {load():.2f}", flush=True)
    for layout in args.layouts:
        geometry = instantiate(scene_cfg(layout, args.noise_v[0]).scene).geometry()
        peers = {name: PyEIT(geometry, name.removeprefix("pyeit_")) for name in ("pyeit_jac", "pyeit_greit")
                 if name in args.methods}
        for name, peer in peers.items():
            print(f"{layout} {name}: set-up {peer.setup_s:.2f} s ({peer.n_elements} elements), load {load():.2f}", flush=True)
        for noise_v in args.noise_v:
            cfg = scene_cfg(layout, noise_v)
            for seed in args.seeds:
                cal = recording(cfg, seed, "calibration", [2.0, 15.0])
                test = recording(cfg, seed, "single_point", sorted(args.forces))
                methods = dict(peers)
                for kind in RECONSTRUCTIONS:
                    if kind in args.methods:
                        methods[kind] = Touchstone(kind, cfg, seed, {"presses_per_sensor": args.greit_presses}
                                                   if kind.startswith("greit") else {})
                for name, method in methods.items():
                    method.fit(cal.channels, cal.targets)
                    error = np.hypot(*(method.predict(test.channels) - test.targets[:, :2]).T)
                    ms = per_frame_ms(method, test.channels)
                    for force in sorted(args.forces):
                        at = test.targets[:, 2] == force
                        rows.append({"layout": layout, "noise_v": noise_v, "seed": seed, "force_n": force,
                                     "method": name, "localisation_mm": float(error[at].mean()),
                                     "localisation_sd_mm": float(error[at].std()), "n_presses": int(at.sum()),
                                     "setup_s": float(method.setup_s), "ms_per_frame": ms, "load": load(),
                                     "chosen": method.chosen()})
                    print(f"{layout} noise {noise_v:g} seed {seed} {name}: "
                          + ", ".join(f"{r['force_n']:g} N {r['localisation_mm']:.2f} mm" for r in rows[-2:])
                          + f"; set-up {method.setup_s:.2f} s, {ms:.3f} ms/frame, {method.chosen()}, load {load():.2f}",
                          flush=True)
    return rows


def record_rows(record, rows, args):
    """One record per layout, noise level and method, with its rows per seed and force."""
    version = metadata.version("pyeit")
    for layout, noise_v, method in dict.fromkeys((r["layout"], r["noise_v"], r["method"]) for r in rows):
        part = [r for r in rows if (r["layout"], r["noise_v"], r["method"]) == (layout, noise_v, method)]
        record.add(f"{layout}/noise_{noise_v:g}/{method}",
                   {"layout": layout, "noise_v": noise_v, "method": method, "forces_n": sorted(args.forces),
                    "greit_presses": args.greit_presses if method.startswith("greit") else None,
                    "pyeit_version": version, "rows": part}, seeds=args.seeds)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--layouts", nargs="*", default=["ert_boundary", "ert_internal"])
    parser.add_argument("--seeds", nargs="*", type=int, default=[0, 1, 2])
    parser.add_argument("--forces", nargs=2, type=float, default=[4.0, 10.0])
    parser.add_argument("--noise-v", nargs="*", type=float, default=[2e-4, 1e-3])
    parser.add_argument("--greit-presses", type=int, default=600, help="training presses per simulated sensor")
    parser.add_argument("--methods", nargs="*", default=["pyeit_jac", "pyeit_greit", *RECONSTRUCTIONS])
    parser.add_argument("--json", type=Path, default=None)
    parser.add_argument("--table-from", nargs="*", type=Path, default=None,
                        help="print the table from the --json files of earlier runs (e.g. methods run apart) and stop")
    args = parser.parse_args(argv)
    if args.table_from:
        print_table([row for path in args.table_from for row in json.loads(path.read_text())])
        return 0
    try:
        import pyeit  # noqa: F401
    except ImportError:
        print("bench/ert_vs_pyeit.py: pyEIT is not installed (pip install pyeit==1.2.4, in requirements-dev.txt); skipped")
        return 0
    # Records only when the comparison ran, one per layout, noise and method: methods run apart
    # (as docs/ert.md's commands do) each keep their newest.
    with result_records.recording("ert_vs_pyeit", MEASURED_CODE) as record:
        rows = compare(args)
        record_rows(record, rows, args)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    print(f"load average at end: {load():.2f}\n")
    print_table(rows)
    return 0


def print_table(rows):
    """Mean +- sd over seeds per layout, noise, force and method; the ratio to the better pyEIT
    method's mean (each method's own per-seed means averaged)."""
    print("| layout | noise (V) | force (N) | method | localisation (mm, mean ± sd over seeds) | ÷ pyEIT's best "
          "| per-press sd (mm) | set-up (s) | per frame (ms) |")
    print("|---|---|---|---|---|---|---|---|---|")
    keys = sorted({(r["layout"], r["noise_v"], r["force_n"]) for r in rows})
    for layout, noise_v, force in keys:
        here = [r for r in rows if (r["layout"], r["noise_v"], r["force_n"]) == (layout, noise_v, force)]
        mean = {m: np.mean([r["localisation_mm"] for r in here if r["method"] == m]) for m in {r["method"] for r in here}}
        peers = [v for m, v in mean.items() if m.startswith("pyeit")]
        for method in dict.fromkeys(r["method"] for r in rows):
            part = [r for r in here if r["method"] == method]
            if not part:
                continue
            errors = np.array([r["localisation_mm"] for r in part])
            sd = errors.std(ddof=1) if len(errors) > 1 else 0.0
            ratio = f"{errors.mean() / min(peers):.2f}" if peers else "–"
            print(f"| {layout} | {noise_v:g} | {force:g} | {method} | {errors.mean():.2f} ± {sd:.2f} (n={len(errors)}) "
                  f"| {ratio} | {np.mean([r['localisation_sd_mm'] for r in part]):.2f} "
                  f"| {np.mean([r['setup_s'] for r in part]):.2f} | {np.mean([r['ms_per_frame'] for r in part]):.3f} |")


if __name__ == "__main__":
    sys.exit(main())
