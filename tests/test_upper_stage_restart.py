"""An upper stage that burns twice (``guidance.peg.upper_stage_first_burn``, the events'
upper-stage cutoff and restart; ``sim/engine.py``, ``models/peg.py``): the J-2X of the
page's example (docs/vehicles.md, "An upper-stage restart") burns to a suborbital cutoff
whose apogee is the target's altitude, coasts to that apogee and circularizes there.

References: the first cutoff lands on the plant step nearest PEG's commanded time (half
a step); the first burn's end state against its own target (the page's orbit, two-body);
no thrust and no propellant used in the coast (the engine off: mass conserved to the
last bit); the restart at the first step the radial speed ``r·v/|r|`` of the logged
state turns negative (the condition, bracketed by the logged samples); the final orbit
against ``guidance.target`` within its tolerance. The coast's pitch and yaw jets: their
accelerations against ``n F |l| / I`` and ``n F / m`` at the configuration's own mass
properties, their commands against the phase plane's switching lines, and the coast's
attitude held within the deadband.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.io.guidance_file import read_guidance
from savant_cli.models import fcs, layout, peg, propulsion, quaternion
from savant_cli.paths import hydra_search_dirs, shipped_config_dir
from savant_cli.sim import engine
from savant_cli.sim.build import build_model
from savant_cli.sim.plant import derivative, mass_state
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare
from savant_cli.sim.summary import orbit_elements, summarize
from savant_cli.vehicle import load_vehicle
from test_boosters import _cfg
from test_vehicle_examples import example_node

FOLDER = shipped_config_dir() / "vehicle" / "ares_i"
JET_FORCE_N = 2 * 445.0  # the page's pods: two jets of 445 N per direction
DEADBAND_DEG = 1.0  # the shipped controller's roll phase plane (controller.roll.attitude_deadband_deg)
#: The page's first burn (docs/models.md, "Two burns"): a suborbital cutoff at 175 km
#: whose apogee is the final orbit's 185 km.
FIRST_BURN = dict(perigee_altitude_km=-2500.0, apogee_altitude_km=185.0, cutoff_altitude_km=175.0,
                  start_after_restart_s=2.5)
TARGET = ("guidance.target.perigee_altitude_km=185.0", "guidance.target.apogee_altitude_km=185.0",
          "guidance.target.cutoff_altitude_km=185.0")


def _overrides(**changes) -> list[str]:
    burn = {**FIRST_BURN, **changes}
    return ["sim.max_time_s=1000", *TARGET,
            "+guidance.peg.upper_stage_first_burn={" + ",".join(f"{k}:{v}" for k, v in burn.items()) + "}"]


def _model(cfg, node=None):
    command_file = prepare(_cfg(), hydra_search_dirs()).command_file  # the shipped vehicle's profile
    return build_model(cfg, load_vehicle(node or example_node("an-upper-stage-restart"), FOLDER),
                       read_guidance(command_file))


@pytest.fixture(scope="module")
def flight():
    cfg = _cfg(*_overrides())
    model = _model(cfg)
    result = simulate(model, progress=False)
    sig = signals(result, model)
    return model, result, sig, summarize(result, sig, target=peg.insertion_target(cfg.guidance), p=model.p)


def _at(sig, t: float) -> int:
    return int(np.searchsorted(sig["time"].data, t - 1e-9))


def _radial_speed(sig) -> np.ndarray:
    r, v = sig["position_eci"].data, sig["velocity_eci"].data
    return np.einsum("ij,ij->i", r, v) / np.linalg.norm(r, axis=1)


def test_peg_cuts_the_first_burn_off_on_its_target(flight):
    model, result, sig, s = flight
    t_cut = result.events[engine.EV_US_CUTOFF]
    assert s["upper_stage_first_shutdown"] == "guidance" and s["time_upper_stage_cutoff_s"] == t_cut
    commanded = sig["peg_cutoff_time"].data[_at(sig, t_cut) - 1]  # PEG's last prediction before the cutoff
    assert abs(t_cut - commanded) <= 0.5 * model.rates.dt + 1e-9
    # the end of its thrust against the page's orbit: radius, speed, flight-path angle
    assert abs(s["upper_stage_first_burn_radius_error_m"]) < 200.0
    assert abs(s["upper_stage_first_burn_speed_error_mps"]) < 0.5
    assert abs(s["upper_stage_first_burn_flight_path_angle_error_deg"]) < 0.01
    i = _at(sig, t_cut + 1.0)
    orbit = orbit_elements(sig["position_eci"].data[i], sig["velocity_eci"].data[i])
    assert orbit["apogee_altitude_km"] == pytest.approx(185.0, abs=0.5)
    assert orbit["perigee_altitude_km"] == pytest.approx(-2500.0, abs=5.0)


def test_the_coast_burns_nothing_and_the_restart_fires_at_apogee(flight):
    model, result, sig, s = flight
    t_cut, t_restart = result.events[engine.EV_US_CUTOFF], result.events[engine.EV_RESTART]
    assert s["time_upper_stage_restart_s"] == t_restart
    t = sig["time"].data
    shutdown_s = model.p[propulsion.P_US_SHUTDOWN_TIME]
    coast = (t >= t_cut + shutdown_s) & (t <= t_restart)
    assert coast.sum() > 100
    assert np.all(sig["thrust"].data[coast] == 0.0)
    prop = sig["propellant_remaining"].data[coast, 1:]
    np.testing.assert_array_equal(prop, np.broadcast_to(prop[0], prop.shape))  # nothing flows
    # armed 10 s after the cutoff, the restart waits for the radial speed to turn negative
    vr = _radial_speed(sig)
    armed = t >= t_cut + 10.0
    before, after = armed & (t < t_restart), t >= t_restart
    assert np.all(vr[before] >= 0.0) and vr[np.argmax(after)] < 0.0
    assert t_restart - t[np.flatnonzero(before)[-1]] <= model.rates.dt * model.rates.n_log + 1e-9
    # the flight control coasts: no gimbal command from the cutoff to the restart
    assert np.all(sig["gimbal_command"].data[(t > t_cut + 0.1) & (t <= t_restart)] == 0.0)


def test_the_restarted_burn_inserts_on_target(flight):
    _, result, sig, s = flight
    assert s["status"] == "complete", s["message"]
    assert result.events[engine.EV_CUTOFF] > result.events[engine.EV_RESTART]
    assert abs(s["insertion_perigee_error_km"]) < 10.0 and abs(s["insertion_apogee_error_km"]) < 10.0
    assert abs(s["insertion_inclination_error_deg"]) < 0.1
    # PEG's burn is a new one from the restart: disengaged, then engaged again after its delay
    active = sig["peg_active"].data > 0.0
    t = sig["time"].data
    t_restart = result.events[engine.EV_RESTART]
    engaged = t[np.argmax(active & (t > t_restart))]
    assert not active[(t > t_restart) & (t < engaged)].any() and active[-1]
    assert t_restart + FIRST_BURN["start_after_restart_s"] <= engaged <= t_restart + FIRST_BURN[
        "start_after_restart_s"] + 2.0  # (a guidance cycle of 1 s for the sample, one to measure the thrust)


def test_without_the_pitch_and_yaw_jets_the_coast_drifts_at_the_cutoffs_rate():
    node = example_node("an-upper-stage-restart")
    jets = node["stages"]["upper_stage"]["roll_jets"]
    del jets["pitch_yaw_thrust_N"], jets["pitch_yaw_jets_per_direction"]
    model = _model(_cfg(*_overrides()), node)
    result = simulate(model, progress=False)
    sig = signals(result, model)
    t_cut, t_restart = result.events[engine.EV_US_CUTOFF], result.events[engine.EV_RESTART]
    i_cut, i_restart = _at(sig, t_cut - 1.0), _at(sig, t_restart)
    pitch_rate = sig["body_rate"].data[i_cut:i_restart, 1]
    error = np.degrees(np.abs(sig["attitude_error"].data[i_restart, 1]))
    # the rate the burn ended with, held through the coast: its angle against the held command
    assert error == pytest.approx(np.degrees(abs(pitch_rate[-1])) * (t_restart - t_cut), rel=0.1)
    assert error > 5.0 * DEADBAND_DEG and "pitch_yaw_jet_command" not in sig


def test_a_restarting_vehicle_needs_the_first_burn_and_only_it_takes_one():
    with pytest.raises(ConfigError, match="guidance.peg.upper_stage_first_burn"):
        _model(_cfg("sim.max_time_s=1000", *TARGET))
    with pytest.raises(ConfigError, match="guidance.peg.upper_stage_first_burn"):
        _model(_cfg(*_overrides()), example_node("a-throttled-upper-stage"))


@pytest.mark.parametrize("changes, key", [
    (dict(apogee_altitude_km=-3000.0), "guidance.peg.upper_stage_first_burn.apogee_altitude_km"),
    (dict(cutoff_altitude_km=190.0), "guidance.peg.upper_stage_first_burn.cutoff_altitude_km"),
    (dict(start_after_restart_s=-1.0), "guidance.peg.upper_stage_first_burn.start_after_restart_s"),
])
def test_a_bad_first_burn_is_refused_naming_its_key(changes, key):
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        validate(compose_config(_overrides(**changes)))


def _events(**changes) -> dict:
    node = example_node("an-upper-stage-restart")
    for name, event in changes.items():
        if event is None:
            del node["events"][name]
        else:
            node["events"][name].update(event)
    return node


@pytest.mark.parametrize("changes, key", [
    (dict(j2x_cutoff={"delay_s": 0.0}), "events.j2x_cutoff.delay_s"),
    (dict(j2x_restart=None), "events.j2x_cutoff"),
    (dict(j2x_cutoff={"after": "separation"}), "events.j2x_cutoff"),
])
def test_a_restart_outside_the_shape_is_refused_naming_its_key(changes, key):
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        load_vehicle(_events(**changes), FOLDER)


def test_the_pitch_and_yaw_jets_turn_the_vehicle_by_their_force_at_their_arm(flight):
    """One plant evaluation at liftoff with each command on against none: the body-axis
    angular acceleration ``I⁻¹ M`` with ``M = n F |x_j − x_cg|`` about the commanded
    axis, the linear one ``n F / m`` across it (both linear in the command)."""
    model = flight[0]
    tb = model.packed_tables
    x, u = model.x0.copy(), model.u0.copy()
    aux = np.zeros(layout.N_AUX)
    _, _, rigid = mass_state(x, model.p, tb, 0, aux)
    mass, cgx = rigid[0], rigid[1]
    ixx, iyy, izz, ixy, ixz, iyz = rigid[4:]
    inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    arm = 35.6 - cgx  # the pods' station (the shipped roll jets' location_m) from the CG, structure x
    r = np.array([-arm, 0.0, 0.0])  # the pods from the CG, body axes (body x forward: −structure x)

    def rates(pitch: float, yaw: float) -> np.ndarray:
        u[layout.U_PY_JETS:layout.U_PY_JETS + 2] = pitch, yaw
        xd = np.zeros_like(x)
        derivative(0.0, x, u, model.p, tb, np.zeros(layout.N_AUX), xd)
        return xd

    rest = rates(0.0, 0.0)
    for axis, (pitch, yaw) in ((1, (1.0, 0.0)), (2, (0.0, -1.0))):
        d = rates(pitch, yaw) - rest
        moment = np.zeros(3)
        moment[axis] = (pitch + yaw) * JET_FORCE_N * abs(arm)
        np.testing.assert_allclose(d[layout.W:layout.W + 3], np.linalg.solve(inertia, moment), rtol=1e-9,
                                   atol=1e-15)
        force = np.cross(moment, r) / np.dot(r, r)  # the lateral force whose r × F is that moment
        np.testing.assert_allclose(np.linalg.norm(force), JET_FORCE_N, rtol=1e-12)
        np.testing.assert_allclose(d[layout.V:layout.V + 3], quaternion.rotate(x[layout.Q:layout.Q + 4], force / mass),
                                   rtol=1e-9, atol=1e-12)
    assert arm < 0.0  # the pods sit forward of the stack's CG: the far side's jets fire


@pytest.mark.parametrize("error_deg, rate_deg_s, expected", [
    (2.0, 0.0, -1.0), (-2.0, 0.0, 1.0), (0.5, 0.0, 0.0), (0.0, 2.0, -1.0), (0.5, 0.3, -1.0)])
def test_the_pitch_and_yaw_jets_fly_the_phase_plane_in_the_coast_only(flight, error_deg, rate_deg_s, expected):
    """The shipped phase plane: a 1° deadband, a 1°/s rate deadband, a 2 s lead (the
    switching function ``e + 2 ė`` against the deadband, the rate limits first)."""
    ft = flight[0].fcs
    for phase in (fcs.FCS_COAST, fcs.FCS_UPPER, fcs.FCS_STACK):
        d = np.zeros(layout.N_DISC)
        d[fcs.D_ERR + 1] = d[fcs.D_ERR + 2] = np.radians(error_deg)
        d[fcs.D_RATE_ERR + 1] = d[fcs.D_RATE_ERR + 2] = np.radians(rate_deg_s)
        fcs.pitch_yaw_jets_step(d, phase, ft)
        assert tuple(d[fcs.D_CMD_PY:fcs.D_CMD_PY + 2]) == ((expected, expected) if phase == fcs.FCS_COAST
                                                           else (0.0, 0.0))


def test_the_coast_holds_its_attitude_on_the_jets(flight):
    _, result, sig, s = flight
    t = sig["time"].data
    t_cut, t_restart = result.events[engine.EV_US_CUTOFF], result.events[engine.EV_RESTART]
    coast = (t > t_cut + 10.0) & (t <= t_restart)  # after the cutoff's rate is taken out
    error = np.degrees(np.abs(sig["attitude_error"].data[coast, 1:3]))
    assert error.max() < 1.2 * DEADBAND_DEG
    jets = sig["pitch_yaw_jet_command"].data
    assert np.all(jets[~((t > t_cut) & (t <= t_restart + 0.1))] == 0.0)  # off in powered flight
    assert s["pitch_yaw_jet_on_time_s"] > 0.0


def _elevation_deg(sig, i: np.ndarray) -> np.ndarray:
    """The commanded body x's elevation above the local horizontal (deg) at samples ``i``."""
    x_cmd = np.array([quaternion.rotate(q, np.array([1.0, 0.0, 0.0])) for q in sig["quaternion_command"].data[i]])
    r = sig["position_eci"].data[i]
    return np.degrees(np.arcsin(np.einsum("ij,ij->i", x_cmd, r) / np.linalg.norm(r, axis=1)))


def test_a_coast_held_in_the_local_horizontal_frame_turns_with_it(flight):
    """``guidance.peg.coast_attitude: local_horizontal``: the held command keeps its
    elevation above the local horizontal through the coast, where the inertial hold
    loses the angle the orbit turns (the angle between the position vectors); PEG's turn
    at the restart is that much smaller."""
    model = _model(_cfg(*_overrides(), "guidance.peg.coast_attitude=local_horizontal"))
    result = simulate(model, progress=False)
    sig = signals(result, model)
    turned = []
    for s, events in ((flight[2], flight[1].events), (sig, result.events)):
        t_cut, t_restart = events[engine.EV_US_CUTOFF], events[engine.EV_RESTART]
        i = np.array([_at(s, t_cut + 2.0), _at(s, t_restart)])
        r = s["position_eci"].data[i]
        orbit_deg = np.degrees(np.arccos(np.dot(r[0], r[1]) / np.linalg.norm(r[0]) / np.linalg.norm(r[1])))
        turned.append((np.diff(_elevation_deg(s, i))[0], orbit_deg))
    (inertial, orbit_deg), (local, _) = turned
    assert inertial == pytest.approx(orbit_deg, abs=0.2)  # the horizon turns down under a fixed direction
    assert abs(local) < 0.05
    assert orbit_deg > 4.0
    summary = summarize(result, sig, target=peg.insertion_target(_cfg(*_overrides()).guidance), p=model.p)
    assert summary["status"] == "complete" and abs(summary["insertion_apogee_error_km"]) < 10.0
    coast = (sig["time"].data > result.events[engine.EV_US_CUTOFF] + 10.0) & (
        sig["time"].data <= result.events[engine.EV_RESTART])
    assert np.degrees(np.abs(sig["attitude_error"].data[coast, 1:3])).max() < 1.2 * DEADBAND_DEG  # the jets follow
