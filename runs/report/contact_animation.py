"""The tracker's view of a stream as Egger et al. 2025 show it (Figs. 13-14): a heatmap of the
load above the rest mean with each contact's id written on its cells and the cells below
threshold black, beside one time-series panel per contact (its peak load over time, a cursor at
the current frame). Written as an animated GIF (matplotlib's PillowWriter) and one PNG frame.
"""
from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd

from common.atomic import atomic_write

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib import animation  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402


def _panel_contacts(contacts: pd.DataFrame, frames: np.ndarray, busiest: int, n_panels: int) -> list[int]:
    """At most n_panels ids: those on the still frame first, then the others, each group by how
    many of the shown frames they are seen in; in order of first appearance."""
    shown = contacts[contacts.frame.isin(frames)]
    if shown.empty:
        return []
    seen = shown.id.value_counts()
    on_still = set(shown[shown.frame == busiest].id)
    ranked = sorted(seen.index, key=lambda i: (i not in on_still, -seen[i]))[:n_panels]
    first = shown.groupby("id").frame.min()
    return sorted(ranked, key=lambda i: first[i])


def _figure(load: np.ndarray, n_panels: int, pitch_mm: float):
    """The heatmap, and beside it one time-series panel per shown contact (none: the heatmap alone)."""
    rows, cols = load.shape[1:]
    figure = plt.figure(figsize=(8.0, 3.8) if n_panels else (4.6, 3.8), dpi=64)
    grid = figure.add_gridspec(max(n_panels, 1), 2 if n_panels else 1, width_ratios=[1.15, 1.0] if n_panels else None)
    heat = figure.add_subplot(grid[:, 0])
    panels = [figure.add_subplot(grid[i, 1]) for i in range(n_panels)]
    colours = plt.get_cmap("Reds")(np.linspace(0.08, 1.0, 256))
    cmap = ListedColormap(colours).with_extremes(bad="black")  # below threshold: noise, as the paper's Fig. 14
    vmax = max(float(np.nanpercentile(load, 99.9)), 1.0)
    image = heat.imshow(np.zeros((rows, cols)), cmap=cmap, vmin=0.0, vmax=vmax, origin="upper",
                        extent=(0, cols * pitch_mm, rows * pitch_mm, 0))
    heat.set_xlabel("x (mm)")
    heat.set_ylabel("y (mm)")
    figure.colorbar(image, ax=heat, fraction=0.046, pad=0.04, label="load above rest (RMC counts)")
    return figure, heat, image, panels


def write_contact_animation(load: np.ndarray, shown: np.ndarray, labels: np.ndarray, contacts: pd.DataFrame,
                            gif_path: str | Path, png_path: str | Path, pitch_mm: float, frame_rate_hz: float,
                            max_frames: int = 60, n_panels: int = 3, fps: int = 15) -> dict:
    """load: [n, rows, cols] reading minus rest mean; shown: [n, rows, cols] bool (above
    threshold); labels: [n, rows, cols] contact id per cell (0 none); contacts: frame (0-based
    index into load), id, peak_load. Animates the `max_frames` frames (every other frame if
    needed) centred on the frame with most contacts; the PNG is that frame."""
    n = len(load)
    per_frame = contacts.groupby("frame").size().reindex(range(n), fill_value=0).to_numpy() if n else np.zeros(0)
    step = max(1, int(np.ceil(min(n, 2 * max_frames) / max_frames)))
    span = min(n, max_frames * step)
    # the stretch centred on the frame with most contacts (first such frame)
    start = int(np.clip(int(np.argmax(per_frame)) - span // 2, 0, max(n - span, 0))) if n else 0
    frames = np.arange(start, start + span, step)
    busiest = int(frames[np.argmax(per_frame[frames])]) if len(frames) else 0
    ids = _panel_contacts(contacts, frames, busiest, n_panels)
    series = {i: contacts[contacts.id == i].set_index("frame").peak_load.reindex(range(n)) for i in ids}
    figure, heat, image, panels = _figure(load, len(ids), pitch_mm)
    time_s = np.arange(n) / frame_rate_hz
    cursors = []
    for axis, i in zip(panels, ids):
        axis.plot(time_s[frames], series[i].to_numpy()[frames], color="tab:red", lw=1.2)
        axis.set_ylabel(f"contact {i}:\npeak load\n(RMC counts)", fontsize=7)
        axis.tick_params(labelsize=7)
        axis.set_xlim(time_s[frames[0]], time_s[frames[-1]])
        cursors.append(axis.axvline(time_s[frames[0]], color="k", lw=0.8))
    if panels:
        panels[0].set_title("each contact's peak load over time", fontsize=9)
        for axis in panels[:-1]:
            axis.tick_params(labelbottom=False)   # one time axis, named under the last panel
        panels[-1].set_xlabel("time (s)")
    texts = []

    def draw(frame):
        for text in texts:
            text.remove()
        texts.clear()
        image.set_data(np.ma.masked_where(~shown[frame], np.maximum(load[frame], 0.0)))
        rows, cols = np.nonzero(labels[frame])
        for r, c in zip(rows.tolist(), cols.tolist()):
            texts.append(heat.text((c + 0.5) * pitch_mm, (r + 0.5) * pitch_mm, str(int(labels[frame][r, c])),
                                   ha="center", va="center", fontsize=9, color="white", weight="bold"))
        heat.set_title(f"frame {frame}  t = {time_s[frame]:.2f} s  contacts: {int(per_frame[frame])}", fontsize=9)
        for cursor in cursors:
            cursor.set_xdata([time_s[frame], time_s[frame]])
        return [image, *texts, *cursors]

    figure.tight_layout()
    movie = animation.FuncAnimation(figure, draw, frames=frames.tolist(), blit=False)
    atomic_write(gif_path, lambda tmp: movie.save(tmp, writer=animation.PillowWriter(fps=fps)))
    draw(busiest)
    atomic_write(png_path, lambda tmp: figure.savefig(tmp, dpi=100, format="png"))
    plt.close(figure)
    return {"animated_frames": int(len(frames)), "first_frame": int(frames[0]) if len(frames) else 0,
            "png_frame": busiest}
