"""The second vehicle, defined by config and data only: it flies to its target orbit and
the studies run on it (slow: through the installed command)."""

from __future__ import annotations

import json

import pytest

from test_end_to_end import run

pytestmark = pytest.mark.slow

# the vehicle config alone selects its guidance, controller, sensors and dispersion set
VEHICLE = ["vehicle=small_launcher", "sim.progress=false"]


def test_small_launcher_reaches_its_orbit_and_the_studies_run(tmp_path):
    proc = run(["run", *VEHICLE, f"hydra.run.dir={tmp_path}/nominal"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    s = json.loads((tmp_path / "nominal" / "summary.json").read_text())
    assert s["status"] == "complete" and "PEG time to go" in s["message"]  # closed-loop guidance by default
    assert abs(s["perigee_altitude_km"] - 200.0) < 0.5 and abs(s["apogee_altitude_km"] - 300.0) < 0.5  # its target
    assert abs(s["inclination_deg"] - 40.0) < 0.01
    assert s["max_dynamic_pressure_Pa"] < 30e3 and s["max_gimbal_deg"] < 6.0  # inside its 6 deg gimbal
    lin = run(["run", *VEHICLE, "study=linear", "study.times=[55,300]", "output.plots=false",
               f"hydra.run.dir={tmp_path}/linear"], cwd=tmp_path)
    assert lin.returncode == 0, lin.stdout + lin.stderr
    margins = json.loads((tmp_path / "linear" / "summary.json").read_text())["margins"]
    assert {m["time_s"] for m in margins} == {55.0, 300.0}
    assert any(m["kind"] == "gain" and m["value"] < 0 and m["time_s"] == 55.0 for m in margins)  # aero-unstable
    mc = run(["run", *VEHICLE, "study=montecarlo", "study.n_runs=4", "output.plots=false",
              f"hydra.run.dir={tmp_path}/mc"], cwd=tmp_path)
    assert mc.returncode == 0, mc.stdout + mc.stderr
    assert json.loads((tmp_path / "mc" / "summary.json").read_text())["n_runs_present"] == 4
    config = (tmp_path / "mc" / ".hydra" / "config.yaml").read_text()
    assert "name: small_launcher" in config.split("dispersions:", 1)[1].split("\n", 2)[1]  # its own set


def test_another_vehicles_guidance_or_controller_is_refused_unless_forced(tmp_path):
    for group, option in (("guidance", "ares_i_iss"), ("controller", "msfc_pid")):
        bad = run(["run", "vehicle=small_launcher", f"{group}={option}", f"hydra.run.dir={tmp_path}/{group}"],
                  cwd=tmp_path)
        assert bad.returncode == 2 and f"{group}.vehicle" in bad.stderr + bad.stdout
        assert f"{group}.allow_other_vehicle=true" in (bad.stderr + bad.stdout).replace("\n", "")
