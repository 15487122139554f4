"""The state's reference point follows the CG of the current configuration without
moving the vehicle (issue 12 item 4): across separation, LES jettison and, with slosh
on, the start on the pad, the nose tip's inertial position r + C (s − cg) and velocity
v + C (ω × (s − cg)) are continuous. The CGs are read from the vehicle's own mass
tables with numpy, not from the plant."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.models import layout, quaternion as qt
from savant_cli.models.configurations import CONFIG_STACK, CONFIG_UPPER, CONFIG_UPPER_LES
from savant_cli.paths import hydra_search_dirs
from savant_cli.sim import engine
from savant_cli.sim.run import simulate
from savant_cli.sim.setup import prepare

NOSE = np.zeros(3)  # structure station 0 on the centerline (the LES tip, then the capsule's)


def _cg(vehicle, config: str, prop_kg: float) -> np.ndarray:
    m = vehicle.configurations[config].mass
    return np.array([np.interp(prop_kg, m.propellant_kg, m.cg_m[:, k]) for k in range(3)])


def _body(ds: np.ndarray) -> np.ndarray:
    """Structure-axis offset (x aft) → body axes (x forward)."""
    return np.array([-ds[0], ds[1], -ds[2]])


def point_state(x: np.ndarray, cg: np.ndarray, s: np.ndarray = NOSE) -> tuple[np.ndarray, np.ndarray]:
    """Inertial position and velocity of structure point ``s`` when the state's reference
    point is the CG ``cg`` (structure axes)."""
    c = qt.dcm(x[layout.Q:layout.Q + 4])
    arm = _body(s - cg)
    return x[layout.R:layout.R + 3] + c @ arm, x[layout.V:layout.V + 3] + c @ np.cross(x[layout.W:layout.W + 3], arm)


@pytest.fixture(scope="module")
def flown():
    prep = prepare(validate(compose_config(["sim.progress=false"])), hydra_search_dirs())
    model = prep.model
    dt = model.rates.dt
    res = simulate(model, progress=False)
    k_sep = int(round(res.events[engine.EV_SEPARATION] / dt))  # the flown separation step
    k_les = int(round(res.events[engine.EV_LES] / dt))
    snaps = simulate(model, progress=False, snapshot_steps=(k_sep, k_les)).snapshots
    return prep, snaps[k_sep], snaps[k_les]


def _apply_events(model, snap):
    x, u, d, ev = snap.x.copy(), snap.u.copy(), snap.d.copy(), snap.events.copy()
    status = engine.handle_events(snap.t, model.rates.dt, x, u, d, ev, model.sched, model.p, model.packed_tables,
                                  engine.work_array(x.size))
    return status, x, u, ev


def test_nose_tip_is_continuous_across_separation(flown):
    prep, snap, _ = flown
    model, vehicle = prep.model, prep.vehicle
    assert snap.u[layout.U_CONFIG] == CONFIG_STACK
    status, x, u, ev = _apply_events(model, snap)
    assert status == engine.RUNNING and u[layout.U_CONFIG] == CONFIG_UPPER_LES and ev[engine.EV_SEPARATION] == snap.t
    cg_before = _cg(vehicle, "stack", snap.x[model.layout.tank("grain")])
    cg_after = _cg(vehicle, "upper_les", snap.x[model.layout.tank("lox")] + snap.x[model.layout.tank("lh2")])
    assert cg_before[0] - cg_after[0] > 10.0  # the CG moves forward by over 10 m
    r0, v0 = point_state(snap.x, cg_before)
    r1, v1 = point_state(x, cg_after)
    np.testing.assert_allclose(r1, r0, rtol=0, atol=1e-6)
    np.testing.assert_allclose(v1, v0, rtol=0, atol=1e-9)
    # the old plant kept r: the nose would have jumped by the CG shift
    assert np.linalg.norm(point_state(snap.x, cg_after)[0] - r0) > 10.0


def test_nose_tip_is_continuous_across_les_jettison(flown):
    prep, _, snap = flown
    model, vehicle = prep.model, prep.vehicle
    assert snap.u[layout.U_CONFIG] == CONFIG_UPPER_LES
    status, x, u, ev = _apply_events(model, snap)
    assert status == engine.RUNNING and u[layout.U_CONFIG] == CONFIG_UPPER
    prop = snap.x[model.layout.tank("lox")] + snap.x[model.layout.tank("lh2")]
    cg_before, cg_after = _cg(vehicle, "upper_les", prop), _cg(vehicle, "upper", prop)
    assert abs(cg_before[0] - cg_after[0]) > 0.1
    r0, v0 = point_state(snap.x, cg_before)
    r1, v1 = point_state(x, cg_after)
    np.testing.assert_allclose(r1, r0, rtol=0, atol=1e-6)
    np.testing.assert_allclose(v1, v0, rtol=0, atol=1e-9)


def test_slosh_on_starts_from_the_same_pad():
    """With slosh on the reference point is the rigid part's CG (the slosh masses left
    out); the vehicle stands on the same pad: its nose tip has the slosh-off start's
    position and velocity."""
    off = prepare(validate(compose_config(["slosh=off"])), hydra_search_dirs())
    on = prepare(validate(compose_config(["slosh=on"])), hydra_search_dirs())
    vehicle = off.vehicle
    cg_whole = _cg(vehicle, "stack", off.model.x0[off.model.layout.tank("grain")])
    # the rigid part's CG, by hand from the plant's slosh masses and stations at the start
    from savant_cli.models import slosh
    from savant_cli.sim.plant import mass_state

    m = on.model
    _, whole, rigid = mass_state(m.x0, m.p, m.packed_tables, CONFIG_STACK, np.zeros(layout.N_AUX))
    np.testing.assert_allclose(whole[1:], cg_whole, rtol=1e-12)
    tanks = [slosh.slosh_tank(m.packed_tables, m.p, j, m.x0[m.layout.tank(name)])
             for j, name in enumerate(m.layout.slosh_tanks)]
    assert m.layout.slosh_tanks == ("lox", "lh2")
    m_rigid = whole[0] - sum(t.mass_kg for t in tanks)
    cg_rigid_x = (whole[0] * whole[1] - sum(t.mass_kg * t.station_m for t in tanks)) / m_rigid
    assert rigid[1] == pytest.approx(cg_rigid_x, rel=1e-12) and abs(cg_rigid_x - cg_whole[0]) > 0.05
    r_off, v_off = point_state(off.model.x0, cg_whole)
    r_on, v_on = point_state(on.model.x0, np.array(rigid[1:4]))
    np.testing.assert_allclose(r_on, r_off, rtol=0, atol=1e-6)
    np.testing.assert_allclose(v_on, v_off, rtol=0, atol=1e-9)
    assert np.linalg.norm(on.model.x0[layout.R:layout.R + 3] - off.model.x0[layout.R:layout.R + 3]) > 0.05

