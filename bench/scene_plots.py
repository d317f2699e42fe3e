"""One picture per scene of what it simulates.

    .venv/bin/python bench/scene_plots.py [--out bench/figures]

rubber12.png: relative change of four channels over the sheet for a 3 mm press, and every
channel against depth at the centre and at a corner point. fingertip.png: triboelectric and
piezoresistive traces of one board at 5 N and 20 N.
"""
import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402
from hydra import compose, initialize_config_dir  # noqa: E402
from omegaconf import OmegaConf  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.atomic import atomic_write  # noqa: E402
from data.scenes.fingertip import FingertipScene  # noqa: E402
from data.scenes.rubber12 import Rubber12Scene  # noqa: E402
from runs.report.plots import panel_grid, readable_log_axis  # noqa: E402


def effects_of(name):
    """The effects a scene variant lists, as Hydra composes it (variants inherit their base)."""
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        return OmegaConf.to_container(compose("config", overrides=[f"scene={name}"]).scene.effects)


def rubber12_figure():
    scene = Rubber12Scene(effects={k: v for k, v in effects_of("rubber12").items()
                                   if k in ("contact", "percolation", "tunneling")}, progress=False)
    rest = scene.simulate([25.0], [25.0], [0.0]).channels[0]
    axis = np.linspace(4, 46, 43)
    xx, yy = np.meshgrid(axis, axis)
    change = 100 * (scene.simulate(xx.ravel(), yy.ravel(), np.full(xx.size, 3.0)).channels / rest - 1)
    # a press next to an electrode changes its reading by up to 10^5 %, the rest of the sheet by
    # 0.2-300 %: a log colour scale between the 1st and 99th percentiles shows both
    norm = LogNorm(*np.percentile(change[:, [0, 1, 2, 4]], [1, 99]))
    fig, axes = panel_grid(6, panel_width=4.2, panel_height=3.4)
    for ax, k in zip(axes[:4], (0, 1, 2, 4)):
        image = ax.imshow(change[:, k].reshape(xx.shape), origin="lower", extent=(4, 46, 4, 46), cmap="viridis",
                          norm=norm)
        ax.set(title=f"channel r_{k + 1:02d}", xlabel="press x (mm)", ylabel="press y (mm)")
        bar = fig.colorbar(image, ax=ax, shrink=0.8, extend="both", label="resistance change (%)")
        readable_log_axis(bar.ax, "y")
    depths = np.linspace(0.0, 3.0, 31)
    for ax, (x, y, label) in zip(axes[4:], ((25, 25, "P5, the centre"), (12.5, 37.5, "P1, a corner point"))):
        r = scene.simulate(np.full(31, x), np.full(31, y), depths).channels / rest - 1
        ax.plot(depths, 100 * r, lw=1, label=[f"r_{k + 1:02d}" for k in range(r.shape[1])])
        ax.set(title=f"all 12 channels, press at {label}", xlabel="press depth (mm)",
               ylabel="resistance change (%)")
    axes[5].legend(fontsize=6, ncol=3, title="channel", title_fontsize=7)
    fig.suptitle("rubber12 scene: each channel's resistance change for a 3 mm press over the sheet, "
                 "and against depth at two points")
    fig.tight_layout()
    return fig


def fingertip_figure():
    recordings = FingertipScene(boards=["silk/circular_5mm", "glass/flat"], force_levels_n=[5, 20],
                                passes_per_level=1, effects=effects_of("fingertip")).generate()
    fig, axes = plt.subplots(2, 2, figsize=(14, 6.4), sharex=True)
    for col, board in enumerate(("silk/circular_5mm", "glass/flat")):
        for force, colour in ((5.0, "tab:blue"), (20.0, "tab:red")):
            row = np.flatnonzero((recordings.labels.board == board) & (recordings.labels.force_level_n == force))[0]
            for r, channel in enumerate(recordings.channel_names):
                axes[r, col].plot(recordings.time_s, recordings.signals[row, r], color=colour, lw=0.7, label=f"{force:.0f} N")
        axes[0, col].set(title=f"board {board}", ylabel="triboelectric current (nA)")
        axes[1, col].set(xlabel="time (s)", ylabel="piezoresistive divider voltage (V)")
        axes[0, col].legend(loc="upper right", title="normal force")
    fig.suptitle("fingertip scene: one pass of the fingertip over two boards at 5 N and 20 N")
    fig.tight_layout()
    return fig


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default=str(ROOT / "bench" / "figures"))
    out = Path(parser.parse_args(argv).out)
    for name, make in (("rubber12", rubber12_figure), ("fingertip", fingertip_figure)):
        figure = make()
        path = atomic_write(out / f"{name}.png", lambda tmp, f=figure: f.savefig(tmp, dpi=90, format="png"))
        print(path)


if __name__ == "__main__":
    main()
