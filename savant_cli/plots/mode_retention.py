"""Mode-retention figures: the closed-loop step responses of every retained-mode count
overlaid, and the critical margins against the count (drawn and written through :mod:`savant_cli.plots.figure`)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from savant_cli.plots.figure import new_figure, save_figure, style_axes
from savant_cli.plots.flyoff import plot_history_overlays


def plot_mode_retention(time_s: np.ndarray, responses: Mapping[str, Mapping[int, np.ndarray]],
                        margins: Mapping[tuple[float, str, str], Mapping[int, float]], folder: Path) -> list[Path]:
    """``mode_retention_<response>.png`` per step response and ``mode_retention_margins.png``.

    Parameters
    ----------
    time_s : numpy.ndarray
        Time after the command step (s).
    responses : mapping
        Response name (``t55_pitch_attitude`` …) → retained-mode count → the closed loop's
        response to a unit attitude-command step on ``time_s`` (rad per rad).
    margins : mapping
        (flight time s, axis, kind) → count → the critical margin over every band (gain
        margins in dB, phase margins in deg).
    folder : pathlib.Path
        Output folder.
    """
    hist = {name: {f"{n} modes": y for n, y in per_count.items()} for name, per_count in responses.items()}
    paths = plot_history_overlays(time_s, hist, folder, prefix="mode_retention", title="attitude-command step response")
    fig = new_figure(8.0, 4.5)
    axes = [fig.add_subplot(1, 2, i + 1) for i in range(2)]
    for ax, kind, unit in zip(axes, ("gain", "phase"), ("dB", "deg")):
        style_axes(ax)
        for (t, axis, k), per_count in margins.items():
            if k != kind:
                continue
            counts = sorted(per_count)
            ax.plot(counts, [per_count[n] for n in counts], marker="o", lw=1.0, label=f"{axis} t={t:g}")
        ax.set_xlabel("retained modes", fontsize=8)
        ax.set_ylabel(f"critical {kind} margin ({unit})", fontsize=8)
        ax.legend(fontsize=6)
    fig.suptitle("critical margins vs retained modes", fontsize=10)
    paths.append(save_figure(fig, folder / "mode_retention_margins.png"))
    return paths
