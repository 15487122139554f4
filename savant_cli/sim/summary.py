"""Scalar results of one run (the keys of ``summary.json``, documented in
docs/outputs.md)."""

from __future__ import annotations

import numpy as np

from savant_cli import constants
from savant_cli.io.record import Signal
from savant_cli.models import boosters, peg, propulsion
from savant_cli.models.layout import U_FS_T_CUT, U_T_CUT
from savant_cli.sim import engine
from savant_cli.sim.run import SimResult
from savant_cli.vehicle.two_stage import usable_load


def orbit_elements(r_eci: np.ndarray, v_eci: np.ndarray, mu: float = constants.MU_EARTH) -> dict[str, float]:
    """Osculating two-body orbit of an inertial state.

    Apsis altitudes are measured from the WGS84 equatorial radius. Inclination from the
    angular-momentum vector (ECI Z is the spin axis).
    """
    r = np.linalg.norm(r_eci)
    v = np.linalg.norm(v_eci)
    h = np.cross(r_eci, v_eci)
    energy = 0.5 * v * v - mu / r
    e_vec = np.cross(v_eci, h) / mu - r_eci / r
    e = float(np.linalg.norm(e_vec))
    inc = float(np.degrees(np.arccos(np.clip(h[2] / np.linalg.norm(h), -1.0, 1.0))))
    if energy < 0.0:
        a = -mu / (2.0 * energy)
        rp, ra = a * (1.0 - e), a * (1.0 + e)
    else:
        a, rp, ra = np.inf, float(np.linalg.norm(h) ** 2 / mu / (1.0 + e)), np.inf
    return {"semi_major_axis_m": float(a), "eccentricity": e, "inclination_deg": inc,
            "perigee_altitude_km": (rp - constants.WGS84_A) / 1e3, "apogee_altitude_km": (ra - constants.WGS84_A) / 1e3}


def _event(result: SimResult, slot: int) -> float | None:
    v = result.events[slot]
    return None if np.isnan(v) else float(v)


def _on_time(t: np.ndarray, command: np.ndarray) -> float:
    """Total time (s) a jet command is on (|command| ≥ 0.5), by the log's sample spacing."""
    if t.size < 2:
        return 0.0
    dt = np.diff(t, append=t[-1])
    return float(np.sum(dt[np.abs(command) >= 0.5]))


#: the keys of :func:`insertion_errors`
INSERTION_KEYS = ("insertion_radius_error_m", "insertion_speed_error_mps", "insertion_flight_path_angle_error_deg",
                  "insertion_velocity_error_mps", "insertion_perigee_error_km", "insertion_apogee_error_km",
                  "insertion_inclination_error_deg", "insertion_node_error_deg")


def radius_speed_gamma(r_eci: np.ndarray, v_eci: np.ndarray) -> tuple[float, float, float]:
    """Radius (m), inertial speed (m/s) and flight-path angle (rad, above the local
    horizontal) of an ECI state."""
    r = float(np.linalg.norm(r_eci))
    v = float(np.linalg.norm(v_eci))
    return r, v, float(np.arcsin(np.clip(np.dot(r_eci, v_eci) / (r * v), -1.0, 1.0)))


def insertion_errors(r_eci: np.ndarray, v_eci: np.ndarray, target) -> dict[str, float]:
    """The cutoff state against the insertion target (:class:`savant_cli.models.peg.InsertionTarget`).

    Radius, speed and flight-path angle errors; the velocity error ``|v − v_d|`` against
    the target velocity at the cutoff position (target speed and flight-path angle, in the
    target plane: what a perfect cutoff still had to gain or lose); perigee, apogee,
    inclination and node (right ascension of the ascending node, ECI at liftoff) of the
    osculating two-body orbit against the target orbit's.
    """
    r, v, gamma = radius_speed_gamma(r_eci, v_eci)
    n = target.plane_normal
    ix = r_eci / r
    iz = np.cross(n, ix)  # downrange in the target plane, normal to r
    iz /= np.linalg.norm(iz)
    ix = np.cross(iz, n)  # the in-plane vertical nearest the actual one
    v_d = target.speed_mps * (np.sin(target.flight_path_angle_rad) * ix + np.cos(target.flight_path_angle_rad) * iz)
    orbit = orbit_elements(r_eci, v_eci)
    rp, ra = target.apsis_altitudes_km
    h = np.cross(r_eci, v_eci)
    node = float(np.arctan2(h[0], -h[1]))
    d_node = float(np.degrees(np.angle(np.exp(1j * (node - target.node_rad)))))
    return {
        "insertion_radius_error_m": r - target.radius_m,
        "insertion_speed_error_mps": v - target.speed_mps,
        "insertion_flight_path_angle_error_deg": float(np.degrees(gamma - target.flight_path_angle_rad)),
        "insertion_velocity_error_mps": float(np.linalg.norm(v_eci - v_d)),
        "insertion_perigee_error_km": orbit["perigee_altitude_km"] - rp,
        "insertion_apogee_error_km": orbit["apogee_altitude_km"] - ra,
        "insertion_inclination_error_deg": orbit["inclination_deg"] - float(np.degrees(target.inclination_rad)),
        "insertion_node_error_deg": d_node,
    }


#: the keys of :func:`load_indicators`
LOAD_KEYS = ("time_max_qalpha_s", "max_qalpha_pitch_Pa_deg", "time_max_qalpha_pitch_s", "max_qbeta_Pa_deg",
             "time_max_qbeta_s", "qalpha_limit_Pa_deg", "qalpha_limit_ratio", "time_above_qalpha_limit_s",
             "qalpha_limit_exceeded")


def load_indicators(t: np.ndarray, qbar: np.ndarray, alpha: np.ndarray, beta: np.ndarray,
                    qalpha_total: np.ndarray, limit: float | None) -> dict[str, float | int | None]:
    """Aerodynamic load indicators of the logged flight (Pa·deg, s).

    ``max_qalpha_pitch_Pa_deg``: max of q·|α| (pitch plane); ``max_qbeta_Pa_deg``: max of
    q·|β| (yaw plane); with ``max_qalpha_Pa_deg`` (the total, q·α_total with
    cos α_total = cos α cos β) each with its time. Against the vehicle's allowable
    ``limit`` on the total (``vehicle.loads.qalpha_limit_Pa_deg``; None: no limit, the
    four limit keys None): the ratio max/limit, the time the total spends above the limit
    (by the log's sample spacing) and ``qalpha_limit_exceeded`` (1 when the maximum is
    above it, else 0)."""
    qa = qbar * np.abs(np.degrees(alpha))
    qb = qbar * np.abs(np.degrees(beta))
    i_t, i_a, i_b = int(np.argmax(qalpha_total)), int(np.argmax(qa)), int(np.argmax(qb))
    out: dict[str, float | int | None] = {
        "time_max_qalpha_s": float(t[i_t]),
        "max_qalpha_pitch_Pa_deg": float(qa[i_a]), "time_max_qalpha_pitch_s": float(t[i_a]),
        "max_qbeta_Pa_deg": float(qb[i_b]), "time_max_qbeta_s": float(t[i_b]),
        "qalpha_limit_Pa_deg": None, "qalpha_limit_ratio": None, "time_above_qalpha_limit_s": None,
        "qalpha_limit_exceeded": None}
    if limit is not None:
        dt = np.diff(t, append=t[-1]) if t.size > 1 else np.zeros(t.size)
        peak = float(qalpha_total[i_t])
        out.update({"qalpha_limit_Pa_deg": float(limit), "qalpha_limit_ratio": peak / float(limit),
                    "time_above_qalpha_limit_s": float(np.sum(dt[qalpha_total > limit])),
                    "qalpha_limit_exceeded": int(peak > limit)})
    return out


def total_alpha_deg(alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """Total angle of attack (deg) from the angle of attack and sideslip (rad):
    ``cos α_total = cos α cos β``."""
    return np.degrees(np.arccos(np.clip(np.cos(alpha) * np.cos(beta), -1.0, 1.0)))


#: the keys of :func:`separation_state`
SEPARATION_KEYS = ("separation_body_rate_deg_s", "separation_attitude_error_deg", "separation_qalpha_Pa_deg")


def separation_state(t: np.ndarray, body_rate: np.ndarray, attitude_error: np.ndarray, qalpha_total: np.ndarray,
                     t_sep: float | None) -> dict[str, float | None]:
    """The vehicle's state at first-stage separation: the logged sample at the separation
    step (the last one at or before ``t_sep``, s): body-rate magnitude |ω| (deg/s, body
    axes, all three), pitch/yaw attitude-error magnitude (deg) and total q·α (Pa·deg).
    None without a separation."""
    if t_sep is None or t.size == 0 or t_sep < t[0]:
        return dict.fromkeys(SEPARATION_KEYS)
    i = int(np.searchsorted(t, t_sep, side="right")) - 1
    return {"separation_body_rate_deg_s": float(np.degrees(np.linalg.norm(body_rate[i]))),
            "separation_attitude_error_deg": float(np.degrees(np.linalg.norm(attitude_error[i, 1:3]))),
            "separation_qalpha_Pa_deg": float(qalpha_total[i])}


def usable_propellant(lox_kg: float, lh2_kg: float, mixture_ratio: float) -> tuple[float, float, str]:
    """Usable and unusable upper-stage propellant (kg) and the limiting propellant.

    The engine burns LOX : LH2 at ``mixture_ratio`` (MR) by mass, so of ``lox_kg`` (L)
    and ``lh2_kg`` (H) it can still burn ``min(L, MR H) (1 + 1/MR)``; the rest of the other
    tank is unusable. The limiting propellant is ``"lox"`` when ``L ≤ MR H`` (LOX runs out
    first), else ``"lh2"``.
    """
    lox, lh2 = max(float(lox_kg), 0.0), max(float(lh2_kg), 0.0)
    usable = usable_load(mixture_ratio, lox, lh2)
    return usable, lox + lh2 - usable, "lox" if lox <= mixture_ratio * lh2 else "lh2"


#: the keys of :func:`propulsion_keys`
PROPULSION_KEYS = ("usable_propellant_remaining_kg", "unusable_propellant_kg", "limiting_propellant",
                   "first_stage_propellant_at_separation_kg", "first_stage_total_impulse_Ns", "shutdown_impulse_Ns")


def propulsion_keys(result: SimResult, p: np.ndarray) -> dict[str, float | str | None]:
    """Propellant and impulse figures of a run from its final state and discrete state.

    ``usable_propellant_remaining_kg``, ``unusable_propellant_kg`` and
    ``limiting_propellant`` (:func:`usable_propellant`) of the final LOX and LH2 at the
    run's engine mixture ratio ``p[P_US_MR]``; ``first_stage_propellant_at_separation_kg``
    (None without a separation) and ``first_stage_total_impulse_Ns``, the vacuum impulse
    the first stage delivered to the vehicle up to separation (the sequencer's
    trapezoid of the sensed thrust at the plant rate); ``shutdown_impulse_Ns``, the
    upper-stage vacuum impulse delivered after the cutoff command (the same trapezoid over
    the shutdown transient; None without a cutoff command)."""
    x, d = result.x, result.d
    lox, lh2 = propulsion.upper_stage_propellant(x, p)
    usable, unusable, limiting = usable_propellant(lox, lh2, p[propulsion.P_US_MR])
    separated = not np.isnan(result.events[engine.EV_SEPARATION])
    at_sep = d[propulsion.D_FS_PROP_SEP] if separated else np.nan
    return {"usable_propellant_remaining_kg": usable, "unusable_propellant_kg": unusable,
            "limiting_propellant": limiting,
            "first_stage_propellant_at_separation_kg": None if np.isnan(at_sep) else float(at_sep),
            "first_stage_total_impulse_Ns": float(d[propulsion.D_FS_IMPULSE]),
            "shutdown_impulse_Ns": float(d[propulsion.D_US_SD_IMPULSE]) if result.u[U_T_CUT] > 0.0 else None}


def first_stage_cutoff_keys(result: SimResult) -> dict[str, float | str | None]:
    """A liquid first stage's shutdown: ``time_first_stage_cutoff_s`` (None: its engines
    still burned at the end of the run) and ``first_stage_shutdown``, ``"guidance"`` (PEG
    commanded it: ``guidance.peg.first_stage_burn``), ``"commanded"`` (by its cutoff
    event) or ``"depletion"`` (a tank ran dry first: no propellant reserve at the
    cutoff)."""
    t_cut = _event(result, engine.EV_FS_CUTOFF)
    how = None if t_cut is None else "guidance" if result.d[peg.D_FS_COMMANDED] != 0.0 \
        else "commanded" if result.u[U_FS_T_CUT] > 0.0 else "depletion"
    return {"time_first_stage_cutoff_s": t_cut, "first_stage_shutdown": how}


#: The guided first-stage burn's keys (:func:`first_stage_burn_errors`).
FIRST_STAGE_BURN_KEYS = ("first_stage_burn_radius_error_m", "first_stage_burn_speed_error_mps",
                         "first_stage_burn_flight_path_angle_error_deg")


#: The upper stage's first burn's keys (:func:`upper_stage_first_burn_errors`).
UPPER_STAGE_FIRST_BURN_KEYS = ("upper_stage_first_burn_radius_error_m", "upper_stage_first_burn_speed_error_mps",
                               "upper_stage_first_burn_flight_path_angle_error_deg")


def first_stage_burn_errors(result: SimResult, sig: dict[str, Signal], p: np.ndarray) -> dict[str, float | None]:
    """A guided first-stage burn (``guidance.peg.first_stage_burn``) against its target: the
    radius, inertial speed and flight-path angle at the end of the stage's thrust (the
    first logged sample at or after its cutoff plus its shutdown transient) less the
    target's; None when the stage was not cut off, or the run ended before the transient
    did."""
    return _burn_errors(_event(result, engine.EV_FS_CUTOFF), p[propulsion.P_FS_SHUTDOWN_TIME], sig,
                        p[peg.P_FS_TARGET:peg.P_FS_TARGET + 3], FIRST_STAGE_BURN_KEYS)


def upper_stage_first_burn_errors(result: SimResult, sig: dict[str, Signal], p: np.ndarray) -> dict[str, float | None]:
    """A restarting upper stage's first burn (``guidance.peg.upper_stage_first_burn``)
    against its target, as :func:`first_stage_burn_errors`: at the end of its thrust after
    its first cutoff."""
    return _burn_errors(_event(result, engine.EV_US_CUTOFF), p[propulsion.P_US_SHUTDOWN_TIME], sig,
                        p[peg.P_US1_TARGET:peg.P_US1_TARGET + 3], UPPER_STAGE_FIRST_BURN_KEYS)


def _burn_errors(t_cut: float | None, shutdown_s: float, sig: dict[str, Signal], target: np.ndarray,
                 keys: tuple[str, str, str]) -> dict[str, float | None]:
    """Radius (m), inertial speed (m/s) and flight-path angle (deg) less ``target``'s (m,
    m/s, rad) at the first logged sample at or after ``t_cut + shutdown_s`` (s); None
    without a cutoff, or when the run ended before that."""
    t = sig["time"].data
    if t_cut is None or t[-1] < t_cut + shutdown_s:
        return dict.fromkeys(keys)
    i = int(np.searchsorted(t, t_cut + shutdown_s - 1e-9))
    r, v, gamma = radius_speed_gamma(sig["position_eci"].data[i], sig["velocity_eci"].data[i])
    r_d, v_d, gamma_d = target
    return dict(zip(keys, (float(r - r_d), float(v - v_d), float(np.degrees(gamma - gamma_d)))))


def upper_stage_restart_keys(result: SimResult) -> dict[str, float | str | None]:
    """A restarting upper stage: ``time_upper_stage_cutoff_s`` (its first burn's cutoff
    command), ``upper_stage_first_shutdown`` (``"guidance"``: PEG commanded it,
    ``"commanded"``: the vehicle's backup event did, None: none) and
    ``time_upper_stage_restart_s`` (None: not restarted by the end of the run)."""
    t_cut = _event(result, engine.EV_US_CUTOFF)
    how = None if t_cut is None else "guidance" if result.d[peg.D_US1_COMMANDED] != 0.0 else "commanded"
    return {"time_upper_stage_cutoff_s": t_cut, "upper_stage_first_shutdown": how,
            "time_upper_stage_restart_s": _event(result, engine.EV_RESTART)}


def booster_keys(result: SimResult) -> dict[str, float | None]:
    """Strap-on boosters' jettison: ``time_booster_jettison_s`` and
    ``booster_propellant_at_jettison_kg`` (their propellant left then, summed; both None
    while they are still attached at the end of the run)."""
    t_jet = _event(result, engine.EV_BOOSTER_JETTISON)
    return {"time_booster_jettison_s": t_jet,
            "booster_propellant_at_jettison_kg": None if t_jet is None else float(result.d[boosters.D_PROP_JET])}


#: the keys of :func:`navigation_keys`
NAVIGATION_KEYS = ("navigation_position_error_m", "navigation_velocity_error_mps", "navigation_attitude_error_deg",
                   "navigated_perigee_altitude_km", "navigated_apogee_altitude_km", "navigated_inclination_deg")


def navigation_keys(r_f: np.ndarray, v_f: np.ndarray, sig: dict[str, Signal]) -> dict[str, float]:
    """The inertial navigation's errors at the end of the run (``navigation=inertial``):
    the magnitudes of the position, velocity and attitude errors (navigated minus true),
    and the orbit the flight software believed it reached, from the navigated state
    ``r_f + δr``, ``v_f + δv`` (ECI)."""
    dr = sig["navigation_position_error"].data[-1]
    dv = sig["navigation_velocity_error"].data[-1]
    phi = sig["navigation_attitude_error"].data[-1]
    believed = orbit_elements(r_f + dr, v_f + dv)
    return {"navigation_position_error_m": float(np.linalg.norm(dr)),
            "navigation_velocity_error_mps": float(np.linalg.norm(dv)),
            "navigation_attitude_error_deg": float(np.degrees(np.linalg.norm(phi))),
            "navigated_perigee_altitude_km": believed["perigee_altitude_km"],
            "navigated_apogee_altitude_km": believed["apogee_altitude_km"],
            "navigated_inclination_deg": believed["inclination_deg"]}


def summarize(result: SimResult, sig: dict[str, Signal], study_wall_s: float | None = None,
              target=None, qalpha_limit: float | None = None, p: np.ndarray | None = None) -> dict:
    """Summary scalars of a run (SI units named in the keys); ``target`` (an
    :class:`~savant_cli.models.peg.InsertionTarget`) adds the insertion errors at cutoff
    (None when the run did not cut off); ``qalpha_limit`` (Pa·deg) the vehicle's q·α
    allowable the load indicators are judged against (:func:`load_indicators`); ``p``
    (the run's plant parameters) adds the propellant and impulse keys
    (:func:`propulsion_keys`)."""
    t = sig["time"].data
    out: dict[str, float | int | str | None] = {"status": result.status, "message": result.message}
    if t.size == 0:
        return out
    qbar = sig["dynamic_pressure"].data
    i_q = int(np.argmax(qbar))
    alpha_total = total_alpha_deg(sig["alpha"].data, sig["beta"].data)
    # aerodynamic angles mean little once the air is gone: report them where q > 1 kPa
    dense = qbar > 1000.0
    gimbal = np.degrees(np.abs(sig["gimbal_angle"].data))
    att_err = np.degrees(np.linalg.norm(sig["attitude_error"].data[:, 1:3], axis=1))
    att_err_roll = np.degrees(np.abs(sig["attitude_error"].data[:, 0]))
    r_f = sig["position_eci"].data[-1]
    v_f = sig["velocity_eci"].data[-1]
    orbit = orbit_elements(r_f, v_f)
    qalpha_total = qbar * alpha_total
    out.update({
        "max_dynamic_pressure_Pa": float(qbar[i_q]),
        "time_max_dynamic_pressure_s": float(t[i_q]),
        "mach_at_max_dynamic_pressure": float(sig["mach"].data[i_q]),
        "altitude_at_max_dynamic_pressure_m": float(sig["altitude"].data[i_q]),
        "max_alpha_deg": float(alpha_total[dense].max()) if dense.any() else 0.0,
        "max_qalpha_Pa_deg": float(np.max(qalpha_total)),
        "max_gimbal_deg": float(gimbal.max()),
        "max_gimbal_rate_deg_s": float(np.degrees(np.abs(sig["gimbal_rate"].data)).max()),
        "max_attitude_error_deg": float(att_err.max()),
        "rms_attitude_error_deg": float(np.sqrt(np.mean(att_err * att_err))),
        "rcs_on_time_s": _on_time(t, sig["rcs_command"].data),
        "max_roll_error_deg": float(att_err_roll.max()),
        "time_separation_s": _event(result, engine.EV_SEPARATION),
        "time_upper_stage_ignition_s": _event(result, engine.EV_IGNITION),
        "time_les_jettison_s": _event(result, engine.EV_LES),
        "time_cutoff_s": _event(result, engine.EV_CUTOFF),
        "final_time_s": float(t[-1]),
        "cutoff_altitude_m": float(sig["altitude"].data[-1]),
        "cutoff_inertial_velocity_mps": float(np.linalg.norm(v_f)),
        "cutoff_mass_kg": float(sig["mass"].data[-1]),
        "propellant_remaining_kg": float(np.sum(sig["propellant_remaining"].data[-1, 1:])),
        "perigee_altitude_km": orbit["perigee_altitude_km"],
        "apogee_altitude_km": orbit["apogee_altitude_km"],
        "inclination_deg": orbit["inclination_deg"],
        "sim_wall_time_s": result.sim_wall_time_s,
        "compile_time_s": result.compile_time_s,
        "realtime_factor": float(result.t_final / result.sim_wall_time_s) if result.sim_wall_time_s > 0 else None,
    })
    out.update(load_indicators(t, qbar, sig["alpha"].data, sig["beta"].data, qalpha_total, qalpha_limit))
    out.update(separation_state(t, sig["body_rate"].data, sig["attitude_error"].data, qalpha_total,
                                _event(result, engine.EV_SEPARATION)))
    if p is not None:
        out.update(propulsion_keys(result, p))
        if p[propulsion.P_FS_LIQUID] != 0.0:
            out.update(first_stage_cutoff_keys(result))
        if p[peg.P_ON] != 0.0 and p[peg.P_FS_ON] != 0.0:
            out.update(first_stage_burn_errors(result, sig, p))
        if p[propulsion.P_US_RESTARTS] != 0.0:
            out.update(upper_stage_restart_keys(result))
        if p[peg.P_US1_ON] != 0.0:
            out.update(upper_stage_first_burn_errors(result, sig, p))
        if p[boosters.P_N_BOOSTERS] > 0.0:
            out.update(booster_keys(result))
    if target is not None:
        cut = not np.isnan(result.events[engine.EV_CUTOFF])
        out.update(insertion_errors(r_f, v_f, target) if cut else dict.fromkeys(INSERTION_KEYS))
    if "pitch_yaw_jet_command" in sig:  # a vehicle with pitch and yaw jets
        jets = sig["pitch_yaw_jet_command"].data
        out["pitch_yaw_jet_on_time_s"] = _on_time(t, jets[:, 0]) + _on_time(t, jets[:, 1])
    if "navigation_position_error" in sig:
        out.update(navigation_keys(r_f, v_f, sig))
    if "peg_time_to_go" in sig:
        t_ign = _event(result, engine.EV_IGNITION)  # the upper stage's burn (PEG may fly the first stage's too)
        active = (sig["peg_active"].data > 0.0) & (t >= (np.inf if t_ign is None else t_ign))
        out["peg_engage_time_s"] = float(t[np.argmax(active)]) if active.any() else None
        out["peg_converged_at_cutoff"] = int(sig["peg_converged"].data[-1]) if active.any() else None
    if study_wall_s is not None:
        out["study_wall_time_s"] = study_wall_s
    return out
