"""Generate an independent reference flight with JSBSim for ``savant compare``.

The case both tools can fly: the default vehicle's integrated stack rising **vertically**
from the pad to first-stage separation, without wind. savant flies it with its full
6-DOF plant and flight control holding the liftoff attitude (the command file
``conf/guidance/vertical_hold_commands.csv``; run it with the overrides in
:data:`SAVANT_OVERRIDES`). JSBSim (``pip install jsbsim``; not a savant dependency)
flies a point-mass-like model generated here from the same vehicle data:

* mass from the stack mass table at the propellant burned, ṁ = F_vac / (g₀ Isp_vac);
* thrust F_vac(t) − p·A_exit with p JSBSim's own ambient pressure and F_vac the motor's
  (the table scaled so that it burns the load at Isp_vac, as the plant's motor), plus the base force
  table, applied along the body axis through the CG (an external reaction);
* drag q̄ S C_A(Mach) from the stack's aero table at zero incidence (vertical flight
  without wind stays at zero incidence, where drag is the axial force);
* JSBSim's own equations of motion, WGS84 ellipsoid and J2 gravity, rotating Earth and
  US 1976 atmosphere.

Only the vehicle data and the initial state (the CG's position on the pad) come from
savant; the dynamics, gravity, atmosphere and Earth model are JSBSim's. The result is
``references/jsbsim_vertical_ascent.csv`` (SI units, JSBSim property names in the
header comment), compared by ``references/jsbsim_names.yaml``::

    python -m savant_cli.datagen.jsbsim_reference
    savant run phase=first_stage winds=none environment.gravity_order=2 \\
        guidance.command_file=vertical_hold_commands.csv hydra.run.dir=runs/vertical
    savant compare runs/vertical references/jsbsim_vertical_ascent.csv --map references/jsbsim_names.yaml
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from savant_cli import constants
from savant_cli.models.propulsion import table_impulse

SAVANT_OVERRIDES = ["phase=first_stage", "winds=none", "environment.gravity_order=2",
                    "guidance.command_file=vertical_hold_commands.csv"]
FT, LBF, LBM = constants.FT, constants.LBF, constants.LBM
PSF = LBF / FT**2
SLUG_FT3 = constants.SLUG / FT**3
DT = 1.0 / 200.0
OUTPUT_EVERY = 20  # steps: the reference is written at 10 Hz
COLUMNS = (("time_s", "simulation/sim-time-sec", 1.0), ("altitude_m", "position/geod-alt-ft", FT),
           ("speed_mps", "velocities/vt-fps", FT), ("mach", "velocities/mach", 1.0),
           ("qbar_Pa", "aero/qbar-psf", PSF), ("pressure_Pa", "atmosphere/P-psf", PSF),
           ("density_kgm3", "atmosphere/rho-slugs_ft3", SLUG_FT3), ("temperature_K", "atmosphere/T-R", 5.0 / 9.0),
           ("latitude_deg", "position/lat-geod-deg", 1.0))


def _aircraft_xml(area_m2: float, mach: np.ndarray, ca: np.ndarray) -> str:
    rows = "\n".join(f"            {m:.6g} {c:.6g}" for m, c in zip(mach, ca))
    return f"""<?xml version="1.0"?>
<fdm_config name="savant_vertical" version="2.0" release="ALPHA">
  <fileheader><author>savant (generated)</author><description>Ares-I-like stack, vertical ascent,
    forces through the CG: mass, thrust and base force set each step from savant's vehicle data</description></fileheader>
  <metrics>
    <wingarea unit="M2"> {area_m2:.6g} </wingarea>
    <wingspan unit="M"> 5.5 </wingspan>
    <chord unit="M"> 5.5 </chord>
    <location name="AERORP" unit="M"><x>0</x><y>0</y><z>0</z></location>
    <location name="EYEPOINT" unit="M"><x>0</x><y>0</y><z>0</z></location>
    <location name="VRP" unit="M"><x>0</x><y>0</y><z>0</z></location>
  </metrics>
  <mass_balance>
    <ixx unit="KG*M2"> 1.0e6 </ixx>
    <iyy unit="KG*M2"> 1.0e8 </iyy>
    <izz unit="KG*M2"> 1.0e8 </izz>
    <emptywt unit="LBS"> 1 </emptywt>
    <location name="CG" unit="M"><x>0</x><y>0</y><z>0</z></location>
    <pointmass name="vehicle">
      <weight unit="LBS"> 1000 </weight>
      <location unit="M"><x>0</x><y>0</y><z>0</z></location>
    </pointmass>
  </mass_balance>
  <ground_reactions>  <!-- required by JSBSim; the CG starts far above the terrain -->
    <contact type="STRUCTURE" name="CG">
      <location unit="M"><x>0</x><y>0</y><z>0</z></location>
      <static_friction> 0 </static_friction>
      <dynamic_friction> 0 </dynamic_friction>
      <spring_coeff unit="LBS/FT"> 1.0e6 </spring_coeff>
      <damping_coeff unit="LBS/FT/SEC"> 1.0e5 </damping_coeff>
    </contact>
  </ground_reactions>
  <external_reactions>
    <force name="thrust" frame="BODY">
      <location unit="M"><x>0</x><y>0</y><z>0</z></location>
      <direction><x>1</x><y>0</y><z>0</z></direction>
    </force>
  </external_reactions>
  <aerodynamics>
    <axis name="DRAG">
      <function name="aero/force/drag">
        <product>
          <property>aero/qbar-psf</property>
          <property>metrics/Sw-sqft</property>
          <table>
            <independentVar>velocities/mach</independentVar>
            <tableData>
{rows}
            </tableData>
          </table>
        </product>
      </function>
    </axis>
  </aerodynamics>
</fdm_config>
"""


def _initial_xml(lat_deg: float, lon_deg: float, alt_m: float) -> str:
    return f"""<?xml version="1.0"?>
<initialize name="pad">
  <ubody unit="FT/SEC"> 0.0 </ubody>
  <vbody unit="FT/SEC"> 0.0 </vbody>
  <wbody unit="FT/SEC"> 0.0 </wbody>
  <latitude unit="DEG" type="geodetic"> {lat_deg:.10f} </latitude>
  <longitude unit="DEG"> {lon_deg:.10f} </longitude>
  <altitude unit="M"> {alt_m:.4f} </altitude>
  <phi unit="DEG"> 0.0 </phi>
  <theta unit="DEG"> 89.9999 </theta>
  <psi unit="DEG"> 90.0 </psi>
</initialize>
"""


def fly(out_csv: Path) -> Path:
    """Fly the JSBSim reference and write it (SI units) to ``out_csv``."""
    import jsbsim
    from hydra import compose, initialize_config_dir

    from savant_cli.config import validate
    from savant_cli.io.atomic import write_text_atomic
    from savant_cli.models import earth, layout
    from savant_cli.paths import shipped_config_dir
    from savant_cli.sim.setup import prepare

    with initialize_config_dir(config_dir=str(shipped_config_dir()), version_base="1.3"):
        cfg = validate(compose(config_name="config", overrides=SAVANT_OVERRIDES))
    prep = prepare(cfg)
    v, model = prep.vehicle, prep.model
    fs, stack = v.first_stage, v.configurations["stack"]
    aero = stack.aero
    ia, ib = int(np.argmin(np.abs(aero.alpha_rad))), int(np.argmin(np.abs(aero.beta_rad)))
    ca = aero.coeffs[0][:, ia, ib]
    lat, lon, alt = earth.ecef_to_geodetic(model.x0[layout.R:layout.R + 3], constants.WGS84_A, constants.WGS84_E2)  # ECI = ECEF at t = 0
    t_stop = model.info["predicted_separation_time_s"]  # before any flight: the table rule
    with tempfile.TemporaryDirectory() as root:
        rd = Path(root)
        (rd / "aircraft" / "savant_vertical").mkdir(parents=True)
        (rd / "aircraft" / "savant_vertical" / "savant_vertical.xml").write_text(
            _aircraft_xml(aero.area_m2, aero.mach, ca))
        (rd / "aircraft" / "savant_vertical" / "pad.xml").write_text(
            _initial_xml(np.degrees(lat), np.degrees(lon), alt))
        for sub in ("engine", "systems"):
            (rd / sub).mkdir()
        fdm = jsbsim.FGFDMExec(str(rd), None)
        fdm.set_debug_level(0)
        fdm.load_model("savant_vertical")
        fdm.load_ic("pad", True)
        fdm.set_dt(DT)
        prop = fs.propellant_kg
        rows = []
        # the motor burns its load in the table's shape, as the plant's (models/propulsion.py
        # first_stage_flow): F_vac = g0 Isp M F_tab / I_tab
        thrust_scale = constants.G0 * fs.isp_vac_s * fs.propellant_kg / table_impulse(fs.thrust_time_s, fs.thrust_vac_N)

        def set_inputs(t: float) -> float:
            f_vac = thrust_scale * float(np.interp(t, fs.thrust_time_s, fs.thrust_vac_N))
            p = fdm["atmosphere/P-psf"] * PSF
            base = float(np.interp(t, aero.base_time_s, aero.base_force_N))
            thrust = max(f_vac - p * fs.nozzle_exit_area_m2, 0.0) if prop > 0 else 0.0
            fdm["external_reactions/thrust/magnitude"] = (thrust + base) / LBF
            mass = float(np.interp(max(prop, 0.0), stack.mass.propellant_kg, stack.mass.mass_kg))
            fdm["inertia/pointmass-weight-lbs[0]"] = mass / LBM
            return f_vac

        set_inputs(0.0)
        fdm.run_ic()
        while True:
            t = fdm["simulation/sim-time-sec"]
            f_vac = set_inputs(t)
            if len(rows) == 0 or round(t / DT) % OUTPUT_EVERY == 0 or t >= t_stop:
                rows.append([fdm[prop_name] * k for _, prop_name, k in COLUMNS])
            if t >= t_stop:
                break
            fdm.run()
            f_next = thrust_scale * float(np.interp(t + DT, fs.thrust_time_s, fs.thrust_vac_N))
            prop -= 0.5 * (f_vac + f_next) / (constants.G0 * fs.isp_vac_s) * DT  # trapezoid of ṁ
    header = [
        "# JSBSim reference flight for `savant compare` (savant_cli.datagen.jsbsim_reference)",
        f"# JSBSim {jsbsim.__version__}: the ares_i stack rising vertically from LC-39B to {t_stop:.2f} s, no wind;",
        "# JSBSim's own EOM, WGS84 + J2 gravity, rotating Earth, US76 atmosphere; savant's vehicle data",
        "# columns (SI) from JSBSim properties: " + ", ".join(f"{c}={p}" for c, p, _ in COLUMNS),
        ",".join(c for c, _, _ in COLUMNS),
    ]
    body = "\n".join(",".join(f"{x:.9g}" for x in r) for r in rows)
    write_text_atomic(out_csv, "\n".join(header) + "\n" + body + "\n")
    return out_csv


def main(argv: list[str] | None = None) -> None:
    from savant_cli.paths import shipped_reference_dir

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=shipped_reference_dir() / "jsbsim_vertical_ascent.csv")
    args = ap.parse_args(argv)
    print(f"wrote {fly(args.out)}")


if __name__ == "__main__":
    main()
