"""What a calibration run writes about its scene fit, each file once:

- `scene/calibrated.yaml`: the fitted scene, a config `scene=` accepts
  (`python train.py hydra.searchpath=[file://<run>] scene=calibrated ...`): the scene's own
  config with the fitted values in place, every listed effect kept;
- `fit_report.md`: parameters ± sd and their 95 % intervals (log scale for log parameters), the ones at a bound flagged,
  residuals per channel at the scene's values and at the fitted ones, what the fit cannot
  identify and which effects it leaves out, and the pretraining choice with its reason;
- `measured_vs_simulated.png` (and TensorBoard `figures/measured_vs_simulated`): per channel,
  the rig's readings against the simulation at the scene's values and at the fitted ones.
"""
from pathlib import Path

import numpy as np
import yaml
from omegaconf import OmegaConf

from common.atomic import atomic_write_text
from runs.report.figure_files import write_figures
from runs.report.plots import panel_grid

SCENE_FILE = Path("scene") / "calibrated.yaml"


def calibrated_config(cfg, fit) -> dict:
    """The run's scene config with each fitted value at its path (seed still follows the run's)."""
    config = OmegaConf.to_container(cfg.scene, resolve=False)
    for p in fit.parameters:
        node = config
        *parents, leaf = p.path.split(".")
        for key in parents:
            node = node.setdefault(key, {}) or {}
        node[leaf] = float(f"{p.value:.6g}")
    noise = fit.notes.get("noise")
    if noise:
        config["effects"][noise[0]][noise[1]] = float(f"{noise[2]:.4g}")
    return config


def _report_text(fit, choice) -> str:
    lines = [f"# Scene fit: {fit.scene}", "",
             f"{len(fit.measured)} training presses, {fit.n_evaluations} simulations, {fit.time_s:.1f} s; "
             f"optimiser: {fit.message}", "",
             "| parameter | unit | scene's value | fitted ± sd | 95 % interval | range | at a bound |",
             "|---|---|---|---|---|---|---|"]
    for p in fit.parameters:
        lines.append(f"| `{p.path}` ({p.what}) | {p.unit} | {p.default:.4g} | {p.value:.4g} ± {p.sd:.2g} | "
                     f"{p.interval()[0]:.4g} … {p.interval()[1]:.4g} | {p.low:.3g} … {p.high:.3g} | "
                     f"{'**yes**: not a confidence interval' if p.at_bound else 'no'} |")
    lines += ["", "Residual rms per column (simulated − measured, the column's unit):", "",
              "| column | scene's values | fitted |", "|---|---|---|"]
    fitted, default = fit.residual_rms, fit.default_residual_rms
    lines += [f"| {c} | {default[c]:.4g} | {fitted[c]:.4g} |" for c in fit.columns]
    lines += ["", "Not fitted (left at the scene's values):", ""]
    lines += [f"- `{name}`: {why}" for name, why in fit.notes.get("not_identifiable", {}).items()]
    lines += ["", f"Effects the fit leaves out (kept in the fitted scene as listed): "
              f"{', '.join(fit.notes.get('unmodelled', [])) or 'none'}.", "",
              f"Pretraining: {choice['reason']}.", ""]
    return "\n".join(lines)


def measured_vs_simulated_figure(fit):
    """One panel per column: measured against simulated (scene's values, fitted), the diagonal."""
    figure, axes = panel_grid(len(fit.columns), 2.4, 2.2)
    for k, ax in enumerate(axes):
        measured = fit.measured[:, k]
        ax.scatter(fit.simulated_default[:, k], measured, s=6, alpha=0.6, label="scene's values")
        ax.scatter(fit.simulated[:, k], measured, s=6, alpha=0.6, label="fitted")
        everything = np.r_[measured, fit.simulated[:, k], fit.simulated_default[:, k]]
        low, high = float(everything.min()), float(everything.max())
        ax.plot([low, high], [low, high], color="black", linewidth=0.6)
        ax.set_title(fit.columns[k], fontsize=7)
        ax.tick_params(labelsize=6)
    axes[0].legend(fontsize=6)
    figure.supxlabel("simulated")
    figure.supylabel("measured")
    figure.suptitle(f"{fit.scene}: the rig's readings against the scene's", fontsize=9)
    figure.tight_layout()
    return figure


def write_fit_report(output_dir: Path, cfg, fit, choice, logger=None) -> None:
    config = calibrated_config(cfg, fit)
    header = (f"# Scene {fit.scene} fitted to {len(fit.measured)} calibration presses (fit_report.md beside it):\n"
              "#   python train.py hydra.searchpath=[file://<this run's folder>] scene=calibrated ...\n")
    (output_dir / SCENE_FILE).parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(output_dir / SCENE_FILE, header + yaml.safe_dump(config, sort_keys=False))
    atomic_write_text(output_dir / "fit_report.md", _report_text(fit, choice))
    write_figures(output_dir, {"measured_vs_simulated": measured_vs_simulated_figure(fit)}, logger)
