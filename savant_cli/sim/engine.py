"""Multi-rate fixed-step simulation engine.

The compiled loop :func:`advance` integrates the plant with RK4 at the plant rate and,
on step boundaries, runs the discrete parts at their own rates with zero-order hold:

* rate gyros every ``n_sensor`` plant steps (200 Hz by default);
* command smoother, flight control and roll-jet logic every ``n_fcs`` steps (50 Hz);
  their commands reach the actuators and jets ``controller.delay_s`` later (the loop's
  transport delay, a whole number of plant steps within the control period); a
  throttled stage's engine controller (the first stage's, or the upper stage's from its
  ignition to its cutoff command) sets its new throttle at the same cycle, at once
  (``models/throttle.py``, from the sensed axial acceleration with a limit);
* a new guidance command every ``n_guid`` steps (1 Hz): from the stored profile
  (``models/guidance.py``, read at mission time or, in the first stage, by relative
  speed: ``models/command_schedule.py``) or, once engaged in the upper stage, from
  Powered Explicit Guidance (``models/peg.py``), whose time to go (less the nominal
  shutdown impulse's lead) also commands the cutoff at the plant step nearest it; PEG
  may fly a liquid first stage's burn too (``guidance.peg.first_stage_burn``), command
  its cutoff the same way, hold that moment's attitude until it engages in the upper
  stage, and blend from it; an upper stage that restarts has its first burn guided to
  that burn's own target (``guidance.peg.upper_stage_first_burn``), cut off the same way,
  the attitude held through the coast, and its restarted burn guided to the insertion;
* the vehicle's events at the first step boundary at which their trigger holds
  (:class:`EventSchedule`, from the vehicle file's ``events``): the strap-on boosters'
  jettison (a delay after liftoff and, with a condition, once it holds: a booster's
  sensed vacuum thrust below a fraction of its own flown peak, or any other quantity;
  a separation before it takes them along); a liquid first stage's
  cutoff (its engines' shutdown command) a delay after liftoff and, with a condition,
  once it holds; separation when the sensed (vacuum) thrust of the flown first stage (its
  motor, or its liquid engines as throttled and shut down) falls below a fraction of its
  own flown peak (the peak is kept in the discrete state), from liftoff or a delay after
  the first stage's cutoff; the upper-stage ignition and each item's (LES, fairing)
  jettison a delay after the event they count from and, with a condition, once it holds
  (axial acceleration, altitude, dynamic pressure, a tank's propellant), a jettison not
  before the one written before it (the items' may come in the first stage's flight, the
  separation then waits for them); a restarting upper stage's first cutoff (a backup of
  guidance's) and its restart, each a delay after the event before it and, with a
  condition, once it holds (the coast between them is the flight control's coast phase);
  then the (last) cutoff command; after the command the upper-stage thrust decays over its shutdown transient
  (``models/propulsion.py``) with guidance frozen (the last attitude command held), and
  the run stops when the decay ends: the insertion state includes the shutdown impulse.

Python calls :func:`advance` in chunks so that a progress bar can be drawn and an
interrupted or diverged run still returns what it computed.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from savant_cli.io.guidance_file import GuidanceTable
from savant_cli.models import (
    actuator, aero, boosters, earth, flex, navigation, peg, propulsion, quaternion as qt, rcs, rigid_body, roll_gimbal,
    slosh, throttle
)
from savant_cli.models.command_schedule import BY_TIME, D_PROFILE_OFFSET, D_PROFILE_RATE, profile_time
from savant_cli.models.earth import A_ALT, P_E2, P_OMEGA_E, P_RE
from savant_cli.models.fcs import (
    D_CMD_PY, FCS_COAST, FCS_STACK, FCS_UPPER, FcsTables, fcs_step, pitch_yaw_jets_step, reset_phase
)
from savant_cli.models.gravity import P_MU
from savant_cli.models.guidance import D_TG, D_VG, SmootherGains, guidance_sample, smoother_step
from savant_cli.models.layout import (
    D_CMD_P, D_CMD_RCS, D_CMD_Y, D_FLEX_NAV, D_GYRO_X, D_GYRO_Y, ENGINE_FIRST, ENGINE_OFF, ENGINE_UPPER, N_AUX,
    U_CONFIG, U_DPC, U_DYC, U_ENGINE, U_FS_T_CUT, U_PY_JETS, U_RCS, U_ROLL, U_T_CUT, U_T_IGN, U_THROTTLE, U_US_THROTTLE,
    Q, R, V, W
)
from savant_cli.models.sensors import (
    GYRO_MISALIGN, GYRO_POINTS, IMU_GYRO, N_GYROS, P_IMU_MISALIGN, GyroModel, gyro_step, misalignment
)
from savant_cli.sim import loop_perturbation
from savant_cli.sim.borrow import borrowed
from savant_cli.sim.plant import derivative, derivative_state, reference_cg

# status codes returned by advance()
RUNNING = 0
STOP_CUTOFF = 1  # target energy reached (stored profile)
STOP_DEPLETION = 2  # an upper-stage propellant ran out
STOP_SEPARATION = 3  # phase ends at separation
STOP_TIME = 4  # maximum time reached
STOP_GUIDANCE_CUTOFF = 5  # PEG's time to go elapsed
DIVERGED_NONFINITE = 10
DIVERGED_GROUND = 11
DIVERGED_RATE = 12
GUIDANCE_FAILED = 13  # PEG failed in flight (the detail says why)

# event slots in `events`
EV_SEPARATION = 0
EV_IGNITION = 1
EV_LES = 2
EV_CUTOFF = 3
EV_FS_CUTOFF = 4
EV_BOOSTER_JETTISON = 5
#: The jettisoned items' events, in the order written: the first (``les_jettison``) and
#: the further ones (``item_jettison_2`` …).
EV_ITEMS = (EV_LES, 6, 7, 8)
EV_US_CUTOFF = 9  # a restarting upper stage's first cutoff (guidance's, or the vehicle's backup)
EV_RESTART = 10  # its second ignition
EVENT_NAMES = ("separation", "upper_stage_ignition", "les_jettison", "cutoff", "first_stage_cutoff",
               "booster_jettison", "item_jettison_2", "item_jettison_3", "item_jettison_4", "upper_stage_cutoff",
               "upper_stage_restart")
#: The vehicle's event slots, in the order a step boundary checks them (the cutoff is
#: guidance's; the boosters' jettison and a liquid first stage's cutoff precede the
#: separation; an item's jettison, which may come before the separation, waits for the
#: jettison written before it: ``EventRule.waits_for``).
SEQUENCE = (EV_BOOSTER_JETTISON, EV_FS_CUTOFF, EV_ITEMS[0], EV_ITEMS[1], EV_ITEMS[2], EV_ITEMS[3], EV_SEPARATION,
            EV_IGNITION, EV_US_CUTOFF, EV_RESTART)

# what an event's condition watches (EventSchedule.when)
WHEN_NONE = 0  # fires once armed
WHEN_THRUST_FRACTION = 1  # the first-stage motor's sensed vacuum thrust over its own flown peak
WHEN_AXIAL_ACCELERATION = 2  # sensed specific force along body x, m/s²
WHEN_ALTITUDE = 3  # geodetic altitude of the CG, m
WHEN_DYNAMIC_PRESSURE = 4  # Pa
WHEN_PROPELLANT = 5  # propellant remaining in a tank (a state of x), kg
WHEN_BOOSTER_THRUST_FRACTION = 6  # a booster's sensed vacuum thrust over its own flown peak
WHEN_RADIAL_SPEED = 7  # the CG's inertial radial speed r·v/|r|, m/s (crosses 0 at apogee)


class EventRule(NamedTuple):
    """One vehicle event's trigger (scalars: no reference counting in the step loop).

    Attributes
    ----------
    after : int
        The event slot it counts from, −1 liftoff.
    delay_s : float
        s after that event.
    when : int
        The condition's quantity (``WHEN_*``).
    of : int
        The propellant state a ``WHEN_PROPELLANT`` condition reads (its index in ``x``),
        or the booster a ``WHEN_BOOSTER_THRUST_FRACTION`` watches (its number); −1
        otherwise.
    above : bool
        The condition holds above the threshold (else below).
    threshold : float
        In the quantity's units (a thrust fraction: of the first-stage motor's own flown
        peak).
    waits_for : int
        The jettison slot that must have fired first (−1: none): the vehicle's jettisons
        happen in the order written, so each configuration follows the one before it.
    """

    after: int
    delay_s: float
    when: int
    of: int
    above: bool
    threshold: float
    waits_for: int = -1


class EventSchedule(NamedTuple):
    """The event rules and run limits :func:`advance` applies at step boundaries (SI).

    Attributes
    ----------
    rules : tuple of EventRule
        One per slot of :data:`EVENT_NAMES`: the vehicle's events (:data:`SEQUENCE`;
        ``vehicle/two_stage.py::Trigger``; a rule that never arms for an event the
        vehicle does not have) and the cutoff's, which never arms (guidance commands
        the cutoff). Armed
        ``delay_s`` after the event slot ``after`` fired (−1: liftoff), each fires at the
        first step boundary from then on at which its condition holds (``WHEN_NONE``: at
        once).
    cutoff_energy_j_kg : float
        The stored profile's cutoff: point-mass specific orbital energy, J/kg.
    max_time_s : float
        The run stops after this mission time, s.
    stop_at_separation : bool
        The phase ends at separation.
    max_body_rate_rad_s : float
        Divergence threshold on the body-rate magnitude |ω|, rad/s.
    command_delay_steps : int
        Plant steps from a flight-control cycle to its commands (``controller.delay_s``).
    profile_schedule : int
        What the stored profile's first stage is indexed by: its position in
        ``models.command_schedule.SCHEDULES``.
    """

    rules: tuple[EventRule, ...]
    cutoff_energy_j_kg: float
    max_time_s: float
    stop_at_separation: bool
    max_body_rate_rad_s: float
    command_delay_steps: int
    profile_schedule: int


class Rates(NamedTuple):
    """Integer step ratios of the multi-rate schedule (plant steps per sample)."""

    dt: float  # plant step, s
    n_sensor: int
    n_fcs: int
    n_guid: int
    n_log: int


@njit(cache=True, error_model="numpy")
def fcs_phase(events: np.ndarray) -> int:
    """The flight control's phase: the stack until separation, the coast until the
    upper-stage ignition and between a restarting stage's cutoff and its restart, the
    upper stage's while it burns."""
    if np.isnan(events[EV_SEPARATION]):
        return FCS_STACK
    if np.isnan(events[EV_IGNITION]) or (not np.isnan(events[EV_US_CUTOFF]) and np.isnan(events[EV_RESTART])):
        return FCS_COAST
    return FCS_UPPER


@njit(cache=True, error_model="numpy")
def rk4(t: float, x: np.ndarray, u: np.ndarray, dt: float, p: np.ndarray, tb: np.ndarray,
        aux: np.ndarray, work: np.ndarray, diagnostics: bool = True) -> None:
    """One classical Runge–Kutta step of ``x`` in place; ``aux`` receives the diagnostics
    at ``t`` (``diagnostics`` False: only the altitude, for steps nothing logs). ``work``
    is a (6, ≥ max(x.size, N_AUX)) scratch array (k1..k4, stage state, aux scratch)."""
    n = x.size
    k1, k2, k3, k4, xs = work[0], work[1], work[2], work[3], work[4]
    scratch = work[5]
    if diagnostics:
        derivative(t, x, u, p, tb, aux, k1)
    else:
        derivative_state(t, x, u, p, tb, aux, k1)
    for i in range(n):
        xs[i] = x[i] + 0.5 * dt * k1[i]
    derivative_state(t + 0.5 * dt, xs, u, p, tb, scratch, k2)
    for i in range(n):
        xs[i] = x[i] + 0.5 * dt * k2[i]
    derivative_state(t + 0.5 * dt, xs, u, p, tb, scratch, k3)
    for i in range(n):
        xs[i] = x[i] + dt * k3[i]
    derivative_state(t + dt, xs, u, p, tb, scratch, k4)
    h6 = dt / 6.0
    for i in range(n):
        x[i] += h6 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


@njit(cache=True, error_model="numpy")
def work_array(n_state: int) -> np.ndarray:
    """Scratch space for :func:`rk4`: rows wide enough for ``n_state`` states and the diagnostics."""
    return np.zeros((6, max(n_state, N_AUX)))


@njit(cache=True, error_model="numpy")
def move_reference(x: np.ndarray, old: tuple[float, float, float], new: tuple[float, float, float]) -> None:
    """The reference point from CG ``old`` to CG ``new`` (structure axes, m) of the same
    structure (:func:`savant_cli.models.rigid_body.move_reference`)."""
    rigid_body.move_reference(x, new[0] - old[0], new[1] - old[1], new[2] - old[2])


@njit(cache=True, error_model="numpy", inline="always")  # every slot, every step: no call
def armed(k: int, t: float, events: np.ndarray, sched: EventSchedule) -> bool:
    """Whether event slot ``k`` waits for its condition at ``t`` (s): not fired, the
    jettison it waits for fired, and ``delay_s`` past the event it counts from."""
    if not np.isnan(events[k]):
        return False
    rule = sched.rules[k]
    if rule.waits_for >= 0 and np.isnan(events[rule.waits_for]):
        return False
    t0 = 0.0 if rule.after < 0 else events[rule.after]
    return not np.isnan(t0) and t >= t0 + rule.delay_s


@njit(cache=True, error_model="numpy")
def condition_holds(k: int, t: float, x: np.ndarray, u: np.ndarray, f_sensed: float, f_booster: float,
                    d: np.ndarray, sched: EventSchedule, p: np.ndarray, tb: np.ndarray, work: np.ndarray) -> bool:
    """Whether the condition of armed event slot ``k`` holds at the step boundary ``t``.

    A thrust fraction compares the first stage's sensed vacuum thrust ``f_sensed`` (N),
    or the watched booster's ``f_booster`` (N), with the fraction of its own flown peak;
    the propellant reads its state in ``x``, the radial speed the CG's position and velocity
    in ``x``; the
    axial acceleration, altitude and dynamic pressure come from one evaluation of the
    plant at ``t`` (its diagnostics, into the scratch rows of ``work``)."""
    rule = sched.rules[k]
    when = rule.when
    if when == WHEN_NONE:
        return True
    limit = rule.threshold
    if when == WHEN_THRUST_FRACTION:
        value, limit = f_sensed, limit * d[propulsion.D_FS_PEAK]
    elif when == WHEN_BOOSTER_THRUST_FRACTION:
        value, limit = f_booster, limit * d[boosters.D_PEAK]
    elif when == WHEN_PROPELLANT:
        value = x[rule.of]
    elif when == WHEN_RADIAL_SPEED:  # the same in the Earth-fixed frame: ω × r is horizontal
        value = (x[R] * x[V] + x[R + 1] * x[V + 1] + x[R + 2] * x[V + 2]) / np.sqrt(
            x[R] * x[R] + x[R + 1] * x[R + 1] + x[R + 2] * x[R + 2])
    else:
        aux = work[5]
        derivative(t, x, u, p, tb, aux, work[4])
        if when == WHEN_ALTITUDE:
            value = aux[A_ALT]
        elif when == WHEN_DYNAMIC_PRESSURE:
            value = aux[aero.A_QBAR]
        else:
            value = aux[rigid_body.A_ACCEL]
    return value > limit if rule.above else value < limit


@njit(cache=True, error_model="numpy")
def handle_events(t: float, dt: float, x: np.ndarray, u: np.ndarray, d: np.ndarray,
                  events: np.ndarray, sched: EventSchedule, p: np.ndarray, tb: np.ndarray, work: np.ndarray) -> int:
    """Apply the vehicle's events at a step boundary; return a stop code.

    Each event slot, in the order of :data:`SEQUENCE`, fires when it is :func:`armed` and
    its condition holds (:func:`condition_holds`), and applies its actions: the boosters'
    jettison drops them (:func:`drop_boosters`; their watched booster's sensed thrust and
    its flown peak, ``d[boosters.D_PEAK]``, are tracked while they are attached), a liquid
    first stage's cutoff commands its engines' shutdown (``u[U_FS_T_CUT]``: the thrust
    decays over their shutdown transient, the throttle held), separation drops the first
    stage (with its boosters, if still attached; the upper-stage nozzle and its command
    start at null, a new modal set starts at rest, the reference point moves to the new
    configuration's CG), ignition lights
    the upper stage (the flight control fades its gains in from here), an item's
    jettison drops it (:func:`next_configuration`: the reference point moves again). Until separation
    the first stage's sensed vacuum thrust at ``t`` (``propulsion.first_stage_flow``, the
    stage flown so far, at its held throttle) is tracked: its largest value so far
    (``d[D_FS_PEAK]``, the thrust fraction's reference) and its trapezoidal integral
    (``d[D_FS_IMPULSE]``, the impulse the stage delivered); its propellant at separation
    (a liquid stage's residual) is kept in ``d[D_FS_PROP_SEP]``. A liquid first stage
    whose tank runs dry before its cutoff command has its cutoff event then (no command:
    ``u[U_FS_T_CUT]`` stays 0). After the cutoff command the upper stage's sensed thrust
    accumulates the same way in ``d[D_US_SD_IMPULSE]``. ``dt`` is the plant step (s), the
    trapezoids' width; ``work``: the scratch rows of :func:`work_array`."""
    f_sensed = 0.0
    if np.isnan(events[EV_SEPARATION]):
        f_sensed = propulsion.first_stage_flow(x, tb, p, t, throttle.held(u[U_THROTTLE], p), u[U_FS_T_CUT])[0]
        if t > 0.0:
            d[propulsion.D_FS_IMPULSE] += 0.5 * (d[propulsion.D_FS_LAST] + f_sensed) * dt
        d[propulsion.D_FS_LAST] = f_sensed
        if f_sensed > d[propulsion.D_FS_PEAK]:
            d[propulsion.D_FS_PEAK] = f_sensed
        if np.isnan(events[EV_FS_CUTOFF]) and p[propulsion.P_FS_LIQUID] != 0.0 and propulsion.liquid_tank_dry(x, p):
            events[EV_FS_CUTOFF] = t  # a tank ran dry before any command: the engines' shutdown is now
        if np.isnan(events[EV_FS_CUTOFF]) and p[peg.P_FS_ON] != 0.0 and d[peg.D_ACTIVE] != 0.0 \
                and t + 0.5 * dt >= d[peg.D_T_CUTOFF]:  # PEG's cutoff of the first stage: the nearest step
            events[EV_FS_CUTOFF] = t
            u[U_FS_T_CUT] = t
            d[peg.D_FS_COMMANDED] = 1.0
    if p[peg.P_US1_ON] != 0.0 and int(u[U_ENGINE]) == ENGINE_UPPER and np.isnan(events[EV_US_CUTOFF]) \
            and d[peg.D_ACTIVE] != 0.0 and t + 0.5 * dt >= d[peg.D_T_CUTOFF]:  # PEG's first cutoff: the nearest step
        events[EV_US_CUTOFF] = t
        upper_stage_cutoff(t, x, u, d, p, tb)
        d[peg.D_US1_COMMANDED] = 1.0
    f_booster = 0.0
    boosted = p[boosters.P_N_BOOSTERS] > 0.0 and np.isnan(events[EV_BOOSTER_JETTISON])
    if boosted and sched.rules[EV_BOOSTER_JETTISON].when == WHEN_BOOSTER_THRUST_FRACTION:
        f_booster = boosters.flow(x, tb, p, t, sched.rules[EV_BOOSTER_JETTISON].of)[0]
        d[boosters.D_PEAK] = max(d[boosters.D_PEAK], f_booster)
    for k in SEQUENCE:
        if not (armed(k, t, events, sched) and condition_holds(k, t, x, u, f_sensed, f_booster, d, sched, p, tb,
                                                                work)):
            continue
        events[k] = t
        if k == EV_FS_CUTOFF:
            u[U_FS_T_CUT] = t
        elif k == EV_BOOSTER_JETTISON:
            drop_boosters(x, u, d, p, tb)
            boosted = False
        elif k == EV_SEPARATION:
            d[propulsion.D_FS_PROP_SEP] = propulsion.first_stage_propellant(x, p)
            if sched.stop_at_separation:
                return STOP_SEPARATION
            if boosted:  # the stage takes its boosters along: they leave with it, now
                events[EV_BOOSTER_JETTISON] = t
                drop_boosters(x, u, d, p, tb)
                boosted = False
            separate(x, u, d, p, tb)
        elif k == EV_IGNITION:
            u[U_ENGINE] = ENGINE_UPPER
            ignite_upper_stage(t, u, p)
            if p[peg.P_FS_ON] != 0.0:  # PEG flew the first stage: the upper stage's burn is a new one
                peg.restart(d)
        elif k == EV_US_CUTOFF:
            upper_stage_cutoff(t, x, u, d, p, tb)
        elif k == EV_RESTART:
            restart_upper_stage(t, u, d, p)
        else:
            next_configuration(x, u, p, tb)
    if int(u[U_ENGINE]) == ENGINE_UPPER:
        if u[U_T_CUT] > 0.0:  # shutdown transient: the impulse after the command (trapezoid)
            f_us = propulsion.upper_stage_thrust_vac(x, tb, p, t, u[U_T_IGN], u[U_T_CUT],
                                                     throttle.held_upper(u[U_US_THROTTLE], p))
            if t > u[U_T_CUT]:
                d[propulsion.D_US_SD_IMPULSE] += 0.5 * (d[propulsion.D_US_SD_LAST] + f_us) * dt
            d[propulsion.D_US_SD_LAST] = f_us
        lox, lh2 = propulsion.upper_stage_propellant(x, p)
        if lox <= 0.0 or lh2 <= 0.0:
            if np.isnan(events[EV_CUTOFF]):
                events[EV_CUTOFF] = t
            return STOP_DEPLETION
    return RUNNING


@njit(cache=True, error_model="numpy")
def upper_stage_cutoff(t: float, x: np.ndarray, u: np.ndarray, d: np.ndarray, p: np.ndarray, tb: np.ndarray) -> None:
    """The cutoff command of a restarting upper stage's first burn at ``t`` (s): its thrust
    decays over the shutdown transient (``u[U_T_CUT]``), its impulse after the command is
    tracked as the final cutoff's, and the coast's attitude hold starts afresh
    (``peg.release_hold``)."""
    command_upper_cutoff(t, x, u, d, p, tb)
    d[propulsion.D_US_SD_IMPULSE] = 0.0
    peg.release_hold(d)


@njit(cache=True, error_model="numpy")
def command_upper_cutoff(t: float, x: np.ndarray, u: np.ndarray, d: np.ndarray, p: np.ndarray,
                         tb: np.ndarray) -> None:
    """The upper stage's cutoff command at ``t`` (s): its thrust decays from here over the
    shutdown transient, the thrust at the command kept for the impulse's trapezoid."""
    u[U_T_CUT] = t
    d[propulsion.D_US_SD_LAST] = propulsion.upper_stage_thrust_vac(x, tb, p, t, u[U_T_IGN], t,
                                                                   throttle.held_upper(u[U_US_THROTTLE], p))


@njit(cache=True, error_model="numpy")
def ignite_upper_stage(t: float, u: np.ndarray, p: np.ndarray) -> None:
    """The upper stage's ignition command at ``t`` (s), first or restart: its start-up
    transient from ``t`` (the flight control fades its gains in from here, models/fcs.py),
    a throttled stage at its command."""
    u[U_T_IGN] = t
    u[U_US_THROTTLE] = p[throttle.P_US_MAX]


@njit(cache=True, error_model="numpy")
def restart_upper_stage(t: float, u: np.ndarray, d: np.ndarray, p: np.ndarray) -> None:
    """The upper stage's second ignition command at ``t`` (s): its start-up transient from
    ``t`` (``u[U_T_IGN]``: the flight control fades its gains in again), no cutoff
    commanded, a throttled stage at its command, and PEG's burn a new one."""
    ignite_upper_stage(t, u, p)
    u[U_T_CUT] = 0.0
    d[propulsion.D_US_SD_IMPULSE] = 0.0
    d[propulsion.D_US_SD_LAST] = 0.0
    if p[peg.P_ON] != 0.0:
        peg.restart(d)


@njit(cache=True, error_model="numpy")
def next_configuration(x: np.ndarray, u: np.ndarray, p: np.ndarray, tb: np.ndarray) -> None:
    """A jettison: the vehicle flies the next configuration of its sequence (the
    configurations are numbered in the order the events reach them), and the reference
    point moves to that configuration's CG (position and velocity of every structural
    point unchanged: :func:`move_reference`)."""
    config = int(u[U_CONFIG])
    cg_before = reference_cg(x, p, tb, config)
    u[U_CONFIG] = config + 1
    move_reference(x, cg_before, reference_cg(x, p, tb, config + 1))


@njit(cache=True, error_model="numpy")
def drop_boosters(x: np.ndarray, u: np.ndarray, d: np.ndarray, p: np.ndarray, tb: np.ndarray) -> None:
    """The boosters' jettison: the next configuration (:func:`next_configuration`), their
    propellant left (summed, kg) kept in ``d[boosters.D_PROP_JET]`` and their states
    emptied (it leaves with them); the first stage's modal set starts at rest, as at
    separation (flex on)."""
    next_configuration(x, u, p, tb)
    fo = int(p[flex.P_OFFSET])
    if fo >= 0:
        x[fo:fo + 2 * int(p[flex.P_N_MODES])] = 0.0
    tank = int(p[boosters.P_TANK])
    left = 0.0
    for i in range(tank, tank + int(p[boosters.P_N_BOOSTERS])):
        left += x[i]
        x[i] = 0.0
    d[boosters.D_PROP_JET] = left


@njit(cache=True, error_model="numpy")
def separate(x: np.ndarray, u: np.ndarray, d: np.ndarray, p: np.ndarray, tb: np.ndarray) -> None:
    """First-stage separation's actions on the state: the next configuration
    (:func:`next_configuration`, the upper stage's), its engine not yet lit, its nozzle
    (and its command, not the first stage's last one) at
    null, the new modal set at rest, the reference point at the new configuration's CG
    (position and velocity of every structural point unchanged)."""
    next_configuration(x, u, p, tb)
    u[U_ENGINE] = ENGINE_OFF
    x[int(p[propulsion.P_FS_TANK])] = 0.0
    if p[propulsion.P_FS_LIQUID] != 0.0:  # a liquid stage's residual leaves with it
        x[int(p[propulsion.P_FS_FUEL_TANK])] = 0.0
    actuator.rest(x, p)
    u[U_DPC] = 0.0
    u[U_DYC] = 0.0
    u[U_ROLL] = 0.0
    fo = int(p[flex.P_OFFSET])
    if fo >= 0:  # new modal set: its modes start at rest (paper: liftoff → ignition set)
        x[fo:fo + 2 * int(p[flex.P_N_MODES])] = 0.0
    reset_phase(d)
    roll_gimbal.reset(d)


@njit(cache=True, error_model="numpy")
def cutoff_step(t: float, dt: float, x: np.ndarray, r_nav: np.ndarray, v_nav: np.ndarray, u: np.ndarray,
                d: np.ndarray, events: np.ndarray, sched: EventSchedule, p: np.ndarray, tb: np.ndarray,
                peg_on: bool) -> int:
    """The upper-stage cutoff at a step boundary: the command (PEG's commanded cutoff time
    at the nearest plant step, or the stored profile's target energy of the navigated
    state ``r_nav``, ``v_nav``), then the end of the shutdown transient ``T_sd`` after it,
    when the run stops. Returns a stop code."""
    if u[U_T_CUT] <= 0.0:
        command = False
        if peg_on:  # PEG's cutoff: the plant step nearest its commanded time
            command = d[peg.D_ACTIVE] != 0.0 and t + 0.5 * dt >= d[peg.D_T_CUTOFF]
        else:
            command = specific_energy(r_nav, v_nav, p[P_MU]) >= sched.cutoff_energy_j_kg
        if not command:
            return RUNNING
        events[EV_CUTOFF] = t
        command_upper_cutoff(t, x, u, d, p, tb)
    if t + 0.5 * dt >= u[U_T_CUT] + p[propulsion.P_US_SHUTDOWN_TIME]:
        return STOP_GUIDANCE_CUTOFF if peg_on else STOP_CUTOFF
    return RUNNING


@njit(cache=True, error_model="numpy")
def schedule_variable(t: float, r: np.ndarray, v: np.ndarray, phase: int, p: np.ndarray) -> float:
    """What the flight control's gains are scheduled on (``models/fcs.py``): the
    geodetic height (m) in the stack phase, the Earth-relative speed (m/s) after it.

    Parameters
    ----------
    t : float
        Time from liftoff (s; sets the Earth's rotation angle).
    r, v : numpy.ndarray
        ECI position (m) and velocity (m/s), as the flight software knows them.
    phase : int
        Flight-control phase (``FCS_STACK``, coast or upper).
    p : numpy.ndarray
        Plant parameters (Earth rotation rate and ellipsoid).
    """
    if phase == FCS_STACK:
        return earth.height_of_eci(t, r[0], r[1], r[2], p[P_OMEGA_E], p[P_RE], p[P_E2])
    ex, ey, ez = earth.earth_relative_velocity_xyz(r[0], r[1], v[0], v[1], v[2], p[P_OMEGA_E])
    return np.sqrt(ex ** 2 + ey ** 2 + ez ** 2)


@njit(cache=True, error_model="numpy")
def specific_energy(r_eci: np.ndarray, v_eci: np.ndarray, mu: float) -> float:
    """Point-mass specific orbital energy (J/kg) of an ECI position (m) and velocity (m/s)."""
    r = np.sqrt(r_eci[0] ** 2 + r_eci[1] ** 2 + r_eci[2] ** 2)
    v2 = v_eci[0] ** 2 + v_eci[1] ** 2 + v_eci[2] ** 2
    return 0.5 * v2 - mu / r


@njit(cache=True, error_model="numpy")
def advance(x: np.ndarray, d: np.ndarray, u: np.ndarray, events: np.ndarray, k0: int,
            n_steps: int, rates: Rates, p: np.ndarray, tb: np.ndarray, ft: FcsTables,
            gyro: GyroModel, smoother: SmootherGains, gt: GuidanceTable, sched: EventSchedule, log: np.ndarray,
            log_row: int, pert: np.ndarray) -> tuple[int, int, int, str]:
    """Advance the coupled plant and flight software by up to ``n_steps`` plant steps.

    ``x``, ``d``, ``u`` and ``events`` are updated in place; logged rows are written to
    ``log`` from row ``log_row``. ``pert``: a gain and delay inserted at one gimbal
    command (``sim/loop_perturbation.py``; its ``NONE``: nothing, updated in place).
    Returns ``(status, steps_done, next_log_row, detail)``.
    """
    aux = np.zeros(N_AUX)
    work = work_array(x.size)
    # the loop runs on reference-count-free views (sim/borrow.py): every array it borrows
    # is held here, or by the caller, until it returns
    return _advance(x, d, u, events, k0, n_steps, rates, p, tb, ft, gyro, smoother, gt, sched, log, log_row, pert, aux,
                    work)


@njit(cache=True, error_model="numpy")
def _advance(x: np.ndarray, d: np.ndarray, u: np.ndarray, events: np.ndarray, k0: int,
             n_steps: int, rates: Rates, p: np.ndarray, tb: np.ndarray, ft: FcsTables,
             gyro: GyroModel, smoother: SmootherGains, gt: GuidanceTable, sched: EventSchedule, log: np.ndarray,
             log_row: int, pert: np.ndarray, aux: np.ndarray, work: np.ndarray) -> tuple[int, int, int, str]:
    """:func:`advance` with its scratch arrays (``aux``: diagnostics, ``work``: RK4)."""
    x, d, u, p, tb, log = borrowed(x), borrowed(d), borrowed(u), borrowed(p), borrowed(tb), borrowed(log)
    aux, work = borrowed(aux), borrowed(work)
    dt = rates.dt
    nx = x.size
    n_cols = log.shape[1]
    flex3 = np.zeros(3)
    # sensor mounting misalignment: each gyro reads R(ε)ᵀ ω, the nav unit q_b2i ⊗ q_s2b
    c_gyro = np.empty((N_GYROS, 3, 3))  # body → sensor axes, per gyro (FCS order)
    for g in range(N_GYROS):
        c_gyro[g] = misalignment(p[GYRO_MISALIGN[g]:GYRO_MISALIGN[g] + 3])[1]
    q_imu = misalignment(p[P_IMU_MISALIGN:P_IMU_MISALIGN + 3])[0]
    q_nav = np.empty(4)
    q_true_nav = np.empty(4)  # the navigated body attitude before the mounting (inertial navigation)
    r_nav = np.empty(3)  # the navigated position and velocity the flight software reads
    v_nav = np.empty(3)
    nav_on = p[navigation.P_ON] != 0.0
    has_flex = int(p[flex.P_OFFSET]) >= 0
    peg_on = p[peg.P_ON] != 0.0
    fs_guided = peg_on and p[peg.P_FS_ON] != 0.0  # PEG flies the first stage's burn too
    perturbed = pert[loop_perturbation.AXIS] >= 0.0
    throttled = p[throttle.P_ON] != 0.0
    us_throttled = p[throttle.P_US_ON] != 0.0
    restarts = p[propulsion.P_US_RESTARTS] != 0.0  # the upper stage's first cutoff is not the run's end
    py_jets = p[rcs.P_PY_FORCE] > 0.0  # pitch and yaw jets for the coasts
    for j in range(n_steps):
        k = k0 + j
        t = k * dt
        status = handle_events(t, dt, x, u, d, events, sched, p, tb, work)
        if status != RUNNING:
            return status, j, log_row, ""
        if nav_on:  # the IMU sample, then the navigated state (true plus the navigation errors)
            if k % rates.n_sensor == 0:
                navigation.imu_sample(d, t, x[R:R + 3], x[V:V + 3], x[Q:Q + 4], p)
            navigation.navigated_state(d, x[R:R + 3], x[V:V + 3], r_nav, v_nav)
        else:
            for i in range(3):
                r_nav[i] = x[R + i]
                v_nav[i] = x[V + i]
        coasting = restarts and not np.isnan(events[EV_US_CUTOFF]) and np.isnan(events[EV_RESTART])
        if int(u[U_ENGINE]) == ENGINE_UPPER and not (restarts and np.isnan(events[EV_RESTART])):  # the last burn's
            status = cutoff_step(t, dt, x, r_nav, v_nav, u, d, events, sched, p, tb, peg_on)
            if status != RUNNING:
                return status, j, log_row, ""
        if t > sched.max_time_s:
            return STOP_TIME, j, log_row, ""
        phase = fcs_phase(events)

        # guidance frozen after the (last) cutoff command
        if k % rates.n_guid == 0 and (u[U_T_CUT] <= 0.0 or coasting):
            steered = False
            period = rates.n_guid * dt
            if peg_on and coasting:  # from the upper stage's first cutoff to its restart: the attitude held
                steered = True
                peg.hold_command(d, t, r_nav, v_nav, p)
            elif peg_on and not np.isnan(events[EV_IGNITION]):
                restarted = not np.isnan(events[EV_RESTART])
                held = fs_guided or restarted  # the burn follows a coast with the attitude held
                if held:  # the attitude held from the cutoff before it (here if no cycle fell between)
                    peg.hold_command(d, t, r_nav, v_nav, p)
                burn = peg.BURN_UPPER_FIRST if restarts and not restarted else peg.BURN_UPPER_STAGE
                code = peg.guidance_cycle(d, t, r_nav, v_nav, events[EV_RESTART] if restarted else events[EV_IGNITION],
                                          period, p, p[P_RE], burn)
                if code != peg.PEG_OK:
                    return GUIDANCE_FAILED, j, log_row, peg.failure_message(code)
                steered = d[peg.D_ACTIVE] != 0.0 or held  # (the held attitude until PEG engages)
                if held:  # blended from the attitude held since the cutoff
                    peg.blend_with_hold(d, t, period, p)
                else:
                    peg.blend_with_profile(d, t, t + d[D_PROFILE_OFFSET], period, p, gt.time, gt.quat, gt.rate)
            elif fs_guided and np.isnan(events[EV_FS_CUTOFF]):  # PEG's first-stage burn
                code = peg.guidance_cycle(d, t, r_nav, v_nav, 0.0, period, p, p[P_RE], peg.BURN_FIRST_STAGE)
                if code != peg.PEG_OK:
                    return GUIDANCE_FAILED, j, log_row, peg.failure_message(code)
                steered = d[peg.D_ACTIVE] != 0.0
                peg.blend_with_profile(d, t, t + d[D_PROFILE_OFFSET], period, p, gt.time, gt.quat, gt.rate)
            elif fs_guided:  # from the first stage's cutoff to the upper stage's guidance: the attitude held
                steered = True
                peg.hold_command(d, t, r_nav, v_nav, p)
            if not steered:
                if sched.profile_schedule == BY_TIME:
                    guidance_sample(d, t, gt.time, gt.quat, gt.rate, k == 0)
                else:
                    ex, ey, ez = earth.earth_relative_velocity_xyz(r_nav[0], r_nav[1], v_nav[0], v_nav[1], v_nav[2],
                                                                  p[P_OMEGA_E])
                    tau = profile_time(d, t, np.sqrt(ex * ex + ey * ey + ez * ez), phase == FCS_STACK, gt.speed,
                                       gt.time[:gt.speed.size], k == 0)
                    guidance_sample(d, tau, gt.time, gt.quat, gt.rate, k == 0)
                    d[D_TG] = t  # the smoother extrapolates in mission time
                    for i in range(3):
                        d[D_VG + i] *= d[D_PROFILE_RATE]
        config = int(u[U_CONFIG])
        if k % rates.n_sensor == 0:
            for g in range(N_GYROS):  # each gyro reads rigid plus flex rate at its node, in its own axes
                if has_flex:
                    flex.flex_point(x, config, p, tb, GYRO_POINTS[g], True, flex3)
                wbx, wby, wbz = x[W] + flex3[0], x[W + 1] + flex3[1], x[W + 2] + flex3[2]
                if nav_on and g == IMU_GYRO:  # the IMU's rate output carries its gyro errors
                    wbx, wby, wbz = navigation.imu_gyro_rate(p, wbx, wby, wbz)
                for ax in range(3):
                    s = D_GYRO_X + 6 * g + 2 * ax
                    w_in = c_gyro[g, ax, 0] * wbx + c_gyro[g, ax, 1] * wby + c_gyro[g, ax, 2] * wbz
                    d[D_GYRO_Y + 3 * g + ax] = gyro_step(d, s, w_in, gyro.ad, gyro.bd, gyro.cd, gyro.dd)
        if k % rates.n_fcs == 0:
            dt_fcs = rates.n_fcs * dt
            smoother_step(d, t, dt_fcs, smoother.damping, smoother.natural_frequency_rad_s)
            sched_var = schedule_variable(t, r_nav, v_nav, phase, p)
            if has_flex:
                flex.flex_point(x, config, p, tb, flex.PT_IMU, False, flex3)  # flex rotation at the nav unit
                d[D_FLEX_NAV:D_FLEX_NAV + 3] = flex3
            if nav_on:  # navigated attitude exp(φ) ⊗ q_b2i ⊗ q_s2b
                navigation.navigated_attitude(d, x[Q:Q + 4], q_true_nav)
                qt.qmul_into(q_true_nav, q_imu, q_nav)
            else:  # sensed attitude q_b2i ⊗ q_s2b
                qt.qmul_into(x[Q:Q + 4], q_imu, q_nav)
            roll_rate_error, engagement = fcs_step(d, q_nav, phase, sched_var, t - u[U_T_IGN], dt_fcs, ft)
            roll_gimbal.roll_gimbal_step(d, ft.roll_gimbal[phase], engagement, roll_rate_error, dt_fcs)
            if py_jets:
                pitch_yaw_jets_step(d, phase, ft)
            if throttled and int(u[U_ENGINE]) == ENGINE_FIRST and not u[U_FS_T_CUT] > 0.0:  # its new setting, at once
                accel = 0.0
                if throttle.acceleration_limited(p):  # the accelerometer: specific force along body x
                    derivative(t, x, u, p, tb, work[5], work[4])
                    accel = work[5][rigid_body.A_ACCEL]
                u[U_THROTTLE] = throttle.cycle(u[U_THROTTLE], t, accel, dt_fcs, p, tb)
            elif us_throttled and int(u[U_ENGINE]) == ENGINE_UPPER and not u[U_T_CUT] > 0.0:
                derivative(t, x, u, p, tb, work[5], work[4])  # the accelerometer, as the first stage's
                u[U_US_THROTTLE] = throttle.cycle_upper(u[U_US_THROTTLE], work[5][rigid_body.A_ACCEL], dt_fcs, p)
        command_update = (k - sched.command_delay_steps) % rates.n_fcs == 0
        if command_update:  # the commands, after the loop delay
            u[U_DPC] = d[D_CMD_P]
            u[U_DYC] = d[D_CMD_Y]
            u[U_RCS] = d[D_CMD_RCS]
            u[U_ROLL] = d[roll_gimbal.D_CMD_ROLL]
            if py_jets:
                u[U_PY_JETS] = d[D_CMD_PY]
                u[U_PY_JETS + 1] = d[D_CMD_PY + 1]
            rcs.step_jets(x, p, u[U_RCS])  # jets without a ramp open and shut at once
        if perturbed:
            loop_perturbation.apply(pert, k, t, dt, command_update, u)

        logging = k % rates.n_log == 0 and log_row < log.shape[0]
        if logging:  # the state before the step, the diagnostics of its first stage
            row = log[log_row]
            row[0] = t
            row[1:1 + nx] = x
        rk4(t, x, u, dt, p, tb, aux, work, logging)
        if logging:
            row[1 + nx:1 + nx + N_AUX] = aux
            row[1 + nx + N_AUX:n_cols] = d
            log_row += 1

        # housekeeping: unit quaternion, physical bounds of bounded states (hard stops)
        qn = 1.0 / np.sqrt(x[Q] ** 2 + x[Q + 1] ** 2 + x[Q + 2] ** 2 + x[Q + 3] ** 2)
        for i in range(Q, Q + 4):
            x[i] *= qn
        for i in (int(p[propulsion.P_FS_TANK]), int(p[propulsion.P_US_OX_TANK]), int(p[propulsion.P_US_FUEL_TANK])):
            if x[i] < 0.0:
                x[i] = 0.0
        if p[propulsion.P_FS_LIQUID] != 0.0 and x[int(p[propulsion.P_FS_FUEL_TANK])] < 0.0:
            x[int(p[propulsion.P_FS_FUEL_TANK])] = 0.0
        for i in range(int(p[boosters.P_TANK]), int(p[boosters.P_TANK] + p[boosters.P_N_BOOSTERS])):
            if x[i] < 0.0:
                x[i] = 0.0
        jets = int(p[rcs.P_STATE_OFFSET])
        for i in (jets, jets + 1):
            x[i] = min(max(x[i], 0.0), 1.0)
        actuator.contain(x, p, int(u[U_ENGINE]))  # the rate and gimbal stops
        slosh.contain(x, p)

        finite = True
        for i in range(x.size):  # no temporary array, this runs every step
            if not np.isfinite(x[i]):
                finite = False
        if not finite:
            return DIVERGED_NONFINITE, j + 1, log_row, "state became non-finite"
        if aux[A_ALT] < -50.0 and t > 1.0:
            return DIVERGED_GROUND, j + 1, log_row, "altitude below ground"
        wmag = np.sqrt(x[W] ** 2 + x[W + 1] ** 2 + x[W + 2] ** 2)
        if wmag > sched.max_body_rate_rad_s:
            return DIVERGED_RATE, j + 1, log_row, "body rate magnitude beyond limit"
    return RUNNING, n_steps, log_row, ""
