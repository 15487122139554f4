"""Closed-loop guidance in the full simulation (guidance=ares_i_peg, the default;
small_launcher_peg), the stored-profile path it replaces, the first-stage schedule by
relative speed, and the refusals of bad guidance input."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import compose_config
from savant_cli import constants
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.models import command_schedule as cs, layout, peg
from savant_cli.sim import engine
from savant_cli.sim.summary import orbit_elements
from savant_cli.studies.flight import fly


def _fly(overrides: list[str]):
    return fly(validate(compose_config(["output.plots=false", "output.hdf5=false", *overrides])), progress=False)


def _insertion_ok(flight, perigee_km: float, apogee_km: float, inclination_deg: float) -> None:
    """Within 0.5 km of the target apsides and 0.01 deg of the inclination (issue 14), from
    the final state by the summary's own two-body elements."""
    r, v = flight.result.x[layout.R:layout.R + 3], flight.result.x[layout.V:layout.V + 3]
    orbit = orbit_elements(r, v)
    assert orbit["perigee_altitude_km"] == pytest.approx(perigee_km, abs=0.5)
    assert orbit["apogee_altitude_km"] == pytest.approx(apogee_km, abs=0.5)
    assert orbit["inclination_deg"] == pytest.approx(inclination_deg, abs=0.01)


@pytest.mark.slow
def test_default_flight_inserts_on_target():
    """The default vehicle, guidance ares_i_peg: PEG engages 40 s after ignition, cuts the
    engine off on its own time to go and inserts on the 56 x 185 km, 51.6 deg target."""
    flight = _fly([])
    assert flight.prep.model.p[peg.P_ON] == 1.0
    assert flight.result.status == "complete", flight.result.message
    assert flight.result.stop_code == engine.STOP_GUIDANCE_CUTOFF
    _insertion_ok(flight, 56.0, 185.0, 51.6)
    s = flight.summary
    assert s["peg_engage_time_s"] == pytest.approx(s["time_upper_stage_ignition_s"] + 40.0, abs=1.0)
    assert s["peg_converged_at_cutoff"] == 1
    # the summary's insertion errors agree with the elements, and the cutoff lands on
    # the plant step nearest PEG's time: |Δv| ≤ a_T dt / 2 ≈ 30 m/s² × 2.5 ms
    assert s["insertion_perigee_error_km"] == pytest.approx(s["perigee_altitude_km"] - 56.0, abs=1e-9)
    assert abs(s["insertion_speed_error_mps"]) < 0.1
    # out-of-plane steering stays small: the target plane is the first stage's own
    steer = flight.signals["peg_steering_angles"].data
    active = flight.signals["peg_active"].data > 0.0
    assert np.degrees(np.abs(steer[active, 1])).max() < 1.5


@pytest.mark.slow
def test_small_launcher_inserts_on_its_own_target():
    flight = _fly(["vehicle=small_launcher"])
    assert flight.result.status == "complete", flight.result.message
    assert flight.result.stop_code == engine.STOP_GUIDANCE_CUTOFF
    _insertion_ok(flight, 200.0, 300.0, 40.0)


@pytest.mark.slow
def test_stored_profile_path_still_cuts_off_on_energy():
    """guidance=ares_i_iss: no PEG, no PEG signals, the cutoff command at the first plant
    step whose two-body specific energy reaches the target orbit's −μ/(r_p + r_a); the
    J-2X shutdown impulse I_sd then adds v·I_sd/m (this rule does not anticipate it)."""
    flight = _fly(["guidance=ares_i_iss"])
    assert flight.prep.model.p[peg.P_ON] == 0.0
    assert "peg_time_to_go" not in flight.signals
    assert flight.result.stop_code == engine.STOP_CUTOFF
    r, v = flight.result.x[layout.R:layout.R + 3], flight.result.x[layout.V:layout.V + 3]
    energy = 0.5 * v @ v - constants.MU_EARTH / np.linalg.norm(r)
    target = -constants.MU_EARTH / (2.0 * constants.WGS84_A + 1e3 * (56.0 + 185.0))
    step_gain = np.linalg.norm(v) * 30.0 * flight.prep.model.rates.dt  # v · a_T · dt at cutoff
    tail = np.linalg.norm(v) * flight.prep.vehicle.upper_stage.shutdown_impulse_Ns / flight.summary["cutoff_mass_kg"]
    assert tail > 40e3  # J/kg: ~6 m/s at 7.8 km/s
    # the tail-off adds v·a_T·cos(θ) dt over its 0.4 s: within 3 % of v·I_sd/m for a thrust
    # direction up to 14° off the velocity (cos 14° = 0.97), plus at most one step
    assert -0.03 * tail <= energy - target - tail <= step_gain


@pytest.mark.slow
def test_relative_velocity_schedule_flies_the_same_nominal():
    """At nominal the reference speed is the flown one to within the 6-DOF's differences,
    so the first stage indexed by relative speed flies nearly the time-indexed ascent."""
    by_time = _fly(["phase=first_stage"])
    by_speed = _fly(["phase=first_stage", "guidance.first_stage_schedule=relative_velocity"])
    a = by_time.signals["altitude"].data[-1]
    b = by_speed.signals["altitude"].data[-1]
    assert b == pytest.approx(a, rel=0.02)
    assert by_speed.summary["max_dynamic_pressure_Pa"] == pytest.approx(by_time.summary["max_dynamic_pressure_Pa"],
                                                                          rel=0.02)


@pytest.mark.slow
def test_failing_guidance_stops_the_run_and_says_why():
    """A PEG that cannot converge at engagement stops the run there: status
    guidance_failed, the time and the reason, the history up to it kept."""
    flight = _fly(["phase=upper_stage", "guidance.peg.max_iterations=1"])
    res = flight.result
    assert res.status == "guidance_failed"
    assert "did not converge" in res.message and "guidance.peg.max_iterations" in res.message
    t_engage = res.events[engine.EV_IGNITION] + 40.0
    assert res.t_final == pytest.approx(t_engage, abs=1.0)
    assert flight.signals["time"].data[-1] == pytest.approx(res.t_final)
    assert flight.summary["insertion_perigee_error_km"] is None  # no cutoff, no insertion


def test_profile_time_by_speed_then_by_time():
    """The schedule kernel: τ interpolated in the reference speed, never backwards, then
    running on in time from the speed peak; the rate scale is dτ/dt."""
    ref_t = np.array([0.0, 10.0, 20.0, 30.0])
    ref_v = np.array([0.0, 100.0, 300.0, 600.0])
    d = np.zeros(layout.N_DISC)
    assert cs.profile_time(d, 0.0, 0.0, True, ref_v, ref_t, True) == 0.0
    # a hot motor: 200 m/s at 12 s is the reference's 15 s
    assert cs.profile_time(d, 12.0, 200.0, True, ref_v, ref_t, False) == pytest.approx(15.0)
    assert d[cs.D_PROFILE_RATE] == pytest.approx(15.0 / 12.0)
    # slower for a moment (a gust): the profile holds
    assert cs.profile_time(d, 13.0, 190.0, True, ref_v, ref_t, False) == pytest.approx(15.0)
    # beyond the reference's peak speed: the table's last speed sample, then on in time
    assert cs.profile_time(d, 25.0, 700.0, True, ref_v, ref_t, False) == pytest.approx(30.0)
    assert cs.profile_time(d, 26.0, 650.0, True, ref_v, ref_t, False) == pytest.approx(31.0)
    assert cs.profile_time(d, 40.0, 9.0, False, ref_v, ref_t, False) == pytest.approx(45.0)
    assert d[cs.D_PROFILE_RATE] == pytest.approx(1.0)


@pytest.mark.parametrize("override, key, words", [
    (["guidance.target.perigee_altitude_km=null"], "guidance.target.perigee_altitude_km", "required"),
    (["guidance.target.perigee_altitude_km=200", "guidance.target.apogee_altitude_km=150"],
     "guidance.target.apogee_altitude_km", "at least the perigee"),
    (["guidance.target.perigee_altitude_km=-10"], "guidance.target.perigee_altitude_km", ""),
    (["guidance.target.cutoff_altitude_km=300"], "guidance.target.cutoff_altitude_km", "between its perigee"),
    (["guidance.target.inclination_deg=20"], "guidance.target.inclination_deg", "unreachable from the launch latitude"),
    (["guidance.peg.start_after_ignition_s=-5"], "guidance.peg.start_after_ignition_s", "before upper-stage ignition"),
    (["guidance.peg.isp_vac_s=null"], "guidance.peg.isp_vac_s", "required"),
    (["guidance.peg.terminal_time_to_go_s=0.5"], "guidance.peg.terminal_time_to_go_s", "one guidance cycle"),
    (["guidance.first_stage_schedule=altitude"], "guidance.first_stage_schedule", "relative_velocity"),
])
def test_bad_guidance_input_is_refused_before_flight(override, key, words):
    with pytest.raises(ConfigError) as exc:
        validate(compose_config(override))
    assert exc.value.key == key
    assert words in str(exc.value)


def test_speed_schedule_needs_the_speed_column(tmp_path):
    """A command file without v_rel_m_s cannot serve first_stage_schedule=relative_velocity."""
    from savant_cli.io.guidance_file import read_guidance
    from savant_cli.paths import shipped_config_dir
    from savant_cli.sim.build import first_stage_profile

    table = read_guidance(shipped_config_dir() / "guidance" / "ares_i_iss_commands.csv")
    cfg = validate(compose_config(["guidance.first_stage_schedule=relative_velocity"]))
    cut = first_stage_profile(table, cfg, 130.0)
    assert 2 < cut.speed.size <= 131 and np.all(np.diff(cut.speed) > 0)
    with pytest.raises(ConfigError) as exc:
        first_stage_profile(table._replace(speed=np.zeros(0)), cfg, 130.0)
    assert exc.value.key == "guidance.first_stage_schedule" and "v_rel_m_s" in str(exc.value)


def test_insertion_statistics_and_reserve():
    """The accuracy band, and the reserve by order statistic against hand counts: 5000 runs
    with usable propellant 1 … 5000 kg, nominal 4000 kg. At 99.865 % and 90 % the order
    statistic is k = 4 (P(Binomial(5000, 0.00135) ≥ 4) = 0.904, ≥ 5: 0.803), so R_(4) =
    4 kg; the total remaining (usable + unusable 900 kg) is never the reserve. Then
    three runs out of propellant (ranked lowest: R_(4) is still a run that cut off), then
    four (R_(4) is one of them: not covered); and 500 runs: too few."""
    from savant_cli.montecarlo.insertion import DEPLETED, insertion_statistics

    n = 5000
    runs = np.arange(n)
    usable = np.arange(1.0, n + 1.0)
    usable[0], usable[3999] = 4000.0, 1.0  # the nominal, and the value it displaced
    perigee = np.linspace(-1.0, 1.0, n)
    keys = ["usable_propellant_remaining_kg", "unusable_propellant_kg", "propellant_remaining_kg",
            "insertion_perigee_error_km"]
    table = np.column_stack([usable, np.full(n, 900.0), usable + 900.0, perigee])
    msgs = ["cutoff: PEG time to go elapsed"] * n
    msgs[5] = "saturated: 1.2 s on the upper stage gimbal stop (more than …; cutoff: PEG time to go elapsed)"
    ins = insertion_statistics(runs, msgs, keys, table, 0.99865, 0.9)
    assert ins["runs_cut_off_on_guidance"] == n
    row = ins["accuracy"][0]
    assert row["variable"] == "insertion_perigee_error_km"
    assert row["p99.865"] == pytest.approx(np.percentile(perigee, 99.865))
    assert row["half_spread"] == pytest.approx(0.5 * (np.percentile(perigee, 99.865) - np.percentile(perigee, 0.135)))
    r = ins["reserve"]
    lowest = np.sort(usable)
    assert r["order_statistic"] == 4 and r["remaining_at_order_statistic_kg"] == lowest[3] == 4.0
    assert r["flight_performance_reserve_kg"] == pytest.approx(3996.0) and r["covered"]
    assert r["propellant"] == "usable" and r["unusable_nominal_kg"] == 900.0
    import json
    assert json.loads(json.dumps(ins))["reserve"] == r  # plain JSON types (the batch writes it)
    msgs[10:13] = [DEPLETED] * 3
    r = insertion_statistics(runs, msgs, keys, table, 0.99865, 0.9)["reserve"]
    assert r["runs_depleted"] == 3 and r["covered"]
    # three ran out and rank lowest: the 4th smallest is now the smallest run that cut off
    assert r["remaining_at_order_statistic_kg"] == np.sort(np.delete(usable, [10, 11, 12]))[0]
    msgs[13] = DEPLETED
    r = insertion_statistics(runs, msgs, keys, table, 0.99865, 0.9)["reserve"]
    assert r["flight_performance_reserve_kg"] is None and not r["covered"] and r["order_statistic_run"] in range(10, 14)
    r = insertion_statistics(runs[:500], ["cutoff: PEG time to go elapsed"] * 500, keys, table[:500], 0.99865,
                             0.9)["reserve"]
    assert r["order_statistic"] is None and r["flight_performance_reserve_kg"] is None and r["runs_needed"] == 1705
