"""Study run `taxel_receptive_field`: Fig. 2 and Fig. 4 of *Effects of the elastic cover on tactile
sensor arrays* (the taxels paper) from the taxels scene.

    python train.py experiment=taxel_receptive_field

Fig. 2: a needle scanned along x over one taxel (10 mN, 180 um cover): the strain components
(gamma_x, gamma_y, eps_z) read back from the bridge voltages with eq. (2), for each cover model
(experiment config `study.models`: eq. 1 at a point, the finite layers, eq. 1 over the taxel's
membrane, and the full default chain with amplifier, noise and ADC). Fig. 4: the eps_z profile's width W (between its zero crossings) and
amplitude A (|eps_z| under the load) against cover thickness, for each cover model, with the
paper's measured laws beside them (its text gives the fitted slope of W, 1.14, and the exponent
of A, -1.45, not the points; the lines are drawn through the model's value at the middle
thickness so only their slopes compare). Writes receptive_field.png, thickness.png, the same
figures to TensorBoard, profiles.csv and thickness.csv; the fitted slopes and exponents, the Fig. 2
ratios and shear sensitivities (max |gamma_x| / max |eps_z|) it returns go to metrics.json (no "val" key: nothing here is a validation score).
"""
from pathlib import Path

import numpy as np
import pandas as pd
from omegaconf import OmegaConf

from common.atomic import atomic_write_text
from data.scenes.taxels import TaxelsScene
from runs.report.figure_files import write_figures
from runs.report.plots import panel_grid, readable_log_axis

PAPER = {"w_slope": 1.14, "a_exponent": -1.45, "ratio": 19.0}
THEORY = {"w_slope": 2.0 * np.sqrt(2.0), "a_exponent": -2.0, "ratio": 5.0**2.5,
          "shear_sensitivity": 0.75 * 0.8**2.5}


def _crossing(x, y, index_from, index_to):
    """x where y changes sign between two neighbouring samples (linear interpolation)."""
    y0, y1 = y[index_from], y[index_to]
    return x[index_from] + (x[index_to] - x[index_from]) * y0 / (y0 - y1)


def profile_metrics(x_mm, eps_z, centre_mm) -> dict:
    """The taxels paper's eq. (3)-(4) measured on a sampled eps_z(x) profile around a taxel at `centre_mm`.

    amplitude: |eps_z| at its compressive peak; zero_crossing_mm: mean distance of the first sign
    changes either side of the peak; width_mm: distance between them (W; nan when eps_z never
    turns positive); minimum_at_mm: distance of the largest tensile value (the lateral lobe);
    ratio: |peak / largest tensile value| (inf when there is none).
    """
    x = np.asarray(x_mm, dtype=float)
    e = np.asarray(eps_z, dtype=float)
    peak = int(np.argmin(e))
    out = {"amplitude": float(-e[peak]), "peak_at_mm": float(x[peak] - centre_mm)}
    right = np.flatnonzero(e[peak:] > 0)
    left = np.flatnonzero(e[:peak + 1][::-1] > 0)
    if right.size and left.size:
        i_right = peak + right[0]
        i_left = peak - left[0]
        x_right = _crossing(x, e, i_right - 1, i_right)
        x_left = _crossing(x, e, i_left + 1, i_left)
        out["width_mm"] = float(x_right - x_left)
        out["zero_crossing_mm"] = float(0.5 * (x_right - x_left))
    else:
        out["width_mm"] = out["zero_crossing_mm"] = float("nan")
    lobe = int(np.argmax(e))
    if e[lobe] > 0:
        if 0 < lobe < len(e) - 1:  # parabola through the three samples around the extreme
            denominator = e[lobe - 1] - 2 * e[lobe] + e[lobe + 1]
            shift = 0.5 * (e[lobe - 1] - e[lobe + 1]) / denominator if denominator else 0.0
        else:
            shift = 0.0
        at = x[lobe] + shift * (x[1] - x[0])
        out["minimum_at_mm"] = float(abs(at - centre_mm))
        out["ratio"] = float(out["amplitude"] / e[lobe])
    else:
        out["minimum_at_mm"], out["ratio"] = float("nan"), float("inf")
    return out


def fit_laws(thickness_um, width_mm, amplitude) -> dict:
    """Slope of W against thickness (least squares with intercept, mm per mm) and the exponent of
    A against thickness (least squares in log-log), over the points where each is defined."""
    z = np.asarray(thickness_um, dtype=float) * 1e-3
    w = np.asarray(width_mm, dtype=float)
    a = np.asarray(amplitude, dtype=float)
    ok = np.isfinite(w)
    slope = float(np.polyfit(z[ok], w[ok], 1)[0]) if ok.sum() >= 2 else float("nan")
    exponent = float(np.polyfit(np.log(z), np.log(a), 1)[0])
    return {"w_slope": slope, "a_exponent": exponent}


def needle_profile(params: dict, effects: dict, thickness_um: float, n_points: int, force_mn: float):
    """Scan a needle along taxel 0's row, +/- 4 thicknesses (at least 1 mm) around it, on the taxels
    scene `params` (its config as a dict) with `effects`. Returns x (mm), taxel 0's strains read
    back from its bridges with eq. (2) (n, 3: gamma_x, gamma_y, eps_z; through whatever reading
    effects are listed), the same without the reading chain (the scene's noise-free strain
    columns), and the taxel's x."""
    node = {k: v for k, v in params.items() if k not in ("_target_", "_convert_", "effects")}
    node.update(protocol="needle_scan", n_samples=n_points, cover_thickness_um=thickness_um,
                needle_force_mn=force_mn)
    scene = TaxelsScene(**node, effects=effects)
    centre = scene.taxel_xy_mm()[0, 0]
    reach = max(4.0 * thickness_um * 1e-3, 1.0)
    scene.scan_range_mm = (centre - reach, centre + reach)
    table = scene.generate()
    gain = effects["amplifier"].get("gain", 55.0) if "amplifier" in effects else 1.0
    read_back = scene.strain_from_bridges(table.channels / gain)[:, 0, :]
    exact = table.frame[["gamma_x_t0", "gamma_y_t0", "eps_z_t0"]].to_numpy()
    return table.frame["x_mm"].to_numpy(), read_back, exact, centre


def shear_sensitivity(strain) -> float:
    """The taxels paper's sec. 7 measure on a normal needle scan: max |gamma_x| / max |eps_z|
    (eq. 1 gives (3/4) (4/5)^(5/2) = 0.429 at any depth)."""
    return float(np.abs(strain[:, 0]).max() / np.abs(strain[:, 2]).max())


def run_receptive_field(cfg, output_dir, logger, models: dict, thickness_um: list, fig2_thickness_um: float = 180.0,
                        n_points: int = 1201, force_mn: float = 10.0) -> dict:
    """The study (module docstring). `models`: label -> effects mapping of the taxels scene."""
    output_dir = Path(output_dir)
    models = {label: OmegaConf.to_container(e, resolve=True) if not isinstance(e, dict) else e
              for label, e in models.items()}
    thickness_um = [float(t) for t in thickness_um]
    params = OmegaConf.to_container(cfg.scene, resolve=True)

    rows, profiles = [], []
    for label, effects in models.items():
        for z in thickness_um:
            x, strain, _, centre = needle_profile(params, effects, z, n_points, force_mn)
            rows.append({"model": label, "thickness_um": z, **profile_metrics(x, strain[:, 2], centre)})
        x, strain, _, centre = needle_profile(params, effects, fig2_thickness_um, n_points, force_mn)
        profiles.append(pd.DataFrame({"model": label, "x_mm": x - centre, "gamma_x": strain[:, 0],
                                      "gamma_y": strain[:, 1], "eps_z": strain[:, 2]}))
        rows.append({"model": label, "thickness_um": fig2_thickness_um, "fig2": True,
                     **profile_metrics(x, strain[:, 2], centre), "shear_sensitivity": shear_sensitivity(strain)})
    table = pd.DataFrame(rows)
    table["fig2"] = table.get("fig2", False)
    table["fig2"] = table["fig2"].astype("boolean").fillna(False).astype(bool)
    profiles = pd.concat(profiles, ignore_index=True)

    metrics = {"paper": dict(PAPER), "half_space_theory": dict(THEORY)}
    for label in models:
        series = table[(table.model == label) & ~table.fig2]
        laws = fit_laws(series.thickness_um, series.width_mm, series.amplitude)
        fig2 = table[(table.model == label) & table.fig2].iloc[0]
        metrics[label] = {**laws, "ratio_fig2": float(fig2.ratio), "width_fig2_mm": float(fig2.width_mm),
                          "amplitude_fig2": float(fig2.amplitude),
                          "shear_sensitivity_fig2": float(fig2.shear_sensitivity)}

    figures = {"receptive_field": _profile_figure(profiles, fig2_thickness_um, force_mn),
               "thickness": _thickness_figure(table[~table.fig2], metrics)}
    write_figures(output_dir, figures, logger, prefix="taxels")
    atomic_write_text(output_dir / "thickness.csv", table.to_csv(index=False))
    atomic_write_text(output_dir / "profiles.csv", profiles.to_csv(index=False))
    return metrics


PAPER_TITLE = "“Effects of the elastic cover on tactile sensor arrays”"
COMPONENTS = {"gamma_x": ("γx (shear)", "-"), "gamma_y": ("γy (shear)", ":"), "eps_z": ("εz (normal)", "-")}


def _profile_figure(profiles, thickness_um, force_mn):
    labels = list(dict.fromkeys(profiles.model))
    figure, axes = panel_grid(len(labels), panel_width=3.4, panel_height=2.7)
    for ax, label in zip(axes, labels):
        p = profiles[profiles.model == label]
        for component, (name, style) in COMPONENTS.items():
            ax.plot(p.x_mm, p[component], style, label=name)
        ax.axhline(0.0, color="grey", lw=0.5)
        ax.set_title(f"cover model {label}", fontsize=9)
        ax.tick_params(labelsize=8)
    axes[0].legend(fontsize=7, title="strain", title_fontsize=7)
    figure.supxlabel("needle position relative to the taxel, x (mm)", fontsize=10)
    figure.supylabel("strain read back through eq. 2 (–)", fontsize=10)
    figure.suptitle(f"Fig. 2 of {PAPER_TITLE}: a {force_mn:g} mN needle scanned over a taxel "
                    f"under a {thickness_um:.0f} µm cover", fontsize=11)
    figure.tight_layout()
    return figure


def _thickness_figure(table, metrics):
    figure, (ax_w, ax_a) = panel_grid(2, panel_width=5.6, panel_height=6.4)
    for label in dict.fromkeys(table.model):
        t = table[table.model == label]
        slope, exponent = (f"{v:.2f}" if np.isfinite(v) else "not defined"
                           for v in (metrics[label]["w_slope"], metrics[label]["a_exponent"]))
        ax_w.plot(t.thickness_um, t.width_mm, "o-", ms=3, label=f"{label} (slope {slope})")
        ax_a.loglog(t.thickness_um, t.amplitude, "o-", ms=3, label=f"{label} (exponent {exponent})")
    z = np.asarray(sorted(set(table.thickness_um)))
    middle = z[len(z) // 2]
    first = table[table.model == table.model.iloc[0]].set_index("thickness_um")
    if np.isfinite(first.width_mm.get(middle, np.nan)):
        w_mid = first.width_mm[middle]
        ax_w.plot(z, w_mid + PAPER["w_slope"] * (z - middle) * 1e-3, "k--",
                  label=f"the paper's slope, {PAPER['w_slope']:.2f}")
    a_mid = first.amplitude[middle]
    ax_a.loglog(z, a_mid * (z / middle) ** PAPER["a_exponent"], "k--",
                label=f"the paper's exponent, {PAPER['a_exponent']:.2f}")
    readable_log_axis(ax_a, "x")
    readable_log_axis(ax_a, "y")
    ax_w.set(xlabel="cover thickness (µm)", ylabel="width W between the zero crossings of εz (mm)",
             title="receptive field width W")
    ax_a.set(xlabel="cover thickness (µm), log scale", ylabel="amplitude A = |εz| under the load (–), log scale",
             title="amplitude A")
    for ax, law in ((ax_w, "W against thickness: fitted slope"), (ax_a, "A against thickness: fitted exponent")):
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, title=f"cover model ({law})",
                  title_fontsize=7)
    figure.suptitle(f"Fig. 4 of {PAPER_TITLE}:\nthe receptive field against cover thickness "
                    "(the paper's lines drawn through the first model's middle point)", fontsize=11)
    figure.tight_layout()
    return figure
