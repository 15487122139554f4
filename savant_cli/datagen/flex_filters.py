"""Design the default flex-filter coefficients of ``conf/controller/msfc_pid.yaml``.

Each flight-control path carries two fourth-order discrete sections in series (source
paper §III.F). The defaults are designed with scipy at the 50 Hz control rate:

* section 1: 4th-order Butterworth low-pass, gain-stabilizing everything above its
  corner (8 Hz on both stages);
* section 2: a pair of second-order notches (quality factor 1.5) at the estimated second
  and third bending frequencies (stack 2.5 / 4.5 Hz; upper stage 6 / 9 Hz, [E]: no public
  Ares I modal data); the first stack mode (~1 Hz) is left to phase stabilization.

Run ``python -m savant_cli.datagen.flex_filters`` to print the YAML block.
"""

from __future__ import annotations

import numpy as np
from scipy import signal

FCS_RATE_HZ = 50.0
DESIGN = {
    "stack": {"lowpass_hz": 8.0, "notch_hz": (2.5, 4.5), "notch_q": 1.5},
    "upper": {"lowpass_hz": 8.0, "notch_hz": (6.0, 9.0), "notch_q": 1.5},
}


def design_set(lowpass_hz: float, notch_hz: tuple[float, float], notch_q: float,
               fs_hz: float = FCS_RATE_HZ) -> list[dict[str, list[float]]]:
    """Two 4th-order sections ``[{b, a}, {b, a}]`` (a₀ = 1) for one filter set."""
    b1, a1 = signal.butter(4, lowpass_hz, fs=fs_hz)
    bn1, an1 = signal.iirnotch(notch_hz[0], notch_q, fs=fs_hz)
    bn2, an2 = signal.iirnotch(notch_hz[1], notch_q, fs=fs_hz)
    b2, a2 = np.convolve(bn1, bn2), np.convolve(an1, an2)
    return [{"b": b1.tolist(), "a": a1.tolist()}, {"b": b2.tolist(), "a": a2.tolist()}]


def main() -> None:
    for name, spec in DESIGN.items():
        sections = design_set(spec["lowpass_hz"], spec["notch_hz"], spec["notch_q"])
        print(f"{name}:")
        for s in sections:
            print(f"  - b: [{', '.join(f'{v:.12g}' for v in s['b'])}]")
            print(f"    a: [{', '.join(f'{v:.12g}' for v in s['a'])}]")


if __name__ == "__main__":
    main()
