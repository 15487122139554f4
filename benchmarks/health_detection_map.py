"""The limit-cycle detector's detection map (docs/outputs.md, *Flight health*): the
smallest detected amplitude of a sine on the guidance-like trend of
``tests/health_signals.py`` against its frequency and duration, at the shipped
``sim.health`` settings, noise-free and with white measurement noise of a fixed RMS.

A cell is found when the detector reports an oscillation within 2 % of its frequency;
the smallest such amplitude is bisected (12 halvings between 0.01 and 10 deg, in ratio)
for all cells at once. "—" : not found at 10 deg.

    python benchmarks/health_detection_map.py [--noise-deg 0.05] [--figure docs/figures/health_detection_map.png]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from health_signals import FS, oscillation, trend  # noqa: E402
from savant_cli.config import shipped_option  # noqa: E402
from savant_cli.sim.oscillation import band_top_hz, find_limit_cycles  # noqa: E402

FREQUENCIES = (0.05, 0.1, 0.175, 0.225, 0.3, 0.5, 1.0, 2.0, 5.0, 10.0, 15.0, 20.0, 22.7)
PERIODS = (4.0, 5.0, 10.0, 20.0, 50.0)
RECORD_S = 240.0


def _rows(amps: np.ndarray, noise_deg: float) -> tuple[np.ndarray, np.ndarray, list[tuple[float, float]]]:
    n = int(round(RECORD_S * FS))
    rows, cells = [], []
    k = 0
    for f in FREQUENCIES:
        for p in PERIODS:
            duration = min(p / f, RECORD_S - 40.0)
            t, y = oscillation(f, float(amps[k]), duration, seed=k)
            y = np.r_[y, trend(np.arange(y.size, n) / FS, f)][:n]
            if noise_deg > 0.0:
                y = y + noise_deg * np.random.default_rng(1000 + k).normal(size=n)
            rows.append(y)
            cells.append((f, duration))
            k += 1
    return np.arange(n) / FS, np.array(rows), cells


def detection_map(noise_deg: float) -> np.ndarray:
    """Smallest detected amplitude (deg) per (frequency, periods), NaN when not found."""
    cfg = shipped_option("sim").health  # the shipped detector settings
    top = band_top_hz(50.0, FS, cfg.min_periods)
    m = len(FREQUENCIES) * len(PERIODS)
    lo, hi = np.full(m, np.log(0.01)), np.full(m, np.log(10.0))

    def found(amps):
        t, rows, cells = _rows(amps, noise_deg)
        out = find_limit_cycles(t, rows, top, cfg.min_amplitude_deg, cfg.tonal_fraction, cfg.min_periods,
                                cfg.max_damping_ratio)
        return np.array([o is not None and abs(o.frequency_hz / f - 1.0) <= 0.02 for o, (f, _) in zip(out, cells)])

    ok_top = found(np.exp(hi))
    for _ in range(12):
        mid = 0.5 * (lo + hi)
        hit = found(np.exp(mid))
        hi = np.where(hit, mid, hi)
        lo = np.where(hit, lo, mid)
    return np.where(ok_top, np.exp(hi), np.nan).reshape(len(FREQUENCIES), len(PERIODS))


def table(amp: np.ndarray) -> str:
    head = "| f (Hz) | " + " | ".join(f"{p:g} periods" for p in PERIODS) + " |"
    rule = "|---|" + "---|" * len(PERIODS)
    body = [f"| {f:g} | " + " | ".join("—" if not np.isfinite(a) else f"{a:.3f}" for a in row) + " |"
            for f, row in zip(FREQUENCIES, amp)]
    return "\n".join([head, rule] + body)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--noise-deg", type=float, default=0.05, help="white-noise RMS of the noisy map, deg")
    ap.add_argument("--figure", type=Path, default=None, help="write the two maps as a PNG")
    args = ap.parse_args()
    maps = {}
    for noise in (0.0, args.noise_deg):
        maps[noise] = detection_map(noise)
        print(f"\nsmallest detected amplitude (deg), white noise {noise:g} deg RMS at {FS:g} Hz, "
              f"durations capped at {RECORD_S - 40:g} s:\n")
        print(table(maps[noise]))
    if args.figure is not None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        fig = Figure(figsize=(8.0, 4.0), dpi=110)
        FigureCanvasAgg(fig)
        for i, (noise, amp) in enumerate(maps.items()):
            ax = fig.add_subplot(1, 2, i + 1)
            for j, p in enumerate(PERIODS):
                ax.loglog(FREQUENCIES, amp[:, j], marker="o", ms=3, label=f"{p:g} periods")
            ax.set_xlabel("frequency (Hz)")
            ax.set_ylabel("smallest detected amplitude (deg)")
            ax.set_ylim(0.03, 10.0)
            ax.set_title(f"noise {noise:g} deg RMS", fontsize=9)
            ax.grid(True, which="both", lw=0.3)
            ax.legend(fontsize=7)
        fig.tight_layout()
        args.figure.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(args.figure)
        print(f"\nfigure: {args.figure}")


if __name__ == "__main__":
    main()
