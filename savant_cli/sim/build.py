"""Assemble the numeric model of one run from a validated config and the vehicle data:
scalar parameters, plant and flight-software tables, multi-rate schedule, event
schedule and the initial state on the pad.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from savant_cli import constants as C
from savant_cli.config import SavantConfig
from savant_cli.models import earth, quaternion as qt
from savant_cli.models.atmosphere import upper_atmosphere_table
from savant_cli.models.fcs import FcsTables
from savant_cli.models.sensors import gyro_discrete, gyro_steady_state, misalignment
from savant_cli.sim import engine as E
from savant_cli.sim import layout as L
from savant_cli.sim.engine import GuidanceTable, GyroModel, Rates
from savant_cli.flex_slosh import SloshData, load_flex, load_slosh
from savant_cli.sim.plant import PlantTables, pack_tables
from savant_cli.vehicle import Vehicle

CONFIG_NAMES = ("stack", "upper_les", "upper")


@dataclass
class SimModel:
    """Everything the compiled engine needs for one run (all SI)."""

    p: np.ndarray
    tables: PlantTables
    fcs: FcsTables
    gyro: GyroModel
    guidance: GuidanceTable
    rates: Rates
    sched: np.ndarray
    x0: np.ndarray
    d0: np.ndarray
    u0: np.ndarray
    k0: int = 0  # first plant step (non-zero when starting from a staging state)
    events0: np.ndarray = field(default_factory=lambda: np.full(4, np.nan))
    info: dict = field(default_factory=dict)
    layout: L.StateLayout = field(default_factory=L.StateLayout)

    @property
    def packed_tables(self) -> np.ndarray:
        """``tables`` packed into the flat array the compiled plant reads."""
        return pack_tables(self.tables)


def _stack(arrays: list[np.ndarray], fill: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Pad 1-D or 2-D arrays along axis 0 to a common length; return (stacked, lengths)."""
    n = max(a.shape[0] for a in arrays)
    out = np.full((len(arrays), n) + arrays[0].shape[1:], fill)
    for i, a in enumerate(arrays):
        out[i, : a.shape[0]] = a
        out[i, a.shape[0]:] = a[-1]  # hold the last row (keeps padding monotone/harmless)
    return np.ascontiguousarray(out), np.array([a.shape[0] for a in arrays], dtype=np.int64)


_AERO_CACHE: list[tuple[tuple, tuple]] = []  # (the aero objects, the resampled grid), newest last


def _common_aero_grid(vehicle: Vehicle):
    """Resample the three configurations' aero tables onto the union of their axes.

    Multilinear interpolation of a multilinear interpolant at refined nodes reproduces it
    exactly, and clamping outside a table is the same before and after, so this is
    lossless; it lets the kernel hold one (3, 6, nM, nA, nB) array. The result is kept
    for the same (immutable) aero objects, so a batch of models of one vehicle resamples
    once; callers must not modify the returned arrays in place.
    """
    aeros = tuple(vehicle.configurations[n].aero for n in CONFIG_NAMES)
    for key, grid in _AERO_CACHE:
        if all(a is b for a, b in zip(key, aeros)):
            return grid
    grid = _resample_aero(aeros)
    for arr in grid:
        arr.setflags(write=False)  # shared between models: an in-place change would leak
    _AERO_CACHE.append((aeros, grid))
    del _AERO_CACHE[:-4]
    return grid


def _resample_aero(aeros: tuple):
    from scipy.interpolate import RegularGridInterpolator

    mach = np.unique(np.concatenate([a.mach for a in aeros]))
    alpha = np.unique(np.concatenate([a.alpha_rad for a in aeros]))
    beta = np.unique(np.concatenate([a.beta_rad for a in aeros]))
    mg, ag, bg = np.meshgrid(mach, alpha, beta, indexing="ij")
    coef = np.empty((3, 6, mach.size, alpha.size, beta.size))
    for c, a in enumerate(aeros):
        pts = np.stack([np.clip(mg, a.mach[0], a.mach[-1]),
                        np.clip(ag, a.alpha_rad[0], a.alpha_rad[-1]),
                        np.clip(bg, a.beta_rad[0], a.beta_rad[-1])], axis=-1)
        for k in range(6):
            f = RegularGridInterpolator((a.mach, a.alpha_rad, a.beta_rad), a.coeffs[k])
            coef[c, k] = f(pts)
    ref = np.array([[a.area_m2, *a.lref_m, *a.mrp_m] for a in aeros])
    return mach, alpha, beta, np.ascontiguousarray(coef), ref


def _slosh(cfg: SavantConfig, vehicle: Vehicle, slosh: SloshData | None) -> SloshData | None:
    """The slosh data when slosh is on (loaded here unless the caller already has it)."""
    if not cfg.slosh.enabled:
        return None
    return slosh if slosh is not None else load_slosh(vehicle, cfg.slosh)


def _flex_slosh_tables(cfg: SavantConfig, vehicle: Vehicle, slosh: SloshData | None) -> dict[str, np.ndarray]:
    """The flex and slosh fields of :class:`PlantTables` (small placeholders when off)."""
    out: dict[str, np.ndarray] = {}
    if cfg.flex.enabled:
        fx = load_flex(vehicle, cfg.flex, cfg.sim.plant_rate_hz)
        out.update(flex_freq=fx.frequency_rad_s, flex_zeta=fx.damping, flex_shape=fx.shapes)
    else:
        out.update(flex_freq=np.zeros((4, 1)), flex_zeta=np.zeros(1), flex_shape=np.zeros((4, 1, L.N_POINTS, 6)))
    sl = _slosh(cfg, vehicle, slosh)
    if sl is not None:
        level, n = _stack([t.level_m for t in sl.tanks])
        data, _ = _stack([np.column_stack([t.frequency_rad_s, t.damping, t.mass_kg, t.height_m]) for t in sl.tanks])
        out.update(slosh_level=level, slosh_data=data, slosh_len=n)
    else:
        out.update(slosh_level=np.tile([0.0, 1.0], (2, 1)), slosh_data=np.zeros((2, 2, 4)),
                   slosh_len=np.array([2, 2]))
    return {k: np.ascontiguousarray(v, dtype=np.int64 if k == "slosh_len" else np.float64) for k, v in out.items()}


def plant_tables(cfg: SavantConfig, vehicle: Vehicle, slosh: SloshData | None = None) -> PlantTables:
    """Tabular plant data from the vehicle and the winds, flex and slosh configs."""
    mach, alpha, beta, coef, ref = _common_aero_grid(vehicle)
    aeros = [vehicle.configurations[n].aero for n in CONFIG_NAMES]
    masses = [vehicle.configurations[n].mass for n in CONFIG_NAMES]
    base_time, base_len = _stack([a.base_time_s for a in aeros])
    base_force, _ = _stack([a.base_force_N for a in aeros])
    mass_prop, mass_len = _stack([m.propellant_kg for m in masses])
    mass_data, _ = _stack([np.column_stack([m.mass_kg, m.cg_m, m.inertia_kgm2]) for m in masses])
    atm_alt, atm_lnp, atm_lnrho = upper_atmosphere_table()
    w = cfg.winds.profile
    if cfg.winds.enabled:
        wind = [np.asarray(w.altitude_m, float), np.asarray(w.north_mps, float), np.asarray(w.east_mps, float)]
    else:
        wind = [np.array([0.0, 1.0]), np.zeros(2), np.zeros(2)]
    fs, us, rcs = vehicle.first_stage, vehicle.upper_stage, vehicle.rcs
    f64 = lambda a: np.ascontiguousarray(a, dtype=np.float64)  # noqa: E731
    return PlantTables(
        aero_mach=f64(mach), aero_alpha=f64(alpha), aero_beta=f64(beta), aero_coef=coef,
        aero_ref=f64(ref), base_time=base_time, base_force=base_force, base_len=base_len,
        mass_prop=mass_prop, mass_data=mass_data, mass_len=mass_len,
        fs_time=f64(fs.thrust_time_s), fs_thrust=f64(fs.thrust_vac_N),
        us_start_time=f64(us.startup_time_s), us_start_frac=f64(us.startup_fraction),
        rcs_alt=f64(rcs.altitude_m), rcs_thrust=f64(rcs.thrust_vac_N),
        atm_alt=f64(atm_alt), atm_lnp=f64(atm_lnp), atm_lnrho=f64(atm_lnrho),
        wind_alt=f64(wind[0]), wind_north=f64(wind[1]), wind_east=f64(wind[2]),
        **_flex_slosh_tables(cfg, vehicle, slosh),
    )


def scalar_parameters(cfg: SavantConfig, vehicle: Vehicle, slosh: SloshData | None = None) -> np.ndarray:
    """The scalar parameter vector ``p`` (see :mod:`savant_cli.sim.layout`)."""
    p = np.zeros(L.N_PARAM)
    p[L.P_MU] = C.MU_EARTH
    p[L.P_RE] = C.WGS84_A
    p[L.P_J2] = C.EGM2008_J2
    p[L.P_J3] = C.EGM2008_J3
    p[L.P_J4] = C.EGM2008_J4
    p[L.P_OMEGA_E] = C.OMEGA_EARTH
    p[L.P_E2] = C.WGS84_E2
    p[L.P_WIND_SCALE] = cfg.winds.scale if cfg.winds.enabled else 0.0
    fs, us, rcs = vehicle.first_stage, vehicle.upper_stage, vehicle.rcs
    p[L.P_FS_ISP_VAC] = fs.isp_vac_s
    p[L.P_FS_ISP_SL] = fs.isp_sl_s
    p[L.P_FS_EXIT_AREA] = fs.nozzle_exit_area_m2
    p[L.P_FS_THRUST_SCALE] = 1.0
    p[L.P_US_THRUST] = us.thrust_vac_N
    p[L.P_US_ISP] = us.isp_vac_s
    p[L.P_US_MR] = us.mixture_ratio
    p[L.P_US_EXIT_AREA] = us.nozzle_exit_area_m2
    p[L.P_FS_GIMBAL_LIMIT] = fs.gimbal_limit_rad
    p[L.P_US_GIMBAL_LIMIT] = us.gimbal_limit_rad
    p[L.P_FS_GIMBAL_X:L.P_FS_GIMBAL_X + 3] = fs.gimbal_m
    p[L.P_US_GIMBAL_X:L.P_US_GIMBAL_X + 3] = us.gimbal_m
    p[L.P_RCS_EXIT_AREA] = rcs.exit_area_m2
    p[L.P_RCS_N] = rcs.jets_per_direction
    p[L.P_RCS_ARM] = rcs.moment_arm_m
    p[L.P_RCS_RAMP_UP] = rcs.ramp_up_s
    p[L.P_RCS_RAMP_DOWN] = rcs.ramp_down_s
    for stage, base in (("first_stage", L.P_ACT_FS_WA), ("upper_stage", L.P_ACT_US_WA)):
        a = getattr(cfg.actuator, stage)
        p[base] = a.loop_gain_rad_s
        p[base + 1] = 2.0 * np.pi * a.natural_frequency_hz
        p[base + 2] = a.damping
        p[base + 3] = np.radians(a.rate_limit_deg_s)
    lay = state_layout(cfg)
    p[L.P_VALVE_OFF] = lay.valve
    p[L.P_SLOSH_OFF] = lay.slosh_offset
    p[L.P_FLEX_OFF] = lay.flex
    p[L.P_N_MODES] = lay.n_modes
    p[L.P_FLEX_SWITCH] = 1.0 if cfg.flex.switching == "propellant" else 0.0
    p[L.P_FS_PROP_FULL] = fs.propellant_kg
    p[L.P_US_PROP_FULL] = us.lox_kg + us.lh2_kg
    p[L.P_TWD_ON] = 1.0 if cfg.twd.enabled else 0.0
    for base, eng in ((L.P_FS_ENG_M, fs.engine), (L.P_US_ENG_M, us.engine)):
        p[base:base + 3] = eng.mass_kg, eng.cg_from_gimbal_m, eng.inertia_about_gimbal_kgm2
    p[L.P_ACT_KIND] = L.ACT_SIMPLEX if cfg.actuator.name == "simplex" else L.ACT_THIRD_ORDER
    for stage, base, eng in (("first_stage", L.P_SPX_FS, fs.engine), ("upper_stage", L.P_SPX_US, us.engine)):
        a = getattr(cfg.actuator, stage)
        p[base:base + L.N_SPX] = (a.loop_gain_rad_s, 2.0 * np.pi * a.valve_frequency_hz, a.valve_damping,
                                  np.radians(a.rate_limit_deg_s), a.stiffness_Nm_per_rad, a.damping_Nms_per_rad,
                                  eng.inertia_about_gimbal_kgm2, a.leakage_rad_s_per_Nm,
                                  1.0 if a.feedback == "nozzle" else 0.0)
    for stage, base in (("first_stage", L.P_FS_GIMBAL_BIAS), ("upper_stage", L.P_US_GIMBAL_BIAS)):
        p[base:base + 2] = np.radians(getattr(cfg.actuator, stage).null_bias_deg)
    mis = cfg.sensors.misalignment_deg
    for base, eps in ((L.P_IMU_MISALIGN, mis.imu), (L.P_GYRO_US_MISALIGN, mis.rate_gyro_upper_stage),
                      (L.P_GYRO_FS_MISALIGN, mis.rate_gyro_first_stage)):
        p[base:base + 3] = np.radians(eps)
    p[L.P_SLOSH_AREF] = 1.0
    p[L.P_SLOSH_FREQ_SCALE] = cfg.slosh.frequency_scale
    p[L.P_SLOSH_ZETA_SCALE] = cfg.slosh.damping_scale
    sl = _slosh(cfg, vehicle, slosh)
    if sl is not None:
        p[L.P_SLOSH_AREF] = sl.reference_accel_mps2
        for j, tank in enumerate(sl.tanks):
            p[L.P_TANK + 3 * j:L.P_TANK + 3 * j + 3] = tank.radius_m, tank.bottom_station_m, tank.density_kgm3
    p[L.P_AERO_ON] = 1.0 if cfg.environment.aero else 0.0
    p[L.P_THRUST_ON] = 1.0 if cfg.environment.thrust else 0.0
    p[L.P_GRAVITY_ORDER] = cfg.environment.gravity_order
    return p


def fcs_tables(cfg: SavantConfig) -> FcsTables:
    """Flight-control data: filters, blending, gain schedules, roll phase plane."""
    c = cfg.controller
    filters = np.zeros((2, 2, 2, 2, 5))
    roll_filters = np.zeros((2, 2, 2, 5))
    blend = np.zeros((2, 3))
    for s, name in enumerate(("stack", "upper")):
        fs = getattr(c.flex_filters, name)
        for path, sections in enumerate((fs.rate, fs.integrated_rate)):
            for i, sec in enumerate(sections):
                a0 = sec.a[0]
                filters[s, path, i, 0] = np.asarray(sec.b) / a0
                filters[s, path, i, 1] = np.asarray(sec.a) / a0
        for i, sec in enumerate(fs.roll):
            roll_filters[s, i, 0] = np.asarray(sec.b) / sec.a[0]
            roll_filters[s, i, 1] = np.asarray(sec.a) / sec.a[0]
        blend[s] = getattr(c.blending, name)
    axes, data = [], []
    for name in ("stack", "coast", "upper"):
        t = getattr(c.gains, name)
        axes.append(np.asarray(t.breakpoints, float))
        cols = []
        for axis in ("pitch", "yaw"):
            g = getattr(t, axis)
            cols += [g.kp, g.ki, g.kd, g.kir]
        data.append(np.asarray(cols, float).T)
    gain_axis, gain_len = _stack(axes)
    gain_data, _ = _stack(data)
    roll = np.array([np.radians(c.roll.attitude_deadband_deg), np.radians(c.roll.rate_deadband_deg_s),
                     c.roll.lead_time_s])
    return FcsTables(filters=filters, roll_filters=roll_filters, blend=blend, gain_axis=gain_axis,
                     gain_data=gain_data, gain_len=gain_len, roll=roll)


def state_layout(cfg: SavantConfig) -> L.StateLayout:
    """The continuous-state layout of the models switched on in ``cfg``."""
    return L.StateLayout(simplex=cfg.actuator.name == "simplex", slosh=cfg.slosh.enabled,
                         n_modes=cfg.flex.n_modes if cfg.flex.enabled else 0)


def rates(cfg: SavantConfig) -> Rates:
    s = cfg.sim
    ratio = lambda hz: int(round(s.plant_rate_hz / hz))  # noqa: E731
    return Rates(dt=1.0 / s.plant_rate_hz, n_sensor=ratio(s.sensor_rate_hz), n_fcs=ratio(s.fcs_rate_hz),
                 n_guid=ratio(s.guidance_rate_hz), n_log=ratio(s.log_rate_hz))


def separation_time(vehicle: Vehicle) -> float:
    """First time after the thrust peak when first-stage thrust falls below the
    configured fraction of its peak (s)."""
    fs = vehicle.first_stage
    t = np.linspace(fs.thrust_time_s[0], fs.thrust_time_s[-1], 200001)
    f = np.interp(t, fs.thrust_time_s, fs.thrust_vac_N)
    ipk = int(np.argmax(f))
    below = np.nonzero(f[ipk:] < vehicle.events.separation_thrust_fraction * f[ipk])[0]
    return float(t[ipk + below[0]]) if below.size else float(t[-1])


def target_energy(cfg: SavantConfig) -> float:
    """Specific orbital energy of the target orbit, J/kg (point-mass μ, radii from the
    WGS84 equatorial radius)."""
    t = cfg.guidance.target
    rp = C.WGS84_A + 1e3 * t.perigee_altitude_km
    ra = C.WGS84_A + 1e3 * t.apogee_altitude_km
    return -C.MU_EARTH / (rp + ra)


def pad_state(cfg: SavantConfig, vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """CG position (ECI = ECEF at t = 0, m), inertial velocity (m/s) and attitude q_b2i of
    the vehicle standing on the pad; body X along the geodetic up, body Z toward
    ``pad_heading_deg`` (clockwise from north)."""
    ls = cfg.guidance.launch_site
    lat, lon = np.radians(ls.latitude_deg), np.radians(ls.longitude_deg)
    stack = vehicle.configurations["stack"].mass
    cg_station = stack.cg_m[-1, 0]  # full propellant is the last (ascending) row
    h_cg = ls.base_altitude_m + vehicle.length_m - cg_station
    r = earth.geodetic_to_ecef(lat, lon, h_cg, C.WGS84_A, C.WGS84_E2)
    v = np.cross([0.0, 0.0, C.OMEGA_EARTH], r)
    c_e2n = earth.dcm_ecef_to_ned(lat, lon)
    north, east, down = c_e2n[0], c_e2n[1], c_e2n[2]
    psi = np.radians(ls.pad_heading_deg)
    x_b = -down
    z_b = np.cos(psi) * north + np.sin(psi) * east
    y_b = np.cross(z_b, x_b)
    q = qt.from_dcm(np.column_stack([x_b, y_b, z_b]))
    return r, v, q


def build_model(cfg: SavantConfig, vehicle: Vehicle, guidance: GuidanceTable) -> SimModel:
    """Numeric model of one run."""
    slosh = _slosh(cfg, vehicle, None)
    p = scalar_parameters(cfg, vehicle, slosh)
    tb = plant_tables(cfg, vehicle, slosh)
    ft = fcs_tables(cfg)
    rt = rates(cfg)
    ad, bd, cd, dd = gyro_discrete(cfg.sensors.rate_gyro.natural_frequency_hz,
                                   cfg.sensors.rate_gyro.damping, rt.dt * rt.n_sensor)
    gyro = GyroModel(ad=ad, bd=bd, cd=cd, dd=dd)

    r0, v0, q0 = pad_state(cfg, vehicle)
    w0 = qt.dcm(q0).T @ np.array([0.0, 0.0, C.OMEGA_EARTH])  # Earth rate, body axes
    layout = state_layout(cfg)
    x0 = np.zeros(layout.n)
    x0[L.R:L.R + 3] = r0
    x0[L.V:L.V + 3] = v0
    x0[L.Q:L.Q + 4] = q0
    x0[L.W:L.W + 3] = w0
    x0[L.MFS] = vehicle.configurations["stack"].mass.propellant_kg[-1]
    x0[L.MLOX] = vehicle.upper_stage.lox_kg
    x0[L.MLH2] = vehicle.upper_stage.lh2_kg

    d0 = np.zeros(L.N_DISC)
    for g in range(3):
        w_sensed = misalignment(p[L.GYRO_MISALIGN[g]:L.GYRO_MISALIGN[g] + 3])[1] @ w0  # in the gyro's axes
        for ax in range(3):
            s = L.D_GYRO_X + 6 * g + 2 * ax
            d0[s:s + 2] = gyro_steady_state(ad, bd, w_sensed[ax])
            d0[L.D_GYRO_Y + 3 * g + ax] = w_sensed[ax]
    u0 = np.zeros(L.N_INPUT)
    u0[L.U_CONFIG] = L.CONFIG_STACK
    u0[L.U_ENGINE] = L.ENGINE_FIRST

    ev = vehicle.events
    sched = np.zeros(E.N_SCHED)
    sched[E.S_T_SEP] = separation_time(vehicle)
    sched[E.S_T_IGN_DELAY] = ev.ignition_delay_s
    sched[E.S_T_LES_DELAY] = ev.les_jettison_delay_s
    sched[E.S_ENERGY_TARGET] = target_energy(cfg)
    sched[E.S_T_MAX] = cfg.sim.max_time_s
    sched[E.S_STOP_AT_SEP] = 1.0 if cfg.phase.stop_at == "separation" else 0.0
    sched[E.S_SMOOTH_ZETA] = cfg.guidance.smoother.damping
    sched[E.S_SMOOTH_WN] = cfg.guidance.smoother.natural_frequency_rad_s
    sched[E.S_MAX_RATE] = np.radians(cfg.sim.max_body_rate_deg_s)
    info = {"separation_time_s": sched[E.S_T_SEP],
            "gyro_wn_rad_s": 2.0 * np.pi * cfg.sensors.rate_gyro.natural_frequency_hz,
            "gyro_zeta": cfg.sensors.rate_gyro.damping}
    return SimModel(p=p, tables=tb, fcs=ft, gyro=gyro, guidance=guidance, rates=rt, sched=sched,
                    x0=x0, d0=d0, u0=u0, info=info, layout=layout)
