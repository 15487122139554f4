"""Powered Explicit Guidance (PEG) of the upper stage: closed-loop linear-tangent
steering to an insertion state, with time-to-go prediction and thrust integrals.

The formulation is the Space Shuttle's Unified Powered Flight Guidance in its standard
(constant-thrust) mode, and in its constant-acceleration mode for a throttled upper
stage (the burn at constant thrust until the throttle's acceleration limit, then at that
acceleration: :func:`burn_integrals`): Space Shuttle GN&C Equation Document No. 24,
"Unified Powered Flight Guidance" (NASA JSC, 1974) and its public derivation by
McHenry, Brand, Long, Cockrell and Thibodeau, "Space Shuttle Ascent Guidance,
Navigation, and Control", J. Astronaut. Sci. 27(1), 1979; the equations are in
``docs/models.md``. Every guidance cycle (``sim.guidance_rate_hz``):

1. navigation: the sensed (non-gravitational) velocity change since the last cycle,
   ``Δv_s = Δv − ½ (g₀ + g₁) Δt``; the thrust acceleration ``a_T = |Δv_s| / Δt`` (the
   mean over the cycle, moved to its end by ``τ = v_e / a_T − Δt/2``);
2. ``v_go ← v_go − Δv_s``; burn time to go from the rocket equation,
   ``t_go = τ (1 − exp(−|v_go| / v_e))`` (with an acceleration limit ``a_L``, the
   constant-thrust part ends at ``t₁ = τ − v_e/a_L`` and the rest of ``|v_go|`` takes
   ``(|v_go| − L₁)/a_L``);
3. thrust integrals ``L, J, S, Q, P, H`` of that burn over ``t_go``;
4. steering: ``λ = v_go/|v_go|``; ``r_grav ← (t_go/t_go,prev)² r_grav``; the position to
   go ``r_go`` (its downrange part free, set so that ``λ · r_go = S``); turning rate ``λ̇ = (r_go − S λ)/(Q − S J/L)``; the
   thrust direction ``i_F(t) = unit(λ + λ̇ (t − t_λ))`` with ``t_λ = t + J/L``;
5. gravity over the rest of the burn, by integrating a coast from the thrust-weighted
   mean state (``v_grav``, ``r_grav``);
6. the predicted cutoff position ``r_p = r + v t_go + r_grav + r_thrust`` projected into
   the target plane sets the target position ``r_d`` (radius ``R_d``) and velocity
   ``v_d`` (speed ``V_d`` at flight-path angle ``γ_d``), and ``v_go = v_d − v − v_grav +
   v_bias``.

The cycle is converged when ``t_go`` changes from the previous cycle's value (less the
cycle time) by at most ``convergence_tolerance`` × max(``t_go``,
``terminal_time_to_go_s``). At engagement it iterates
at the same state, up to ``max_iterations`` times, until ``t_go`` settles so and the
thrust direction moves by at most ``steering_tolerance_deg`` between passes; the
command then turns from the stored profile's to PEG's along a cosine ramp of
``blend_s`` (:func:`blend_with_profile`). Once ``t_go`` falls below
``terminal_time_to_go_s`` the steering law is frozen (its ``λ̇`` would grow without
bound as ``t_go → 0``) and only ``v_go``, ``t_go`` and the predicted cutoff time are
updated. The engine cuts off at the plant step nearest that time.

PEG may fly a liquid first stage's burn first, to its own target (``BURN_FIRST_STAGE``:
:func:`burn_loads`, :func:`_target`); the upper stage's burn is then a new one
(:func:`restart`), blended from the attitude held since the first stage's cutoff
(:func:`hold_command`, :func:`blend_with_hold`). An upper stage that restarts flies its
first burn to its own target (``BURN_UPPER_FIRST``) the same way, and its restarted
burn to the insertion target.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli import constants
from savant_cli.errors import ConfigError
from savant_cli.models import blocks, quaternion as qt
from savant_cli.models.gravity import P_J2, P_J3, P_J4, P_MU, P_ORDER, gravity_at, gravity_zonal, gravity_zonal_xyz
from savant_cli.models.guidance import D_QG, D_TG, D_VG, command_at

_PARAMS = blocks.PARAMETERS.block("peg")
P_ON = _PARAMS.scalar("on", "1", "1: closed-loop upper-stage guidance (guidance.peg.enabled)")
P_START = _PARAMS.scalar("start_after_ignition", "s", "PEG engages this long after upper-stage ignition")
P_R_TARGET = _PARAMS.scalar("target_radius", "m", "insertion radius R_d")
P_V_TARGET = _PARAMS.scalar("target_speed", "m/s", "insertion inertial speed V_d")
P_GAMMA_TARGET = _PARAMS.scalar("target_flight_path_angle", "rad", "insertion flight-path angle γ_d")
P_IY = _PARAMS.array("target_plane_normal", 3, "1", "i_y = −(unit angular momentum) of the target orbit, ECI")
P_VE = _PARAMS.scalar("exhaust_velocity", "m/s", "guidance's effective exhaust velocity g0 Isp (an I-load)")
P_TOL = _PARAMS.scalar("convergence_tolerance", "1", "largest relative change of t_go of a converged cycle")
P_TERMINAL = _PARAMS.scalar("terminal_time_to_go", "s", "steering frozen below this t_go")
P_MAX_ITER = _PARAMS.scalar("max_iterations", "1", "passes allowed for convergence at engagement")
P_MAX_UNCONVERGED = _PARAMS.scalar("max_unconverged_cycles", "1", "consecutive unconverged cycles that fail the run")
P_GRAV_STEPS = _PARAMS.scalar("gravity_steps", "1", "RK4 steps of the gravity prediction over t_go")
P_STEER_TOL = _PARAMS.scalar("steering_tolerance", "rad", "largest change of the thrust direction between passes "
                             "of a converged engagement")
P_SHUTDOWN_LEAD = _PARAMS.scalar("shutdown_impulse_time", "s", "nominal shutdown impulse in seconds of rated "
                                  "thrust (an I-load): the cutoff is commanded this much before t_go ends")
P_BLEND = _PARAMS.scalar("blend_time", "s", "the command turns from the stored profile to PEG's over this time")
P_ACCEL_LIMIT = _PARAMS.scalar("acceleration_limit", "m/s^2", "the thrust acceleration the upper stage's throttle "
                               "holds (0: constant thrust to cutoff)")
P_COAST_LOCAL = _PARAMS.scalar("coast_local_horizontal", "1", "1: a coast holds the cutoff's attitude in the local-"
                                                              "horizontal frame (guidance.peg.coast_attitude), 0: "
                                                              "inertially")
_FIRST = blocks.PARAMETERS.block("peg_first_stage")
P_FS_ON = _FIRST.scalar("on", "1", "1: PEG flies the first stage's burn too (guidance.peg.first_stage_burn)")
P_FS_START = _FIRST.scalar("start", "s", "mission time PEG engages in the first stage")
P_FS_TARGET = _FIRST.array("target", 3, "m, m/s, rad", "the first stage's cutoff radius, inertial speed and "
                           "flight-path angle")
P_FS_VE = _FIRST.scalar("exhaust_velocity", "m/s", "guidance's first-stage g0 Isp (an I-load)")
P_FS_LEAD = _FIRST.scalar("shutdown_impulse_time", "s", "the first stage's nominal shutdown impulse in seconds of "
                          "rated thrust: its cutoff is commanded this much before t_go ends")
P_FS_ACCEL_LIMIT = _FIRST.scalar("acceleration_limit", "m/s^2", "the thrust acceleration the first stage's throttle "
                                 "holds (0: none)")
P_FS_OWN_PLANE = _FIRST.scalar("own_plane", "1", "1: the first stage's burn stays in the osculating plane at its "
                               "engagement; 0: it steers into the target's plane")

_UPPER_FIRST = blocks.PARAMETERS.block("peg_upper_first_burn")
P_US1_ON = _UPPER_FIRST.scalar("on", "1", "1: the upper stage burns twice, PEG flying its first burn to its own "
                                          "target (guidance.peg.upper_stage_first_burn)")
P_US1_TARGET = _UPPER_FIRST.array("target", 3, "m, m/s, rad", "the upper stage's first cutoff radius, inertial "
                                  "speed and flight-path angle (in the target's plane)")
P_US1_RESTART_START = _UPPER_FIRST.scalar("start_after_restart", "s", "PEG engages this long after the upper "
                                                                      "stage's restart")

#: The burns PEG flies (``guidance_cycle``'s ``burn``).
BURN_FIRST_STAGE = 0
BURN_UPPER_STAGE = 1  # the upper stage's (last) burn, to guidance.target
BURN_UPPER_FIRST = 2  # the upper stage's first burn of two (guidance.peg.upper_stage_first_burn)

_DISCRETE = blocks.DISCRETE.block("peg")
D_ACTIVE = _DISCRETE.scalar("active", "1", "1 once PEG steers the vehicle")
D_CONVERGED = _DISCRETE.scalar("converged", "1", "1: the latest cycle converged")
D_TERMINAL = _DISCRETE.scalar("terminal", "1", "1: steering frozen (t_go below the terminal value)")
D_TGO = _DISCRETE.scalar("time_to_go", "s", "burn time to go")
D_VGO = _DISCRETE.array("velocity_to_go", 3, "m/s", "velocity to be gained, ECI")
D_LAMBDA = _DISCRETE.array("lambda", 3, "1", "steering unit vector λ, ECI")
D_LAMBDA_DOT = _DISCRETE.array("lambda_dot", 3, "1/s", "steering turning rate λ̇, ECI")
D_T_LAMBDA = _DISCRETE.scalar("t_lambda", "s", "time at which the thrust points along λ")
D_RBIAS = _DISCRETE.array("position_bias", 3, "m", "r_bias: position error of the thrust-integral model, ECI")
D_RGRAV = _DISCRETE.array("position_gravity", 3, "m", "r_grav: gravity's share of the position to go, ECI")
D_RD = _DISCRETE.array("cutoff_position", 3, "m", "predicted (target) cutoff position r_d, ECI")
D_VD = _DISCRETE.array("cutoff_velocity", 3, "m/s", "target cutoff velocity v_d at r_d, ECI")
D_T_CUTOFF = _DISCRETE.scalar("cutoff_time", "s", "commanded cutoff time t + t_go − the shutdown lead "
                                                 "(0 before PEG engages)")
D_ACCEL = _DISCRETE.scalar("thrust_acceleration", "m/s^2", "sensed thrust acceleration over the last cycle")
D_UNCONVERGED = _DISCRETE.scalar("unconverged_cycles", "1", "consecutive unconverged cycles")
D_ITERATIONS = _DISCRETE.scalar("iterations", "1", "passes made in the latest cycle")
D_T_NAV = _DISCRETE.scalar("navigation_time", "s", "time of the latest navigation sample (0: none yet)")
D_V_NAV = _DISCRETE.array("navigation_velocity", 3, "m/s", "inertial velocity at the latest navigation sample, ECI")
D_G_NAV = _DISCRETE.array("navigation_gravity", 3, "m/s^2", "gravity at the latest navigation sample, ECI")
D_T_ENGAGED = _DISCRETE.scalar("engage_time", "s", "time PEG engaged in this burn (0 before)")
D_FS_COMMANDED = _DISCRETE.scalar("first_stage_cutoff", "1", "1 once PEG commanded the first stage's cutoff")
D_FS_IY = _DISCRETE.array("first_stage_plane", 3, "1", "i_y of the first stage's burn: the target's, or the "
                          "osculating plane's at its engagement (−unit(r × v)), ECI")
D_HOLD_Q = _DISCRETE.array("hold_quaternion", 4, "1", "the attitude held from a cutoff before a coast until "
                           "PEG steers the next burn (q_c2i)")
D_HOLD_LOCAL = _DISCRETE.array("hold_local", 4, "1", "the held attitude in the local-horizontal frame of the hold's "
                                                      "moment (q_c2l: coast_attitude local_horizontal)")
D_US1_COMMANDED = _DISCRETE.scalar("upper_stage_first_cutoff", "1", "1 once PEG commanded the cutoff of the upper "
                                                                     "stage's first burn")

#: guidance_cycle results
PEG_OK = 0
PEG_NOT_CONVERGED = 1  # no convergence within max_iterations at engagement
PEG_LOST_CONVERGENCE = 2  # max_unconverged_cycles in a row
PEG_NONFINITE = 3


@njit(cache=True, error_model="numpy")
def failure_message(code: int) -> str:
    """Why a guidance cycle failed (its ``PEG_*`` code)."""
    if code == PEG_NOT_CONVERGED:
        return "PEG time-to-go did not converge at engagement within guidance.peg.max_iterations"
    if code == PEG_LOST_CONVERGENCE:
        return "PEG time-to-go stopped converging for guidance.peg.max_unconverged_cycles cycles in a row"
    if code == PEG_NONFINITE:
        return "PEG produced a non-finite steering solution"
    return ""


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """PEG's target and tunings (``guidance.peg``, ``guidance.target``); zero when off."""
    g = inputs.cfg.guidance
    if g.peg is None or not g.peg.enabled:
        p[P_ON] = 0.0
        return
    tgt = insertion_target(g)
    p[P_ON] = 1.0
    p[P_START] = g.peg.start_after_ignition_s
    p[P_R_TARGET] = tgt.radius_m
    p[P_V_TARGET] = tgt.speed_mps
    p[P_GAMMA_TARGET] = tgt.flight_path_angle_rad
    p[P_IY:P_IY + 3] = -tgt.plane_normal
    p[P_VE] = constants.G0 * g.peg.isp_vac_s
    p[P_TOL] = g.peg.convergence_tolerance
    p[P_TERMINAL] = g.peg.terminal_time_to_go_s
    p[P_MAX_ITER] = g.peg.max_iterations
    p[P_MAX_UNCONVERGED] = g.peg.max_unconverged_cycles
    p[P_GRAV_STEPS] = g.peg.gravity_steps
    p[P_STEER_TOL] = np.radians(g.peg.steering_tolerance_deg)
    p[P_BLEND] = g.peg.blend_s
    p[P_COAST_LOCAL] = 1.0 if g.peg.coast_attitude == "local_horizontal" else 0.0
    p[P_SHUTDOWN_LEAD] = g.peg.shutdown_impulse_time_s
    upper = inputs.vehicle.upper_stage.throttle  # the flight software's own limit
    p[P_ACCEL_LIMIT] = upper.axial_acceleration_limit_mps2 if upper is not None else 0.0
    _build_upper_first_burn(g.peg.upper_stage_first_burn, inputs.vehicle, p)
    burn = g.peg.first_stage_burn
    if burn is None:
        p[P_FS_ON] = 0.0
        return
    liquid = inputs.vehicle.first_stage.liquid
    if liquid is None:
        raise ConfigError("guidance.peg.first_stage_burn", "set",
                          "a liquid first stage, whose cutoff guidance commands (this vehicle's first stage is a solid "
                          "motor, which burns to its end): leave first_stage_burn out")
    r, v, gamma = insertion_state(burn.perigee_altitude_km, burn.apogee_altitude_km, burn.cutoff_altitude_km)
    p[P_FS_ON] = 1.0
    p[P_FS_START] = burn.start_s
    p[P_FS_TARGET:P_FS_TARGET + 3] = (r, v, gamma)
    p[P_FS_VE] = constants.G0 * burn.isp_vac_s
    p[P_FS_LEAD] = burn.shutdown_impulse_time_s
    limit = liquid.throttle.axial_acceleration_limit_mps2 if liquid.throttle is not None else None
    p[P_FS_ACCEL_LIMIT] = limit if limit is not None else 0.0
    p[P_FS_OWN_PLANE] = 1.0 if burn.plane == "engagement" else 0.0


def _build_upper_first_burn(burn, vehicle, p: np.ndarray) -> None:
    """The upper stage's first burn (``guidance.peg.upper_stage_first_burn``), which a
    vehicle with an upper-stage restart needs, and only such a vehicle takes."""
    restarts = vehicle.events.has("upper_stage_restart")
    if restarts != (burn is not None):
        raise ConfigError("guidance.peg.upper_stage_first_burn", "set" if burn is not None else None,
                          "set exactly when the vehicle restarts its upper stage (an event igniting its engines "
                          "again after one shutting them down)" + (": this vehicle does not" if burn is not None else
                                                                   ": this vehicle does, and PEG needs the first "
                                                                   "burn's cutoff orbit"))
    p[P_US1_ON] = 0.0
    if burn is not None:
        p[P_US1_ON] = 1.0
        p[P_US1_TARGET:P_US1_TARGET + 3] = insertion_state(burn.perigee_altitude_km, burn.apogee_altitude_km,
                                                           burn.cutoff_altitude_km)
        p[P_US1_RESTART_START] = burn.start_after_restart_s


class InsertionTarget:
    """The insertion state PEG flies to, from ``guidance.target`` and the launch site.

    Attributes
    ----------
    radius_m, speed_mps, flight_path_angle_rad : float
        Cutoff radius (WGS84 equatorial radius + ``cutoff_altitude_km``), inertial speed
        and flight-path angle (ascending branch) of the orbit with the target perigee and
        apogee (two-body, μ of EGM2008).
    plane_normal : ndarray (3,)
        Unit angular momentum of the target orbit, ECI (X through Greenwich at liftoff).
    inclination_rad, node_rad : float
        Its inclination and right ascension of the ascending node (ECI at liftoff).
    apsis_altitudes_km : tuple of float
        Its perigee and apogee altitudes (km above the WGS84 equatorial radius).
    """

    def __init__(self, radius_m: float, speed_mps: float, flight_path_angle_rad: float,
                 inclination_rad: float, node_rad: float, apsis_altitudes_km: tuple[float, float]) -> None:
        self.apsis_altitudes_km = apsis_altitudes_km
        self.radius_m = radius_m
        self.speed_mps = speed_mps
        self.flight_path_angle_rad = flight_path_angle_rad
        self.inclination_rad = inclination_rad
        self.node_rad = node_rad
        si = np.sin(inclination_rad)
        self.plane_normal = np.array([si * np.sin(node_rad), -si * np.cos(node_rad), np.cos(inclination_rad)])


def insertion_state(perigee_altitude_km: float, apogee_altitude_km: float,
                    cutoff_altitude_km: float) -> tuple[float, float, float]:
    """Radius (m), speed (m/s) and flight-path angle (rad, ascending) at the cutoff altitude
    of the orbit with the given apsis altitudes (above the WGS84 equatorial radius)."""
    rp = constants.WGS84_A + 1e3 * perigee_altitude_km
    ra = constants.WGS84_A + 1e3 * apogee_altitude_km
    r = constants.WGS84_A + 1e3 * cutoff_altitude_km
    a = 0.5 * (rp + ra)
    v = float(np.sqrt(constants.MU_EARTH * (2.0 / r - 1.0 / a)))
    h = np.sqrt(constants.MU_EARTH * 2.0 * rp * ra / (rp + ra))
    return r, v, float(np.arccos(np.clip(h / (r * v), -1.0, 1.0)))


def in_plane_node(site_eci: np.ndarray, inclination_rad: float) -> float:
    """Right ascension of the ascending node (rad) of the plane of inclination
    ``inclination_rad`` through ``site_eci`` that passes it northbound (the ascending,
    north-easterly launch for a prograde inclination).

    The plane normal ``(sin i sin Ω, −sin i cos Ω, cos i)`` is perpendicular to the site
    vector ``s`` when ``ρ sin(Ω − φ) = −s_z cot i`` (``ρ, φ``: the site's equatorial
    distance and right ascension); of the two roots, the northbound pass is the one
    with ``(h × s)_z > 0``.
    """
    sx, sy, sz = site_eci
    rho = np.hypot(sx, sy)
    phi = np.arctan2(sy, sx)
    arg = -sz / (np.tan(inclination_rad) * rho)
    base = np.arcsin(np.clip(arg, -1.0, 1.0))
    for node in (phi + base, phi + np.pi - base):
        si = np.sin(inclination_rad)
        h = np.array([si * np.sin(node), -si * np.cos(node), np.cos(inclination_rad)])
        if np.cross(h, site_eci)[2] > 0.0:
            return float(np.mod(node, 2.0 * np.pi))
    return float(np.mod(phi + base, 2.0 * np.pi))  # pragma: no cover (one root is always northbound)


def insertion_target(guidance) -> InsertionTarget:
    """:class:`InsertionTarget` of a (validated) ``guidance`` config section. The plane
    passes through the launch site at ``target.in_plane_time_s`` after liftoff."""
    from savant_cli.models import earth

    tgt, ls = guidance.target, guidance.launch_site
    r, v, gamma = insertion_state(tgt.perigee_altitude_km, tgt.apogee_altitude_km, tgt.cutoff_altitude_km)
    site = earth.geodetic_to_ecef(np.radians(ls.latitude_deg), np.radians(ls.longitude_deg), ls.base_altitude_m,
                                  constants.WGS84_A, constants.WGS84_E2)
    spin = constants.OMEGA_EARTH * tgt.in_plane_time_s  # ECEF → ECI rotation at that time
    site_eci = np.array([np.cos(spin) * site[0] - np.sin(spin) * site[1],
                         np.sin(spin) * site[0] + np.cos(spin) * site[1], site[2]])
    inc = np.radians(tgt.inclination_deg)
    return InsertionTarget(r, v, gamma, inc, in_plane_node(site_eci, inc),
                           (float(tgt.perigee_altitude_km), float(tgt.apogee_altitude_km)))


# ----------------------------------------------------------------------------- kernels


@njit(cache=True, error_model="numpy")
def thrust_integrals(ve: float, tau: float, tgo: float) -> tuple[float, float, float, float, float, float]:
    """Thrust integrals of a constant-thrust burn of ``tgo`` seconds (exhaust velocity
    ``ve``, m/s; ``τ = ve / a_T``, s; ``tgo < τ``).

    ``L = ∫a dt`` (m/s), ``J = ∫a t dt`` (m), ``S = ∫∫a`` (m), ``Q = ∫∫a t`` (m·s),
    ``P = ∫∫a t²`` (m·s²), ``H = J t_go − Q`` (m·s), with ``a(t) = ve / (τ − t)``."""
    L = ve * np.log(tau / (tau - tgo))
    J = L * tau - ve * tgo
    S = -J + tgo * L
    Q = S * tau - 0.5 * ve * tgo * tgo
    P = Q * tau - ve * tgo * tgo * tgo / 6.0
    H = J * tgo - Q
    return L, J, S, Q, P, H


@njit(cache=True, error_model="numpy")
def constant_acceleration_integrals(a: float, tb: float) -> tuple[float, float, float, float, float, float]:
    """:func:`thrust_integrals` of a burn at the constant acceleration ``a`` (m/s²) for
    ``tb`` s: ``L = a t``, ``J = S = a t²/2``, ``Q = a t³/6``, ``P = a t⁴/12``,
    ``H = a t³/3``."""
    L = a * tb
    J = 0.5 * L * tb
    Q = J * tb / 3.0
    return L, J, J, Q, 0.5 * Q * tb, 2.0 * Q


@njit(cache=True, error_model="numpy")
def burn_integrals(ve: float, tau: float, vgo: float, a_limit: float) -> tuple[float, float, float, float, float,
                                                                             float, float]:
    """Burn time to go (s) for the velocity to go ``vgo`` (m/s) and the thrust integrals
    ``L, J, S, Q, P, H`` of that burn (:func:`thrust_integrals`' units).

    Without an acceleration limit (``a_limit`` ≤ 0) the burn is at constant thrust:
    ``t_go = τ (1 − exp(−v_go/v_e))``. With one, as UPFG's constant-acceleration mode, the
    thrust acceleration ``v_e/(τ − t)`` reaches ``a_L`` at ``t₁ = τ − v_e/a_L`` (0 if it is
    there already); if the constant-thrust part delivers ``L₁ < v_go`` the rest is flown
    at ``a_L`` for ``t₂ = (v_go − L₁)/a_L``, and the two parts combine as integrals of
    ``a(t)`` over ``[0, t₁]`` and ``[t₁, t₁ + t₂]``::

        L = L₁ + L₂            J = J₁ + J₂ + t₁ L₂         S = S₁ + S₂ + t₂ L₁
        Q = Q₁ + Q₂ + t₂ J₁ + t₁ S₂
        P = P₁ + P₂ + t₂ H₁ + 2 t₁ Q₂ + t₁² S₂                H = J t_go − Q
    """
    t1 = tau - ve / a_limit if a_limit > 0.0 else tau
    if a_limit <= 0.0 or t1 > 0.0 and ve * np.log(tau / (tau - t1)) >= vgo:
        tgo = tau * (1.0 - np.exp(-vgo / ve))
        L, J, S, Q, P, H = thrust_integrals(ve, tau, tgo)
        return tgo, L, J, S, Q, P, H
    t1 = max(t1, 0.0)
    L1, J1, S1, Q1, P1, H1 = thrust_integrals(ve, tau, t1)
    t2 = (vgo - L1) / a_limit
    L2, J2, S2, Q2, P2, _ = constant_acceleration_integrals(a_limit, t2)
    tgo = t1 + t2
    J = J1 + J2 + t1 * L2
    Q = Q1 + Q2 + t2 * J1 + t1 * S2
    return (tgo, L1 + L2, J, S1 + S2 + t2 * L1, Q, P1 + P2 + t2 * H1 + 2.0 * t1 * Q2 + t1 * t1 * S2,
            J * tgo - Q)


@njit(cache=True, error_model="numpy")
def coast(r: np.ndarray, v: np.ndarray, duration: float, grav: np.ndarray,
          n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Position and velocity after a coast of ``duration`` s under gravity alone.

    ``grav = [μ, R_e, J2, J3, J4, g_x, g_y, g_z]``: zonal gravity (m³/s², m) with
    ``n_steps`` RK4 steps, or, with μ = 0, the uniform field ``g`` (m/s², exact)."""
    if grav[0] == 0.0:
        g = grav[5:8]
        return r + v * duration + 0.5 * g * duration * duration, v + g * duration
    h = duration / n_steps
    y = np.empty(6)
    y[0:3] = r
    y[3:6] = v
    k = np.empty((4, 6))
    ys = np.empty(6)
    for _ in range(n_steps):
        for s in range(4):
            if s == 0:
                ys[:] = y
            elif s < 3:
                ys[:] = y + 0.5 * h * k[s - 1]
            else:
                ys[:] = y + h * k[2]
            ax, ay, az = gravity_zonal_xyz(ys[0], ys[1], ys[2], grav[0], grav[1], grav[2], grav[3], grav[4])
            k[s, 0:3] = ys[3:6]
            k[s, 3] = ax
            k[s, 4] = ay
            k[s, 5] = az
        y += h / 6.0 * (k[0] + 2.0 * k[1] + 2.0 * k[2] + k[3])
    return y[0:3].copy(), y[3:6].copy()


@njit(cache=True, error_model="numpy")
def _unit(a: np.ndarray) -> np.ndarray:
    return a / np.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


@njit(cache=True, error_model="numpy")
def initial_guess(r: np.ndarray, v: np.ndarray, target: np.ndarray, grav: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First ``r_d`` and ``v_go``: the target state above the current position, in plane.

    ``target = [R_d, V_d, γ_d, i_y (3)]``; ``grav`` as for :func:`coast`."""
    iy = target[3:6]
    rp = r - np.dot(r, iy) * iy
    rd = _target_position(rp, target, grav)
    vd = _target_velocity(rd, target, grav)
    return rd, vd - v


@njit(cache=True, error_model="numpy")
def _up(rd: np.ndarray, grav: np.ndarray) -> np.ndarray:
    """Local vertical at ``rd``: radial, or against a uniform field."""
    if grav[0] == 0.0:
        return -_unit(grav[5:8])
    return _unit(rd)


@njit(cache=True, error_model="numpy")
def _target_position(rp: np.ndarray, target: np.ndarray, grav: np.ndarray) -> np.ndarray:
    """The in-plane predicted position ``rp`` moved to the target radius (or, in a
    uniform field, to the target height ``R_d`` along the vertical)."""
    if grav[0] == 0.0:
        up = _up(rp, grav)
        return rp + (target[0] - np.dot(rp, up)) * up
    return target[0] * _unit(rp)


@njit(cache=True, error_model="numpy")
def _target_velocity(rd: np.ndarray, target: np.ndarray, grav: np.ndarray) -> np.ndarray:
    ix = _up(rd, grav)
    iz = np.cross(ix, target[3:6])
    return target[1] * (np.sin(target[2]) * ix + np.cos(target[2]) * iz)


@njit(cache=True, error_model="numpy")
def upfg_pass(r: np.ndarray, v: np.ndarray, vgo: np.ndarray, rd: np.ndarray, rbias: np.ndarray,
              rgrav: np.ndarray, tgo_prev: float, first: bool, ve: float, tau: float, target: np.ndarray,
              grav: np.ndarray, n_grav: int, a_limit: float = 0.0):
    """One UPFG pass (steps 2–6 of the module notes) at state ``r, v`` (ECI, m, m/s).

    Parameters
    ----------
    vgo, rd, rbias, rgrav : ndarray (3,)
        The previous pass's velocity to go, target position, position bias and gravity
        position term (``rgrav`` and ``rbias`` are re-initialised when ``first``).
    tgo_prev : float
        The time to go ``rgrav`` was computed for (s); ``rgrav ∝ t_go²`` is rescaled to
        this pass's ``t_go``.
    ve, tau : float
        Exhaust velocity (m/s) and ``ve / a_T`` now (s).
    target : ndarray (6,)
        ``[R_d (m), V_d (m/s), γ_d (rad), i_y (3)]``.
    grav : ndarray (8,)
        Gravity model (:func:`coast`); ``n_grav`` its RK4 steps.
    a_limit : float
        The thrust acceleration a throttle holds (m/s²; 0: none), :func:`burn_integrals`.

    Returns
    -------
    tgo : float
        Burn time to go used in this pass (s), from ``|vgo|``.
    vgo, rd, rbias, rgrav, vd : ndarray (3,)
        The updated terms (``vd``: the target velocity at ``rd``).
    lam, lam_dot : ndarray (3,)
        Steering vector and turning rate (1/s).
    j_over_l : float
        ``J/L`` (s): the thrust is along ``lam`` at ``t + J/L``.
    """
    iy = target[3:6]
    vgo_mag = np.sqrt(np.dot(vgo, vgo))
    tgo, L, J, S, Q, P, H = burn_integrals(ve, tau, vgo_mag, a_limit)
    j_over_l = J / L
    if first:
        g0 = grav[5:8] if grav[0] == 0.0 else gravity_zonal(r, grav[0], grav[1], grav[2], grav[3], grav[4])
        rgrav = 0.5 * tgo * tgo * g0
        rbias = np.zeros(3)
    else:
        rgrav = (tgo / tgo_prev) ** 2 * rgrav
    lam = vgo / vgo_mag
    rgo = rd - (r + v * tgo + rgrav)
    iz = _unit(np.cross(_up(rd, grav), iy))  # downrange at the target (rd × i_y in a central field)
    rgoxy = rgo - np.dot(iz, rgo) * iz
    rgoz = (S - np.dot(lam, rgoxy)) / np.dot(lam, iz)
    rgo = rgoxy + rgoz * iz + rbias
    lam_dot = (rgo - S * lam) / (Q - S * j_over_l)
    i_f = _unit(lam - lam_dot * j_over_l)
    phi = np.arccos(min(max(np.dot(i_f, lam), -1.0), 1.0))
    phi_dot = -phi / j_over_l
    ld_mag = np.sqrt(np.dot(lam_dot, lam_dot))
    ld_hat = lam_dot / ld_mag if ld_mag > 0.0 else np.zeros(3)
    v_thrust = (L - 0.5 * L * phi * phi - J * phi * phi_dot - 0.5 * H * phi_dot * phi_dot) * lam \
        - (L * phi + J * phi_dot) * ld_hat
    r_thrust = (S - 0.5 * S * phi * phi - Q * phi * phi_dot - 0.5 * P * phi_dot * phi_dot) * lam \
        - (S * phi + Q * phi_dot) * ld_hat
    v_bias = vgo - v_thrust
    rbias = rgo - r_thrust
    # gravity over the burn, from the thrust-weighted mean state
    rc1 = r - 0.1 * r_thrust - tgo / 30.0 * v_thrust
    vc1 = v + 1.2 * r_thrust / tgo - 0.1 * v_thrust
    rc2, vc2 = coast(rc1, vc1, tgo, grav, n_grav)
    v_grav = vc2 - vc1
    rgrav = rc2 - rc1 - vc1 * tgo
    # the predicted cutoff position sets the target, in plane
    rp = r + v * tgo + rgrav + r_thrust
    rp = rp - np.dot(rp, iy) * iy
    rd = _target_position(rp, target, grav)
    vd = _target_velocity(rd, target, grav)
    vgo = vd - v - v_grav + v_bias
    return tgo, vgo, rd, rbias, rgrav, vd, lam, lam_dot, j_over_l


@njit(cache=True, error_model="numpy")
def thrust_direction(lam: np.ndarray, lam_dot: np.ndarray, t_lambda: float, t: float) -> np.ndarray:
    """Commanded thrust direction ``unit(λ + λ̇ (t − t_λ))`` at time ``t`` (ECI)."""
    return _unit(lam + lam_dot * (t - t_lambda))


@njit(cache=True, error_model="numpy")
def command_attitude(i_f: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Commanded attitude q_c2i: body X along the thrust direction ``i_f``, body Z toward
    the local down (the wings-level roll of the stored upper-stage commands)."""
    down = -_unit(r)
    z = _unit(down - np.dot(down, i_f) * i_f)
    return _frame(i_f, np.cross(z, i_f), z)


@njit(cache=True, error_model="numpy")
def _frame(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The quaternion of the frame whose axes are the orthonormal ``x, y, z`` (ECI)."""
    m = np.empty((3, 3))
    m[:, 0] = x
    m[:, 1] = y
    m[:, 2] = z
    return qt.from_dcm(m)


@njit(cache=True, error_model="numpy")
def gravity_model(p: np.ndarray, re: float) -> np.ndarray:
    """The :func:`coast` gravity array of the plant's configured zonal model."""
    g = np.zeros(8)
    g[0] = p[P_MU]
    g[1] = re
    order = p[P_ORDER]
    g[2] = p[P_J2] if order >= 2 else 0.0
    g[3] = p[P_J3] if order >= 3 else 0.0
    g[4] = p[P_J4] if order >= 4 else 0.0
    return g


@njit(cache=True, error_model="numpy")
def _target(p: np.ndarray, d: np.ndarray, burn: int) -> np.ndarray:
    """``[R_d, V_d, γ_d, i_y (3)]`` of ``burn``: the upper stage's insertion state (or its
    first burn's cutoff state) in the target plane, or the first stage's cutoff state in
    its burn's plane (``D_FS_IY``)."""
    out = np.empty(6)
    if burn == BURN_FIRST_STAGE:
        out[0:3] = p[P_FS_TARGET:P_FS_TARGET + 3]
        out[3:6] = d[D_FS_IY:D_FS_IY + 3]
        return out
    if burn == BURN_UPPER_FIRST:
        out[0:3] = p[P_US1_TARGET:P_US1_TARGET + 3]
    else:
        out[0] = p[P_R_TARGET]
        out[1] = p[P_V_TARGET]
        out[2] = p[P_GAMMA_TARGET]
    out[3:6] = p[P_IY:P_IY + 3]
    return out


@njit(cache=True, error_model="numpy")
def burn_loads(p: np.ndarray, burn: int) -> tuple[float, float, float]:
    """Guidance's I-loads of ``burn``: exhaust velocity (m/s), the acceleration its throttle
    holds (m/s², 0: none) and its shutdown lead (s); both of the upper stage's burns take
    its own."""
    if burn == BURN_FIRST_STAGE:
        return p[P_FS_VE], p[P_FS_ACCEL_LIMIT], p[P_FS_LEAD]
    return p[P_VE], p[P_ACCEL_LIMIT], p[P_SHUTDOWN_LEAD]


@njit(cache=True, error_model="numpy")
def restart(d: np.ndarray) -> None:
    """A new burn: PEG disengaged, its convergence and steering state cleared, until it
    engages again (its first cycle of the burn takes a fresh navigation sample)."""
    for k in (D_ACTIVE, D_CONVERGED, D_TERMINAL, D_TGO, D_T_CUTOFF, D_UNCONVERGED, D_ITERATIONS, D_T_NAV, D_T_ENGAGED):
        d[k] = 0.0


@njit(cache=True, error_model="numpy")
def local_horizontal(r: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``q_l2i`` of the local-horizontal frame at the ECI state ``r, v`` (m, m/s): its
    axes up (``r̂``), downrange (``ĥ × r̂``) and along the orbit normal ``ĥ``."""
    up = _unit(r)
    normal = _unit(np.cross(r, v))
    return _frame(up, np.cross(normal, up), normal)


@njit(cache=True, error_model="numpy")
def hold_command(d: np.ndarray, t: float, r: np.ndarray, v: np.ndarray, p: np.ndarray) -> None:
    """From a cutoff before a coast (a guided first stage's, or the upper stage's first):
    hold the guidance command's attitude at ``t`` (s) and keep it (``D_HOLD_Q``) for the
    next burn's engagement blend; once held, nothing more until :func:`release_hold`.
    Held inertially at zero rate, or (``P_COAST_LOCAL``) fixed in the local-horizontal
    frame of the navigated state ``r, v`` (ECI, m, m/s): each call turns it with that
    frame, at the frame's rate ``(r × v) / r²``."""
    held = np.dot(d[D_HOLD_Q:D_HOLD_Q + 4], d[D_HOLD_Q:D_HOLD_Q + 4]) > 0.0
    local = p[P_COAST_LOCAL] != 0.0
    if held and not local:
        return
    if held:
        q = qt.qmul(local_horizontal(r, v), d[D_HOLD_LOCAL:D_HOLD_LOCAL + 4])
    else:
        h = t - d[D_TG]
        q = qt.qmul(d[D_QG:D_QG + 4], qt.from_rotation_vector(d[D_VG:D_VG + 3] * h))
        d[D_HOLD_LOCAL:D_HOLD_LOCAL + 4] = qt.qmul(qt.qconj(local_horizontal(r, v)), q)
    d[D_QG:D_QG + 4] = q
    d[D_HOLD_Q:D_HOLD_Q + 4] = q
    d[D_VG:D_VG + 3] = 0.0
    if local:  # the frame's inertial rate, in the commanded axes
        d[D_VG:D_VG + 3] = qt.rotate_inverse(q, np.cross(r, v) / np.dot(r, r))
    d[D_TG] = t


@njit(cache=True, error_model="numpy")
def release_hold(d: np.ndarray) -> None:
    """A new coast's cutoff: the next :func:`hold_command` holds the attitude of its own moment."""
    d[D_HOLD_Q:D_HOLD_Q + 4] = 0.0


@njit(cache=True, error_model="numpy")
def guidance_cycle(d: np.ndarray, t: float, r: np.ndarray, v: np.ndarray, t_ignition: float, period: float,
                   p: np.ndarray, re: float, burn: int = BURN_UPPER_STAGE) -> int:
    """One guidance cycle of ``burn`` at time ``t`` (s): the upper stage's (either of its
    burns) after its ignition at ``t_ignition`` (engaging ``P_START`` later; a restarted burn
    ``P_US1_RESTART_START`` after its restart), or the first stage's
    (``t_ignition`` 0, liftoff; engaging at ``P_FS_START``), each with its own target and
    I-loads (:func:`_target`, :func:`burn_loads`).

    Takes a navigation sample (``r, v``: ECI, m, m/s); once engaged, runs PEG and writes
    the guidance command (``guidance.command_quaternion``, ``command_rate``,
    ``command_time``: the attitude that points body X along the thrust direction, and
    the eigenaxis rate to the next cycle ``period`` s later). Returns ``PEG_OK`` or a
    failure code (:func:`failure_message`); ``d[D_ACTIVE]`` says whether PEG steers.
    """
    grav = gravity_model(p, re)
    g = gravity_at(r[0], r[1], r[2], p, re)
    t_prev = d[D_T_NAV]
    have_nav = t_ignition < t_prev < t  # a sample of this burn to difference against
    dt = t - t_prev if have_nav else 0.0
    dv_sensed = np.zeros(3)
    if have_nav:
        for i in range(3):
            dv_sensed[i] = v[i] - d[D_V_NAV + i] - 0.5 * (g[i] + d[D_G_NAV + i]) * dt
        d[D_ACCEL] = np.sqrt(np.dot(dv_sensed, dv_sensed)) / dt
    d[D_T_NAV] = t
    d[D_V_NAV:D_V_NAV + 3] = v
    d[D_G_NAV] = g[0]
    d[D_G_NAV + 1] = g[1]
    d[D_G_NAV + 2] = g[2]
    start = p[P_FS_START] if burn == BURN_FIRST_STAGE else t_ignition + (
        p[P_US1_RESTART_START] if burn == BURN_UPPER_STAGE and p[P_US1_ON] != 0.0 else p[P_START])
    if not have_nav or t < start or d[D_ACCEL] <= 0.0:
        return PEG_OK
    ve, a_limit, lead = burn_loads(p, burn)
    tau = ve / d[D_ACCEL] - 0.5 * dt
    if burn == BURN_FIRST_STAGE and d[D_ACTIVE] == 0.0:  # the burn's plane, fixed at engagement
        h = np.cross(r, v) if p[P_FS_OWN_PLANE] != 0.0 else -p[P_IY:P_IY + 3]
        d[D_FS_IY:D_FS_IY + 3] = -_unit(h)
    target = _target(p, d, burn)
    n_grav = int(p[P_GRAV_STEPS])
    tol = p[P_TOL]
    terminal = p[P_TERMINAL]
    if d[D_ACTIVE] == 0.0:  # engagement: iterate at this state until t_go settles
        rd, vgo = initial_guess(r, v, target, grav)
        rbias = np.zeros(3)
        rgrav = np.zeros(3)
        tgo_prev = np.inf
        i_f_prev = np.zeros(3)
        converged = False
        n_iter = 0
        for it in range(int(p[P_MAX_ITER])):
            n_iter = it + 1
            tgo, vgo, rd, rbias, rgrav, vd, lam, lam_dot, jl = upfg_pass(
                r, v, vgo, rd, rbias, rgrav, tgo_prev, it == 0, ve, tau, target, grav, n_grav, a_limit)
            i_f = _unit(lam - lam_dot * jl)
            turn = np.arccos(min(max(np.dot(i_f, i_f_prev), -1.0), 1.0))
            if abs(tgo - tgo_prev) <= tol * tgo and turn <= p[P_STEER_TOL]:
                converged = True
                break
            tgo_prev = tgo
            i_f_prev = i_f
        d[D_ITERATIONS] = n_iter
        if not converged:
            return PEG_NOT_CONVERGED
        d[D_ACTIVE] = 1.0
        d[D_T_ENGAGED] = t
        d[D_UNCONVERGED] = 0.0
    else:
        vgo = d[D_VGO:D_VGO + 3] - dv_sensed
        d[D_ITERATIONS] = 1.0
        if d[D_TERMINAL] == 0.0:
            rd = d[D_RD:D_RD + 3].copy()
            rbias = d[D_RBIAS:D_RBIAS + 3].copy()
            rgrav = d[D_RGRAV:D_RGRAV + 3].copy()
            tgo_expected = d[D_TGO] - dt
            tgo, vgo, rd, rbias, rgrav, vd, lam, lam_dot, jl = upfg_pass(
                r, v, vgo, rd, rbias, rgrav, d[D_TGO], False, ve, tau, target, grav, n_grav, a_limit)
            converged = abs(tgo - tgo_expected) <= tol * max(tgo, terminal)
            d[D_UNCONVERGED] = 0.0 if converged else d[D_UNCONVERGED] + 1.0
            if d[D_UNCONVERGED] >= p[P_MAX_UNCONVERGED]:
                return PEG_LOST_CONVERGENCE
        else:  # steering frozen: only the time to go
            converged = True
            tgo = burn_integrals(ve, tau, np.sqrt(np.dot(vgo, vgo)), a_limit)[0]
    if not (np.isfinite(tgo) and np.all(np.isfinite(vgo))):
        return PEG_NONFINITE
    d[D_CONVERGED] = 1.0 if converged else 0.0
    d[D_TGO] = tgo
    d[D_VGO:D_VGO + 3] = vgo
    d[D_T_CUTOFF] = t + tgo - lead  # the tail-off delivers the rest
    if d[D_TERMINAL] == 0.0:
        d[D_RD:D_RD + 3] = rd
        d[D_VD:D_VD + 3] = vd
        d[D_RBIAS:D_RBIAS + 3] = rbias
        d[D_RGRAV:D_RGRAV + 3] = rgrav
        d[D_LAMBDA:D_LAMBDA + 3] = lam
        d[D_LAMBDA_DOT:D_LAMBDA_DOT + 3] = lam_dot
        d[D_T_LAMBDA] = t + jl
        if tgo < terminal:
            d[D_TERMINAL] = 1.0
    lam = d[D_LAMBDA:D_LAMBDA + 3]
    lam_dot = d[D_LAMBDA_DOT:D_LAMBDA_DOT + 3]
    q0 = command_attitude(thrust_direction(lam, lam_dot, d[D_T_LAMBDA], t), r)
    q1 = command_attitude(thrust_direction(lam, lam_dot, d[D_T_LAMBDA], t + period), r + v * period)
    if np.dot(q0, q1) < 0.0:
        q1 = -q1
    rate = qt.to_rotation_vector(qt.qmul(qt.qconj(q0), q1)) / period
    for i in range(4):
        if not np.isfinite(q0[i]):
            return PEG_NONFINITE
    d[D_QG:D_QG + 4] = q0
    d[D_VG:D_VG + 3] = rate
    d[D_TG] = t
    return PEG_OK


@njit(cache=True, error_model="numpy")
def _slerp(a: np.ndarray, b: np.ndarray, s: float) -> np.ndarray:
    """The attitude a fraction ``s`` of the way from ``a`` to ``b`` along the great circle."""
    dq = qt.qmul(qt.qconj(a), b)
    if dq[0] < 0.0:
        dq = -dq
    return qt.qnormalize(qt.qmul(a, qt.from_rotation_vector(s * qt.to_rotation_vector(dq))))


@njit(cache=True, error_model="numpy")
def _ramp(t: float, start: float, duration: float) -> float:
    if duration <= 0.0 or t >= start + duration:
        return 1.0
    return 0.5 * (1.0 - np.cos(np.pi * max(t - start, 0.0) / duration))


@njit(cache=True, error_model="numpy")
def blend_with_profile(d: np.ndarray, t: float, tau: float, period: float, p: np.ndarray, times: np.ndarray,
                       quats: np.ndarray, rates: np.ndarray) -> None:
    """During the ``blend_time`` after engagement, replace PEG's command in ``d`` by the
    attitude a cosine-ramp fraction of the way from the stored profile's (read at profile
    time ``tau`` for mission time ``t``) to PEG's, with the eigenaxis rate to the next
    cycle's blended attitude."""
    if d[D_ACTIVE] == 0.0 or t >= d[D_T_ENGAGED] + p[P_BLEND]:
        return
    qp0, _ = command_at(tau, times, quats, rates)
    qp1, _ = command_at(tau + period, times, quats, rates)
    _blend(d, t, period, p, qp0, qp1)


@njit(cache=True, error_model="numpy")
def blend_with_hold(d: np.ndarray, t: float, period: float, p: np.ndarray) -> None:
    """:func:`blend_with_profile` from the attitude held since a guided first-stage cutoff
    (``D_HOLD_Q``) instead of the stored profile's."""
    if d[D_ACTIVE] == 0.0 or t >= d[D_T_ENGAGED] + p[P_BLEND]:
        return
    held = d[D_HOLD_Q:D_HOLD_Q + 4].copy()
    _blend(d, t, period, p, held, held)


@njit(cache=True, error_model="numpy")
def _blend(d: np.ndarray, t: float, period: float, p: np.ndarray, qp0: np.ndarray, qp1: np.ndarray) -> None:
    """PEG's command in ``d`` replaced by the attitude a cosine-ramp fraction of the way
    from ``qp0`` (at ``t``; ``qp1`` a cycle later) to PEG's, with the eigenaxis rate to
    the next cycle's blended attitude."""
    start = d[D_T_ENGAGED]
    qg0 = d[D_QG:D_QG + 4].copy()
    w = d[D_VG:D_VG + 3]
    qg1 = qt.qmul(qg0, qt.from_rotation_vector(w * period))
    qa = _slerp(qp0, qg0, _ramp(t, start, p[P_BLEND]))
    qb = _slerp(qp1, qg1, _ramp(t + period, start, p[P_BLEND]))
    if np.dot(qa, qb) < 0.0:
        qb = -qb
    d[D_QG:D_QG + 4] = qa
    d[D_VG:D_VG + 3] = qt.to_rotation_vector(qt.qmul(qt.qconj(qa), qb)) / period
