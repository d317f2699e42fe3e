"""The information floor of ERT press localisation in Touchstone's scene: a Cramer-Rao bound on
(x, y) per test press, from the scene's own forward model and the frame's noise.

    OMP_NUM_THREADS=1 .venv/bin/python bench/ert_localisation_floor.py --json floor.json

Why: the learned inverse stops near 3.5 mm at 10 N and pyEIT's best near 4.2 mm. If no unbiased
estimator can go much lower on these frames, the limit is the information in the frames, not the
model. For each layout, sensor seed (0-2) and adc noise level, at the 324 `single_point` test
presses at 4 and 10 N (the bench's test recording, bench/ert_vs_pyeit.py):

- the mean frame mu(x, y, F) is the scene's deterministic chain (ERTScene.transfer_resistance with
  the random press effect, hysteresis, left out), in the 276 unique transfer resistances dz
  (data/ert/readings.py: channels = K dz; u = K^T v is sufficient, so nothing is lost);
  d mu / d(x, y, F) by central differences (`--step-mm`, force step `--step-relative`);
- the frame's noise, each term read off the effect that makes it (data/scenes/ert_effects.py):
  adc noise on the frame and on the recording's unloaded frame (2 sigma^2 per channel; the
  24-bit quantisation, 1.2 uV, is left out), baseline drift at press k of the recording
  ((k + 1) f^2 / 50 on each patch's relative conductance, through the unloaded sensor's patch
  Jacobian), and hysteresis, which multiplies a press's load by (1 + h): the same frame as a
  press of force (1 + h) F, so with the force unknown it costs the position nothing;
- the force is a nuisance (estimated jointly); the bound is the inverse of the (x, y) Fisher
  information left once the nuisances are estimated (a Schur complement), plus a prior of a
  uniform spread over one patch (sd 20 / sqrt(12) mm): which patch is pressed is never in doubt
  here, and without it a press that moves no patch share above the scene's 1e-3 cut-off (edge
  presses near a patch border) would have an infinite bound. Presses whose frame tells less
  than that prior along one axis are counted as "uninformed"; the optimistic reading takes
  such an axis as known exactly (no estimator does better than that). `unknown_sensitivity` also treats the log sensitivity of every patch the
  press loads as unknown, with the scene's lognormal spread as a prior (a hybrid bound): a
  reconstruction of an unseen sensor does not know them. The sensor's other spread (base
  resistance, electrode positions) is left known, so every bound here is still optimistic.

Reported per press: E|e| for e ~ N(0, C) (C the bound on the (x, y) covariance), the same
statistic as the bench's mean localisation error, averaged over presses and then over the
sensors. A bound is local: a biased estimator (one that knows presses lie on the sheet) can
beat it where the information is poor, and at low signal no estimator reaches it.

Check (`--check-sessions`): the same presses re-simulated in independent sessions with every
effect but hysteresis; the whitened residual's chi^2 per press should average the number of
transfer resistances (276) if the noise model above is the scene's.

Appends one record per layout (the table's cells per sensor, and the check) to
results/ert_localisation_floor.jsonl.
"""
import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402
from common.spread import format_mean_sd  # noqa: E402
from data.ert.patch_loads import patch_loads_n  # noqa: E402
from data.ert.readings import transfer_basis, unique_transfer_entries  # noqa: E402
from data.scenes.ert import ERTScene  # noqa: E402

RANDOM_PRESS_EFFECTS = ("hysteresis", "viscoelastic_hysteresis")
# reading effects, left out of the mean frame; the noise model has adc noise and baseline drift only
# (a scene with electrode_contact_impedance would show its drift in the chi^2 check)
READING = ("electrode_contact_impedance", "baseline_drift", "adc_noise")
BOUNDS = ("adc", "adc_drift", "unknown_sensitivity")
# What the bound is computed from: the scene's forward model and effects (and their configs), the
# transfer-resistance basis, and this file, where the Fisher information itself is worked out.
MEASURED_CODE = ["data/scenes/ert.py", "data/scenes/ert_effects.py", "data/physics/sheet_conduction.py",
                 "data/physics/press_update.py", "data/physics/textile_contact.py", "data/ert/",
                 "configs/scene/", "bench/ert_localisation_floor.py"]


def scene_node(layout: str) -> dict:
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("config", overrides=[f"scene={layout}", "seed=0"])
    node = OmegaConf.to_container(cfg.scene, resolve=True)
    node.pop("_target_")
    node.pop("_convert_", None)
    return node


def recording_contacts(scene: ERTScene, forces) -> np.ndarray:
    """(n, 1, 3) the `single_point` recording's presses in its order (each point at each force)."""
    points = scene.grid_points_mm()
    return np.column_stack([np.repeat(points, len(forces), axis=0), np.tile(forces, len(points))])[:, None, :]


class Frames:
    """The sensor's mean frame in unique transfer resistances (changes from unloaded)."""

    def __init__(self, scene: ERTScene):
        self.scene, self.sensor = scene, scene.sensor()
        entries = unique_transfer_entries(scene.n_electrodes)
        self.i, self.j = entries[:, 0], entries[:, 1]
        self.z0 = self._z(np.zeros((1, 1, 3)), self.sensor)

    def _z(self, contacts, sensor):
        return self.scene.transfer_resistance(contacts, sensor)[:, self.i, self.j]

    def __call__(self, contacts, sensor=None):
        return self._z(contacts, self.sensor if sensor is None else sensor) - self.z0


def derivatives(frames: Frames, contacts, step_mm, step_relative):
    """(n, n_z, 3) d dz / d (x, y, F) by central differences."""
    columns = []
    for axis, step in ((0, step_mm), (1, step_mm), (2, None)):
        h = np.full((len(contacts), 1, 1), step) if step is not None else step_relative * contacts[:, :, 2:3]
        up, down = contacts.copy(), contacts.copy()
        up[:, :, axis:axis + 1] += h
        down[:, :, axis:axis + 1] -= h
        columns.append((frames(up) - frames(down)) / (2.0 * np.reshape(h, (len(contacts), -1))))
    return np.stack(columns, axis=-1)


def sensitivity_derivatives(frames: Frames, contacts, loads, step):
    """{press: (patches, (n_z, n_patches) d dz / d log patch sensitivity)} for the patches each press loads."""
    out = {k: ([], []) for k in range(len(contacts))}
    scale = frames.sensor["patch_sensitivity_scale"]
    for patch in range(loads.shape[1]):
        rows = np.flatnonzero(loads[:, patch] > 0)
        if rows.size == 0:
            continue
        difference = 0.0
        for sign in (1.0, -1.0):
            sensor = dict(frames.sensor, patch_sensitivity_scale=scale * np.where(np.arange(len(scale)) == patch,
                                                                                  np.exp(sign * step), 1.0))
            difference = difference + sign * frames(contacts[rows], sensor)
        for row, column in zip(rows, difference / (2.0 * step)):
            out[row][0].append(patch)
            out[row][1].append(column)
    return {k: (np.array(p), np.array(c).T) for k, (p, c) in out.items()}


class Noise:
    """The inverse covariance of dz estimated from one frame: W = (A^-1 + c_k Jz Jz^T)^-1 with
    A = K^T K / (2 sigma^2) and c_k the drift variance at press k; applied to G as G^T W G
    through Woodbury, so only 100 x 100 systems are solved per press."""

    def __init__(self, basis, drift_jacobian_z, noise_v):
        self.a = np.asarray((basis.T @ basis).todense()) / (2.0 * noise_v ** 2)
        self.jz = drift_jacobian_z
        self.a_jz = self.a @ self.jz
        self.m = self.jz.T @ self.a_jz

    def quadratic(self, g, drift_variance):
        """g^T W g for (n_z, p) g."""
        base = g.T @ self.a @ g
        if drift_variance <= 0:
            return base
        cross = self.a_jz.T @ g
        return base - cross.T @ np.linalg.solve(np.eye(len(self.m)) / drift_variance + self.m, cross)


def mean_radial(covariance, normals):
    """E|e| for e ~ N(0, covariance), by a fixed set of standard normal draws."""
    value, vector = np.linalg.eigh(covariance)
    return float(np.hypot(*(normals @ (vector * np.sqrt(np.clip(value, 0, None))).T).T).mean())


def bounds_for(layout, node, seed, noise_levels, forces, args, normals):
    effects = node.get("effects") or {}
    deterministic = {k: v for k, v in effects.items() if k not in RANDOM_PRESS_EFFECTS + READING}
    scene = ERTScene(**{**node, "effects": deterministic, "seed": seed, "protocol": "single_point"})
    frames = Frames(scene)
    contacts = recording_contacts(scene, forces)
    mean = frames(contacts)
    g = derivatives(frames, contacts, args.step_mm, args.step_relative)
    spread = float((effects.get("foam_spread") or {}).get("spread_per_thickness", 1.0)) * scene.foam_thickness_mm \
        if "foam_spread" in effects else 0.0
    loads = patch_loads_n(contacts, scene.side_mm, scene.patch_mm, scene.indenter_diameter_mm / 2.0, spread)
    nuisance = sensitivity_derivatives(frames, contacts, loads, args.step_relative)
    prior_sd = float((effects.get("specimen_variation") or {}).get("sensitivity_spread", 0.0))
    basis = transfer_basis(scene.geometry())
    jacobian_channels = scene.patch_jacobian(frames.sensor)
    drift_jz = np.linalg.lstsq(basis.toarray(), jacobian_channels, rcond=None)[0]
    drift_f = float((effects.get("baseline_drift") or {}).get("fraction_per_50_presses", 0.0))
    position_prior_sd = scene.patch_mm / np.sqrt(12.0)
    rows = []
    for noise_v in noise_levels:
        noise = Noise(basis, drift_jz, noise_v)
        for k in range(len(contacts)):
            drift_variance = (k + 1) * drift_f ** 2 / 50.0
            patches, gn = nuisance[k]
            row = {"layout": layout, "seed": seed, "noise_v": noise_v, "force_n": float(contacts[k, 0, 2]),
                   "x_mm": float(contacts[k, 0, 0]), "y_mm": float(contacts[k, 0, 1])}
            for name in BOUNDS:
                unknown = name == "unknown_sensitivity" and prior_sd > 0 and len(patches) > 0
                columns = np.column_stack([g[k], gn]) if unknown else g[k]
                fisher = noise.quadratic(columns, drift_variance if name != "adc" else 0.0)
                if unknown:
                    fisher[3:, 3:] += np.eye(len(patches)) / prior_sd ** 2
                # what the frame says about (x, y) once the force and the sensitivities are estimated too
                position = fisher[:2, :2] - fisher[:2, 2:] @ np.linalg.solve(fisher[2:, 2:], fisher[2:, :2])
                row[name] = mean_radial(np.linalg.inv(position + np.eye(2) / position_prior_sd ** 2), normals)
                value, vector = np.linalg.eigh(position)
                informed = value >= 1.0 / position_prior_sd ** 2
                row[f"{name}_uninformed"] = bool(not informed.all())
                # the optimistic reading: an axis the frame says less about than the prior is taken as
                # known exactly (a biased estimator can beat the bound there, by how much is unknown)
                row[f"{name}_optimistic"] = mean_radial((vector[:, informed] / value[informed]) @ vector[:, informed].T,
                                                        normals)
            rows.append(row)
    checks = residual_check(node, seed, contacts, mean, drift_jz, basis, noise_levels, drift_f, args.check_sessions)
    return rows, checks


def residual_check(node, seed, contacts, mean, drift_jz, basis, noise_levels, drift_f, sessions):
    """Mean chi^2 / n_z of the whitened residual of independently simulated recordings (every effect
    but hysteresis) around the deterministic frame: about 1 if the noise model is the scene's."""
    out = []
    effects = {k: v for k, v in (node.get("effects") or {}).items() if k not in RANDOM_PRESS_EFFECTS}
    dense = basis.toarray()
    projector = np.linalg.pinv(dense)
    for noise_v in noise_levels:
        effects_here = {**effects, "adc_noise": {**(effects.get("adc_noise") or {}), "noise_v": noise_v}}
        noise = Noise(basis, drift_jz, noise_v)
        chi2 = []
        for session in range(1, sessions + 1):
            scene = ERTScene(**{**node, "effects": effects_here, "seed": seed, "protocol": "single_point",
                                "n_force_levels": 2, "force_range_n": [float(contacts[0, 0, 2]), float(contacts[1, 0, 2])],
                                "session": session})
            table = scene.generate()
            residual = table.channels @ projector.T - mean                      # dz estimated from each frame
            for k, r in enumerate(residual):
                chi2.append(float(noise.quadratic(r[:, None], (k + 1) * drift_f ** 2 / 50.0)[0, 0]))
        out.append({"seed": seed, "noise_v": noise_v, "chi2_per_dof": float(np.mean(chi2)) / len(mean[0]),
                    "n_frames": len(chi2)})
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--layouts", nargs="*", default=["ert_boundary", "ert_internal"])
    parser.add_argument("--seeds", nargs="*", type=int, default=[0, 1, 2])
    parser.add_argument("--forces", nargs=2, type=float, default=[4.0, 10.0])
    parser.add_argument("--noise-v", nargs="*", type=float, default=[2e-4, 1e-3])
    parser.add_argument("--step-mm", type=float, default=0.25, help="position step of the central differences")
    parser.add_argument("--step-relative", type=float, default=0.01, help="relative force / sensitivity step")
    parser.add_argument("--check-sessions", type=int, default=1, help="re-simulated recordings for the noise check")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args(argv)
    normals = np.random.default_rng(0).standard_normal((4000, 2))
    rows, checks = [], []
    print(f"load average at start: {os.getloadavg()[0]:.2f}", flush=True)
    with recording("ert_localisation_floor", MEASURED_CODE) as record:
        for layout in args.layouts:
            node = scene_node(layout)
            for seed in args.seeds:
                part, check = bounds_for(layout, node, seed, args.noise_v, sorted(args.forces), args, normals)
                rows += part
                checks += [{"layout": layout, **c} for c in check]
                for c in check:
                    print(f"{layout} seed {seed} noise {c['noise_v']:g}: noise-model check chi2/dof "
                          f"{c['chi2_per_dof']:.3f} over {c['n_frames']} frames", flush=True)
        print(f"load average at end: {os.getloadavg()[0]:.2f}\n")
        cells = summarise(rows)
        print_table(cells)
        record_layouts(record, cells, checks, args)
    if args.json:
        args.json.write_text(json.dumps({"rows": rows, "checks": checks}, indent=1))
    return 0


def summarise(rows) -> list[dict]:
    """Per layout, noise and force, per sensor: each bound's mean E|e| over the presses, its
    optimistic reading's, and the presses it leaves uninformed on one axis; and each bound's
    median press over all sensors. What the table prints and the records keep."""
    cells = []
    for key in sorted({(r["layout"], r["noise_v"], r["force_n"]) for r in rows}):
        here = [r for r in rows if (r["layout"], r["noise_v"], r["force_n"]) == key]
        seeds = sorted({r["seed"] for r in here})

        def per_seed(field, reduce=np.mean):
            return [float(reduce([r[field] for r in here if r["seed"] == s])) for s in seeds]

        cells.append({"layout": key[0], "noise_v": key[1], "force_n": key[2], "seeds": seeds,
                      "presses_per_sensor": len(here) // len(seeds),
                      "mean_mm_per_seed": {b: per_seed(b) for b in BOUNDS},
                      "optimistic_mm_per_seed": {b: per_seed(f"{b}_optimistic") for b in BOUNDS},
                      "uninformed_per_seed": {b: per_seed(f"{b}_uninformed", np.sum) for b in BOUNDS},
                      "median_press_mm": {b: float(np.median([r[b] for r in here])) for b in BOUNDS}})
    return cells


def record_layouts(record, cells, checks, args):
    """One record per layout: its cells (per sensor) and its noise-model checks, with the settings."""
    for layout in dict.fromkeys(cell["layout"] for cell in cells):
        record.add(layout, {"layout": layout, "forces_n": sorted(args.forces), "noise_v": args.noise_v,
                            "step_mm": args.step_mm, "step_relative": args.step_relative,
                            "check_sessions": args.check_sessions, "bounds": list(BOUNDS),
                            "cells": [cell for cell in cells if cell["layout"] == layout],
                            "noise_check": [check for check in checks if check["layout"] == layout]},
                   seeds=args.seeds)


def print_table(cells):
    """Per layout, noise and force: each bound's mean E|e| over presses, mean +- sd over sensors;
    for the last, also its optimistic reading, its median press and how many presses it leaves
    uninformed on one axis."""
    last = BOUNDS[-1]
    print("| layout | noise (V) | force (N) | " + " | ".join(f"{b} (mm)" for b in BOUNDS)
          + f" | {last}, uninformed axes exact (mm) | {last}, median press (mm) | presses uninformed on one axis |")
    print("|---|---|---|" + "---|" * (len(BOUNDS) + 3))
    for cell in cells:
        texts = [format_mean_sd(cell["mean_mm_per_seed"][bound]) for bound in BOUNDS]
        texts.append(format_mean_sd(cell["optimistic_mm_per_seed"][last]))
        texts.append(f"{cell['median_press_mm'][last]:.2f}")
        texts.append(f"{np.mean(cell['uninformed_per_seed'][last]):.1f} of {cell['presses_per_sensor']}")
        print(f"| {cell['layout']} | {cell['noise_v']:g} | {cell['force_n']:g} | " + " | ".join(texts) + " |")


if __name__ == "__main__":
    sys.exit(main())
