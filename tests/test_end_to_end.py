"""End to end through the installed `savant` command: the nominal ascent lands in
credible ranges, every output is written, a bad config exits 2, a diverging run writes
its partial history and exits 1, and `savant report` redraws the plots."""

import json
import shutil
import subprocess
import sys

import h5py
import numpy as np
import pytest

pytestmark = pytest.mark.slow


def savant_cmd() -> list[str]:
    exe = shutil.which("savant")
    return [exe] if exe else [sys.executable, "-m", "savant_cli.cli"]


def run(args, cwd, timeout=900):
    return subprocess.run(savant_cmd() + args, cwd=cwd, capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def nominal(tmp_path_factory):
    out = tmp_path_factory.mktemp("nominal")
    proc = run(["run", f"hydra.run.dir={out}/run", "sim.progress=false"], cwd=out)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return out / "run", proc


def test_nominal_ascent_is_credible(nominal):
    run_dir, _ = nominal
    s = json.loads((run_dir / "summary.json").read_text())
    assert s["status"] == "complete"
    assert 30e3 <= s["max_dynamic_pressure_Pa"] <= 50e3
    assert 45.0 <= s["time_max_dynamic_pressure_s"] <= 75.0
    assert 120.0 <= s["time_separation_s"] <= 140.0
    assert s["time_upper_stage_ignition_s"] > s["time_separation_s"]
    assert s["time_les_jettison_s"] > s["time_upper_stage_ignition_s"]
    assert 100e3 <= s["cutoff_altitude_m"] <= 200e3
    assert s["cutoff_inertial_velocity_mps"] >= 7300.0
    assert s["inclination_deg"] == pytest.approx(51.6, abs=0.3)
    assert s["perigee_altitude_km"] == pytest.approx(56.0, abs=10.0)
    assert s["apogee_altitude_km"] == pytest.approx(185.0, abs=10.0)
    # the flight control keeps the vehicle on its commands
    assert s["max_attitude_error_deg"] < 3.0
    assert s["max_gimbal_deg"] < 5.0
    for key in ("max_alpha_deg", "sim_wall_time_s", "realtime_factor"):
        assert key in s


def test_outputs_are_self_describing(nominal):
    run_dir, proc = nominal
    required = ["time", "position_eci", "velocity_eci", "gravity_eci", "altitude", "latitude", "longitude",
                "velocity_relative", "mach", "dynamic_pressure", "density", "pressure", "temperature",
                "speed_of_sound", "alpha", "beta", "body_rate", "quaternion", "quaternion_command",
                "rate_command", "attitude_error", "gimbal_angle", "gimbal_command", "rcs_command", "mass",
                "propellant_remaining", "thrust", "wind_ned"]
    with h5py.File(run_dir / "savant.h5", "r") as f:
        th = f["time_history"]
        for name in required:
            assert name in th, name
            assert th[name].attrs["units"], name
        assert bool(f.attrs["complete"])
        assert "vehicle" in f["config"][()].decode()
        assert f.attrs["savant_version"]
        t = th["time"][()]
        assert np.all(np.diff(t) > 0)
        # the recorded gravity is the zonal model's: about 9.8 m/s^2 at liftoff
        assert np.linalg.norm(th["gravity_eci"][0]) == pytest.approx(9.79, abs=0.03)
    pngs = sorted(p.name for p in (run_dir / "plots").glob("*.png"))
    assert len(pngs) == 8 and "guidance.png" in pngs  # the paper's seven and PEG's
    assert (run_dir / ".hydra" / "config.yaml").is_file()
    assert "perigee" in proc.stdout  # the console summary


def test_report_redraws_plots(nominal, tmp_path):
    run_dir, _ = nominal
    copy = tmp_path / "copy"
    shutil.copytree(run_dir, copy)
    shutil.rmtree(copy / "plots")
    proc = run(["report", str(copy)], cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert len(list((copy / "plots").glob("*.png"))) == 8


def test_bad_config_exits_2_before_computing(tmp_path):
    for args in (["run", "sim.plant_rat_hz=100"],  # unknown key (Hydra)
                 ["run", "vehicle=no_such_vehicle"],  # unknown group option (Hydra)
                 ["run", "controller.blending.stack=[0.5,0.1,0.1]"]):  # physical check (savant)
        proc = run(args + [f"hydra.run.dir={tmp_path}/bad"], cwd=tmp_path)
        assert proc.returncode == 2, (args, proc.stdout, proc.stderr)
        assert not (tmp_path / "bad" / "savant.h5").exists()
    proc = run(["run", "controller.blending.stack=[0.5,0.1,0.1]", f"hydra.run.dir={tmp_path}/bad"], cwd=tmp_path)
    assert "controller.blending.stack" in proc.stderr and "sum to 1" in proc.stderr


def test_diverging_run_writes_partial_history_and_exits_1(tmp_path):
    # a body-rate limit below the roll program's rate is a "nonsensical state"
    proc = run(["run", "sim.max_body_rate_deg_s=1.0", f"hydra.run.dir={tmp_path}/div", "sim.progress=false"],
               cwd=tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    s = json.loads((tmp_path / "div" / "summary.json").read_text())
    assert s["status"] == "diverged"
    assert "body rate" in s["message"] and "t =" in s["message"]
    with h5py.File(tmp_path / "div" / "savant.h5", "r") as f:
        assert not bool(f.attrs["complete"])
        assert f["time_history/time"].shape[0] > 10


def test_version_and_help():
    proc = subprocess.run(savant_cmd() + ["--version"], capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stdout.startswith("savant ")
    proc = subprocess.run(savant_cmd() + ["--help"], capture_output=True, text=True)
    assert proc.returncode == 0 and "report" in proc.stdout


def test_upper_stage_phase_continues_the_ascent_exactly(nominal, tmp_path):
    """first_stage → staging_state.json → upper_stage reproduces the full ascent's cutoff
    bit for bit (the state is taken before separation is applied)."""
    run_dir, _ = nominal
    proc = run(["run", "phase=first_stage", f"hydra.run.dir={tmp_path}/fs", "sim.progress=false"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    fs = json.loads((tmp_path / "fs" / "summary.json").read_text())
    assert fs["message"].startswith("end of phase at first-stage separation")
    staging = tmp_path / "fs" / "staging_state.json"
    proc = run(["run", "phase=upper_stage", f"phase.staging_state_file={staging}", f"hydra.run.dir={tmp_path}/us",
                "sim.progress=false"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    us = json.loads((tmp_path / "us" / "summary.json").read_text())
    full = json.loads((run_dir / "summary.json").read_text())
    for key in ("time_cutoff_s", "cutoff_altitude_m", "cutoff_inertial_velocity_mps", "perigee_altitude_km",
                "apogee_altitude_km", "inclination_deg"):
        assert us[key] == full[key], key
    with h5py.File(tmp_path / "us" / "savant.h5", "r") as f:
        t0 = f["time_history/time"][0]
    assert 0.0 <= t0 - fs["time_separation_s"] <= 0.02  # first logged sample (50 Hz)


def test_shipped_staging_state_flies_to_orbit(tmp_path):
    proc = run(["run", "phase=upper_stage", f"hydra.run.dir={tmp_path}/us", "sim.progress=false", "output.plots=false"],
               cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    s = json.loads((tmp_path / "us" / "summary.json").read_text())
    assert s["inclination_deg"] == pytest.approx(51.6, abs=0.3)
    assert s["cutoff_inertial_velocity_mps"] >= 7300.0


def test_user_config_dir_layers_over_the_shipped_tree(tmp_path):
    """`-cd DIR` with only one group file: that group comes from the user, all others from
    the shipped tree (the search-path plugin); the keys it leaves out (gust, shear) from
    the shipped option it names first."""
    (tmp_path / "mine" / "winds").mkdir(parents=True)
    (tmp_path / "mine" / "winds" / "calm.yaml").write_text(
        "defaults: [none, _self_]\nname: calm\nenabled: true\nscale: 0.5\nprofile:\n  altitude_m: [0, 20000]\n"
        "  north_mps: [0, 0]\n  east_mps: [2, 10]\n")
    proc = run(["run", "-cd", str(tmp_path / "mine"), "winds=calm", "phase=first_stage", "output.plots=false",
                f"hydra.run.dir={tmp_path}/run", "sim.progress=false"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(tmp_path / "run" / "savant.h5", "r") as f:
        wind = f["time_history/wind_ned"][()]
        alt = f["time_history/altitude"][()]
    i = int(np.argmin(np.abs(alt - 10000.0)))
    # 0.5 x linear 2 -> 10 m/s over 0-20 km: 3 m/s east at 10 km
    assert wind[i, 1] == pytest.approx(0.5 * (2.0 + 8.0 * alt[i] / 20000.0), rel=1e-6)
