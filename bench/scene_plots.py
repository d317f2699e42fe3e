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
from hydra import compose, initialize_config_dir  # noqa: E402
from omegaconf import OmegaConf  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.atomic import atomic_write  # noqa: E402
from data.scenes.fingertip import FingertipScene  # noqa: E402
from data.scenes.rubber12 import Rubber12Scene  # noqa: E402


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
    change = scene.simulate(xx.ravel(), yy.ravel(), np.full(xx.size, 3.0)).channels / rest - 1
    fig, axes = plt.subplots(1, 6, figsize=(22, 3.6))
    for ax, k in zip(axes[:4], (0, 1, 2, 4)):
        image = ax.imshow(100 * change[:, k].reshape(xx.shape), origin="lower", extent=(4, 46, 4, 46), cmap="viridis_r")
        ax.set(title=f"r_{k + 1:02d}: change at 3 mm (%)", xlabel="x (mm)", ylabel="y (mm)")
        fig.colorbar(image, ax=ax, shrink=0.8)
    depths = np.linspace(0.0, 3.0, 31)
    for ax, (x, y, label) in zip(axes[4:], ((25, 25, "P5 (centre)"), (12.5, 37.5, "P1 (corner)"))):
        r = scene.simulate(np.full(31, x), np.full(31, y), depths).channels / rest - 1
        ax.plot(depths, 100 * r)
        ax.set(title=f"all channels at {label}", xlabel="depth (mm)", ylabel="change (%)")
    fig.tight_layout()
    return fig


def fingertip_figure():
    recordings = FingertipScene(boards=["silk/circular_5mm", "glass/flat"], force_levels_n=[5, 20],
                                passes_per_level=1, effects=effects_of("fingertip")).generate()
    fig, axes = plt.subplots(2, 2, figsize=(14, 6), sharex=True)
    for col, board in enumerate(("silk/circular_5mm", "glass/flat")):
        for force, colour in ((5.0, "tab:blue"), (20.0, "tab:red")):
            row = np.flatnonzero((recordings.labels.board == board) & (recordings.labels.force_level_n == force))[0]
            for r, channel in enumerate(recordings.channel_names):
                axes[r, col].plot(recordings.time_s, recordings.signals[row, r], color=colour, lw=0.7, label=f"{force:.0f} N")
        axes[0, col].set(title=board, ylabel="triboelectric current (nA)")
        axes[1, col].set(xlabel="time (s)", ylabel="piezoresistive divider (V)")
        axes[0, col].legend(loc="upper right")
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
