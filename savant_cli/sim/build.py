"""Assemble the numeric model of one run from a validated config and the vehicle data:
scalar parameters, plant and flight-software tables, multi-rate schedule, event
schedule and the initial state on the pad.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from savant_cli import constants
from savant_cli.config import SavantConfig
from savant_cli.errors import ConfigError
from savant_cli.flex_slosh import FlexTables, SloshData, load_flex, load_slosh
from savant_cli.io.guidance_file import SPEED_COLUMN, GuidanceTable
from savant_cli.io.table_order import table_key
from savant_cli.models import (
    PLANT_MODELS, blocks, earth, flex as flex_model, layout, propulsion, quaternion as qt, rigid_body, throttle
)
from savant_cli.models.command_schedule import SCHEDULES
from savant_cli.models.fcs import FcsTables, fcs_tables
from savant_cli.models.guidance import SmootherGains, smoother_gains
from savant_cli.models.sensors import GYRO_MISALIGN, GyroModel, build_gyro, gyro_steady_state, misalignment
from savant_cli.sim import engine
from savant_cli.sim.booster_trace import booster_trace
from savant_cli.sim.engine import EventRule, EventSchedule, Rates
from savant_cli.sim.plant import PlantTables, mass_state, pack_tables
from savant_cli.vehicle import Vehicle
from savant_cli.vehicle.two_stage import BURNOUT_DROP_S, usable_load


@dataclass
class SimModel:
    """Everything the compiled engine needs for one run (all SI)."""

    p: np.ndarray
    tables: PlantTables
    fcs: FcsTables
    gyro: GyroModel
    smoother: SmootherGains
    guidance: GuidanceTable
    rates: Rates
    sched: EventSchedule
    x0: np.ndarray
    d0: np.ndarray
    u0: np.ndarray
    k0: int = 0  # first plant step (non-zero when starting from a staging state)
    events0: np.ndarray = field(default_factory=lambda: np.full(len(engine.EVENT_NAMES), np.nan))
    info: dict = field(default_factory=dict)
    layout: layout.StateLayout = field(default_factory=layout.StateLayout)

    @property
    def packed_tables(self) -> np.ndarray:
        """``tables`` packed into the flat array the compiled plant reads."""
        return pack_tables(self.tables)


def model_inputs(cfg: SavantConfig, vehicle: Vehicle, slosh: SloshData | None = None,
                 flex: FlexTables | None = None) -> blocks.ModelInputs:
    """What the models' builders read: the slosh and flex data are loaded here, once, when
    their model is on and they are not handed in (``savant_cli.flex_slosh``)."""
    if cfg.slosh.enabled and slosh is None:
        slosh = load_slosh(vehicle, cfg.slosh)
    if cfg.flex.enabled and vehicle.boosters is not None and vehicle.boosters.count > flex_model.MAX_BOOSTERS:
        raise ConfigError("flex", "on", f"off for a vehicle with more than {flex_model.MAX_BOOSTERS} strap-on boosters "
                                        f"({vehicle.boosters.count}): their nozzles are flex points, at most "
                                        f"{flex_model.MAX_BOOSTERS}")
    if cfg.flex.enabled and flex is None:
        flex = load_flex(vehicle, cfg.flex, cfg.sim.plant_rate_hz)
    return blocks.ModelInputs(cfg=cfg, vehicle=vehicle, layout=state_layout(cfg, vehicle),
                              slosh=slosh if cfg.slosh.enabled else None, flex=flex if cfg.flex.enabled else None)


def plant_data(cfg: SavantConfig, vehicle: Vehicle, slosh: SloshData | None = None,
               flex: FlexTables | None = None) -> tuple[np.ndarray, PlantTables]:
    """The scalar parameters ``p`` and the tables of the plant: every model of
    :data:`savant_cli.models.PLANT_MODELS` fills its own block."""
    inputs = model_inputs(cfg, vehicle, slosh, flex)
    p = np.zeros(layout.N_PARAM)
    tables: dict[str, np.ndarray] = {}
    for model in PLANT_MODELS:
        model.build(inputs, p, tables)
    missing = set(PlantTables._fields) - set(tables)
    if missing:  # pragma: no cover - a model that declares a table must build it
        raise RuntimeError(f"tables declared but not built: {sorted(missing)}")
    return p, PlantTables(**{name: _contiguous(tables[name]) for name in PlantTables._fields})


def _contiguous(a) -> np.ndarray:
    a = np.asarray(a)
    return np.ascontiguousarray(a, dtype=np.int64 if a.dtype.kind in "iu" else np.float64)


def state_layout(cfg: SavantConfig, vehicle: Vehicle) -> layout.StateLayout:
    """The continuous-state layout of ``vehicle`` with the models switched on in ``cfg``."""
    engines = max(vehicle.first_stage_engine_count + vehicle.gimbaled_boosters, len(vehicle.upper_stage.mounts), 1)
    return layout.StateLayout(tanks=vehicle.tanks + vehicle.booster_tanks, channels=layout.channel_names(engines),
                              simplex=cfg.actuator.name == "simplex",
                              slosh_tanks=tuple(vehicle.slosh_spec or ()) if cfg.slosh.enabled else (),
                              n_modes=cfg.flex.n_modes if cfg.flex.enabled else 0)


def rates(cfg: SavantConfig) -> Rates:
    s = cfg.sim
    ratio = lambda hz: int(round(s.plant_rate_hz / hz))  # noqa: E731
    return Rates(dt=1.0 / s.plant_rate_hz, n_sensor=ratio(s.sensor_rate_hz), n_fcs=ratio(s.fcs_rate_hz),
                 n_guid=ratio(s.guidance_rate_hz), n_log=ratio(s.log_rate_hz))


def predicted_separation_time(vehicle: Vehicle, p: np.ndarray | None = None, tb: np.ndarray | None = None) -> float:
    """A prediction, from the nominal thrust trace alone, of the separation time (s): the
    first time after the trace's peak, and once the separation is armed (from liftoff,
    or its delay after a liquid first stage's cutoff), when the thrust falls below the
    configured fraction of that peak. The flight itself separates on board at the step
    its flown stage meets the rule (``sim/engine.py``); this is only for what is needed
    before any flight (the command table's first-stage samples, reference trajectories).
    A throttled or commanded-cutoff liquid stage's trace needs the run's parameters ``p``
    and packed tables ``tb`` (:func:`first_stage_march`)."""
    return separation_on_trace(vehicle, *first_stage_march(vehicle, p, tb))


def separation_on_trace(vehicle: Vehicle, time_s: np.ndarray, thrust: np.ndarray, t_cut: float) -> float:
    """:func:`predicted_separation_time` on a trace already marched
    (:func:`first_stage_march`: vacuum thrust N vs mission time s, cutoff time s)."""
    t = np.linspace(time_s[0], time_s[-1], 200001)
    f = np.interp(t, time_s, thrust)
    ipk = int(np.argmax(f))
    sep = vehicle.events.trigger(engine.EV_SEPARATION)
    t_armed = (t_cut if sep.after == engine.EV_FS_CUTOFF else 0.0) + sep.delay_s
    start = max(ipk, int(np.searchsorted(t, t_armed)))
    below = np.nonzero(f[start:] < vehicle.events.separation_thrust_fraction * f[ipk])[0]
    return float(t[start + below[0]]) if below.size else max(float(t[-1]), t_armed)  # (no thrust after the trace)


#: The step of the throttled trace's march (s).
TRACE_STEP_S = 0.05


def nominal_first_stage_trace(vehicle: Vehicle, p: np.ndarray | None = None,
                              tb: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The first stage's nominal vacuum thrust (N) against mission time (s)
    (:func:`first_stage_march`)."""
    time_s, thrust, _ = first_stage_march(vehicle, p, tb)
    return time_s, thrust


def event_times(vehicle: Vehicle, slots: tuple[int, ...], t_sep: float = np.inf, t_fs_cut: float | None = None,
                t_boosters: float = np.inf) -> dict[int, float]:
    """A prediction's time of each event slot in ``slots`` (s from liftoff; ``inf``: none,
    or after an event the prediction does not reach): the separation ``t_sep``, a liquid
    first stage's cutoff ``t_fs_cut`` and the boosters' jettison ``t_boosters`` as given,
    every other event its delay after the event it counts from, a jettison not before
    the one written before it (``Trigger.waits_for``); conditions are not waited for."""
    times = {-1: 0.0, engine.EV_SEPARATION: t_sep, engine.EV_FS_CUTOFF: np.inf if t_fs_cut is None else t_fs_cut,
             engine.EV_BOOSTER_JETTISON: t_boosters}

    def time_of(slot: int) -> float:
        if slot not in times:
            trigger = vehicle.events.trigger(slot)
            t = time_of(trigger.after) + trigger.delay_s
            times[slot] = t if trigger.waits_for < 0 else max(t, time_of(trigger.waits_for))
        return times[slot]

    return {slot: time_of(slot) for slot in slots}


def first_stage_mass(vehicle: Vehicle) -> Callable[[float, float], float]:
    """The mass (kg) of the configuration flown with the first stage at ``t`` (s) with
    ``left_kg`` of the stage's propellant, strap-on boosters apart: its mass table at that
    propellant, each configuration from the jettison that starts it, the boosters' at
    their predicted jettison, the items' at their delays (:func:`event_times`; a
    condition is not waited for)."""
    n_fs = vehicle.first_stage_configurations
    tables = [c.mass for c in list(vehicle.configurations.values())[:n_fs]]
    drops = [j.slot for j in vehicle.jettisons[:n_fs - 1]]
    boosters = booster_trace(vehicle)
    times = event_times(vehicle, tuple(drops), t_boosters=boosters.jettison_s if boosters is not None else np.inf)
    starts = np.array([times[s] for s in drops])
    first = 1 if boosters is not None else 0  # with boosters: the stack's table, the boosters' own mass apart

    def mass(t: float, left_kg: float) -> float:
        table = tables[max(int(np.searchsorted(starts, t, side="right")), first)]
        return float(np.interp(left_kg, table.propellant_kg, table.mass_kg))

    return mass


def first_stage_march(vehicle: Vehicle, p: np.ndarray | None = None,
                      tb: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, float]:
    """The first stage's nominal vacuum thrust (N) against mission time (s), and its
    cutoff time (s: a liquid stage's commanded cutoff, else the end of its burn; NaN for
    a motor).

    A motor's, and an unthrottled liquid stage's without a commanded cutoff, is its
    thrust table. Otherwise the stage is marched at :data:`TRACE_STEP_S` with the
    flight's own throttle law (``models/throttle.py::cycle``, each step a cycle; an
    unthrottled stage at rated thrust), its sensed axial acceleration taken as the
    vacuum thrust over the mass of the configuration flown at the propellant left
    (:func:`first_stage_mass`: an item dropped in the stage's flight leaves at its delay),
    the strap-on boosters' nominal thrust and mass added until their predicted jettison
    (``sim/booster_trace.py``;
    no drag, no back-pressure loss: an acceleration a little high, so the predicted
    throttling comes a little early and the burn a little long), until the cutoff's trigger holds
    (``events.first_stage_cutoff``: its delay after liftoff is landed on; a tank's
    propellant crossing its threshold is placed within the step by linear interpolation;
    an axial acceleration at the step's end) or the usable load is burned. From the
    cutoff the thrust decays linearly to zero over the engines' shutdown transient
    ``2 I_sd / F_rated`` (``models/propulsion.py``), the setting held. The trace's own
    (trapezoidal) impulse is ``g0 Isp`` times the propellant it burns."""
    fs = vehicle.first_stage
    cut = vehicle.events.trigger(engine.EV_FS_CUTOFF)
    if fs.liquid is None:
        return fs.thrust_time_s, fs.thrust_vac_N, float("nan")
    throttled = fs.liquid.throttle is not None
    if not throttled and not np.isfinite(cut.delay_s):
        return fs.thrust_time_s, fs.thrust_vac_N, float(fs.thrust_time_s[-2])
    if throttled and (p is None or tb is None):
        raise ValueError("a throttled first stage's trace needs the run's parameters and tables")
    stack_mass = first_stage_mass(vehicle)
    rated = fs.liquid.thrust_vac_N * float(fs.liquid.startup_fraction[-1])
    flow_per_thrust = 1.0 / (constants.G0 * fs.isp_vac_s)
    mr = fs.liquid.mixture_ratio
    load = usable_load(mr, fs.oxidizer_kg, fs.fuel_kg)
    ox_tank = vehicle.first_stage_tanks[0]
    boosters = booster_trace(vehicle)

    def accel(t: float, f: float, left_kg: float) -> float:
        """The drag-free axial acceleration at ``t`` (s) with the stage's vacuum thrust ``f``
        (N) and ``left_kg`` of its propellant: the boosters' thrust and mass added while
        they are attached."""
        mass = stack_mass(t, left_kg)
        if boosters is None:
            return f / mass
        f_b, m_b = boosters.at(t)
        return (f + f_b) / (mass + m_b)

    def watched(t: float, burned: float, f: float) -> float:
        """The cutoff condition's quantity at ``t`` with ``burned`` kg burned at thrust ``f`` (N)."""
        if cut.quantity == "propellant_kg":
            ox, fuel = fs.oxidizer_kg - burned * mr / (1.0 + mr), fs.fuel_kg - burned / (1.0 + mr)
            return ox if cut.tank == ox_tank else fuel
        return accel(t, f, fs.propellant_kg - burned)

    def holds(value: float) -> bool:
        return value > cut.threshold if cut.above else value < cut.threshold

    def cycle(k: float, t: float, accel: float) -> float:
        return throttle.cycle(k, t, accel, TRACE_STEP_S, p, tb) if throttled else 1.0

    time_s = list(fs.thrust_time_s[fs.thrust_time_s < 0.0])
    thrust = list(fs.thrust_vac_N[fs.thrust_time_s < 0.0])
    t, burned, k = 0.0, 0.0, throttle.start(p, tb) if throttled else 1.0
    time_s.append(t)
    thrust.append(k * rated)
    while not (t >= cut.delay_s and (cut.quantity is None or holds(watched(t, burned, k * rated)))):
        f = k * rated
        left = load - burned
        h = min(TRACE_STEP_S, cut.delay_s - t) if cut.delay_s > t else TRACE_STEP_S
        burned_step = left
        if f * flow_per_thrust * h < left:  # a cycle: the setting from the acceleration at its end
            a_end = accel(t + h, f, fs.propellant_kg - burned - f * flow_per_thrust * h)
            k_next = cycle(k, t + h, a_end) if h == TRACE_STEP_S else k  # (a step cut short: the setting held)
            burned_step = 0.5 * (f + k_next * rated) * flow_per_thrust * h  # the table's trapezoid
        if burned_step >= left:  # the last step, at the setting held: the load burned exactly
            t += left / (f * flow_per_thrust)
            time_s.append(t)
            thrust.append(f)
            time_s.append(t + BURNOUT_DROP_S)
            thrust.append(0.0)
            return np.asarray(time_s), np.asarray(thrust), t
        if cut.quantity == "propellant_kg" and t + h >= cut.delay_s:
            before, after = watched(t, burned, f), watched(t + h, burned + burned_step, k_next * rated)
            if holds(after) and after != before:  # the crossing, within the step
                s = min(max((cut.threshold - before) / (after - before), 0.0), 1.0)
                h, k_next = s * h, k + s * (k_next - k)
                burned_step = 0.5 * (f + k_next * rated) * flow_per_thrust * h
                burned += burned_step
                t += h
                k = k_next
                time_s.append(t)
                thrust.append(k * rated)
                break
        burned += burned_step
        t += h
        k = k_next
        time_s.append(t)
        thrust.append(k * rated)
    t_cut, f_cut = t, k * rated
    t_sd = 2.0 * fs.liquid.shutdown_impulse_Ns / fs.liquid.thrust_vac_N
    left = load - burned
    if t_sd > 0.0 and 0.5 * f_cut * t_sd * flow_per_thrust <= left:
        time_s.append(t_cut + t_sd)
        thrust.append(0.0)
    elif t_sd > 0.0:  # a tank empties during the decay: f_cut (τ − τ²/2T) burns what is left
        tau = t_sd * (1.0 - np.sqrt(1.0 - 2.0 * left / (f_cut * flow_per_thrust * t_sd)))
        time_s += [t_cut + tau, t_cut + tau + BURNOUT_DROP_S]
        thrust += [f_cut * (1.0 - tau / t_sd), 0.0]
    else:
        time_s.append(t_cut + BURNOUT_DROP_S)
        thrust.append(0.0)
    return np.asarray(time_s), np.asarray(thrust), t_cut


def target_energy(cfg: SavantConfig) -> float:
    """Specific orbital energy of the target orbit, J/kg (point-mass μ, radii from the
    WGS84 equatorial radius)."""
    t = cfg.guidance.target
    rp = constants.WGS84_A + 1e3 * t.perigee_altitude_km
    ra = constants.WGS84_A + 1e3 * t.apogee_altitude_km
    return -constants.MU_EARTH / (rp + ra)


def pad_state(cfg: SavantConfig, vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """CG position (ECI = ECEF at t = 0, m), inertial velocity (m/s) and attitude q_b2i of
    the vehicle standing on the pad; body X along the geodetic up, body Z toward
    ``pad_heading_deg`` (clockwise from north)."""
    ls = cfg.guidance.launch_site
    lat, lon = np.radians(ls.latitude_deg), np.radians(ls.longitude_deg)
    stack = vehicle.configurations["stack"].mass
    cg_station = stack.cg_m[-1, 0]  # full propellant is the last (ascending) row
    h_cg = ls.base_altitude_m + vehicle.length_m - cg_station
    r = earth.geodetic_to_ecef(lat, lon, h_cg, constants.WGS84_A, constants.WGS84_E2)
    v = np.cross([0.0, 0.0, constants.OMEGA_EARTH], r)
    c_e2n = earth.dcm_ecef_to_ned(lat, lon)
    north, east, down = c_e2n[0], c_e2n[1], c_e2n[2]
    psi = np.radians(ls.pad_heading_deg)
    x_b = -down
    z_b = np.cos(psi) * north + np.sin(psi) * east
    y_b = np.cross(z_b, x_b)
    q = qt.from_dcm(np.column_stack([x_b, y_b, z_b]))
    return r, v, q


def first_stage_profile(table: GuidanceTable, cfg: SavantConfig, t_sep: float) -> GuidanceTable:
    """The command table with its reference speeds cut to the first-stage samples it is
    indexed by under ``guidance.first_stage_schedule=relative_velocity``: from liftoff to
    the reference's fastest sample before separation at ``t_sep`` (s; the tail-off slows
    the vehicle), strictly increasing (models/command_schedule.py)."""
    if cfg.guidance.first_stage_schedule == "time":
        return table._replace(speed=np.zeros(0))
    key = "guidance.first_stage_schedule"
    if table.speed.size != table.time.size:
        raise ConfigError(key, cfg.guidance.first_stage_schedule,
                          f"needs the command file's v_rel_m_s column (the reference ascent's Earth-relative speed); "
                          f"{cfg.guidance.command_file} has none: add it with `python -m "
                          f"savant_cli.datagen.guidance_commands --add-speed` or use first_stage_schedule=time")
    n_first = int(np.searchsorted(table.time, t_sep, side="right"))
    m = int(np.argmax(table.speed[:n_first])) + 1 if n_first else 0
    speed = table.speed[:m]
    if m < 2 or not np.all(np.diff(speed) > 0.0):
        i = int(np.argmin(np.diff(speed) > 0.0)) + 1 if m >= 2 else 0
        key = table_key(Path("guidance") / cfg.guidance.command_file)  # looked up in <config dir>/guidance/
        raise ConfigError(f"{key}:{SPEED_COLUMN}", float(table.speed[i]),
                          f"guidance.first_stage_schedule=relative_velocity needs the reference speed strictly "
                          f"increasing from liftoff to its first-stage peak; it is not at sample {i + 1} "
                          f"(t = {table.time[i]:g} s); put the rows in order or use first_stage_schedule=time")
    return table._replace(speed=np.ascontiguousarray(speed))


#: A condition's quantity (vehicle/tree.py) → the engine's code of it.
WHEN_CODES = {None: engine.WHEN_NONE, "thrust_fraction": engine.WHEN_THRUST_FRACTION,
              "axial_acceleration_mps2": engine.WHEN_AXIAL_ACCELERATION, "altitude_m": engine.WHEN_ALTITUDE,
              "dynamic_pressure_Pa": engine.WHEN_DYNAMIC_PRESSURE, "propellant_kg": engine.WHEN_PROPELLANT,
              "radial_speed_mps": engine.WHEN_RADIAL_SPEED}


def event_schedule(cfg: SavantConfig, vehicle: Vehicle, rt: Rates) -> EventSchedule:
    """The event rules and run limits of one run, from the vehicle's events and the config."""
    triggers = [vehicle.events.trigger(k) for k in range(len(engine.EVENT_NAMES))]
    x_layout = state_layout(cfg, vehicle)
    return EventSchedule(
        rules=tuple(EventRule(after=int(tr.after), delay_s=float(tr.delay_s),
                              when=engine.WHEN_BOOSTER_THRUST_FRACTION if tr.booster is not None
                              else WHEN_CODES[tr.quantity],
                              of=x_layout.tank(tr.tank) if tr.tank else tr.booster if tr.booster is not None else -1,
                              above=bool(tr.above), threshold=float(tr.threshold), waits_for=int(tr.waits_for))
                    for tr in triggers),
        cutoff_energy_j_kg=float(target_energy(cfg)),
        max_time_s=float(cfg.sim.max_time_s),
        stop_at_separation=cfg.phase.stop_at == "separation",
        max_body_rate_rad_s=float(np.radians(cfg.sim.max_body_rate_deg_s)),
        command_delay_steps=int(round(cfg.controller.delay_s / rt.dt)),
        profile_schedule=SCHEDULES.index(cfg.guidance.first_stage_schedule))


def build_model(cfg: SavantConfig, vehicle: Vehicle, guidance: GuidanceTable) -> SimModel:
    """Numeric model of one run."""
    p, tb = plant_data(cfg, vehicle)
    ft = fcs_tables(cfg.controller)
    rt = rates(cfg)
    gyro = build_gyro(cfg.sensors.rate_gyro, rt.dt * rt.n_sensor)

    r0, v0, q0 = pad_state(cfg, vehicle)
    w0 = qt.dcm(q0).T @ np.array([0.0, 0.0, constants.OMEGA_EARTH])  # Earth rate, body axes
    x_layout = state_layout(cfg, vehicle)
    x0 = np.zeros(x_layout.n)
    x0[layout.R:layout.R + 3] = r0
    x0[layout.V:layout.V + 3] = v0
    x0[layout.Q:layout.Q + 4] = q0
    x0[layout.W:layout.W + 3] = w0
    fs_tanks, (ox, fuel) = vehicle.first_stage_tanks, vehicle.upper_stage_tanks
    fs = vehicle.first_stage
    if fs.liquid is None:
        x0[x_layout.tank(fs_tanks[0])] = vehicle.configurations["stack"].mass.propellant_kg[-1]
    else:
        x0[x_layout.tank(fs_tanks[0])] = fs.oxidizer_kg
        x0[x_layout.tank(fs_tanks[1])] = fs.fuel_kg
    x0[x_layout.tank(ox)] = vehicle.upper_stage.lox_kg
    for tank in vehicle.booster_tanks:
        x0[x_layout.tank(tank)] = vehicle.boosters.propellant_kg
    x0[x_layout.tank(fuel)] = vehicle.upper_stage.lh2_kg
    # the pad state is the whole vehicle's CG; with slosh on the state's reference point
    # is the rigid part's (the slosh masses left out): move it there
    _, whole, rigid = mass_state(x0, p, pack_tables(tb), layout.CONFIG_STACK, np.zeros(layout.N_AUX))
    rigid_body.move_reference(x0, rigid[1] - whole[1], rigid[2] - whole[2], rigid[3] - whole[3])

    d0 = np.zeros(layout.N_DISC)
    d0[propulsion.D_FS_PROP_SEP] = 0.0  # set at separation (read only once the event has happened)
    for g in range(3):
        w_sensed = misalignment(p[GYRO_MISALIGN[g]:GYRO_MISALIGN[g] + 3])[1] @ w0  # in the gyro's axes
        for ax in range(3):
            s = layout.D_GYRO_X + 6 * g + 2 * ax
            d0[s:s + 2] = gyro_steady_state(gyro.ad, gyro.bd, w_sensed[ax])
            d0[layout.D_GYRO_Y + 3 * g + ax] = w_sensed[ax]
    u0 = np.zeros(layout.N_INPUT)
    u0[layout.U_CONFIG] = layout.CONFIG_STACK
    u0[layout.U_ENGINE] = layout.ENGINE_FIRST
    packed = pack_tables(tb)
    u0[layout.U_THROTTLE] = throttle.start(p, packed)
    u0[layout.U_US_THROTTLE] = p[throttle.P_US_MAX]  # set again at the upper stage's ignition

    sched = event_schedule(cfg, vehicle, rt)
    t_sep_predicted = predicted_separation_time(vehicle, p, packed)
    guidance = first_stage_profile(guidance, cfg, t_sep_predicted)
    info = {"predicted_separation_time_s": t_sep_predicted}
    return SimModel(p=p, tables=tb, fcs=ft, gyro=gyro, smoother=smoother_gains(cfg.guidance.smoother),
                    guidance=guidance, rates=rt, sched=sched, x0=x0, d0=d0, u0=u0, info=info, layout=x_layout)
