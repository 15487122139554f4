"""Overlay and difference plot of one signal of a run against a reference simulation
(drawn and written through :mod:`savant_cli.plots.figure`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from savant_cli.plots.figure import new_figure, save_figure, style_axes


def plot_comparison(time_s: np.ndarray, run: np.ndarray, reference: np.ndarray, name: str, units: str,
                    out_path: Path) -> Path:
    """Top: the run and the reference (interpolated onto the run's times); bottom: the
    difference run − reference. Time in s; values in ``units``."""
    fig = new_figure(8.0, 5.2, hspace=0.15)
    top = fig.add_subplot(2, 1, 1)
    bottom = fig.add_subplot(2, 1, 2, sharex=top)
    for ax in (top, bottom):
        style_axes(ax)
    label = f"{name} [{units}]" if units else name
    top.plot(time_s, run, lw=1.2, color="C0", label="savant")
    top.plot(time_s, reference, lw=1.0, ls="--", color="C3", label="reference")
    top.set_ylabel(label, fontsize=8)
    top.legend(fontsize=7)
    top.tick_params(labelbottom=False)
    bottom.plot(time_s, run - reference, lw=1.0, color="C2")
    bottom.axhline(0.0, color="0.3", lw=0.6)
    bottom.set_ylabel(f"savant − reference [{units}]" if units else "savant − reference", fontsize=8)
    bottom.set_xlabel("time (s)", fontsize=8)
    fig.suptitle(f"comparison: {name}", fontsize=10)
    return save_figure(fig, out_path)
