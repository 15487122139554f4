"""Strap-on boosters on the first stage (``vehicle/two_stage.py``, ``models/propulsion.py``,
``models/mass.py``, ``sim/engine.py``): the worked example of docs/vehicles.md, two
GEM-63-class solid motors without TVC beside the ares_i first stage, jettisoned on their
own thrust tail-off.

References: the parallel-axis composition of ``vehicle/composition.py`` (numpy, at
load) for the plant's in-flight exchange of each booster's full-load row for its row at
its own propellant; numpy's cross products for a canted booster's thrust moment; the
booster's thrust trace itself for the tail-off step; the rigid body's velocity field for
the momentum across the jettison (the boosters leave with the velocity of their own CG,
the rest keeps its own, and the sum is the whole's before).
"""

from __future__ import annotations

import copy
import dataclasses

import h5py
import numpy as np
import pytest
from omegaconf import OmegaConf

from conftest import compose_config
from savant_cli import constants
from savant_cli.config import validate
from savant_cli.datagen import strap_on_boosters
from savant_cli.datagen.guidance_commands import Program, Reference
from savant_cli.errors import ConfigError
from savant_cli.io.guidance_file import read_guidance
from savant_cli.linear.plant import linearize_plant
from savant_cli.models import boosters, earth, layout, mass as mass_model, propulsion, quaternion as qt, rigid_body
from savant_cli.models.gravity import gravity_zonal
from savant_cli.montecarlo.targets import apply_samples, resolve
from savant_cli.paths import hydra_search_dirs, shipped_config_dir
from savant_cli.sim import build, engine
from savant_cli.sim.booster_trace import booster_trace
from savant_cli.sim.build import build_model, plant_data
from savant_cli.sim.plant import derivative, mass_state
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare
from savant_cli.sim.summary import summarize
from savant_cli.vehicle import load_vehicle
from savant_cli.vehicle.composition import combine
from test_end_to_end import run
from test_vehicle_examples import example_node

SHIPPED = shipped_config_dir() / "vehicle"
EXAMPLE = "strap-on-boosters"
LOAD = 44200.0  # each booster's propellant, kg (the page's)
INERT = 5100.0  # each booster's inert mass, kg
TAIL_OFF = 0.02  # the jettison's thrust fraction


def _vehicle(node: dict | None = None):
    return load_vehicle(node or example_node(EXAMPLE), SHIPPED / "ares_i")


def _cfg(*overrides: str):
    return validate(compose_config(["sim.progress=false", *overrides]))


def _model(vehicle=None):
    cfg = _cfg()
    return build_model(cfg, vehicle or _vehicle(), read_guidance(prepare(cfg, hydra_search_dirs()).command_file))


def _booster_states(model) -> list[int]:
    return [model.layout.tank(t) for t in model.layout.tanks if t.startswith("booster_")]


# ------------------------------------------------------------------ the data


def test_the_booster_tables_hold_the_load_and_the_impulse():
    rows = strap_on_boosters.thrust_table()
    impulse = np.trapezoid(rows[:, 1], rows[:, 0])
    assert impulse == pytest.approx(constants.G0 * 279.0 * LOAD, rel=1e-12)
    left, right = (strap_on_boosters.mass_table(s) for s in (-1.0, 1.0))
    np.testing.assert_allclose(left[:, 1], INERT + left[:, 0], rtol=1e-15)  # mass = inert + propellant
    np.testing.assert_array_equal(left[:, 3], -right[:, 3])  # mirror images in y
    np.testing.assert_array_equal(left[:, 5:], right[:, 5:])
    # the full booster: a thin case, a solid nozzle and a solid grain on one axis, by hand
    b = strap_on_boosters.BOOSTER
    case_x, noz_x, grain_x = (0.5 * (b[f"{k}_fore_m"] + b[f"{k}_aft_m"]) for k in ("case", "nozzle", "grain"))
    cg = (b["case_kg"] * case_x + b["nozzle_kg"] * noz_x + LOAD * grain_x) / (INERT + LOAD)
    assert right[-1, 2] == pytest.approx(cg, rel=1e-14)
    ixx = b["case_kg"] * 0.64 + 0.5 * b["nozzle_kg"] * 0.36 + 0.5 * LOAD * 0.64
    assert right[-1, 5] == pytest.approx(ixx, rel=1e-14)


def test_the_example_loads_four_configurations_with_the_boosters_burning_in_the_first():
    v = _vehicle()
    assert list(v.configurations) == ["boosted", "stack", "upper_les", "upper"]
    assert v.first_stage_configurations == 2 and v.boosters.count == 2
    assert v.booster_tanks == ("booster_left_grain", "booster_right_grain")
    trig = v.events.trigger(engine.EV_BOOSTER_JETTISON)
    assert (trig.quantity, trig.booster, trig.threshold, trig.after) == ("thrust_fraction", 0, TAIL_OFF, -1)
    # the liftoff configuration (composed: the boosters at their full load) less the
    # boosters is the stack without them, at every level of the stage's propellant
    boosted, stack = v.configurations["boosted"].mass, v.configurations["stack"].mass
    np.testing.assert_allclose(boosted.mass_kg - 2 * (INERT + LOAD), stack.mass_kg, rtol=1e-13)


# ------------------------------------------------------------- mass in flight


@pytest.mark.parametrize("left,right", [(LOAD, LOAD), (20000.0, 20000.0), (30000.0, 5000.0), (0.0, 44200.0)])
def test_the_boosters_mass_in_flight_is_the_parallel_axis_composition_of_the_parts(left, right):
    """The plant's liftoff configuration with its boosters at (left, right) kg against
    the numpy composition of its parts: the first stage at a row of its own table, the
    upper stage full, the LES, and each booster at its row for its own propellant."""
    v = _vehicle()
    model = _model(v)
    parts = v.tree.parts
    first = parts["first_stage"].mass
    core = float(first.propellant_kg[len(first.propellant_kg) * 2 // 3])  # a row: the composed table is exact there
    x = model.x0.copy()
    x[model.layout.tank("grain")] = core
    x[_booster_states(model)] = left, right
    whole = mass_state(x, model.p, model.packed_tables, 0, np.zeros(layout.N_AUX))[1]
    m, cx, cy, cz, ixx, iyy, izz, ixy, ixz, iyz = mass_model.mass_properties(model.packed_tables, 0, core)
    m, cx, cy, cz, *inertia = boosters.exchange(x, model.p, model.packed_tables, m, cx, cy, cz, ixx, iyy,
                                                           izz, ixy, ixz, iyz)

    def row(table, prop):
        return (float(np.interp(prop, table.propellant_kg, table.mass_kg)),
                np.array([np.interp(prop, table.propellant_kg, table.cg_m[:, k]) for k in range(3)]),
                np.array([np.interp(prop, table.propellant_kg, table.inertia_kgm2[:, k]) for k in range(6)]))

    upper = parts["upper_stage"].mass
    pieces = [row(first, core), row(upper, upper.propellant_kg[-1]),
              (parts["les"].inert_mass_kg, parts["les"].cg_m, parts["les"].inertia_kgm2),
              row(parts["booster_left"].mass, left), row(parts["booster_right"].mass, right)]
    ref_m, ref_cg, ref_i = combine(np.array([q[0] for q in pieces]), np.array([q[1] for q in pieces]),
                                   np.array([q[2] for q in pieces]))
    assert m == pytest.approx(ref_m, rel=1e-14) and whole[0] == m
    np.testing.assert_allclose([cx, cy, cz], ref_cg, rtol=1e-13, atol=1e-12)
    # the plant returns tensor elements: the products' negatives
    np.testing.assert_allclose(inertia, [*ref_i[:3], *(-ref_i[3:])], rtol=1e-11, atol=1e-4)
    assert (cy == 0.0) == (left == right)  # a symmetric pair keeps the CG on the axis


# ---------------------------------------------------------------- thrust


def test_a_canted_booster_pushes_along_its_cant_at_its_arm():
    """Each booster's delivered thrust along its fixed cant, at its nozzle, against
    numpy's cross product r × F (body axes)."""
    node = example_node(EXAMPLE)
    node["boosters"]["booster_right"]["engines"]["booster_right_motor"]["cant_deg"] = [2.0, -3.0]
    model = _model(_vehicle(node))
    p, tb = model.p, model.packed_tables
    x = model.x0.copy()
    t, pres, cg = 40.0, 30000.0, np.array([60.0, 0.1, -0.05])
    xd = np.zeros_like(x)
    thrust, fx, fy, fz, mx, my, mz, *reaction = boosters.loads(x, tb, p, t, pres, True, *cg, xd, np.zeros(layout.N_AUX))
    assert reaction == [0.0, 0.0, 0.0]  # fixed nozzles: no tail-wags-dog
    s_to_b = np.array([-1.0, 1.0, -1.0])
    f_total, m_total, each = np.zeros(3), np.zeros(3), []
    for i, (nozzle, cant) in enumerate(((np.array([91.5, -2.755, 0.0]), (0.0, 0.0)),
                                        (np.array([91.5, 2.755, 0.0]), np.radians([2.0, -3.0])))):
        f_vac, mdot = boosters.flow(x, tb, p, t, i)
        assert mdot == pytest.approx(f_vac / (constants.G0 * 279.0), rel=1e-15)
        f = f_vac - pres * 2.0
        each.append(f)
        cp, cy = cant
        force = f * np.array([np.cos(cp) * np.cos(cy), -np.sin(cy), np.sin(cp) * np.cos(cy)])
        f_total += force
        m_total += np.cross((nozzle - cg) * s_to_b, force)
        assert xd[_booster_states(model)[i]] == -mdot
    assert thrust == pytest.approx(sum(each), rel=1e-15)
    np.testing.assert_allclose([fx, fy, fz], f_total, rtol=1e-14)
    np.testing.assert_allclose([mx, my, mz], m_total, rtol=1e-12, atol=1e-6 * abs(m_total).max())
    # jettisoned: no thrust and the states still
    xd[:] = 1.0
    assert boosters.loads(x, tb, p, t, pres, False, *cg, xd, np.zeros(layout.N_AUX)) == (0.0,) * 10
    assert np.all(xd[_booster_states(model)] == 0.0)


def _csv_trace() -> np.ndarray:
    """The boosters' thrust table as shipped (the plant's own numbers)."""
    return np.loadtxt(SHIPPED / "ares_i" / "booster_thrust.csv", delimiter=",", comments="#", skiprows=3)


def test_a_booster_burn_rate_compresses_its_trace_and_keeps_its_impulse():
    """Booster burn rates 1.03 and 0.97: each booster's vacuum thrust is ``k F(k t)`` of
    its table (the table's impulse is the load's, so its scale is 1), its impulse the
    load's ``g0 Isp M`` in a burn ``1/k`` as long, and the pair's thrust difference
    turns the vehicle in yaw by the arm of their nozzles (numpy's cross products)."""
    v = _vehicle()
    rates = np.array([1.03, 0.97])
    v = dataclasses.replace(v, boosters=dataclasses.replace(v.boosters, burn_rate=rates))
    model = _model(v)
    p, tb = model.p, model.packed_tables
    x = model.x0.copy()
    rows = _csv_trace()
    scale = constants.G0 * 279.0 * LOAD / np.trapezoid(rows[:, 1], rows[:, 0])
    assert scale == pytest.approx(1.0, rel=1e-9)
    times = np.linspace(0.0, 100.0, 400001)
    for i, k in enumerate(rates):
        thrust = np.array([boosters.flow(x, tb, p, t, i)[0] for t in times])
        expected = k * scale * np.interp(k * times, rows[:, 0], rows[:, 1], right=0.0)
        np.testing.assert_allclose(thrust, expected, rtol=1e-13, atol=1e-6)
        assert np.trapezoid(thrust, times) == pytest.approx(constants.G0 * 279.0 * LOAD, rel=1e-6)
    t, pres, cg = 50.0, 20000.0, np.array([60.0, 0.0, 0.0])
    xd = np.zeros_like(x)
    _, fx, fy, fz, mx, my, mz, *_ = boosters.loads(x, tb, p, t, pres, True, *cg, xd, np.zeros(layout.N_AUX))
    moment = np.zeros(3)
    for y, k in zip((-2.755, 2.755), rates):
        f = k * scale * np.interp(k * t, rows[:, 0], rows[:, 1]) - pres * 2.0
        moment += np.cross((np.array([91.5, y, 0.0]) - cg) * np.array([-1.0, 1.0, -1.0]), [f, 0.0, 0.0])
    np.testing.assert_allclose([mx, my, mz], moment, rtol=1e-12, atol=1e-6)
    assert mz > 0.0  # the left booster pushes harder: the nose turns right (positive yaw, body z down)


def test_booster_dispersion_targets_scale_one_booster_or_all():
    cfg = _cfg()
    v = _vehicle()
    one = resolve("d.target", "tables.boosters.booster_right.burn_rate", cfg, v, hydra_search_dirs())
    both = resolve("d.target", "tables.boosters.burn_rate", cfg, v, hydra_search_dirs())
    applied = apply_samples(cfg, v, [(one, "scale", 1.02), (both, "scale", 0.99)], {}).vehicle
    np.testing.assert_allclose(applied.boosters.burn_rate, [0.99, 0.99 * 1.02], rtol=1e-15)
    for text, vehicle in (("tables.boosters.booster_middle.burn_rate", v),
                          ("tables.boosters.burn_rate", _vehicle(example_node("a-liquid-first-stage")))):
        with pytest.raises(ConfigError) as info:
            resolve("dispersions.items.x.target", text, cfg, vehicle, hydra_search_dirs())
        assert info.value.key == "dispersions.items.x.target"


def test_a_first_stage_mass_dispersion_reaches_the_configuration_with_the_boosters():
    """``tables.first_stage.dry_mass`` and ``tables.stack.cg_x`` change every
    configuration flown with the first stage, the boosters' included."""
    cfg = _cfg()
    v = _vehicle()
    dry = resolve("d", "tables.first_stage.dry_mass", cfg, v, hydra_search_dirs())
    cg = resolve("d", "tables.stack.cg_x", cfg, v, hydra_search_dirs())
    applied = apply_samples(cfg, v, [(dry, "offset", 500.0), (cg, "offset", 0.1)], {}).vehicle
    for name in ("boosted", "stack"):
        np.testing.assert_allclose(applied.configurations[name].mass.mass_kg,
                                   v.configurations[name].mass.mass_kg + 500.0, rtol=1e-15)
        np.testing.assert_allclose(applied.configurations[name].mass.cg_m[:, 0],
                                   v.configurations[name].mass.cg_m[:, 0] + 0.1, rtol=1e-15)
    np.testing.assert_array_equal(applied.configurations["upper"].mass.mass_kg, v.configurations["upper"].mass.mass_kg)


# ---------------------------------------------------------------- the events


def _at_boundary(model, t: float):
    """The state at the example's liftoff, its clock moved to ``t`` (s), ready for one
    call of the engine's event logic."""
    x, d, u = model.x0.copy(), model.d0.copy(), model.u0.copy()
    x[layout.W:layout.W + 3] = (0.01, -0.02, 0.005)  # a rotating body: the reference moves with its velocity field
    events = np.full(len(engine.EVENT_NAMES), np.nan)
    return x, d, u, events


def _momentum(x, p, tb, config, states=()) -> tuple[float, np.ndarray]:
    """Mass (kg) and linear momentum (ECI, kg m/s) of the configuration ``config``
    from its reference point's velocity (that point is the CG)."""
    m = mass_state(x, p, tb, config, np.zeros(layout.N_AUX))[1][0]
    return m, m * x[layout.V:layout.V + 3]


def _row(table, prop: float) -> tuple[float, np.ndarray]:
    """Mass (kg) and CG (structure frame, m) of a part's own table at ``prop`` kg."""
    return (float(np.interp(prop, table.propellant_kg, table.mass_kg)),
            np.array([np.interp(prop, table.propellant_kg, table.cg_m[:, k]) for k in range(3)]))


def _jettison(model, event: int):
    """One jettison of the example at a step boundary where its trigger holds: the state
    before, the configuration before, and what leaves (part mass kg, CG m) by the parts'
    own tables; the boosters with 300 kg each left, the first stage with 500 kg."""
    v = _vehicle()
    x, d, u, events = _at_boundary(model, 0.0)
    if event == engine.EV_BOOSTER_JETTISON:  # past their trace's end: no thrust, the fraction holds
        t = 100.0
        x[_booster_states(model)] = 300.0
        d[boosters.D_PEAK] = 1.5e6
        dropped = [_row(table, 300.0) for table in v.boosters.mass]
    else:
        x[_booster_states(model)] = 0.0
        events[engine.EV_BOOSTER_JETTISON] = 94.665
        u[layout.U_CONFIG] = 1
        if event == engine.EV_SEPARATION:  # past the motor's trace: no thrust
            t = 135.0
            x[model.layout.tank("grain")] = 500.0
            d[propulsion.D_FS_PEAK] = 1.6e7
            dropped = [_row(v.tree.parts["first_stage"].mass, 500.0)]
        else:
            t = 200.0
            events[engine.EV_SEPARATION], events[engine.EV_IGNITION] = 130.0, 131.5
            u[layout.U_CONFIG], u[layout.U_ENGINE], u[layout.U_T_IGN] = 2, layout.ENGINE_UPPER, 131.5
            x[model.layout.tank("grain")] = 0.0
            les = v.tree.parts["les"]
            dropped = [(les.inert_mass_kg, les.cg_m)]
    before, config = x.copy(), int(u[layout.U_CONFIG])
    status = engine.handle_events(t, model.rates.dt, x, u, d, events, model.sched, model.p, model.packed_tables,
                                  engine.work_array(x.size))
    assert status == engine.RUNNING and events[event] == t and u[layout.U_CONFIG] == config + 1
    if event == engine.EV_BOOSTER_JETTISON:  # their propellant left, kept
        assert np.isnan(events[engine.EV_SEPARATION]) and d[boosters.D_PROP_JET] == 600.0
    return before, config, x, dropped


@pytest.mark.parametrize("event,tol", [(engine.EV_BOOSTER_JETTISON, 1e-12), (engine.EV_SEPARATION, 1e-6),
                                       (engine.EV_LES, 1e-6)])
def test_every_jettison_keeps_the_mass_and_the_momentum(event, tol):
    """The boosters', the first stage's and the LES's jettison on a rotating body: the
    mass drops by what leaves (by the parts' own tables), and the momentum the rest keeps
    plus what leaves carries (its CG's velocity in the rigid velocity field) is the
    whole's before. Tolerances: roundoff for the boosters, whose mass is composed in
    flight from their own tables; for the others 1e-6, the configurations' own tables
    (files of their own) agreeing with the parts' tables to about 1e-7."""
    model = _model()
    p, tb = model.p, model.packed_tables
    x0, config, x1, dropped = _jettison(model, event)
    m0, p0 = _momentum(x0, p, tb, config)
    m1, p1 = _momentum(x1, p, tb, config + 1)
    cg0 = np.array(mass_state(x0, p, tb, config, np.zeros(layout.N_AUX))[1][1:])
    assert m0 - m1 == pytest.approx(sum(b[0] for b in dropped), rel=10 * tol)
    c_b2i = qt.dcm(x0[layout.Q:layout.Q + 4])
    w = x0[layout.W:layout.W + 3]
    carried = np.zeros(3)
    for mb, cb in dropped:  # each part's CG velocity: v_cg0 + C (ω × Δ), Δ in body axes
        carried += mb * (p0 / m0 + c_b2i @ np.cross(w, (cb - cg0) * np.array([-1.0, 1.0, -1.0])))
    np.testing.assert_allclose(p1 + carried, p0, rtol=0.0, atol=tol * np.linalg.norm(p0))
    if event == engine.EV_BOOSTER_JETTISON:  # their propellant left with them
        assert np.all(x1[_booster_states(model)] == 0.0)


def test_a_separation_before_the_boosters_jettison_takes_them_along():
    model = _model()
    p, tb = model.p, model.packed_tables
    x, d, u, events = _at_boundary(model, 50.0)
    x[model.layout.tank("grain")] = 0.0  # the core's thrust gone: its thrust fraction holds
    d[propulsion.D_FS_PEAK] = 1.6e7
    loads = x[_booster_states(model)].copy()
    engine.handle_events(50.0, model.rates.dt, x, u, d, events, model.sched, p, tb, engine.work_array(x.size))
    assert events[engine.EV_SEPARATION] == events[engine.EV_BOOSTER_JETTISON] == 50.0
    assert u[layout.U_CONFIG] == 2 and u[layout.U_ENGINE] == layout.ENGINE_OFF
    assert d[boosters.D_PROP_JET] == loads.sum()


@pytest.fixture(scope="module")
def flight():
    model = _model()
    result = simulate(model, progress=False)
    return model, result, signals(result, model)


@pytest.mark.slow
def test_the_boosters_leave_at_the_first_step_their_thrust_falls_below_the_fraction(flight):
    """The plant step of the jettison against the booster's own trace: the first step
    boundary at which its vacuum thrust is below 2 % of its peak."""
    model, result, sig = flight
    assert result.status == "complete"
    dt = model.rates.dt
    rows = strap_on_boosters.thrust_table()  # the flown trace: its impulse is the load's exactly
    steps = np.arange(0.0, rows[-1, 0] + dt, dt)
    f = np.interp(steps, rows[:, 0], rows[:, 1], right=0.0)
    after_peak = steps >= steps[np.argmax(f)]
    expected = steps[np.flatnonzero(after_peak & (f < TAIL_OFF * f.max()))[0]]
    t_jet = result.events[engine.EV_BOOSTER_JETTISON]
    assert t_jet == pytest.approx(expected, abs=1e-9)
    assert t_jet < result.events[engine.EV_SEPARATION]
    t = sig["time"].data
    assert np.all(sig["booster_thrust"].data[t >= t_jet + dt] == 0.0)
    pres = sig["pressure"].data[0]  # the pad's
    assert sig["booster_thrust"].data[0] == pytest.approx(2 * (rows[0, 1] - pres * 2.0), rel=1e-9)  # the CSV's digits
    # what the boosters held at the jettison: their load less the flown trace's impulse
    burned = np.trapezoid(np.interp(np.linspace(0, t_jet, 200001), rows[:, 0], rows[:, 1]),
                          np.linspace(0, t_jet, 200001)) / (constants.G0 * 279.0)
    assert result.d[boosters.D_PROP_JET] == pytest.approx(2 * (LOAD - burned), rel=1e-3)


@pytest.mark.slow
def test_the_summary_reports_the_jettison_and_leaves_the_boosters_propellant_out(flight):
    model, result, sig = flight
    out = summarize(result, sig, p=model.p, qalpha_limit=160000.0)
    assert out["time_booster_jettison_s"] == result.events[engine.EV_BOOSTER_JETTISON]
    assert out["booster_propellant_at_jettison_kg"] == pytest.approx(3.6, abs=0.05)  # the page's
    assert out["max_qalpha_Pa_deg"] == pytest.approx(125e3, rel=0.01) and not out["qalpha_limit_exceeded"]
    assert out["booster_propellant_at_jettison_kg"] == pytest.approx(float(result.d[boosters.D_PROP_JET]))
    lay = model.layout
    core = [lay.tank(t) for t in lay.tanks if not t.startswith("booster_")]
    assert out["propellant_remaining_kg"] == pytest.approx(float(result.x[core[1:]].sum()))
    assert out["status"] == "complete"


@pytest.mark.slow
def test_the_linear_plant_in_the_boosted_phase_turns_on_the_composed_inertia():
    """At 40 s, boosters burning: the linear plant's pitch acceleration per radian of the
    first stage's gimbal is the stage's delivered thrust times its arm from the CG over
    the pitch inertia, ``F (x_g − x_cg) / I_yy``, with the CG and inertia those of the
    numpy composition of the parts at the snapshot's propellant (2e-3: the finite
    differences and the tables' interpolation); the stack's I_yy without the boosters
    would miss by 9 %."""
    model = _model()
    step = int(round(40.0 / model.rates.dt))
    snap = simulate(model, progress=False, snapshot_steps=(step,), t_stop=41.0).snapshots[step]
    lin = linearize_plant(model, snap)
    row = list(lin.z_index).index(layout.W + 1)  # pitch rate q
    col = list(lin.z_index).index(model.layout.channel(0))  # the pitch gimbal angle
    aux, xd = np.zeros(layout.N_AUX), np.zeros(snap.x.size)
    derivative(snap.t, snap.x, snap.u, model.p, model.packed_tables, aux, xd)
    v = _vehicle()
    parts = v.tree.parts
    core = snap.x[model.layout.tank("grain")]

    def row_at(table, prop):
        return (float(np.interp(prop, table.propellant_kg, table.mass_kg)),
                np.array([np.interp(prop, table.propellant_kg, table.cg_m[:, k]) for k in range(3)]),
                np.array([np.interp(prop, table.propellant_kg, table.inertia_kgm2[:, k]) for k in range(6)]))

    upper = parts["upper_stage"].mass
    pieces = [row_at(parts["first_stage"].mass, core), row_at(upper, upper.propellant_kg[-1]),
              (parts["les"].inert_mass_kg, parts["les"].cg_m, parts["les"].inertia_kgm2)]
    pieces += [row_at(parts[b].mass, snap.x[s]) for b, s in zip(("booster_left", "booster_right"),
                                                                 _booster_states(model))]
    _, cg, inertia = combine(np.array([q[0] for q in pieces]), np.array([q[1] for q in pieces]),
                             np.array([q[2] for q in pieces]))
    arm = v.first_stage.gimbal_m[0] - cg[0]
    expected = aux[propulsion.A_THRUST] * arm / inertia[1]
    assert lin.sys.A[row, col] == pytest.approx(expected, rel=2e-3)
    stack = v.configurations["stack"].mass  # the same stage without its boosters' inertia
    i_stack = np.interp(core, stack.propellant_kg, stack.inertia_kgm2[:, 1])
    assert abs(lin.sys.A[row, col] / (aux[propulsion.A_THRUST] * arm / i_stack) - 1.0) > 0.05


@pytest.mark.slow
def test_a_monte_carlo_batch_of_the_boosted_vehicle_from_a_users_folder(tmp_path):
    """The example as a user would fly it: a vehicle file and a dispersion set of their
    own (``-cd my_configs``, the shipped tables by an absolute ``data_dir``, ares_i's
    guidance and controller allowed), the shipped items plus each booster's own burn rate; the first
    stage of four runs. Each
    run's boosters leave when the left booster's trace, compressed by its burn rate
    ``k``, falls below 2 % of its peak: the nominal time over ``k`` (within a plant
    step each side)."""
    folder = tmp_path / "my_configs"
    (folder / "vehicle").mkdir(parents=True)
    (folder / "dispersions").mkdir()
    shipped = OmegaConf.load(SHIPPED / "ares_i.yaml")
    node = example_node(EXAMPLE)
    node.update(name="strap_on", data_dir=str(SHIPPED / "ares_i"))
    defaults = [d if "/dispersions" not in str(d) else {"override /dispersions": "strap_on"}
                for d in OmegaConf.to_container(shipped.defaults)]
    (folder / "vehicle" / "strap_on.yaml").write_text(
        "# @package _global_\n" + OmegaConf.to_yaml(OmegaConf.create({"defaults": defaults, "vehicle": node})))
    dispersions = OmegaConf.load(shipped_config_dir() / "dispersions" / "ares_i.yaml")
    dispersions.name = "strap_on"
    for b in ("booster_left", "booster_right"):
        dispersions["items"][f"{b}_rate"] = {"target": f"tables.boosters.{b}.burn_rate", "apply": "scale",
                                          "sigma": 0.01, "source": "[E] motor to motor, ±3 % at 3σ"}
    OmegaConf.save(dispersions, folder / "dispersions" / "strap_on.yaml")
    proc = run(["run", "-cd", str(folder), "vehicle=strap_on", "study=montecarlo", "phase=first_stage",
                "study.n_runs=4", "study.workers=2", "sim.progress=false", "output.plots=false",
                "guidance.allow_other_vehicle=true", "controller.allow_other_vehicle=true",  # ares_i's (the page)
                f"hydra.run.dir={tmp_path / 'out'}"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    with h5py.File(tmp_path / "out" / "savant.h5") as f:
        mc = f["montecarlo"]
        assert list(mc["runs/status"].asstr()[()]) == ["complete"] * 4
        k_left = mc["dispersions/booster_left_rate"][()]
        t_jet = mc["events/booster_jettison_s"][()]
        t_sep = mc["events/separation_s"][()]
        assert k_left[0] == 1.0 and np.all(k_left[1:] != 1.0)
        assert t_jet[0] == pytest.approx(94.665, abs=1e-9)
        np.testing.assert_allclose(t_jet, t_jet[0] / k_left, atol=2 * 0.005)
        assert np.all(t_jet < t_sep)


def _liquid_core_with_boosters(limit_mps2: float):
    """docs/vehicles.md's liquid first stage with the example's boosters, its throttle
    holding ``limit_mps2``."""
    node = example_node("a-liquid-first-stage")
    ex = example_node(EXAMPLE)
    node["boosters"] = ex["boosters"]
    node["configurations"]["stack_with_boosters"] = dict(ex["configurations"]["stack_with_boosters"],
                                                         mass_tanks=["first_stage_lox", "rp1"])
    node["events"] = {"booster_jettison": ex["events"]["booster_jettison"], **node["events"]}
    node["stages"]["first_stage"]["engines"]["booster_engine"]["throttle"]["axial_acceleration_limit_mps2"] = limit_mps2
    return _vehicle(node)


@pytest.mark.slow
def test_the_nominal_trace_of_a_throttled_core_carries_the_boosters(monkeypatch):
    """A liquid core holding 22 m/s² with the boosters burning (its throttle comes off
    full at about 54 s, the boosters leave at 94.7 s): the nominal trace, whose
    drag-free acceleration is a little high, predicts the separation a little late; a
    trace without the boosters' thrust and mass predicts it early, by more."""
    v = _liquid_core_with_boosters(22.0)
    model = _model(v)
    result = simulate(model, progress=False)
    sig = signals(result, model)
    t_sep = result.events[engine.EV_SEPARATION]
    setting = sig["throttle"].data
    assert sig["time"].data[np.argmax(setting < 1.0)] < result.events[engine.EV_BOOSTER_JETTISON]
    predicted = model.info["predicted_separation_time_s"]
    assert 0.0 < predicted - t_sep < 2.0
    monkeypatch.setattr(build, "booster_trace", lambda vehicle: None)
    without = build.predicted_separation_time(v, model.p, model.packed_tables)
    assert without < t_sep and t_sep - without > predicted - t_sep


# ----------------------------------------------------------------- refusals


@pytest.mark.parametrize("change,key", [
    (lambda n: n["boosters"]["booster_left"]["engines"]["booster_left_motor"].update(
        gimbal_axes=["pitch"], gimbal_limit_deg=5.0,
        moving_mass={"mass_kg": 500.0, "cg_from_gimbal_m": 1.0, "inertia_about_gimbal_kgm2": 600.0}),
     "vehicle.boosters.booster_left.engines.booster_left_motor.gimbal_axes"),
    (lambda n: n["boosters"]["booster_right"].update(attached_to="upper_stage"),
     "vehicle.boosters.booster_right.attached_to"),
    (lambda n: n["boosters"]["booster_right"]["engines"]["booster_right_motor"].update(isp_vac_s=270.0),
     "vehicle.boosters.booster_right.engines.booster_right_motor.thrust"),
    (lambda n: n["boosters"]["booster_right"].update(inert_mass_kg=5200.0),
     "vehicle.boosters.booster_right.inert_mass_kg"),
    (lambda n: n["events"]["booster_jettison"]["when"].update(of="five_segment_motor"),
     "vehicle.events.booster_jettison.when"),
])
def test_a_booster_outside_what_the_plant_flies_is_refused_naming_the_key(change, key):
    node = copy.deepcopy(example_node(EXAMPLE))
    change(node)
    with pytest.raises(ConfigError) as info:
        _vehicle(node)
    assert info.value.key == key


def test_a_liftoff_table_that_disagrees_with_the_boosters_is_refused():
    node = copy.deepcopy(example_node(EXAMPLE))
    node["configurations"]["boosted_stack"] = node["configurations"].pop("stack_with_boosters")
    node["configurations"]["boosted_stack"]["mass_table"] = "mass_stack.csv"  # the stack alone: no boosters
    with pytest.raises(ConfigError, match="minus their full masses") as info:
        _vehicle(node)
    assert info.value.key == "mass_stack.csv"


def test_flex_without_the_nozzle_nodes_is_refused_naming_the_key():
    with pytest.raises(ConfigError) as info:
        plant_data(_cfg("flex=on"), _vehicle())
    assert info.value.key == "vehicle.flex.nodes.nozzle_booster_left"


def test_the_reference_ascent_carries_the_boosters_as_the_flight_does():
    """The command generator's 3-DOF reference with the boosters: at liftoff its specific
    force (the first stage's and the boosters' delivered thrust over the stack's mass
    without them plus theirs, no air speed yet) is the plant's sensed one at the same
    state; it flies the boosted configuration until their predicted jettison (their own
    trace's), then the stack's."""
    v = _vehicle()
    ref = Reference(_cfg(), v, Program())
    t_jet = booster_trace(v).jettison_s
    assert ref.jettison_times[0] == t_jet and 80.0 < t_jet < 120.0
    assert (ref.config_at(t_jet - 0.01), ref.config_at(t_jet + 0.01)) == (0, 1)
    y = ref.initial()
    gravity = gravity_zonal(y[0:3], constants.MU_EARTH, constants.WGS84_A, constants.EGM2008_J2,
                            constants.EGM2008_J3, constants.EGM2008_J4)
    sensed_ref = ref.rhs(0.0, y, 0.0, (0.0, 0.0), {})[3:6] - gravity
    model = _model(v)
    aux = np.zeros(layout.N_AUX)
    derivative(0.0, model.x0, model.u0, model.p, model.packed_tables, aux, np.zeros(model.x0.size))
    sensed = aux[rigid_body.A_ACCEL:rigid_body.A_ACCEL + 3]
    assert sensed[0] > constants.G0  # it lifts off: the motor and both boosters at liftoff thrust
    # to the motor's table consistency: the plant's motor burns its load in the table's
    # shape, thrust g0 Isp M F_tab / I_tab, 0.007 % off the table the reference reads
    # (docs/models.md, "Propulsion"); the boosters left out would be percents
    assert np.linalg.norm(sensed_ref) == pytest.approx(np.linalg.norm(sensed), rel=1.5e-4)


@pytest.mark.slow
def test_a_profile_made_for_the_boosted_vehicle_predicts_its_flight_and_eases_its_loads(tmp_path, monkeypatch):
    """The generator's attitude profile for the example (its reference ascent carrying the
    boosters): the reference's altitude and speed match the flight's through the boosted
    ascent to 1 % (without the boosters' thrust and mass it would lag by tens of
    percent), and its peak q·α (in the first stage, where the air is) is below the one the
    shipped profile (made for the stack without boosters) gives the same vehicle. The gain
    generator designs on the same reference: every stack breakpoint, the boosted ones
    included, has a finite μα and a positive μc (its values against the plant's own:
    ``tests/test_booster_tvc.py``)."""
    from savant_cli.datagen import fcs_gains
    from savant_cli.datagen.guidance_commands import commands, solve
    from savant_cli.io.guidance_file import write_guidance_csv
    from savant_cli.sim.summary import total_alpha_deg
    v = _vehicle()
    cfg = _cfg()
    ref, sols, turn, azimuth, steer, sol = solve(cfg, v, verbose=False)
    times, quats, rates, _, speeds = commands(ref, sols, turn, azimuth, steer, sol)
    path = tmp_path / "strap_on_commands.csv"
    write_guidance_csv(path, times, quats, rates, "the strap-on example's profile", speed=speeds)
    flights = {}
    for name, file in (("own", path), ("shipped", prepare(cfg, hydra_search_dirs()).command_file)):
        model = build_model(cfg, v, read_guidance(file))
        result = simulate(model, progress=False, t_stop=ref.t_sep)  # the first stage's flight
        assert result.status == "complete", result.message
        flights[name] = signals(result, model)
    sig = flights["own"]
    t = sig["time"].data
    for when in (30.0, 60.0, 90.0, 120.0):
        segment = next(s for s in sols if when <= s.t[-1])
        y = segment.sol(when)
        c_i2e = earth.dcm_eci_to_ecef(when, constants.OMEGA_EARTH)
        altitude = earth.ecef_to_geodetic(c_i2e @ y[0:3], constants.WGS84_A, constants.WGS84_E2)[2]
        speed = np.linalg.norm(earth.velocity_relative_eci(y[0:3], y[3:6], constants.OMEGA_EARTH))
        i = int(np.argmin(np.abs(t - when)))
        assert sig["altitude"].data[i] == pytest.approx(altitude, rel=0.01)
        assert np.linalg.norm(sig["velocity_earth_relative"].data[i]) == pytest.approx(speed, rel=0.01)
    peak = {name: float(np.max(s["dynamic_pressure"].data * total_alpha_deg(s["alpha"].data, s["beta"].data)))
            for name, s in flights.items()}
    assert peak["own"] < peak["shipped"]
    monkeypatch.setattr(fcs_gains, "solve", lambda *args, **kwargs: (ref, sols, turn, azimuth, steer, sol))
    stack = fcs_gains.design_points(cfg, v)["stack"]
    assert any(t < ref.boosters.jettison_s for t, _, _ in stack)
    assert all(np.isfinite(mu_alpha) and mu_c > 0.0 for _, mu_alpha, mu_c in stack)
