"""Time-domain margin figures: one per search, its bisection history (every judged change
in order, stable or not) beside the last stable and first unstable responses
overlaid (drawn and written through :mod:`savant_cli.plots.figure`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from savant_cli.plots.figure import new_figure, save_figure, style_axes
from savant_cli.timedomain.search import UNITS, SearchResult


def plot_search(res: SearchResult, folder: Path) -> Path:
    """``t<time>_<axis>_<kind>.png`` in ``folder``: the search history and the bracketing
    responses (gimbal angle, excited minus unexcited run, deg)."""
    s = res.search
    fig = new_figure(9.0, 3.6, wspace=0.3)
    ax1, ax2 = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    for ax in (ax1, ax2):
        style_axes(ax)
    n = np.arange(1, len(res.trials) + 1)
    vals = np.array([tr.value for tr in res.trials])
    bad = np.array([tr.growth.unstable for tr in res.trials], bool)
    ax1.plot(n, vals, color="0.6", lw=0.8)
    ax1.plot(n[~bad], vals[~bad], "o", color="tab:green", ms=4, label="stable")
    ax1.plot(n[bad], vals[bad], "x", color="tab:red", ms=5, label="not stable")
    if np.isfinite(res.margin):
        ax1.axhline(res.margin, color="k", lw=0.8, ls="--", label=f"margin {res.margin:.2f} {UNITS[s.kind]}")
    ax1.set_xlabel("trial", fontsize=8)
    ax1.set_ylabel(f"{s.kind.replace('_', ' ')} ({UNITS[s.kind]})", fontsize=8)
    ax1.legend(fontsize=7)
    for resp, label, color in ((res.last_stable, "last stable", "tab:green"),
                               (res.first_unstable, "first unstable", "tab:red")):
        if resp is not None:
            ax2.plot(resp[0], resp[1], color=color, lw=0.8, label=label)
    ax2.set_xlabel("mission time (s)", fontsize=8)
    ax2.set_ylabel(f"{s.axis} gimbal response (deg)", fontsize=8)
    ax2.legend(fontsize=7)
    fig.suptitle(f"t = {s.time_s:g} s, {s.axis}, {s.kind}: window {s.start_s:.1f}-{s.end_s:.1f} s", fontsize=9)
    return save_figure(fig, folder / f"t{s.time_s:g}_{s.axis}_{s.kind}.png")
