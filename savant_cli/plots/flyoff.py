"""Fly-off comparison figures: the controllers' nominal histories overlaid, and their
dispersed distributions of each metric overlaid (drawn and written through :mod:`savant_cli.plots.figure`)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from savant_cli.plots.figure import bin_count, file_stem, new_figure, save_figure, style_axes


def plot_history_overlays(time_s: np.ndarray, histories: Mapping[str, Mapping[str, np.ndarray]], folder: Path,
                          units: Mapping[str, str] | None = None, prefix: str = "flyoff",
                          title: str = "fly-off, nominal run") -> list[Path]:
    """One PNG per signal, ``<prefix>_<signal>.png``: several variants' histories
    overlaid (the fly-off: each controller's nominal run).

    Parameters
    ----------
    time_s : numpy.ndarray
        Common time grid (s).
    histories : mapping
        signal → variant (legend label) → history on ``time_s`` (NaN after the run ended).
    folder : pathlib.Path
        Output folder.
    units : mapping, optional
        signal → unit label.
    prefix, title : str
        File-name prefix and figure title.
    """
    paths = []
    for name, per_controller in histories.items():
        fig = new_figure(8.0, 3.6)
        ax = fig.add_subplot(1, 1, 1)
        style_axes(ax)
        for k, (ctrl, y) in enumerate(per_controller.items()):
            ax.plot(time_s, y, lw=1.0, color=f"C{k}", label=ctrl)
        unit = (units or {}).get(name, "")
        ax.set_xlabel("time (s)", fontsize=8)
        ax.set_ylabel(f"{name} [{unit}]" if unit else name, fontsize=8)
        ax.legend(fontsize=7, loc="best")
        fig.suptitle(f"{title}: {name}", fontsize=10)
        paths.append(save_figure(fig, folder / f"{prefix}_{file_stem(name)}.png"))
    return paths


def plot_metric_histograms(values: Mapping[str, Mapping[str, np.ndarray]], out_path: Path,
                           winners: Mapping[str, str] | None = None, per_row: int = 3) -> Path:
    """The dispersed distribution of every metric, one panel per metric, the
    controllers' histograms overlaid on common bins (``winners``: metric → controller,
    named in the panel title)."""
    names = list(values)
    rows = max(1, -(-len(names) // per_row))
    fig = new_figure(3.2 * per_row, 2.4 * rows + 0.9, left=0.5, bottom=0.45, top=0.95, wspace=0.3, hspace=0.55)
    for i, name in enumerate(names):
        ax = fig.add_subplot(rows, per_row, i + 1)
        style_axes(ax, 4, 4)
        data = {c: v[np.isfinite(v)] for c, v in values[name].items()}
        pooled = np.concatenate(list(data.values())) if data else np.zeros(0)
        if pooled.size:
            edges = np.histogram_bin_edges(pooled, bins=max(bin_count(pooled), 1))
            for k, (ctrl, v) in enumerate(data.items()):
                counts, _ = np.histogram(v, bins=edges)
                ax.stairs(counts, edges, color=f"C{k}", lw=1.2, label=ctrl)
        win = (winners or {}).get(name)
        ax.set_title(f"{name}" + (f"\nbest: {win}" if win else ""), fontsize=7.5)
        if i == 0:
            ax.legend(fontsize=6.5)
    fig.suptitle("fly-off: dispersed distributions", fontsize=10)
    return save_figure(fig, out_path)
