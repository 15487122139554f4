"""Reproducible generator of the default guidance command file.

A three-degree-of-freedom ascent (point mass with the vehicle's own thrust, mass, and
aerodynamic tables of the configuration flown, each jettison at its predicted time;
strap-on boosters' thrust and mass on their own nominal trace while they are attached;
J2–J4 gravity; US76 atmosphere; rotating Earth, no wind) is flown
with an attitude program, and the attitude is written at 1 Hz as inertial quaternions and
eigenaxis rates — the form the source paper's guidance commands take (§III.E).

Attitude program (body axes relative to the launch frame, the pad's NED axes frozen in
inertial space at liftoff):

1. vertical rise (body X up, body Z toward ``pad_heading_deg``);
2. roll program about body X, from the pad heading to the flight azimuth (cosine-shaped
   angle profile, from ``roll_start_s`` over ``roll_duration_s``);
3. pitch-over: tilt toward the flight azimuth by ``pitchover_angle_deg`` (cosine profile,
   from ``pitchover_start_s`` over ``pitchover_duration_s``);
4. gravity turn: body X along the Earth-relative velocity, the angle left at the end of
   the pitch-over fading with time constant ``alpha_fade_s`` — near-zero α through max-Q;
   this continues through separation and the coast;
5. upper stage from J-2X ignition: linear-tangent steering in the orbit plane of the
   ignition state, tan θ = A + B·(t − t_ign), θ the thrust elevation above the local
   horizontal. A and B are solved so that the target orbital energy is reached at the
   target cutoff altitude with the target orbit's flight-path angle.

The flight azimuth is solved so that the cutoff orbit has the target inclination.

Regenerate with::

    python -m savant_cli.datagen.guidance_commands            # default config
    python -m savant_cli.datagen.guidance_commands guidance.generator.pitchover_angle_deg=2.5

which writes the file named by ``guidance.command_file`` into ``conf/guidance/`` of the
source tree (or ``--out PATH``).
"""

from __future__ import annotations

import argparse
import bisect
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import optimize
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from savant_cli import constants
from savant_cli.config import SavantConfig
from savant_cli.errors import ConfigError
from savant_cli.io.guidance_file import SPEED_COLUMN
from savant_cli.models import aero, atmosphere as atm, earth, mass as mass_model, quaternion as qt
from savant_cli.models.boosters import thrust_direction
from savant_cli.models.gravity import gravity_zonal
from savant_cli.models.peg import insertion_state
from savant_cli.sim import build, engine
from savant_cli.sim.booster_trace import booster_trace
from savant_cli.sim.plant import pack_tables
from savant_cli.vehicle import Vehicle

G0 = constants.G0


@dataclass
class Program:
    """Attitude-program settings (``guidance.generator`` in the config)."""

    roll_start_s: float = 5.0
    roll_duration_s: float = 20.0
    pitchover_start_s: float = 10.0
    pitchover_duration_s: float = 15.0
    pitchover_angle_deg: float = 3.0
    alpha_fade_s: float = 8.0
    steering_blend_s: float = 15.0  # from the coast attitude to linear-tangent steering after ignition
    extend_s: float = 40.0  # commands continue this long past the reference cutoff

    @classmethod
    def from_config(cls, gen: dict) -> "Program":
        known = set(cls.__dataclass_fields__)
        unknown = set(gen) - known
        if unknown:
            raise ConfigError(f"guidance.generator.{sorted(unknown)[0]}", gen[sorted(unknown)[0]],
                              f"unknown key; known: {', '.join(sorted(known))}")
        return cls(**{k: float(v) for k, v in gen.items()})


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a × b`` of two 3-vectors: numpy's own products and differences, term for term
    (so bit for bit ``np.cross``), without its general-shape overhead, which was a third
    of the reference ascent's integration time."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _norm(a: np.ndarray) -> float:
    """Euclidean norm of a 3-vector: ``np.linalg.norm``'s own ``sqrt(a·a)`` (bit for bit),
    without its general-shape overhead."""
    return math.sqrt(a.dot(a))


def _columns(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """The 3×3 matrix of columns ``a``, ``b``, ``c`` (``np.column_stack``'s, without its overhead)."""
    m = np.empty((3, 3))
    m[:, 0], m[:, 1], m[:, 2] = a, b, c
    return m


def _cosine_ramp(t: float, start: float, duration: float) -> float:
    """0 before ``start``, 1 after ``start + duration``, half-cosine in between."""
    if t <= start:
        return 0.0
    if t >= start + duration:
        return 1.0
    return 0.5 * (1.0 - np.cos(np.pi * (t - start) / duration))


#: The events this reference places at their delays: the ignition and the items' jettisons.
TIMED_SLOTS = (engine.EV_IGNITION, *engine.EV_ITEMS)


def timed_events(vehicle: Vehicle) -> None:
    """Refuse a vehicle whose ignition or an item's jettison waits for a condition: this
    reference places those events at their delays (``sim/build.py::event_times``)."""
    names = vehicle.events.names
    for slot in TIMED_SLOTS:
        if vehicle.events.trigger(slot).quantity is not None:
            key = f"vehicle.events.{names[slot]}.when" if len(names) > slot else "vehicle.events"
            raise ConfigError(key, vehicle.events.trigger(slot).quantity,
                              f"the reference ascent of this generator places the ignition and the jettisons at "
                              f"their delays: generate the command file without the condition, with a delay that "
                              f"stands for it ('~{key}' and {key[:-5]}.delay_s=...; docs/vehicles.md)")


class Reference:
    """Three-degree-of-freedom reference ascent for a given azimuth and steering."""

    def __init__(self, cfg: SavantConfig, vehicle: Vehicle, prog: Program):
        self.cfg = cfg
        self.vehicle = vehicle
        self.prog = prog
        #: the strap-on boosters' nominal thrust, mass and jettison (None: none)
        self.boosters = booster_trace(vehicle)
        b = vehicle.boosters
        #: the boosters' delivered thrust along body x per N of it (their cants' mean cosine)
        self.booster_axial = float(thrust_direction(b.cant_rad)[:, 0].mean()) if b is not None else 0.0
        self.params, self.tb = build.plant_data(cfg, vehicle)
        self.packed = pack_tables(self.tb)  # the plant's own kernels read these
        # the first stage's nominal trace (a throttled liquid stage's under the flight's own law)
        self.fs_time, self.fs_thrust, t_fs_cut = build.first_stage_march(vehicle, self.params, self.packed)
        self.r0, self.v0, self.q0 = build.pad_state(cfg, vehicle)
        ls = cfg.guidance.launch_site
        lat, lon = np.radians(ls.latitude_deg), np.radians(ls.longitude_deg)
        self.c_e2n = earth.dcm_ecef_to_ned(lat, lon)  # = ECI→launch frame at t = 0
        self.pad_heading = np.radians(ls.pad_heading_deg)
        # a prediction: no flight exists here (the flight separates on board)
        self.t_sep = build.separation_on_trace(vehicle, self.fs_time, self.fs_thrust, t_fs_cut)
        timed_events(vehicle)
        t_boosters = self.boosters.jettison_s if self.boosters is not None else np.inf
        times = build.event_times(vehicle, (engine.EV_SEPARATION, engine.EV_BOOSTER_JETTISON, *TIMED_SLOTS),
                                  self.t_sep, t_fs_cut, t_boosters)
        self.t_ign = times[engine.EV_IGNITION]
        #: each jettison's time (the boosters', the separation's and the items'), ascending:
        #: the k-th moves to configuration k (s)
        self.jettison_times = np.sort([times[k] for k in (engine.EV_BOOSTER_JETTISON, engine.EV_SEPARATION,
                                                          *engine.EV_ITEMS)])
        self._us_t_end = float(self.tb.us_start_time[-1])
        self._us_frac_end = float(self.tb.us_start_frac[-1])
        self._jettison_list = self.jettison_times.tolist()  # config_at's bisection (searchsorted's answer)
        #: each configuration's aerodynamic reference area (m²)
        self._ref_area = [float(aero.reference(self.packed, k)[aero.REF_AREA])
                          for k in range(self.jettison_times.size + 1)]
        self.n_first_stage_configs = vehicle.first_stage_configurations
        self.energy_target = build.target_energy(cfg)
        tgt = cfg.guidance.target
        self.r_cut, _, self.fpa_cut = insertion_state(tgt.perigee_altitude_km, tgt.apogee_altitude_km,
                                                      tgt.cutoff_altitude_km)  # ascending branch
        self.inclination = np.radians(tgt.inclination_deg)

    # ----------------------------------------------------------------- attitude
    def _roll_angles(self, t: float, azimuth: float) -> tuple[float, float]:
        """Roll-program angle at ``t`` and its final value (rad, about body X)."""
        delta = np.angle(np.exp(1j * (azimuth - self.pad_heading)))  # shortest roll
        final = -delta
        return final * _cosine_ramp(t, self.prog.roll_start_s, self.prog.roll_duration_s), final

    def _residual_roll(self, t: float, azimuth: float) -> np.ndarray:
        """Body-fixed rotation by the roll still to go (identity once the roll is done)."""
        roll, final = self._roll_angles(t, azimuth)
        return Rotation.from_rotvec([roll - final, 0.0, 0.0]).as_matrix()

    def launch_attitude(self, t: float, azimuth: float) -> np.ndarray:
        """Body→ECI DCM of the vertical-rise, roll and pitch-over phases: the pad attitude
        turned to the flight azimuth, pitched over by the tilt, then rolled back about
        the (tilted) body X by the roll still to go — so the roll program and the
        pitch-over may overlap and the gravity turn continues the same residual roll."""
        x0 = -self.c_e2n[2]  # up
        z0 = np.cos(self.pad_heading) * self.c_e2n[0] + np.sin(self.pad_heading) * self.c_e2n[1]
        c0 = np.column_stack([x0, _cross(z0, x0), z0])
        _, final = self._roll_angles(t, azimuth)
        pr = self.prog
        tilt = np.radians(pr.pitchover_angle_deg) * _cosine_ramp(t, pr.pitchover_start_s, pr.pitchover_duration_s)
        rot = Rotation.from_rotvec([final, 0.0, 0.0]) * Rotation.from_rotvec([0.0, -tilt, 0.0])
        return c0 @ rot.as_matrix() @ self._residual_roll(t, azimuth)

    @staticmethod
    def _frame_from_x(x_b: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Body→ECI DCM with body X along ``x_b`` and body Z toward local down (wings level)."""
        down = -r / _norm(r)
        z = down - down.dot(x_b) * x_b
        z /= _norm(z)
        return _columns(x_b, _cross(z, x_b), z)

    def attitude(self, t: float, y: np.ndarray, azimuth: float, steer: tuple[float, float],
                 turn: dict) -> np.ndarray:
        """Commanded body→ECI DCM at time ``t`` and 3-DOF state ``y``."""
        pr = self.prog
        t_turn = pr.pitchover_start_s + pr.pitchover_duration_s
        if t < t_turn or "axis" not in turn:  # the pitch-over leg itself is integrated without turn data
            return self.launch_attitude(t, azimuth)
        r, v = y[0:3], y[3:6]
        if t < self.t_ign or "plane_normal" not in turn:
            v_rel = earth.velocity_relative_eci(r, v, constants.OMEGA_EARTH)
            v_hat = v_rel / _norm(v_rel)
            axis = turn["axis"]
            x_b = Rotation.from_rotvec(axis * turn["alpha0"] * np.exp(-(t - t_turn) / pr.alpha_fade_s)).apply(v_hat)
            return self._frame_from_x(x_b, r) @ self._residual_roll(t, azimuth)
        r_hat = r / _norm(r)
        h_hat = turn["plane_normal"]
        downrange = _cross(h_hat, r_hat)
        theta = np.arctan(steer[0] + steer[1] * (t - self.t_ign))
        x_b = np.cos(theta) * downrange + np.sin(theta) * r_hat
        # continuous command at ignition: rotate from the (inertially held) coast
        # attitude to the steering direction along a cosine ramp
        s = _cosine_ramp(t, self.t_ign, pr.steering_blend_s)
        if s < 1.0:
            x0 = turn["x_ignition"]
            axis = _cross(x0, x_b)
            sin_a = _norm(axis)
            if sin_a > 1e-12:
                ang = np.arctan2(sin_a, x0.dot(x_b))
                x_b = Rotation.from_rotvec(axis / sin_a * ang * s).apply(x0)
        return self._frame_from_x(x_b, r)

    # ----------------------------------------------------------------- dynamics
    def config_at(self, t: float) -> int:
        """The configuration flown at ``t`` (s): its number, one more for each jettison."""
        return bisect.bisect_right(self._jettison_list, t)

    def rhs(self, t: float, y: np.ndarray, azimuth: float, steer, turn) -> np.ndarray:
        """3-DOF derivative of [r, v, m_fs, m_lox, m_lh2] (ECI, SI)."""
        r, v = y[0:3], y[3:6]
        tb = self.tb
        cfg_i = self.config_at(t)
        prop = y[6] if cfg_i < self.n_first_stage_configs else y[7] + y[8]
        boosted = self.boosters is not None and cfg_i == 0
        # with the boosters attached: the stack's mass without them (the next configuration's)
        # and theirs on their own trace, as the flight exchanges their rows (models/boosters.py)
        mass = mass_model.mass_properties(self.packed, 1 if boosted else cfg_i, max(prop, 0.0))[0]
        f_boosters = 0.0
        if boosted:
            f_boosters, m_boosters = self.boosters.at(t)
            mass += m_boosters
        c_b2i = self.attitude(t, y, azimuth, steer, turn)
        x_b = c_b2i[:, 0]
        c_i2e = earth.dcm_eci_to_ecef(t, constants.OMEGA_EARTH)
        lat, lon, alt = earth.ecef_to_geodetic(c_i2e @ r, constants.WGS84_A, constants.WGS84_E2)
        _, pres, rho, sos = atm.air_at_packed(alt, self.packed)
        g = gravity_zonal(r, constants.MU_EARTH, constants.WGS84_A, constants.EGM2008_J2, constants.EGM2008_J3, constants.EGM2008_J4)
        v_rel = earth.velocity_relative_eci(r, v, constants.OMEGA_EARTH)
        f = np.zeros(3)
        mdot = np.zeros(3)
        vv = _norm(v_rel)
        if vv > 1e-3:
            qbar = 0.5 * rho * vv * vv
            cos_a = min(max(x_b.dot(v_rel) / vv, -1.0), 1.0)
            alpha_t = np.arccos(cos_a)
            ca, _, cn, _, _, _ = aero.coefficients_at(self.packed, cfg_i, vv / sos, alpha_t, 0.0)
            s_ref = self._ref_area[cfg_i]
            f += -qbar * s_ref * ca * x_b
            n_dir = v_rel / vv - cos_a * x_b  # normal force pushes against the crossflow
            nn = _norm(n_dir)
            if nn > 1e-9:
                f += -qbar * s_ref * cn * n_dir / nn
        fs, us = self.vehicle.first_stage, self.vehicle.upper_stage
        if boosted:  # delivered: each booster's vacuum thrust less its exit area's back pressure
            b = self.vehicle.boosters
            f += max(f_boosters - pres * b.count * b.nozzle_exit_area_m2, 0.0) * self.booster_axial * x_b
        if cfg_i < self.n_first_stage_configs and y[6] > 0.0:
            f_vac = np.interp(t, self.fs_time, self.fs_thrust)
            f += max(f_vac - pres * fs.nozzle_exit_area_m2, 0.0) * x_b
            mdot[0] = f_vac / (G0 * fs.isp_vac_s)
        elif t >= self.t_ign and y[7] > 0.0 and y[8] > 0.0:
            dt = t - self.t_ign  # past the start transient: its table's last value (np.interp's answer)
            frac = self._us_frac_end if dt >= self._us_t_end else np.interp(dt, tb.us_start_time, tb.us_start_frac)
            f_vac = frac * us.thrust_vac_N
            th = us.throttle
            if th is not None:  # at its command, the maximum, down to its acceleration limit (in vacuum, no rate
                # limit), not below its minimum: the flight's law (models/throttle.py) without its lag
                held = max(th.axial_acceleration_limit_mps2 * mass, th.minimum * us.thrust_vac_N)
                f_vac = min(th.maximum * f_vac, held)
            f += max(f_vac - pres * us.nozzle_exit_area_m2, 0.0) * x_b
            md = f_vac / (G0 * us.isp_vac_s)
            mdot[1] = md * us.mixture_ratio / (1.0 + us.mixture_ratio)
            mdot[2] = md / (1.0 + us.mixture_ratio)
        out = np.empty(9)
        out[0:3] = v
        out[3:6] = f / mass + g
        out[6:9] = -mdot
        return out

    def initial(self) -> np.ndarray:
        y = np.zeros(9)
        y[0:3], y[3:6] = self.r0, self.v0
        y[6] = self.vehicle.configurations["stack"].mass.propellant_kg[-1]
        y[7], y[8] = self.vehicle.upper_stage.lox_kg, self.vehicle.upper_stage.lh2_kg
        return y

    # ------------------------------------------------------------------ flights
    def fly_to_ignition(self, azimuth: float):
        """Integrate liftoff → J-2X ignition; returns (solution, turn data)."""
        pr = self.prog
        t_turn = pr.pitchover_start_s + pr.pitchover_duration_s
        kw = dict(rtol=1e-9, atol=1e-6, max_step=1.0, dense_output=True)
        turn: dict = {}
        s1 = solve_ivp(self.rhs, (0.0, t_turn), self.initial(), args=(azimuth, (0.0, 0.0), turn), **kw)
        y = s1.y[:, -1]
        x_b = self.launch_attitude(t_turn, azimuth)[:, 0]
        v_rel = earth.velocity_relative_eci(y[0:3], y[3:6], constants.OMEGA_EARTH)
        v_hat = v_rel / np.linalg.norm(v_rel)
        axis = _cross(v_hat, x_b)
        sin_a = np.linalg.norm(axis)
        turn["axis"] = axis / sin_a if sin_a > 1e-12 else np.array([1.0, 0.0, 0.0])
        turn["alpha0"] = float(np.arctan2(sin_a, np.dot(v_hat, x_b)))
        s2 = solve_ivp(self.rhs, (t_turn, self.t_sep), y, args=(azimuth, (0.0, 0.0), turn), **kw)
        s3 = solve_ivp(self.rhs, (self.t_sep, self.t_ign), s2.y[:, -1], args=(azimuth, (0.0, 0.0), turn), **kw)
        y_ign = s3.y[:, -1]
        turn["x_ignition"] = self.attitude(self.t_ign, y_ign, azimuth, (0.0, 0.0), turn)[:, 0]
        hvec = _cross(y_ign[0:3], y_ign[3:6])
        turn["plane_normal"] = hvec / np.linalg.norm(hvec)
        return (s1, s2, s3), turn

    def fly_upper(self, y_ign: np.ndarray, azimuth: float, steer, turn, t_end: float | None = None):
        """Integrate ignition → target energy (or ``t_end``)."""
        def energy(t, y, *args):
            v = y[3:6]
            return 0.5 * v.dot(v) - constants.MU_EARTH / _norm(y[0:3]) - self.energy_target
        energy.terminal = t_end is None
        energy.direction = 1.0
        t_stop = t_end if t_end is not None else self.t_ign + 900.0
        return solve_ivp(self.rhs, (self.t_ign, t_stop), y_ign, args=(azimuth, steer, turn), events=energy,
                         rtol=1e-9, atol=1e-6, max_step=2.0, dense_output=True)

    def cutoff_residual(self, sol) -> np.ndarray:
        """Residuals (altitude km, flight-path angle deg) at the energy cutoff."""
        if sol.status != 1 or not sol.t_events[0].size:
            # never reached the energy target: penalize by the energy shortfall
            y = sol.y[:, -1]
            short = self.energy_target - (0.5 * np.dot(y[3:6], y[3:6]) - constants.MU_EARTH / np.linalg.norm(y[0:3]))
            return np.array([short / 1e4, short / 1e4])
        y = sol.y_events[0][0]
        r = np.linalg.norm(y[0:3])
        fpa = np.arcsin(np.dot(y[0:3], y[3:6]) / (r * np.linalg.norm(y[3:6])))
        return np.array([(r - self.r_cut) / 1e3, np.degrees(fpa - self.fpa_cut)])

    def inclination_of(self, y: np.ndarray) -> float:
        h = _cross(y[0:3], y[3:6])
        return float(np.arccos(h[2] / np.linalg.norm(h)))


def solve(cfg: SavantConfig, vehicle: Vehicle, verbose: bool = True):
    """Solve azimuth and upper-stage steering; return the reference and its solution."""
    prog = Program.from_config(dict(cfg.guidance.generator))
    ref = Reference(cfg, vehicle, prog)
    lat = np.radians(cfg.guidance.launch_site.latitude_deg)
    az_inertial = np.arcsin(np.clip(np.cos(ref.inclination) / np.cos(lat), -1.0, 1.0))
    # Earth-relative azimuth of the inertial one (speed near orbital)
    v_orb = 7800.0
    v_e = constants.OMEGA_EARTH * constants.WGS84_A * np.cos(lat)
    azimuth = float(np.arctan2(v_orb * np.sin(az_inertial) - v_e, v_orb * np.cos(az_inertial)))
    steer = np.array([0.4, -0.004])

    def upper(az, steer0):
        sols, turn = ref.fly_to_ignition(az)
        y_ign = sols[2].y[:, -1]
        # starting guess: continue the flight-path angle at ignition
        res = optimize.least_squares(lambda s: ref.cutoff_residual(ref.fly_upper(y_ign, az, s, turn)),
                                     steer0, x_scale=[0.1, 0.001], diff_step=1e-4, xtol=1e-10, ftol=1e-10)
        sol = ref.fly_upper(y_ign, az, res.x, turn)
        return sols, turn, res.x, sol

    prev = (azimuth, 0.0)
    for it in range(10):
        sols, turn, steer, sol = upper(azimuth, steer)
        y_cut = sol.y_events[0][0] if sol.t_events[0].size else sol.y[:, -1]
        err = ref.inclination_of(y_cut) - ref.inclination
        if verbose:
            print(f"iteration {it}: azimuth {np.degrees(azimuth):8.4f} deg, steering A={steer[0]:.5f} "
                  f"B={steer[1]:.6f}/s, inclination error {np.degrees(err):+.5f} deg, "
                  f"cutoff residual {ref.cutoff_residual(sol)}")
        if abs(err) < np.radians(0.002):
            break
        if it == 0:
            # d(inclination)/d(azimuth) ≈ −sin(az_i)·cos(lat)/sin(i) for a launch from latitude lat
            slope = -np.cos(lat) * np.sin(az_inertial) / np.sin(ref.inclination)
        else:
            slope = (err - prev[1]) / (azimuth - prev[0])
        prev = (azimuth, err)
        azimuth -= err / slope
    return ref, sols, turn, azimuth, steer, sol


def commands(ref: Reference, sols, turn, azimuth: float, steer, sol_upper, rate_hz: float = 1.0):
    """Sample the attitude program at ``rate_hz``: times, quaternions q_c2i, eigenaxis
    rates, the cutoff time and the reference's Earth-relative speed at each sample (m/s)."""
    t_cut = sol_upper.t_events[0][0] if sol_upper.t_events[0].size else sol_upper.t[-1]
    t_end = np.ceil(t_cut + ref.prog.extend_s)
    ext = ref.fly_upper(sol_upper.y[:, 0], azimuth, steer, turn, t_end=t_end)
    times = np.arange(0.0, t_end + 0.5 / rate_hz, 1.0 / rate_hz)
    quats = np.empty((times.size, 4))
    speeds = np.empty(times.size)
    for i, t in enumerate(times):
        if t <= sols[0].t[-1]:
            y = sols[0].sol(t)
        elif t <= sols[1].t[-1]:
            y = sols[1].sol(t)
        elif t <= sols[2].t[-1]:
            y = sols[2].sol(t)
        else:
            y = ext.sol(min(t, ext.t[-1]))
        quats[i] = qt.from_dcm(ref.attitude(t, y, azimuth, steer, turn))
        speeds[i] = np.linalg.norm(earth.velocity_relative_eci(y[0:3], y[3:6], constants.OMEGA_EARTH))
    # keep the sign continuous (q and −q are the same attitude)
    for i in range(1, times.size):
        if np.dot(quats[i], quats[i - 1]) < 0.0:
            quats[i] = -quats[i]
    rates = np.zeros((times.size, 3))
    for i in range(times.size - 1):
        dq = qt.qmul(qt.qconj(quats[i]), quats[i + 1])
        rates[i] = qt.to_rotation_vector(dq) / (times[i + 1] - times[i])
    rates[-1] = rates[-2]
    return times, quats, rates, t_cut, speeds


def add_speed_column(path: Path, times: np.ndarray, quats: np.ndarray, speeds: np.ndarray) -> None:
    """Append the reference speed to each row of an existing CSV command file, keeping
    every other byte, after checking that it holds this reference's samples (times equal,
    attitudes within 1e-5 rad)."""
    from savant_cli.io.atomic import atomic_path
    from savant_cli.io.guidance_file import SPEED_COLUMN, read_guidance

    table = read_guidance(path)
    if table.speed.size:
        raise SystemExit(f"{path} already has the {SPEED_COLUMN} column")
    if table.time.shape != times.shape or np.any(table.time != times):
        raise SystemExit(f"{path}: its sample times are not this reference's")
    dots = np.abs(np.sum(table.quat * quats, axis=1))
    worst = float(np.max(2.0 * np.arccos(np.clip(dots, -1.0, 1.0))))
    if worst > 1e-5:
        raise SystemExit(f"{path}: its attitudes differ from this reference's by up to {worst:.3g} rad")
    lines = path.read_text().splitlines()
    out, row = [], 0
    for line in lines:
        if line.lstrip().startswith("#") or not line.strip():
            out.append(line)
        elif line.startswith("time_s"):
            out.append(f"{line},{SPEED_COLUMN}")
        else:
            out.append(f"{line},{speeds[row]:.12g}")
            row += 1
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(out) + "\n")


def _compose(overrides: list[str]):
    from hydra import compose, initialize_config_dir

    from savant_cli.config import validate
    from savant_cli.paths import shipped_config_dir

    with initialize_config_dir(config_dir=str(shipped_config_dir()), version_base="1.3"):
        raw = compose(config_name="config", overrides=overrides)
    return validate(raw)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("overrides", nargs="*", help="Hydra overrides, as for `savant run`")
    ap.add_argument("--out", type=Path, default=None, help="output CSV (default: conf/guidance/<command_file>)")
    ap.add_argument("--add-speed", action="store_true",
                    help="only add the v_rel_m_s column to the existing command file, its other bytes unchanged "
                         "(refused unless the regenerated attitudes match the file's)")
    args = ap.parse_args(argv)
    from savant_cli.io.guidance_file import write_guidance_csv
    from savant_cli.paths import resolve_data_path, shipped_config_dir
    from savant_cli.vehicle import load_vehicle

    cfg = _compose(args.overrides)
    vdir = resolve_data_path("vehicle.data_dir", "vehicle", cfg.vehicle["data_dir"], [shipped_config_dir()], must_be_dir=True)
    vehicle = load_vehicle(cfg.vehicle, vdir)
    ref, sols, turn, azimuth, steer, sol = solve(cfg, vehicle)
    times, quats, rates, t_cut, speeds = commands(ref, sols, turn, azimuth, steer, sol)
    y_cut = sol.y_events[0][0]
    out = args.out or (shipped_config_dir() / "guidance" / cfg.guidance.command_file)
    if args.add_speed:
        add_speed_column(out, times, quats, speeds)
        print(f"added the {SPEED_COLUMN} column to {out}")
        return
    tgt = cfg.guidance.target
    header = (f"savant guidance commands for vehicle {cfg.vehicle['name']}, generated by "
              f"savant_cli.datagen.guidance_commands {' '.join(args.overrides)}\n"
              f"launch site {cfg.guidance.launch_site.latitude_deg} deg N, {cfg.guidance.launch_site.longitude_deg} deg E; "
              f"ECI X through Greenwich at liftoff\n"
              f"target {tgt.perigee_altitude_km} x {tgt.apogee_altitude_km} km, {tgt.inclination_deg} deg, cutoff at "
              f"{tgt.cutoff_altitude_km} km\n"
              f"solution: flight azimuth {np.degrees(azimuth):.4f} deg, linear tangent A = {steer[0]:.6f}, "
              f"B = {steer[1]:.7f} 1/s; reference cutoff at {t_cut:.2f} s, "
              f"{(np.linalg.norm(y_cut[0:3]) - constants.WGS84_A) / 1e3:.2f} km\n"
              f"q = q_c2i (commanded body to ECI, scalar first); rate = eigenaxis rate to the next sample, commanded-body axes")
    write_guidance_csv(out, times, quats, rates, header, speed=speeds)
    print(header)
    print(f"wrote {out} ({times.size} samples)")


if __name__ == "__main__":
    main()
