"""The flex filters' first estimate, and the filter sections of every controller.

Each flight-control path carries two fourth-order discrete sections in series (source
paper §III.F), designed with scipy at the 50 Hz control rate (:func:`design_set`). The
shipped controllers' filter values are tuned by ``study=fcs_design`` (their ``design``
blocks; docs/design_studies.md); :data:`DESIGN` is the first estimate it started from:

* section 1: 4th-order Butterworth low-pass, gain-stabilizing everything above its
  corner (8 Hz on both stages);
* section 2: a pair of second-order notches at bending frequencies: on the stack the
  second and third estimated modes (2.5 / 4.5 Hz, quality factor 1.5; the beam model of
  ``datagen.ares_i_flex`` gives 2.5 / 5.0 Hz); on the upper stage the beam model's first
  and second bending modes at ignition (9.5 / 21.7 Hz, quality factor 1.0: wide enough
  for the rise toward burnout). With the earlier 6 / 9 Hz estimates the 9.5 Hz mode
  limit-cycled at the valve-flow limit with the simplex actuator and tail-wags-dog on.

The integrated-stack rate blending nulls the first bending mode instead of filtering it
(:func:`stack_blend`): the first-stage gyro sits aft of the mode's antinode, where its
slope has the opposite sign to the upper-stage gyro's, and the weights make the blended
slope zero. The mode (~1 Hz, modal gain far too high to gain-stabilize next to a 0.2 Hz
rigid-body loop) then barely enters the rate feedback; the attitude path's lag damps it.

Run ``python -m savant_cli.datagen.flex_filters`` to print the YAML block.
"""

from __future__ import annotations

import numpy as np
from scipy import signal

from savant_cli.errors import ConfigError

FCS_RATE_HZ = 50.0
DESIGN = {
    "stack": {"lowpass_hz": 8.0, "notch_hz": (2.5, 4.5), "notch_q": 1.5},
    "upper": {"lowpass_hz": 8.0, "notch_hz": (9.5, 21.7), "notch_q": 1.0},
}


def design_set(lowpass_hz: float, notch_hz: tuple[float, float], notch_q: float | tuple[float, float],
               fs_hz: float = FCS_RATE_HZ) -> list[dict[str, list[float]]]:
    """Two 4th-order sections ``[{b, a}, {b, a}]`` (a₀ = 1) for one filter set: a
    Butterworth low-pass at ``lowpass_hz``, and two notches at ``notch_hz`` with quality
    factors ``notch_q`` (one for both, or one each)."""
    q1, q2 = (notch_q, notch_q) if np.isscalar(notch_q) else notch_q
    b1, a1 = signal.butter(4, lowpass_hz, fs=fs_hz)
    bn1, an1 = signal.iirnotch(notch_hz[0], q1, fs=fs_hz)
    bn2, an2 = signal.iirnotch(notch_hz[1], q2, fs=fs_hz)
    b2, a2 = np.convolve(bn1, bn2), np.convolve(an1, an2)
    return [{"b": b1.tolist(), "a": a1.tolist()}, {"b": b2.tolist(), "a": a2.tolist()}]


def stack_blend(slope_upper: float, slope_first: float) -> list[float]:
    """Blend weights ``[upper-stage gyro, IMU, first-stage gyro]`` with
    ``w_u σ_u + w_f σ_f = 0`` and ``w_u + w_f = 1`` for the first mode's slopes σ (rad per
    unit modal coordinate, same axis) at the two gyros; rounded to 3 decimals."""
    if slope_upper * slope_first >= 0.0:
        raise ValueError("the gyros' slopes must have opposite signs to null the mode with positive weights")
    w_first = round(slope_upper / (slope_upper - slope_first), 3)
    return [round(1.0 - w_first, 3), 0.0, w_first]


def stack_liftoff_set(vehicle_cfg) -> str:
    """The stack's liftoff modal set of a vehicle section: ``first_stage_liftoff``, or
    with ``flex.sets`` the first set of the first configuration (in the file's order)
    that carries no strap-on booster."""
    sets = vehicle_cfg["flex"].get("sets")
    if not sets:
        return "first_stage_liftoff"
    boosters = set(vehicle_cfg.get("boosters") or ())
    for name, config in vehicle_cfg["configurations"].items():
        if not boosters & set(config.get("parts") or ()) and name in sets:
            return str(sets[name][0]["set"])
    raise ConfigError("vehicle.flex.sets", list(sets), "the stack without boosters needs its sets")


def vehicle_stack_blend(vehicle_cfg, vehicle_dir) -> list[float]:
    """:func:`stack_blend` for a vehicle's stack liftoff modal set (pitch plane,
    :func:`stack_liftoff_set`)."""
    from pathlib import Path

    from savant_cli.io.modal_data import read_modal_set

    spec = vehicle_cfg["flex"]
    units = (spec["units"]["length"], spec["units"]["force"])
    ms = read_modal_set(Path(vehicle_dir) / spec["directory"], stack_liftoff_set(vehicle_cfg), units, "vehicle.flex")
    nodes = spec["nodes"]
    first_pitch_mode = ms.at_nodes(list(nodes["rate_gyro_upper_stage"]), "")[:, 4] != 0.0
    mode = int(np.argmax(first_pitch_mode))  # lowest mode with a pitch (body y) rotation
    s_u = ms.at_nodes(list(nodes["rate_gyro_upper_stage"]), "vehicle.flex.nodes.rate_gyro_upper_stage")[mode, 4]
    s_f = ms.at_nodes(list(nodes["rate_gyro_first_stage"]), "vehicle.flex.nodes.rate_gyro_first_stage")[mode, 4]
    return stack_blend(float(s_u), float(s_f))


def main() -> None:
    for name, spec in DESIGN.items():
        sections = design_set(spec["lowpass_hz"], spec["notch_hz"], spec["notch_q"])
        print(f"{name}:")
        for s in sections:
            print(f"  - b: [{', '.join(f'{v:.12g}' for v in s['b'])}]")
            print(f"    a: [{', '.join(f'{v:.12g}' for v in s['a'])}]")


if __name__ == "__main__":
    main()
