"""Design the gain schedules of ``conf/controller/msfc_pid.yaml`` (the default) and of
``conf/controller/larc_pd.yaml`` (the fly-off's alternative).

Along the reference ascent of :mod:`savant_cli.datagen.guidance_commands`, the rigid
pitch-plane model θ̈ = μα·α + μc·δ gives, at each schedule breakpoint,

* μc = T·l_c / I  (thrust, gimbal-to-CG arm, pitch inertia), 1/s²; while strap-on
  boosters are attached the mass properties hold each at its propellant on the
  reference's trace, and gimbaled boosters add their nozzles' moments through the control
  mixer (:func:`pitch_coefficients`);
* μα = ∂M_cg/∂α / I from the vehicle's aerodynamic tables (positive: unstable), 1/s².

A PD pole placement at natural frequency ω and damping ζ gives Kp = (ω² + μα)/μc and
Kd = 2ζω/μc; the integral gain is Ki = ω_i·Kp with ω_i = ``integral_ratio``·ω. The
attitude feedback Kp is shared between the navigation attitude error (1 − ``kir_share``)
and the integrated-rate path (``kir_share``), whose sum is the designed stiffness.

**First-stage tail-off.** From ``stack_design_end_before_separation_s`` before separation
the solid motor's thrust, hence μc, collapses (to ~3 % of its peak 0.5 s before
separation); a pole placement there would raise the gains without bound, into the bending
modes, the actuator and the tail-wags-dog zero. The stack schedule gets
``stack_tailoff_breakpoints`` more breakpoints at the reference's altitudes evenly spaced
in time from the design end to ``stack_tailoff_end_before_separation_s`` before
separation, where each gain is the pole placement's, capped at ``tailoff_kp_cap`` (the
attitude stiffness) and ``tailoff_kd_cap`` (the rate gain) times its value at the last
regular breakpoint, and the integral gain is 0: with the control power collapsing, the
integrator's phase lag at the falling crossover costs more margin than its trim is worth
(the trim it holds, a lateral CG offset over the gimbal arm, is ~0.1°).

**Coast and J-2X start.** Between separation and ignition the engine gives no thrust and
the nozzle no authority: the coast table is zero (the nozzle stays at null where
separation leaves it). From the ignition command the flight control fades its gains from
the coast table to the upper-stage table (``models/fcs.py::engagement``) over the engine's
thrust build-up, which :func:`ignition_fade` reads from the vehicle's start-transient
table: from its last zero-thrust time to the time it reaches rated thrust.

Design rules (:data:`CONTROLLERS`; each shipped file is ``study=fcs_design``'s tuning of
its rules, recorded in the file's ``design`` block):

* :data:`FIRST_ESTIMATE` (MSFC-like): PID, ω = 1.3 / 1.0 rad/s, ζ = 0.7, integral and
  integrated-rate paths, the rate-path flex filters of :mod:`.flex_filters` and the
  mode-nulling gyro blend; ``small_pid`` starts from it.
* ``msfc_pid`` (:data:`DESIGN`): the first estimate with the stack's values of an earlier
  ``study=fcs_design`` run on it, so the study starts there.
* :data:`PD_FIRST_ESTIMATE` (LaRC-like): PD only (Ki = Kir = 0, held fixed in the
  study), ω = 1.5 / 1.2 rad/s, ζ = 0.6, a lower low-pass corner (6 Hz) and wider notches
  (quality factor 1.0); ``small_pd`` starts from it.
* ``larc_pd`` (:data:`LARC_PD`): the PD first estimate with the stack's values of an
  earlier ``study=fcs_design`` run on it.

Run ``python -m savant_cli.datagen.fcs_gains [--controller larc_pd]`` to rewrite the YAML.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from savant_cli import constants
from savant_cli.datagen import flex_filters
from savant_cli.datagen.guidance_commands import _compose, solve
from savant_cli.models import aero, atmosphere as atm, boosters, cluster, earth, mass as mass_model, mixer

#: The first estimate of the MSFC-like design (the rigid-body pole placement and the
#: filters of :data:`.flex_filters.DESIGN`): where ``study=fcs_design`` began.
FIRST_ESTIMATE = {
    "name": "msfc_pid",
    "title": "MSFC-like gain-scheduled PID",
    "filters": None,  # flex_filters.DESIGN
    "stack": {"omega": 1.3, "zeta": 0.7},
    "upper": {"omega": 1.0, "zeta": 0.7},
    "integral_ratio": 0.15,
    "kir_share": 0.2,
    "stack_altitudes_m": [0, 1000, 3000, 6000, 9000, 12000, 15000, 20000, 30000, 40000, 50000],
    "upper_speeds_mps": [2000, 2500, 3000, 4000, 5000, 6000, 7000, 8000],
    # design window: before the first-stage tail-off (thrust, hence μc, collapses there
    # and a pole-placement gain would grow without bound) and after the J-2X start
    "stack_design_end_before_separation_s": 12.0,
    "upper_design_start_after_ignition_s": 5.0,
    # tail-off (module notes): breakpoints from the design end to this close to separation
    "stack_tailoff_breakpoints": 4,
    "stack_tailoff_end_before_separation_s": 0.5,
    "tailoff_kp_cap": 1.0,   # attitude stiffness, x its value at the last regular breakpoint
    "tailoff_kd_cap": 2.0,   # rate gain, likewise
}
#: msfc_pid's design rules: the first estimate with the stack's values from a
#: ``study=fcs_design`` run on it (docs/design_studies.md), so the study starts there.
DESIGN = {**FIRST_ESTIMATE,
          "stack": {"omega": 0.8782, "omega_end": 0.8518, "zeta": 0.8419, "integral_ratio": 0.155,
                    "kir_share": 0.2569, "tailoff_kp_cap": 1.465, "tailoff_kd_cap": 1.476},
          "stack_blend": [0.3465, 0.0, 0.6535],
          "filters": {"stack": {"lowpass_hz": 7.55, "notch_hz": (2.012, 5.674), "notch_q": (0.4, 2.601)},
                      "upper": flex_filters.DESIGN["upper"]}}
#: The PD first estimate (the small launcher's ``small_pd`` starts from it).
PD_FIRST_ESTIMATE = {**FIRST_ESTIMATE, "name": "larc_pd", "title": "LaRC-like gain-scheduled PD (no integral paths)",
                     "stack": {"omega": 1.5, "zeta": 0.6}, "upper": {"omega": 1.2, "zeta": 0.6},
                     "integral_ratio": 0.0, "kir_share": 0.0,
                     "fixed_parameters": ("integral_ratio", "kir_share"),  # a PD law: study=fcs_design keeps them 0
                     "filters": {"stack": {"lowpass_hz": 6.0, "notch_hz": (2.5, 4.5), "notch_q": 1.0},
                                 "upper": {"lowpass_hz": 6.0, "notch_hz": (9.5, 21.7), "notch_q": 1.0}}}
#: larc_pd's design rules: the PD first estimate with the stack's values from a
#: ``study=fcs_design`` run on it (docs/design_studies.md), so the study starts there.
LARC_PD = {**PD_FIRST_ESTIMATE,
           "stack": {"omega": 0.825, "omega_end": 0.9475, "zeta": 0.6465, "tailoff_kp_cap": 1.484,
                     "tailoff_kd_cap": 1.317},
           "stack_blend": [0.292, 0.0, 0.708],
           "filters": {"stack": {"lowpass_hz": 9.862, "notch_hz": (2.003, 5.457), "notch_q": (0.648, 2.764)},
                       "upper": PD_FIRST_ESTIMATE["filters"]["upper"]}}
#: The design rules by name (``--controller``, ``study.design``); the small launcher's
#: start from the first estimates (its own blend, its own search).
CONTROLLERS = {"msfc_pid": DESIGN, "larc_pd": LARC_PD,
               "small_pid": {**FIRST_ESTIMATE, "name": "small_pid"}, "small_pd": {**PD_FIRST_ESTIMATE, "name": "small_pd"}}


def _boosted_mass(ref, t: float, prop: float) -> tuple[np.ndarray, float]:
    """The CG (structure frame, m) and pitch inertia (kg·m², about the CG) of the liftoff
    configuration at ``t`` (s) with ``prop`` kg of the first stage's propellant and each
    strap-on booster at its own propellant on the reference's trace: the table's
    full-load booster rows exchanged as the flight exchanges them
    (``models/boosters.py::exchange``)."""
    packed, p = ref.packed, ref.params
    _, each_prop = ref.boosters.each_at(t)
    first_tank = int(p[boosters.P_TANK])
    x = np.zeros(first_tank + each_prop.size)
    x[first_tank:] = each_prop
    whole = boosters.exchange(x, p, packed, *mass_model.mass_properties(packed, 0, max(prop, 0.0)))
    return np.array(whole[1:4]), float(whole[5])


def _boosted_control_moment(ref, t: float, pres: float, cg: np.ndarray) -> float:
    """The pitch moment (N·m, about ``cg``) of one radian of the flight control's pitch
    command while gimbaled boosters are attached: the mixer's pitch column over the first
    stage's engines and the boosters' nozzles (``cluster.boosted_mixer``, at their rated
    thrusts) times each channel's moment effectiveness at the thrusts delivered at ``t``
    (s; the stage's share per engine and each booster's, on the reference's traces, less
    its exit area's back pressure ``pres`` Pa)."""
    v = ref.vehicle
    fs, b = v.first_stage, v.boosters
    gimbal, offsets, cants, _, _ = cluster.stage_geometry(v, 0)
    n = offsets.shape[0]
    f_stage = max(float(np.interp(t, ref.fs_time, ref.fs_thrust)) - pres * fs.nozzle_exit_area_m2, 0.0)
    each_vac, _ = ref.boosters.each_at(t)
    thrust = np.concatenate([np.full(n, f_stage / n), np.maximum(each_vac - pres * b.nozzle_exit_area_m2, 0.0)])
    effect, _ = cluster.effectiveness(np.concatenate([gimbal + offsets, b.nozzle_m]),
                                      np.concatenate([cants, b.cant_rad]), thrust, cg)
    k_pitch = cluster.boosted_mixer(v).reshape(-1, 3)[:, mixer.PITCH]  # each channel, pitch then yaw per engine
    return float(effect[1] @ k_pitch)


def pitch_coefficients(ref, t: float, y: np.ndarray, config: int) -> tuple[float, float]:
    """μα and μc (1/s²) of the rigid pitch plane at reference time ``t`` (s) and 3-DOF
    state ``y``, in configuration ``config``. While strap-on boosters are attached (the
    liftoff configuration) the mass properties hold each at its propellant on the
    reference's trace, and with gimbaled boosters μc is the pitch moment of one radian
    of the flight control's pitch command through the mixer over the stage's engines and
    the boosters' nozzles (:func:`_boosted_control_moment`); a booster without TVC adds
    no control moment."""
    packed = ref.packed
    v = ref.vehicle
    first_stage = config < v.first_stage_configurations
    boosted = ref.boosters is not None and config == 0
    prop = y[6] if first_stage else y[7] + y[8]
    if boosted:
        cg, iyy = _boosted_mass(ref, t, prop)
    else:
        _, cg, inertia = mass_model.inertia_tensor(packed, config, max(prop, 0.0))
        iyy = inertia[1, 1]
    r, vel = y[0:3], y[3:6]
    c_i2e = earth.dcm_eci_to_ecef(t, constants.OMEGA_EARTH)
    _, _, alt = earth.ecef_to_geodetic(c_i2e @ r, constants.WGS84_A, constants.WGS84_E2)
    _, pres, rho, sos = atm.air_at_packed(alt, packed)
    vv = np.linalg.norm(earth.velocity_relative_eci(r, vel, constants.OMEGA_EARTH))
    qbar = 0.5 * rho * vv * vv
    ref_row = aero.reference(packed, config)
    arm = -(ref_row[aero.REF_MRP_X] - cg[0])  # body-X arm of the MRP from the CG (structure X is aft)

    def m_cg(alpha):
        _, _, cn, _, cm, _ = aero.coefficients_at(packed, config, vv / sos, alpha, 0.0)
        # M_y about CG = qS l Cm + (r_mrp × F)_y with F_z = −qS CN
        return qbar * ref_row[aero.REF_AREA] * (ref_row[aero.REF_LY] * cm + arm * cn)

    da = np.radians(1.0)
    mu_alpha = (m_cg(da) - m_cg(-da)) / (2 * da) / iyy
    if boosted and v.boosters.tvc:
        return float(mu_alpha), _boosted_control_moment(ref, t, pres, cg) / iyy
    if first_stage:
        f_vac = np.interp(t, ref.fs_time, ref.fs_thrust)  # the reference's own trace (a throttled stage's law)
        thrust = f_vac - pres * v.first_stage.nozzle_exit_area_m2
        gimbal_x = v.first_stage.gimbal_m[0]
    else:
        thrust = v.upper_stage.thrust_vac_N - pres * v.upper_stage.nozzle_exit_area_m2
        gimbal_x = v.upper_stage.gimbal_m[0]
    mu_c = thrust * (gimbal_x - cg[0]) / iyy
    return float(mu_alpha), float(mu_c)


def ignition_fade(startup_time_s: np.ndarray, startup_fraction: np.ndarray) -> tuple[float, float]:
    """The upper-stage engine's thrust build-up (s after the ignition command): the last
    time its start-transient table gives zero thrust before the thrust rises, and the
    first time it reaches rated thrust (fraction 1). The flight control fades its gains in
    over this window (module notes).

    Parameters
    ----------
    startup_time_s : ndarray
        Start-transient times since the ignition command, s, increasing.
    startup_fraction : ndarray
        Fraction of rated thrust at those times.
    """
    t = np.asarray(startup_time_s, float)
    f = np.asarray(startup_fraction, float)
    rising = np.flatnonzero(f > 0.0)
    rated = np.flatnonzero(f >= 1.0)
    if rising.size == 0 or rated.size == 0:
        raise ValueError("the start-transient table must rise from 0 to rated thrust (fraction 1)")
    return float(t[max(rising[0] - 1, 0)]), float(t[rated[0]])


def design_points(cfg, vehicle, spec: dict = DESIGN) -> dict[str, list[tuple[float, float, float]]]:
    """Per schedule (``stack`` vs altitude, ``upper`` vs relative speed): the reference
    ascent's (t s, μα 1/s², μc 1/s²) at each breakpoint of ``spec``; key
    ``stack_tailoff``: (altitude m, t s, μα, μc) at the tail-off breakpoints; and key
    ``ignition_fade``: the engine's thrust build-up (:func:`ignition_fade`; module
    notes)."""
    ref, sols, turn, azimuth, steer, sol = solve(cfg, vehicle, verbose=False)
    # dense reference history
    ts, ys = [], []
    for s in (*sols, sol):
        tt = np.linspace(s.t[0], s.t[-1], 400)
        ts.append(tt)
        ys.append(s.sol(tt).T)
    t = np.concatenate(ts)
    y = np.concatenate(ys)
    alt = np.array([earth.ecef_to_geodetic(earth.dcm_eci_to_ecef(ti, constants.OMEGA_EARTH) @ yi[0:3], constants.WGS84_A, constants.WGS84_E2)[2]
                    for ti, yi in zip(t, y)])
    vrel = np.array([np.linalg.norm(earth.velocity_relative_eci(yi[0:3], yi[3:6], constants.OMEGA_EARTH)) for yi in y])
    points = {}
    for name, axis_vals, sel, var, config in (
        ("stack", spec["stack_altitudes_m"], t < ref.t_sep - spec["stack_design_end_before_separation_s"], alt,
         None),
        ("upper", spec["upper_speeds_mps"], t > ref.t_ign + spec["upper_design_start_after_ignition_s"], vrel,
         len(vehicle.configurations) - 1),
    ):
        points[name] = []
        for val in axis_vals:
            i = int(np.argmin(np.abs(np.where(sel, var, np.inf) - val)))
            flown = ref.config_at(t[i]) if config is None else config  # the upper stage's last configuration
            points[name].append((float(t[i]), *pitch_coefficients(ref, t[i], y[i], flown)))
    t_tail = np.linspace(ref.t_sep - spec["stack_design_end_before_separation_s"],
                         ref.t_sep - spec["stack_tailoff_end_before_separation_s"],
                         int(spec["stack_tailoff_breakpoints"]) + 1)[1:]
    points["stack_tailoff"] = []
    for tt in t_tail:
        i = int(np.argmin(np.abs(np.where(t < ref.t_sep, t, np.inf) - tt)))
        a = round(float(alt[i]), -2)  # a breakpoint to 100 m
        if a <= (points["stack_tailoff"][-1][0] if points["stack_tailoff"] else spec["stack_altitudes_m"][-1]):
            raise ValueError(f"tail-off breakpoint at {tt:.1f} s ({a:.0f} m) is not above the previous one")
        points["stack_tailoff"].append((a, float(t[i]), *pitch_coefficients(ref, t[i], y[i], ref.config_at(t[i]))))
    points["ignition_fade"] = ignition_fade(vehicle.upper_stage.startup_time_s, vehicle.upper_stage.startup_fraction)
    return points


def _pole_placement(w: float, z: float, mu_a: float, mu_c: float) -> tuple[float, float]:
    """Attitude stiffness (ω² + max(μα, 0))/μc and rate gain 2ζω/μc of the rigid pitch
    plane at natural frequency ``w`` (rad/s) and damping ``z``."""
    return (w * w + max(mu_a, 0.0)) / mu_c, 2.0 * z * w / mu_c


def gain_tables(points: dict[str, list[tuple[float, float, float]]], spec: dict = DESIGN) -> dict:
    """The pole-placement gain tables of ``spec`` at the design points of
    :func:`design_points`: per schedule the natural frequency ``omega`` (rad/s; with
    ``omega_end``, linear in the breakpoint index from ``omega`` at the first breakpoint
    to ``omega_end`` at the last) and damping ``zeta``, and ``integral_ratio`` and
    ``kir_share`` (the schedule's own when given, else the spec's). The stack's tail-off
    breakpoints (``points["stack_tailoff"]``, if any) follow: the pole placement at the
    last ω, each gain capped at ``tailoff_kp_cap`` / ``tailoff_kd_cap`` (the stack's own,
    else the spec's) times its last regular value, Ki = 0 (module notes). Key
    ``ignition_fade``, when the points have it, is theirs (the writer needs it)."""
    tables = {"ignition_fade": tuple(points["ignition_fade"])} if "ignition_fade" in points else {}
    for name, axis_key in (("stack", "stack_altitudes_m"), ("upper", "upper_speeds_mps")):
        d = spec[name]
        z = d["zeta"]
        share = d.get("kir_share", spec["kir_share"])
        ratio = d.get("integral_ratio", spec["integral_ratio"])
        n = len(points[name])
        omegas = np.linspace(d["omega"], d.get("omega_end", d["omega"]), n) if n > 1 else [d["omega"]]
        breakpoints = list(map(float, spec[axis_key]))
        k_att, kd, ki = [], [], []
        for w, (_, mu_a, mu_c) in zip(omegas, points[name]):
            k, d_gain = _pole_placement(w, z, mu_a, mu_c)
            k_att.append(k)
            kd.append(d_gain)
            ki.append(ratio * w * k)
        design = list(points[name])
        if name == "stack" and points.get("stack_tailoff"):
            cap_p = d.get("tailoff_kp_cap", spec["tailoff_kp_cap"]) * k_att[n - 1]
            cap_d = d.get("tailoff_kd_cap", spec["tailoff_kd_cap"]) * kd[n - 1]
            w = omegas[-1]
            for alt, t, mu_a, mu_c in points["stack_tailoff"]:
                k, d_gain = _pole_placement(w, z, mu_a, mu_c)
                breakpoints.append(float(alt))
                k_att.append(min(k, cap_p))
                kd.append(min(d_gain, cap_d))
                ki.append(0.0)
                design.append((t, mu_a, mu_c))
        tables[name] = {"breakpoints": breakpoints, "kp": [k * (1.0 - share) for k in k_att], "ki": ki, "kd": kd,
                        "kir": [k * share for k in k_att], "design_points": design}
    return tables


def design(cfg, vehicle, spec: dict = DESIGN) -> dict:
    """Gain tables for the stack (vs altitude) and the upper stage (vs relative speed)."""
    return gain_tables(design_points(cfg, vehicle, spec), spec)


def _fmt(vals) -> str:
    return "[" + ", ".join(f"{v:.4g}" for v in vals) + "]"


def controller_yaml(tables: dict, stack_blend: list[float], spec: dict = DESIGN, vehicle: str = "ares_i",
                    design: dict | None = None) -> str:
    """The whole controller YAML text of the design ``spec`` for the vehicle named
    ``vehicle`` (the spec's own ``stack_blend``, when it has one, replaces
    ``stack_blend``); ``design`` (``{"rules": name, "parameters": {(schedule, name):
    value}}``, from ``study=fcs_design``) becomes the ``design`` block, values written to
    round-trip exactly."""
    stack_blend = list(spec.get("stack_blend") or stack_blend)
    made_by = (f"`savant run study=fcs_design study.design={design['rules']}` (the values in `design`"
               if design else f"`python -m savant_cli.datagen.fcs_gains --controller {spec['name']}` (gains and filters")
    lines = [
        f"# {spec['title']} pitch/yaw control with flex filters and rate blending,",
        "# and phase-plane roll control (source paper III.F). Generated by",
        f"# {made_by},",
        "# design rules in savant_cli.datagen.fcs_gains and .flex_filters). Units: Kp and Kir",
        "# rad/rad, Ki 1/s, Kd s.",
        f"name: {spec['name']}",
        f"vehicle: {vehicle:<18} # designed for this vehicle; another is refused ...",
        "allow_other_vehicle: false # ... unless this is true",
        "delay_s: 0.005       # loop delay, sensor sample to actuator command, s (computation + output) [E]",
        "blending:            # weights of [upper-stage gyro, IMU, first-stage gyro]; sum to 1",
        f"  stack: {_fmt(stack_blend)}   # " + ("tuned by study=fcs_design" if spec.get("stack_blend")
                                            else "nulls the first bending mode (flex_filters.stack_blend)"),
        "  upper: [1.0, 0.0, 0.0]",
        "flex_filters:        # two 4th-order discrete sections in series per path, at 50 Hz",
    ]
    for name, fspec in (spec["filters"] or flex_filters.DESIGN).items():
        sections = flex_filters.design_set(fspec["lowpass_hz"], fspec["notch_hz"], fspec["notch_q"])
        lines.append(f"  {name}:")
        for path in ("rate", "integrated_rate", "roll"):
            lines.append(f"    {path}:")
            for s in sections:
                lines.append(f"      - b: [{', '.join(f'{v:.12g}' for v in s['b'])}]")
                lines.append(f"        a: [{', '.join(f'{v:.12g}' for v in s['a'])}]")
    lines.append("gains:")
    for name, schedule, src in (("stack", "altitude_m", "stack"), ("coast", "velocity_mps", "upper"),
                                ("upper", "velocity_mps", "upper")):
        tb = tables[src]
        lines.append(f"  {name}:")
        if name == "coast":
            lines.append("    # no thrust in the coast: no authority, the nozzle held at null (zero gains);")
            lines.append("    # from ignition the gains fade to the upper-stage table (ignition_fade)")
        lines.append(f"    schedule: {schedule}")
        lines.append(f"    breakpoints: {_fmt(tb['breakpoints'])}")
        lines.append("    pitch:")
        for g in ("kp", "ki", "kd", "kir"):
            lines.append(f"      {g}: {_fmt([0.0] * len(tb[g]) if name == 'coast' else tb[g])}")
        lines.append("    yaw: ${.pitch}")
        if name != "coast":
            lines.append("    # design points (t s, mu_alpha 1/s^2, mu_c 1/s^2): " +
                         "; ".join(f"{a:.0f} {b:.3f} {c:.3f}" for a, b, c in tb["design_points"]))
    fade = tables["ignition_fade"]
    lines += [
        "ignition_fade:       # gains from the coast table to the upper stage's, s after the ignition",
        f"  start_s: {fade[0]!r}        # command: the engine's thrust build-up (vehicle start-transient table)",
        f"  end_s: {fade[1]!r}",
        "roll:                # phase plane of roll error vs roll-rate error",
        "  attitude_deadband_deg: 1.0",
        "  rate_deadband_deg_s: 1.0",
        "  lead_time_s: 2.0",
        "  gimbal:             # roll by the engines' gimbals, a cluster's (docs/models.md): none",
        "    stack: {kp: 0.0, ki: 0.0, kd: 0.0}",
        "    upper: {kp: 0.0, ki: 0.0, kd: 0.0}",
    ]
    if design:
        lines += ["design:              # how this file was made (provenance; the flight uses the tables above)",
                  f"  rules: {design['rules']}", "  parameters:"]
        for sched in dict.fromkeys(s for s, _ in design["parameters"]):
            lines.append(f"    {sched}:")
            lines += [f"      {n}: {float(v)!r}" for (s, n), v in design["parameters"].items() if s == sched]
    return "\n".join(lines + [""])


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("overrides", nargs="*")
    ap.add_argument("--controller", choices=sorted(CONTROLLERS), default="msfc_pid", help="design rules")
    ap.add_argument("--name", default=None, help="controller name (default: the design's); names the YAML")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args(argv)
    from savant_cli.io.atomic import write_text_atomic
    from savant_cli.paths import resolve_data_path, shipped_config_dir
    from savant_cli.vehicle import load_vehicle

    cfg = _compose(args.overrides)
    vdir = resolve_data_path("vehicle.data_dir", "vehicle", cfg.vehicle["data_dir"], [shipped_config_dir()], must_be_dir=True)
    vehicle = load_vehicle(cfg.vehicle, vdir)
    spec = {**CONTROLLERS[args.controller], **({"name": args.name} if args.name else {})}
    text = controller_yaml(design(cfg, vehicle, spec), flex_filters.vehicle_stack_blend(cfg.vehicle, vdir), spec,
                           cfg.vehicle["name"])
    out = args.out or shipped_config_dir() / "controller" / f"{spec['name']}.yaml"
    write_text_atomic(out, text)
    print(text)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
