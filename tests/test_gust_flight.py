"""Gusts and load indicators in flight: the angle-of-attack response to a gust at max-Q
against the quasi-steady estimate, the design wind flown to orbit through `savant run`
(the gust visible in α, gimbal and q·α; the q·α limit reported), and a Monte Carlo with
dispersed gusts reporting its load extremes with their run numbers."""

from __future__ import annotations

import json

import h5py
import numpy as np
import pytest
from rich.console import Console

from conftest import compose_config
from savant_cli.config import DispersionSetConfig, DispersionSpec, validate
from savant_cli.studies.flight import fly

FIRST = ["phase=first_stage", "sim.progress=false", "output.plots=false"]
A = 9.0  # gust amplitude, m/s


def _fly(overrides):
    return fly(validate(compose_config(FIRST + overrides)), progress=False)


@pytest.fixture(scope="module")
def still_air():
    return _fly(["winds=none"])


@pytest.mark.parametrize("phi, angle, length", [(0.0, "alpha", 240.0), (90.0, "beta", 240.0),
                                                (180.0, "alpha", 240.0), (0.0, "alpha", 1000.0)])
def test_gust_at_max_q_moves_alpha_by_the_quasi_steady_gust_over_v(still_air, phi, angle, length):
    """A flight-path gust peaking at the max-Q altitude of the still-air flight. At the
    peak the air crosses the path at A, so the air-relative velocity turns by
    Δα ≈ A/V (V the air speed) toward +α (φ = 0), +β (φ = 90°) or −α (φ = 180°).
    Bounds: 0.9–1.15 A/V for the 240 m gust (0.6 s of climb, against a 0.3 Hz control
    loop: the attitude barely moves; measured 1.004), 0.9–1.2 for 1000 m (2.6 s: the
    aerodynamically unstable vehicle turns into the gust before the control catches it,
    measured 1.083). The flight is bit for bit the still-air one until the onset."""
    sig0 = still_air.signals
    q, h = sig0["dynamic_pressure"].data, sig0["altitude"].data
    h_q = float(h[np.argmax(q)])
    g = _fly(["winds=none", "winds.gust.enabled=true", f"winds.gust.amplitude_mps={A}",
              f"winds.gust.direction_deg={phi}", f"winds.gust.onset_altitude_m={h_q - length / 2}",
              f"winds.gust.length_m={length}"])
    sig = g.signals
    d = np.degrees(sig[angle].data - sig0[angle].data)
    j = int(np.argmax(np.abs(d)))
    estimate = np.degrees(A / sig["velocity_relative"].data[j])
    sign = -1.0 if phi == 180.0 else 1.0
    low, high = (0.9, 1.15) if length == 240.0 else (0.9, 1.2)
    assert low <= sign * d[j] / estimate <= high, (d[j], estimate)
    assert abs(sig["altitude"].data[j] - h_q) < length  # the peak response sits at the gust
    other = "beta" if angle == "alpha" else "alpha"
    assert np.max(np.abs(np.degrees(sig[other].data - sig0[other].data))) < 0.1 * abs(d[j])
    before = sig["altitude"].data < h_q - length / 2 - 50.0
    for name in ("alpha", "beta", "gimbal_angle", "position_eci"):
        assert np.array_equal(sig[name].data[before], sig0[name].data[before])


@pytest.mark.slow
def test_design_gust_flies_to_orbit_and_shows_the_gust(tmp_path):
    from test_end_to_end import run

    proc = run(["run", "winds=design_gust", f"hydra.run.dir={tmp_path}/run", "sim.progress=false"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    run_dir = tmp_path / "run"
    s = json.loads((run_dir / "summary.json").read_text())
    assert s["status"] == "complete" and s["time_cutoff_s"] is not None
    assert abs(s["insertion_perigee_error_km"]) < 1.0 and abs(s["insertion_apogee_error_km"]) < 1.0
    assert s["qalpha_limit_Pa_deg"] == 160000.0
    assert s["qalpha_limit_exceeded"] == 1 and s["time_above_qalpha_limit_s"] > 0.0
    assert s["qalpha_limit_ratio"] == pytest.approx(s["max_qalpha_Pa_deg"] / 160000.0)
    assert 50.0 < s["time_max_qalpha_s"] < 65.0
    assert (run_dir / "plots" / "alpha_beta.png").is_file()
    with h5py.File(run_dir / "savant.h5") as f:
        th = f["time_history"]
        t, h = th["time"][()], th["altitude"][()]
        alpha, gimbal, qbar = th["alpha"][()], th["gimbal_angle"][()], th["dynamic_pressure"][()]
        wind = th["wind_ned"][()]
    # the same flight without the gust (in process, same compiled plant)
    calm = fly(validate(compose_config(["winds=design_gust", "winds.gust.enabled=false", "sim.progress=false"])),
               progress=False).signals
    assert np.array_equal(calm["time"].data, t)
    g = validate(compose_config(["winds=design_gust"])).winds.gust
    lo, hi = g.onset_altitude_m, g.onset_altitude_m + g.length_m
    in_gust = (h > lo + 0.25 * g.length_m) & (h < hi - 0.25 * g.length_m)  # the gust above half its peak
    assert in_gust.sum() >= 10
    d_alpha = np.degrees(np.abs(alpha - calm["alpha"].data))
    d_gimbal = np.degrees(np.abs(gimbal - calm["gimbal_angle"].data)).max(axis=1)
    qa = qbar * np.degrees(np.arccos(np.cos(alpha) * np.cos(th_beta(run_dir))))
    qa0 = calm["dynamic_pressure"].data * np.degrees(np.arccos(np.cos(calm["alpha"].data) * np.cos(calm["beta"].data)))
    assert d_alpha[in_gust].max() > 0.5  # 9 m/s at ~470 m/s, ~0.8 deg of it in pitch
    assert d_gimbal.max() > 0.05
    assert (qa - qa0)[in_gust].max() > 20000.0
    gust_wind = np.linalg.norm(wind - calm["wind_ned"].data, axis=1)
    assert gust_wind.max() == pytest.approx(9.0, abs=0.2) and gust_wind[h < lo - 10.0].max() == 0.0
    after = (h > hi + 10.0) & (t < 120.0)  # the profile along a slightly different path
    assert gust_wind[after].max() < 0.1


def th_beta(run_dir):
    with h5py.File(run_dir / "savant.h5") as f:
        return f["time_history/beta"][()]


def test_dispersed_gusts_report_load_extremes_with_run_numbers(tmp_path):
    """The committed gust set (conf/dispersions/ares_i_gust.yaml): every dispersed run
    draws its own gust; the load extremes name the runs that hold them, in summary.json,
    the h5 attribute and the console."""
    from savant_cli.studies.montecarlo import fly_batch

    cfg = validate(compose_config(["study=montecarlo", "winds=design_gust", "dispersions=ares_i_gust",
                                   "study.n_runs=5", "study.workers=1", "study.histories.signals=[]", *FIRST]))
    assert cfg.dispersions.items["wind_profile"].value == "design_gust"
    console = Console(record=True, width=300)
    summary, stop = fly_batch(cfg, "{}", tmp_path, console)
    assert stop.reason == "done" and summary["status_counts"] == {"complete": 5}
    with h5py.File(tmp_path / "savant.h5") as f:
        g = f["montecarlo"]
        runs = g["runs/run"][()]
        draws = {k: g[f"dispersions/{k}"][()] for k in g["dispersions"]}
        qa = g["summary/max_qalpha_Pa_deg"][()]
        qa_pitch = g["summary/max_qalpha_pitch_Pa_deg"][()]
        above = g["summary/qalpha_limit_exceeded"][()]
        loads_attr = json.loads(g.attrs["loads"])
    for name in ("gust_amplitude", "gust_onset_altitude", "gust_direction"):  # each run its own gust
        assert len(set(draws[name][runs > 0].tolist())) == 4, name
    assert len(set(qa.tolist())) == 5
    loads = summary["loads"]
    assert loads == loads_attr
    worst = int(runs[np.argmax(qa)])
    assert loads["max_qalpha_Pa_deg"] == {"max": float(qa.max()), "max_run": worst}
    assert loads["max_qalpha_pitch_Pa_deg"]["max_run"] == int(runs[np.argmax(qa_pitch)])
    assert loads["runs_above_qalpha_limit"] == int(above.sum())
    assert loads["qalpha_limit_Pa_deg"] == 160000.0
    row = next(r for r in summary["statistics"] if r["variable"] == "max_qbeta_Pa_deg")
    assert row["max_run"] in runs.tolist()
    text = console.export_text()
    assert f"max q-alpha total {qa.max():,.0f} Pa deg (run {worst})" in text
    assert f"{int(above.sum())} of 5 runs above the q-alpha limit 160,000 Pa deg" in text
    # the swept gust length: the worst q-alpha of each drawn length, with its run
    lengths = draws["gust_length"]
    by = loads["by_choice"]
    assert [r["value"] for r in by] == sorted(set(lengths[runs > 0].tolist()))
    for r in by:
        at = (runs > 0) & (lengths == r["value"])
        assert r["dispersion"] == "gust_length" and r["units"] == "m" and r["runs"] == int(at.sum())
        assert r["max_qalpha_Pa_deg"] == float(qa[at].max()) and r["max_run"] == int(runs[at][np.argmax(qa[at])])
        assert r["margin_Pa_deg"] == pytest.approx(160000.0 - r["max_qalpha_Pa_deg"])
    assert sum(r["worst"] for r in by) == 1
    assert "max q-alpha total by gust_length (Pa deg): " in text


def _tables(values, qa, runs=None, status=None):
    from savant_cli.montecarlo.results import Tables

    n = len(qa)
    runs = np.arange(n) if runs is None else np.asarray(runs)
    keys = ["max_qalpha_Pa_deg", "qalpha_limit_Pa_deg"]
    return Tables(runs, status or ["complete"] * n, [""] * n, np.zeros(n), np.zeros(n), np.asarray(values, float),
                  keys, np.column_stack([qa, np.full(n, 160000.0)]), np.zeros((n, 1)), np.zeros((0, 9)), [])


def test_loads_by_choice_takes_the_worst_run_of_each_value():
    """Hand-built tables: per value of a numeric choice the largest q-alpha and its run,
    the ratio and margin to the 160,000 Pa deg limit and the runs above it; the nominal
    run 0 (NaN draw), failed runs without results and a group choice (option indices)
    stay out."""
    from savant_cli.montecarlo.analysis import loads_by_choice
    from savant_cli.montecarlo.console_summary import loads_by_choice_lines

    disp = [{"name": "gust_length", "dist": "choice", "units": "m"},
            {"name": "wind_profile", "dist": "choice", "units": "", "choices": ["a", "b"]},
            {"name": "gust_amplitude", "dist": "normal", "units": "m/s"}]
    values = [[np.nan, np.nan, 0.0], [60, 0, 9], [60, 1, 9], [1086, 0, 9], [1086, 1, 9], [371, 0, 9], [60, 0, 9]]
    qa = [500000.0, 150000.0, 170000.0, 210000.0, 120000.0, 90000.0, 900000.0]
    tb = _tables(values, qa, status=["complete"] * 6 + ["invalid"])
    rows = loads_by_choice(tb, disp, 160000.0)
    assert [(r["dispersion"], r["value"], r["runs"], r["max_qalpha_Pa_deg"], r["max_run"], r["runs_above_limit"])
            for r in rows] == [("gust_length", 60.0, 2, 170000.0, 2, 1), ("gust_length", 371.0, 1, 90000.0, 5, 0),
                               ("gust_length", 1086.0, 2, 210000.0, 3, 1)]
    assert [r["worst"] for r in rows] == [False, False, True]
    assert rows[2]["ratio"] == pytest.approx(210000.0 / 160000.0) and rows[2]["margin_Pa_deg"] == -50000.0
    (line, ok), = loads_by_choice_lines({"by_choice": rows})
    assert ok is False and line.startswith("max q-alpha total by gust_length (Pa deg): 60 m: 170,000 (run 2, 1.06 ")
    assert line.endswith("worst 1086 m, margin -50,000 Pa deg to the limit")
    assert loads_by_choice(tb, disp, None)[0]["ratio"] is None


def test_swept_gust_lengths_are_tuned_to_the_vehicles_modes_at_the_reference_altitude():
    """conf/dispersions/ares_i_gust.yaml's gust lengths hold the two tuned ones: the
    half-wavelength crossed at the climb rate at the 11 km reference altitude lasts half
    the period (d = ḣ/f) of the first bending mode (the flown modal set's, at 1.00 Hz)
    and of the closed-loop rigid-body mode (the complex closed-loop pole nearest the
    pitch gain crossover of the linear model there); within 3 %."""
    import warnings

    import control

    from savant_cli.linear.point_analysis import analyse
    from savant_cli.paths import shipped_config_dir
    from savant_cli.studies import flight as flight_mod

    cfg = validate(compose_config(FIRST + ["study=linear", "winds=design_gust", "study.times=[56.8]"]))
    lengths = validate(compose_config(["study=montecarlo", "dispersions=ares_i_gust"])).dispersions.items[
        "gust_length"].values
    steps = flight_mod.control_steps(cfg, [56.8])
    f = flight_mod.fly(cfg, progress=False, snapshot_steps=steps)
    t, h = f.signals["time"].data, f.signals["altitude"].data
    hdot = np.interp(11000.0, h, np.gradient(h, t))
    rt = f.prep.model.rates
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pa = analyse(f.prep.model, f.result.snapshots[steps[0]], cfg.study, rt.dt * rt.n_fcs)
    crossover = next(r.frequency_hz for r in pa.rows if r.axis == "pitch" and r.kind == "phase")
    wn, zeta, poles = control.damp(pa.point.closed, doprint=False)
    osc = [(w / (2 * np.pi)) for w, z, s in zip(wn, zeta, poles) if abs(s.imag) > 1e-9 and z < 1.0]
    f_rigid = min(osc, key=lambda fr: abs(fr - crossover))
    text = (shipped_config_dir() / "vehicle/ares_i/flex/first_stage_liftoff_modes.csv").read_text()
    header, first = [line.split(",") for line in text.splitlines() if not line.startswith("#")][:2]
    f_bend = float(first[header.index("frequency_hz")])  # mode 1 of the set flown to separation
    for f_mode in (f_rigid, f_bend):
        assert min(abs(d - hdot / f_mode) / (hdot / f_mode) for d in lengths) < 0.03, (f_mode, hdot)
    assert {60.0, 300.0} <= set(lengths)  # the ends of the classical 60-300 m set


@pytest.mark.slow
def test_a_bad_gust_exits_2_naming_the_key(tmp_path):
    from test_end_to_end import run

    proc = run(["run", "winds=design_gust", "winds.gust.length_m=-240", f"hydra.run.dir={tmp_path}/run"], cwd=tmp_path)
    assert proc.returncode == 2
    assert "winds.gust.length_m" in proc.stdout + proc.stderr and "-240" in proc.stdout + proc.stderr
