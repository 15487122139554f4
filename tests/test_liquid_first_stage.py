"""A liquid first stage and its throttle (models/propulsion.py, models/throttle.py).

References: the throttle law's fixed point and per-cycle error ratio in closed form (a
vehicle whose axial acceleration is ``(k F − L)/m``); a schedule table's linear
interpolation; the usable load of two tanks at a mixture ratio; and, in flight, the
conservation the plant must keep whatever its numerics: the oxidizer and fuel burned in
the mixture ratio, the impulse the sequencer integrates equal to ``g0 Isp`` times the
propellant burned, the delivered thrust ``k F_rated − p A_exit`` of the logged throttle
and pressure, and the acceleration held at the limit by the law.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from omegaconf import OmegaConf

from conftest import compose_config
from savant_cli import constants
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.io.guidance_file import read_guidance
from savant_cli.models import earth, layout, propulsion, throttle
from savant_cli.montecarlo.targets import _apply_table
from savant_cli.paths import hydra_search_dirs, shipped_config_dir
from savant_cli.sim import engine
from savant_cli.sim.build import build_model, nominal_first_stage_trace, plant_data
from savant_cli.sim.plant import pack_tables
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare
from savant_cli.sim.staging_state import read_staging_state
from savant_cli.vehicle import load_vehicle
from savant_cli.vehicle.two_stage import usable_load
from test_vehicle_examples import example_node

SHIPPED = shipped_config_dir() / "vehicle"
EXAMPLE = "a-liquid-first-stage"
F_RATED, ISP, MR, EXIT_AREA = 14.0e6, 311.0, 2.6, 8.0  # the page's engine
OX, FUEL = 467600.0, 180000.0  # its tanks, kg
A_LIMIT = 39.2  # its acceleration limit, m/s²


def _vehicle(**throttle_section):
    node = example_node(EXAMPLE)
    engine_node = node["stages"]["first_stage"]["engines"]["booster_engine"]
    if throttle_section:
        engine_node["throttle"] = throttle_section
    return load_vehicle(node, SHIPPED / "ares_i")


def _refusal(node_change, match: str, data_dir=None):
    node = example_node(EXAMPLE)
    node_change(node)
    with pytest.raises(ConfigError, match=match):
        load_vehicle(node, data_dir or SHIPPED / "ares_i")


def _scheduled(tmp_path, rows: str, minimum: float, rate: float):
    """The example's node with a throttle schedule of ``rows`` (``time_s,throttle`` CSV
    lines) and no acceleration limit, and a copy of ares_i's data folder holding it."""
    data = tmp_path / "ares_i"
    data.mkdir()
    for f in (SHIPPED / "ares_i").iterdir():
        if f.is_file():
            (data / f.name).symlink_to(f)
    (data / "schedule.csv").write_text(f"time_s,throttle\n{rows}\n")
    node = example_node(EXAMPLE)
    node["stages"]["first_stage"]["engines"]["booster_engine"]["throttle"] = {
        "minimum": minimum, "rate_per_s": rate, "table": "schedule.csv"}
    return node, data


# ----------------------------------------------------------------- the law
def test_the_acceleration_limit_converges_at_the_closed_form_ratio():
    """a = (k F − L)/m: the fixed point k* = (m a_lim + L)/F, each cycle's error the last
    one's times −L/(m a_lim) exactly (the ratio law's derivative at k*)."""
    f, loss, m = 1.0e7, 6.0e5, 2.0e5
    k_star = (m * A_LIMIT + loss) / f
    k = 0.99
    errors = []
    for _ in range(6):
        k = throttle.throttle_step(k, 1.0, (k * f - loss) / m, A_LIMIT, 0.3, 1.0, 1.0)
        errors.append(k - k_star)
    ratios = np.array(errors[1:]) / np.array(errors[:-1])
    ratio = -loss / (m * A_LIMIT)
    # the exact ratio at k*; away from it the secant's, (k_n − k*) times a correction of
    # order (k_n − k*) F/(m a_lim): within 1 % by the second cycle, and converging
    assert abs(ratios[-1] - ratio) < 1e-4
    assert abs(errors[-1]) < 1e-6 * k_star


def test_the_law_clamps_to_its_bounds_and_its_rate():
    step = throttle.throttle_step
    assert step(0.9, 1.0, 80.0, 40.0, 0.6, 1.0, 1.0) == 0.6  # the ratio asks 0.45: the minimum
    assert step(0.9, 1.0, 30.0, 40.0, 0.6, 0.95, 1.0) == 0.95  # below the limit: the schedule, at most the maximum
    assert step(0.9, 1.0, 80.0, 40.0, 0.3, 1.0, 0.02) == pytest.approx(0.88, abs=1e-15)  # the rate limit
    assert step(0.7, 1.0, 0.0, 40.0, 0.3, 1.0, 0.02) == pytest.approx(0.72, abs=1e-15)  # no acceleration sensed
    assert step(0.7, 0.8, 30.0, 0.0, 0.3, 1.0, 1.0) == 0.8  # no limit: the schedule


def test_a_schedule_table_is_interpolated_linearly_and_held_past_its_ends(tmp_path):
    vehicle = load_vehicle(*_scheduled(tmp_path, "0,1.0\n40,1.0\n42,0.7\n70,0.7\n80,0.9", minimum=0.6, rate=0.05))
    cfg = validate(compose_config(["sim.progress=false"]))
    guidance = read_guidance(prepare(cfg, hydra_search_dirs()).command_file)
    model = build_model(cfg, vehicle, guidance)
    tb = model.packed_tables
    for t, want in ((0.0, 1.0), (41.0, 0.85), (60.0, 0.7), (75.0, 0.8), (200.0, 0.9)):
        assert throttle.scheduled(model.p, tb, t) == pytest.approx(want, abs=1e-15)
    assert model.u0[layout.U_THROTTLE] == 1.0
    # the nominal trace follows the schedule at the rate limit where the schedule is
    # steeper: 0.3 down at 0.05/s takes 6 s from 40 s (the schedule's 2 s); within a step
    time_s, thrust = nominal_first_stage_trace(vehicle, model.p, tb)
    k = np.interp([43.0, 46.1, 60.0, 75.0], time_s, thrust) / F_RATED
    np.testing.assert_allclose(k, [0.85, 0.7, 0.7, 0.8], atol=0.05 * 0.05 + 1e-12)


# ------------------------------------------------------------ the vehicle
def test_the_example_stage_holds_its_tanks_and_its_rated_trace():
    vehicle = _vehicle()
    fs = vehicle.first_stage
    assert vehicle.tanks == ("first_stage_lox", "rp1", "lox", "lh2")
    assert (fs.oxidizer_kg, fs.fuel_kg, fs.propellant_kg) == (OX, FUEL, OX + FUEL)
    load = usable_load(MR, OX, FUEL)
    assert load == pytest.approx(OX * (1 + MR) / MR, rel=1e-15)  # the oxidizer runs out first
    # rated thrust from liftoff (the start transient ends there) until the load is burned
    t_burn = load * constants.G0 * ISP / F_RATED
    assert fs.thrust_time_s[-2] == pytest.approx(t_burn, rel=1e-12)
    assert np.interp(0.0, fs.thrust_time_s, fs.thrust_vac_N) == F_RATED
    assert fs.isp_sl_s == pytest.approx(ISP * (1 - constants.P0 * EXIT_AREA / F_RATED), rel=1e-12)


def test_the_acceleration_limited_trace_burns_the_usable_load_at_the_limit():
    vehicle = _vehicle()
    cfg = validate(compose_config(["sim.progress=false"]))
    p, tables = plant_data(cfg, vehicle)
    time_s, thrust = nominal_first_stage_trace(vehicle, p, pack_tables(tables))
    on = (time_s >= 0.0) & (time_s <= time_s[-2])  # liftoff to burnout (the drop after is the table's)
    burned = np.trapezoid(thrust[on], time_s[on]) / (constants.G0 * ISP)
    assert burned == pytest.approx(usable_load(MR, OX, FUEL), rel=1e-9)
    stack = vehicle.configurations["stack"].mass
    left = vehicle.first_stage.propellant_kg - np.concatenate(
        [[0.0], np.cumsum(0.5 * (thrust[on][1:] + thrust[on][:-1]) * np.diff(time_s[on]))]) / (constants.G0 * ISP)
    accel = thrust[on] / np.interp(left, stack.propellant_kg, stack.mass_kg)
    # the trace never exceeds the limit by more than one step's growth, and ends at it
    assert accel[:-1].max() < A_LIMIT * (1 + 1e-3)
    assert accel[-2] == pytest.approx(A_LIMIT, rel=1e-3)
    # it burns longer than the rated trace by the time the throttle gave up: ∫(1 − k) dt
    given_up = np.trapezoid(1.0 - thrust[on] / F_RATED, time_s[on])
    assert given_up > 1.0
    assert time_s[-2] - vehicle.first_stage.thrust_time_s[-2] == pytest.approx(given_up, rel=1e-9)


def test_the_gain_design_sees_the_throttled_thrust():
    """The flight-control design's μc (``fcs_gains.pitch_coefficients``) where the
    acceleration limit throttles the stage is the throttled trace's delivered thrust at
    the gimbal's arm over I_yy (hand-computed from the trace, the stack's mass table and
    the US 1976 troposphere's back pressure on the pad), not the rated thrust's."""
    from savant_cli.datagen import fcs_gains, guidance_commands as gc

    vehicle = _vehicle()
    cfg = validate(compose_config(["sim.progress=false"]))
    ref = gc.Reference(cfg, vehicle, gc.Program.from_config(dict(cfg.guidance.generator)))
    throttled = np.flatnonzero((ref.fs_time > 10.0) & (ref.fs_thrust < 0.9 * F_RATED))  # past the start
    t = float(ref.fs_time[throttled[0]]) + 5.0
    f_vac = float(np.interp(t, ref.fs_time, ref.fs_thrust))
    assert f_vac < 0.9 * F_RATED
    on = ref.fs_time <= t
    burned = (np.trapezoid(ref.fs_thrust[on], ref.fs_time[on])
              + 0.5 * (ref.fs_thrust[on][-1] + f_vac) * (t - ref.fs_time[on][-1])) / (constants.G0 * ISP)
    y = ref.initial()
    y[6] = vehicle.first_stage.propellant_kg - burned
    stack = vehicle.configurations["stack"].mass
    cg_x = np.interp(y[6], stack.propellant_kg, stack.cg_m[:, 0])
    iyy = np.interp(y[6], stack.propellant_kg, stack.inertia_kgm2[:, 1])
    c_i2e = earth.dcm_eci_to_ecef(t, constants.OMEGA_EARTH)
    alt = earth.ecef_to_geodetic(c_i2e @ y[0:3], constants.WGS84_A, constants.WGS84_E2)[2]
    pres = constants.P0 * (1.0 - 0.0065 * alt / 288.15) ** 5.255877  # US 1976 troposphere, closed form
    expected = (f_vac - pres * EXIT_AREA) * (vehicle.first_stage.gimbal_m[0] - cg_x) / iyy
    assert fcs_gains.pitch_coefficients(ref, t, y, 0)[1] == pytest.approx(expected, rel=1e-4)


# ------------------------------------------------------------- refusals
@pytest.mark.parametrize("section, key, match", [
    ({"minimum": 0.8, "maximum": 0.7, "rate_per_s": 0.1, "axial_acceleration_limit_mps2": 40.0}, "minimum",
     r"throttle\.minimum.*within \(0, maximum = 0\.7\]"),
    ({"minimum": 0.5, "maximum": 1.2, "rate_per_s": 0.1, "axial_acceleration_limit_mps2": 40.0}, "maximum",
     r"throttle\.maximum.*within \(0, 1\]"),
    ({"minimum": 0.5, "rate_per_s": 0.0, "axial_acceleration_limit_mps2": 40.0}, "rate", r"rate_per_s.*positive"),
    ({"minimum": 0.5, "rate_per_s": 0.1}, "neither", r"needs a table, an axial_acceleration_limit_mps2 or both"),
    ({"minimum": 0.5, "rate_per_s": 0.1, "axial_acceleration_limit_mps2": -1.0}, "limit",
     r"axial_acceleration_limit_mps2.*positive"),
])
def test_a_bad_throttle_is_refused_naming_its_key(section, key, match):
    with pytest.raises(ConfigError, match=match):
        _vehicle(**section)


def test_a_setting_of_the_schedule_outside_the_bounds_is_refused_naming_the_column(tmp_path):
    with pytest.raises(ConfigError, match=r"schedule\.csv:throttle.*0\.4.*\[0\.5, 1\]"):
        load_vehicle(*_scheduled(tmp_path, "0,1.0\n50,0.4", minimum=0.5, rate=0.1))


def test_a_mixed_first_stage_is_refused():
    """Trace and liquid engines on one stage (an upper stage's throttle is
    tests/test_throttled_upper_stage.py's)."""
    def mixed(node):
        shipped = OmegaConf.to_container(OmegaConf.load(SHIPPED / "ares_i.yaml").vehicle.stages.first_stage)
        node["stages"]["first_stage"]["tanks"]["grain"] = {"propellant_kg": 1000.0}
        node["stages"]["first_stage"]["tanks"]["rp1"] = {"propellant_kg": FUEL - 1000.0}  # the same stage load
        node["stages"]["first_stage"]["engines"]["motor"] = {
            **shipped["engines"]["five_segment_motor"], "tanks": ["grain"]}
    _refusal(mixed, r"vehicle\.stages\.first_stage\.engines.*all trace or all liquid")


def test_a_solid_motors_dispersions_are_refused_on_a_liquid_stage():
    vehicle = _vehicle()
    for name in ("tables.first_stage.burn_rate", "tables.first_stage.propellant_load"):
        with pytest.raises(ConfigError, match=f"{name}.*this first stage is liquid"):
            _apply_table(vehicle, name, 1.01)


def test_a_staging_state_written_before_the_throttle_reads_it_as_rated(tmp_path):
    shipped = shipped_config_dir() / "phase" / "ares_i_peg_staging_state.json"
    doc = json.loads(shipped.read_text())
    assert len(doc["inputs"]) < layout.U_THROTTLE
    assert read_staging_state(shipped).u[layout.U_THROTTLE] == 1.0
    doc["inputs"] = doc["inputs"] + [0.0] * (layout.U_THROTTLE - len(doc["inputs"])) + [0.8]
    path = tmp_path / "staging.json"
    path.write_text(json.dumps(doc))
    assert read_staging_state(path).u[layout.U_THROTTLE] == 0.8  # written with it: kept


# ---------------------------------------------------------------- flight
@pytest.fixture(scope="module")
def flight():
    vehicle = _vehicle()
    cfg = validate(compose_config(["sim.progress=false"]))
    guidance = read_guidance(prepare(cfg, hydra_search_dirs()).command_file)
    model = build_model(cfg, vehicle, guidance)
    result = simulate(model, progress=False)
    return model, result, signals(result, model)


def test_the_example_flies_to_cutoff_and_separates_when_its_oxidizer_runs_out(flight):
    model, result, sig = flight
    assert result.status == "complete"
    t_sep = result.events[engine.EV_SEPARATION]
    dt = model.rates.dt
    t = sig["time"].data
    ox = sig["propellant_remaining"].data[:, 0]
    stack = t < t_sep
    # a step's flow: the oxidizer's at the last throttle, over one plant step
    k_end = sig["throttle"].data[stack][-1]
    ox_flow = k_end * F_RATED / (constants.G0 * ISP) * MR / (1 + MR)
    assert ox[stack][-1] < ox_flow * 0.1 + ox_flow * (t_sep - t[stack][-1])  # nearly empty at the last logged row
    # the fuel left in the stage at separation: the usable load's residual, within a step's flow
    residual = FUEL - usable_load(MR, OX, FUEL) / (1 + MR)
    at_sep = result.d[propulsion.D_FS_PROP_SEP]
    assert abs(at_sep - residual) < ox_flow / MR * dt * 2
    # the trace's prediction is late, never early: its drag-free acceleration throttles
    # sooner, so it burns longer; the throttle comes off after max-Q, where drag is a few
    # per cent of the limited thrust, so by a fraction of a second (measured: 0.03 s)
    assert 0.0 <= model.info["predicted_separation_time_s"] - t_sep < 0.5


def test_the_flight_burns_in_the_mixture_ratio_and_delivers_g0_isp_per_kg(flight):
    model, result, sig = flight
    t = sig["time"].data
    stack = t < result.events[engine.EV_SEPARATION]
    prop = sig["propellant_remaining"].data[stack]
    burned_ox, burned_fuel = OX - prop[:, 0], FUEL - prop[:, 1]
    late = burned_fuel > 1000.0
    np.testing.assert_allclose(burned_ox[late] / burned_fuel[late], MR, rtol=1e-9)
    burned = OX + FUEL - result.d[propulsion.D_FS_PROP_SEP]
    impulse = result.d[propulsion.D_FS_IMPULSE]
    assert impulse == pytest.approx(constants.G0 * ISP * burned, rel=5e-5)


def test_the_delivered_thrust_is_the_throttled_rated_thrust_less_back_pressure(flight):
    model, result, sig = flight
    t = sig["time"].data
    stack = (t >= 0.0) & (t < result.events[engine.EV_SEPARATION] - 0.5)
    k = sig["throttle"].data[stack]
    want = k * F_RATED - sig["pressure"].data[stack] * EXIT_AREA
    np.testing.assert_allclose(sig["thrust"].data[stack], want, rtol=1e-12)
    assert k[0] == 1.0 and k.min() >= 0.5


def test_the_throttle_holds_the_acceleration_limit(flight):
    model, result, sig = flight
    t = sig["time"].data
    stack = t < result.events[engine.EV_SEPARATION] - 0.5
    accel = sig["sensed_acceleration"].data[stack, 0]
    k = sig["throttle"].data[stack]
    dt_fcs = model.rates.dt * model.rates.n_fcs
    # between cycles the acceleration grows by a ṁ Δt / m at most (the mass burned)
    mdot = k * F_RATED / (constants.G0 * ISP)
    growth = accel * mdot * dt_fcs / sig["mass"].data[stack]
    assert np.all(accel <= A_LIMIT + growth.max() * 1.05)
    throttled = k < 0.999
    assert throttled.any() and not throttled[t[stack] < 60.0].any()
    onset = t[stack][throttled][0]
    held = t[stack] > onset + 5.0
    np.testing.assert_allclose(accel[held], A_LIMIT, rtol=2e-3)
