"""Figures: the one writer. Each figure goes to its PNG in the run folder (atomically) and to
TensorBoard under the same name, once, and is closed."""
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from common.atomic import atomic_write  # noqa: E402

DPI = 110


def write_figures(output_dir, figures: dict, logger=None, prefix: str = "figures") -> list[Path]:
    """{file stem: matplotlib figure} -> <output_dir>/<stem>.png and TensorBoard `<prefix>/<stem>`."""
    paths = []
    for name, figure in figures.items():
        if logger is not None:
            logger.log_figure(f"{prefix}/{name}", figure)
        paths.append(atomic_write(Path(output_dir) / f"{name}.png",
                                  lambda tmp, f=figure: f.savefig(tmp, dpi=DPI, format="png")))
        plt.close(figure)
    return paths
