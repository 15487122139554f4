"""Reproducible generator of the default vehicle's tables (``conf/vehicle/ares_i/*.csv``).

Run ``python -m savant_cli.datagen.ares_i_tables [--out DIR] [--fit]``. The output is
a pure function of the constants below, which come only from the public figures of
``shared/data/ares_i_public_data.md`` (marks **[P]** public, **[E]** estimate, **[D]**
derived; ``conf/vehicle/ares_i/README.md`` cites each one).

Mass properties — uniform-segment model
---------------------------------------
The stack is a set of axisymmetric segments, each a uniform solid cylinder, thin shell or
thick-walled tube over a station range ``[x_fwd, x_aft]`` (structure frame: x aft of the
nose tip, m). Masses are the public figures; the station layout is [E]: its free lengths
were fitted (bounded ``scipy.optimize.least_squares``, :func:`fit_layout`, ``--fit``)
so that the model reproduces the data file's [D] mass-property figures (liftoff CG and
pitch inertia, first-stage burnout CG and pitch inertia, upper-stage ignition and burnout
pitch inertias), then rounded and frozen in :data:`LAYOUT` so the tables do not depend
on an optimizer run. Within a configuration:

* the first-stage grain burns radially and uniformly along its length: a tube between
  a fixed outer radius and a bore that grows as propellant burns (density [E]), so its
  CG stays put while its mass and radius of gyration change;
* liquid propellant settles at the aft end of its tank as a solid cylinder whose height
  is proportional to the mass remaining; the J-2X burns LOX and LH2 at its mixture
  ratio 5.5 [E], and the tanks are loaded at that ratio [D] with the public total
  135.1 t [P] (the public 112.9 t / 22.2 t split is a ratio of 5.09: at 5.5 it would
  leave 1.67 t of LH2 that cannot burn), so both run out together;
* inertias are about the configuration's CG (parallel-axis theorem), in body axes; the
  model is axisymmetric, so Iyy = Izz and the products of inertia are zero.

Aerodynamics — slender-body stand-in
------------------------------------
No public Ares I tables exist. A body-of-revolution model in the total angle of attack
``alpha_t`` (``cos alpha_t = cos alpha cos beta``): axial force from the Atlas SLV-3D
``CA(M)`` table [P] (independent of the angles), total normal force
``C_Nt = CNa(M) sin alpha_t`` acting in the crossflow plane against the crossflow,
which with ``alpha = atan2(w, u)`` and ``beta = asin(v/V)`` gives exactly
``CN = CNa sin(alpha) cos(beta)`` and ``CY = -CNa sin(beta)``; a centre of pressure at
0.20–0.26 of each configuration's length from its nose [P range 0.1–0.3], ahead of the
CG, so the stack is aerodynamically unstable like Ares I. Moments about the moment
reference point (MRP) at the configuration's nose follow from ``r x F`` with
``r = diag(-1, 1, -1) (x_cp - x_mrp, 0, 0)`` (body axes), ``F = qS (-CA, CY, -CN)``:
``Cm = -CN (x_cp - x_mrp) / l_ref``, ``Cn = -CY (x_cp - x_mrp) / l_ref``, ``Cl = 0``.

Base force
----------
``F_base(t) = C_pb(M) q A_base`` (negative = drag) along a two-dimensional point-mass
ascent (:func:`point_mass_ascent`, ``scipy.integrate.solve_ivp``) flown with the public
thrust, Isp and masses, the Atlas ``CA``, the US76 atmosphere of
:mod:`savant_cli.models.atmosphere` and a vertical rise + 6 deg pitch kick + gravity
turn; it reproduces the data file's max-Q figure (~40 kPa at t ~ 57 s, Mach 1.6, 11 km).
"""

from __future__ import annotations

import argparse
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

try:  # shared constants (savant_cli/constants.py), with local fallbacks
    from savant_cli.constants import G0, MU_EARTH, P0, WGS84_A
except ImportError:  # pragma: no cover - only while constants.py is being written
    G0, MU_EARTH, P0, WGS84_A = 9.80665, 3.986004418e14, 101325.0, 6378137.0

# ====================================================================== public figures
LENGTH_M = 94.0                    # [P] overall length (308 ft)
US_DIAMETER_M = 5.5                # [P] upper-stage diameter
FS_DIAMETER_M = 3.71               # [E] first-stage diameter (146 in)
REF_AREA_M2 = float(np.pi * US_DIAMETER_M**2 / 4.0)   # [D] 23.76 m^2
REF_LENGTH_M = US_DIAMETER_M       # [E] reference length of all three moment axes

M_LES = 7060.0                     # [P] launch abort system
M_CM = 9700.0                      # [P] Orion crew module
M_SM = 8800.0                      # [P] Orion service module
M_SA = 1600.0                      # [P] spacecraft adapter
M_US_DRY = 15500.0                 # [E] upper-stage dry mass (includes the J-2X)
M_J2X = 2500.0                     # [E] J-2X engine (part of the stage dry mass)
M_HYDRAZINE = 500.0                # [E] roll-control hydrazine (not consumed in the tables)
M_INTERSTAGE = 5900.0              # [E]
M_FS_INERT = 85500.0               # [E] first-stage inert
M_FS_PROP = 647600.0               # [E] first-stage propellant
MIXTURE_RATIO = 5.5                # [E] J-2X LOX/LH2 mass ratio in flight
M_US_PROP = 135100.0               # [P] upper-stage LOX + LH2 (112.9 t + 22.2 t)
M_LOX = round(M_US_PROP * MIXTURE_RATIO / (1.0 + MIXTURE_RATIO), 3)  # [D] LOX load at the mixture ratio
M_LH2 = M_US_PROP - M_LOX          # [D] LH2 load at the mixture ratio
RHO_GRAIN = 1760.0                 # [E] PBAN propellant density, kg/m^3

FS_ISP_VAC_S = 266.0               # [E]
FS_ISP_SL_S = 242.0                # [E]
US_THRUST_VAC_N = 1307500.0        # [P] 294,000 lbf
US_ISP_VAC_S = 448.0               # [P]
US_EXIT_AREA_M2 = 7.3              # [E] ~3.05 m J-2X nozzle exit diameter
RCS_THRUST_VAC_N = 3100.0          # [E] per roll-control jet

# First-stage vacuum thrust vs time [D] (data file, MN)
FS_THRUST_TIME_S = np.array([0.0, 0.3, 1, 5, 20, 25, 30, 40, 50, 60, 70, 80, 85, 90, 100, 110, 116,
                             118, 120, 122, 124, 126, 130, 132.5])
FS_THRUST_VAC_MN = np.array([11.06, 13.31, 15.75, 15.74, 15.78, 15.24, 14.34, 13.05, 12.69, 13.14,
                             13.99, 14.60, 14.68, 14.57, 13.65, 12.27, 11.15, 9.78, 7.17, 4.25, 2.54,
                             1.30, 0.38, 0.03])
# [D] A_e p0 = F_vac (1 - Isp_sl / Isp_vac), with F_vac the peak (design-pressure) thrust
FS_EXIT_AREA_M2 = float(FS_THRUST_VAC_MN.max() * 1e6 * (1.0 - FS_ISP_SL_S / FS_ISP_VAC_S) / P0)

# Atlas SLV-3D axial-force coefficient vs Mach [P]
CA_MACH = np.array([0, .25, .5, .6, .7, .8, .85, .9, .93, .95, 1.0, 1.05, 1.1, 1.15, 1.25, 1.4, 1.5,
                    1.75, 2, 2.5, 3.5, 4.5, 6, 8, 10])
CA_TABLE = np.array([.373, .347, .345, .350, .365, .391, .425, .481, .565, .610, .725, .760, .773, .770,
                     .740, .665, .622, .530, .459, .374, .303, .273, .259, .267, .289])
# Normal-force slope per rad on the 23.76 m^2 reference area: ~3.2 subsonic, ~4.3 at
# Mach 1, ~4.6 at Mach 4-7 [P]; the shape between the anchors [E].
CNA_MACH = np.array([0.0, 0.6, 0.8, 0.9, 1.0, 1.2, 2.0, 3.0, 4.0, 7.0, 10.0])
CNA_TABLE = np.array([3.2, 3.2, 3.3, 3.7, 4.3, 4.3, 4.4, 4.5, 4.6, 4.6, 4.5])
# Centre of pressure, fraction of the configuration's length from its nose [P 0.1-0.3,
# shape E]: moves aft through the transonic region (shock-induced loads on the flare).
XCP_MACH = np.array([0.0, 0.8, 1.0, 1.2, 2.0, 4.0, 10.0])
XCP_FRACTION = np.array([0.20, 0.20, 0.24, 0.26, 0.24, 0.22, 0.22])
STACK_ANGLES_DEG = np.arange(-10.0, 10.0 + 1e-9, 2.0)            # alpha and beta grid, stack
UPPER_ANGLES_DEG = np.array([-20.0, -16.0, -12.0, *np.arange(-10.0, 10.0 + 1e-9, 2.0), 12.0, 16.0, 20.0])

# Base-pressure coefficient C_pb = (p_base - p_inf) / q vs Mach [E]: generic power-on
# base of a large solid motor; bounded below by the vacuum limit -2 / (gamma M^2).
CPB_MACH = np.array([0.0, 0.8, 1.0, 1.2, 1.5, 2.0, 3.0, 5.0, 10.0])
CPB_TABLE = np.array([-0.10, -0.12, -0.22, -0.25, -0.22, -0.17, -0.11, -0.05, -0.014])
FS_AFT_SKIRT_DIAMETER_M = 5.38     # [E] flared first-stage aft skirt (Shuttle SRB heritage)
FS_BASE_AREA_M2 = float(np.pi * FS_AFT_SKIRT_DIAMETER_M**2 / 4.0 - FS_EXIT_AREA_M2)  # [D] annulus

# Ascent used for the base force [E]: vertical rise, then a fixed pitch kick, then a
# gravity turn; the kick reproduces the data file's max-Q figure.
ASCENT_VERTICAL_S = 8.0
ASCENT_KICK_DEG = 6.0
ASCENT_KICK_HOLD_S = 10.0
SEPARATION_THRUST_FRACTION = 0.02  # as conf/vehicle/ares_i.yaml events
IGNITION_DELAY_S = 1.5             # as conf/vehicle/ares_i.yaml events
LES_JETTISON_DELAY_S = 30.0        # as conf/vehicle/ares_i.yaml events
ASCENT_END_S = 250.0               # the base force is negligible beyond (q < 30 Pa)


# ============================================================================ layout
@dataclass(frozen=True)
class Layout:
    """Free lengths (m) and one mass (kg) of the segment layout [E]; stations follow.

    From the nose tip aft: LES ``[0, les]``; crew module (3.3 m) under the LES cover,
    its apex ``cm_overlap`` ahead of the LES's aft end; service module; spacecraft
    adapter; upper stage = forward skirt, LH2 tank, LOX tank, aft skirt/thrust structure;
    interstage (J-2X nozzle inside); first stage from ``fs_fwd`` to the nozzle exit at
    94 m, its grain from ``fs_fwd + grain_fwd_gap`` to ``94 - grain_aft_gap``.
    """

    les: float = 6.5
    cm_overlap: float = 3.2
    sm: float = 3.0
    sa: float = 1.0
    fwd_skirt: float = 0.5
    fwd_skirt_mass: float = 5000.0   # forward skirt, avionics, forward dome structure
    lh2_tank: float = 19.8
    lox_tank: float = 4.2
    aft_skirt: float = 1.0
    fs_fwd: float = 41.6
    grain_fwd_gap: float = 3.6
    grain_aft_gap: float = 2.0


CM_LENGTH_M = 3.3                  # [E] Orion crew-module height
J2X_LENGTH_M = 3.0                 # [E] engine modelled as a solid from gimbal to 3 m aft
J2X_RADIUS_M = 1.0                 # [E]
FS_NOZZLE = dict(mass_kg=7000.0, cg_from_gimbal_m=2.0, inertia_about_gimbal_kgm2=35000.0)  # [E]
FS_GIMBAL_ABOVE_EXIT_M = 3.5       # [E] flex-bearing pivot above the nozzle exit

# Bounds of the layout fit (plausible ranges [E]) and the nominal layout it is pulled
# toward (weakly) so the under-determined fit has a unique, physical answer.
FIT_BOUNDS = {
    "les": (6.5, 10.0), "cm_overlap": (2.5, 3.3), "sm": (3.0, 4.5), "sa": (1.0, 2.5),
    "fwd_skirt": (0.5, 2.0), "fwd_skirt_mass": (0.0, 5000.0), "lh2_tank": (13.2, 20.0),
    "lox_tank": (4.2, 7.0), "aft_skirt": (1.0, 3.0), "fs_fwd": (40.0, 48.0),
    "grain_fwd_gap": (0.5, 4.0), "grain_aft_gap": (2.0, 5.0),
}
FIT_NOMINAL = Layout(les=9.0, cm_overlap=3.0, sm=4.0, sa=2.0, fwd_skirt=1.5, fwd_skirt_mass=2000.0,
                     lh2_tank=14.0, lox_tank=5.0, aft_skirt=2.0, fs_fwd=44.0, grain_fwd_gap=2.0,
                     grain_aft_gap=3.0)

# The data file's [D] figures the layout is fitted to: (state, quantity, value)
TARGETS = (
    ("liftoff", "cg_above_exit_m", 33.9), ("liftoff", "iyy_kgm2", 4.2e8),
    ("fs_burnout", "cg_above_exit_m", 54.9), ("fs_burnout", "iyy_kgm2", 1.4e8),
    ("us_ignition", "iyy_kgm2", 2.1e7), ("us_burnout", "iyy_kgm2", 3.7e6),
)

LAYOUT = Layout()                  # frozen, rounded result of fit_layout()


@dataclass(frozen=True)
class Segment:
    """One uniform axisymmetric segment: a tube of outer radius ``r_out`` and inner
    radius ``r_in`` (0: solid cylinder; equal: thin shell) over ``[x_fwd, x_aft]``."""

    name: str
    mass_kg: float
    x_fwd_m: float
    x_aft_m: float
    r_out_m: float
    r_in_m: float = 0.0


def stations(lay: Layout) -> dict[str, float]:
    """Named stations (m aft of the nose tip) of a layout."""
    s: dict[str, float] = {"les_fwd": 0.0, "les_aft": lay.les}
    s["cm_fwd"] = lay.les - lay.cm_overlap
    s["sm_fwd"] = s["cm_fwd"] + CM_LENGTH_M
    s["sa_fwd"] = s["sm_fwd"] + lay.sm
    s["us_fwd"] = s["sa_fwd"] + lay.sa
    s["lh2_fwd"] = s["us_fwd"] + lay.fwd_skirt
    s["lox_fwd"] = s["lh2_fwd"] + lay.lh2_tank
    s["lox_aft"] = s["lox_fwd"] + lay.lox_tank
    s["us_aft"] = s["lox_aft"] + lay.aft_skirt
    s["j2x_gimbal"] = s["lox_aft"]               # engine top at the LOX tank's aft dome
    s["fs_fwd"] = lay.fs_fwd
    s["grain_fwd"] = lay.fs_fwd + lay.grain_fwd_gap
    s["grain_aft"] = LENGTH_M - lay.grain_aft_gap
    s["fs_gimbal"] = LENGTH_M - FS_GIMBAL_ABOVE_EXIT_M
    s["nozzle_exit"] = LENGTH_M
    return s


def dry_segments(lay: Layout) -> dict[str, list[Segment]]:
    """Inert segments grouped by what leaves together: ``les``, ``upper`` (Orion CM/SM/SA
    and the upper stage's dry mass), ``first_stage`` (inert + interstage)."""
    s = stations(lay)
    r_us = US_DIAMETER_M / 2.0
    r_fs = FS_DIAMETER_M / 2.0
    tank_structure = M_US_DRY - M_J2X - lay.fwd_skirt_mass
    return {
        "les": [Segment("launch_abort_system", M_LES, 0.0, s["les_aft"], 0.8)],
        "upper": [
            Segment("crew_module", M_CM, s["cm_fwd"], s["sm_fwd"], 2.0),
            Segment("service_module", M_SM, s["sm_fwd"], s["sa_fwd"], 2.5),
            Segment("spacecraft_adapter", M_SA, s["sa_fwd"], s["us_fwd"], r_us, r_us),
            Segment("us_forward_skirt", lay.fwd_skirt_mass, s["us_fwd"], s["lh2_fwd"], r_us, r_us),
            Segment("us_tank_structure", tank_structure, s["lh2_fwd"], s["lox_aft"], r_us, r_us),
            Segment("j2x_engine", M_J2X, s["j2x_gimbal"], s["j2x_gimbal"] + J2X_LENGTH_M, J2X_RADIUS_M),
            Segment("roll_control_hydrazine", M_HYDRAZINE, s["us_aft"] - 1.0, s["us_aft"], 2.5),
        ],
        "first_stage": [
            Segment("interstage", M_INTERSTAGE, s["us_aft"], s["fs_fwd"], r_us * 0.85, r_us * 0.85),
            Segment("first_stage_inert", M_FS_INERT, s["fs_fwd"], LENGTH_M, r_fs, r_fs),
        ],
    }


def propellant_segments(lay: Layout, fs_kg: float, lox_kg: float, lh2_kg: float) -> list[Segment]:
    """Propellant segments for the given loads (kg)."""
    s = stations(lay)
    r_us = US_DIAMETER_M / 2.0
    segs = []
    if fs_kg > 0.0:
        length = s["grain_aft"] - s["grain_fwd"]
        r_out = FS_DIAMETER_M / 2.0 - 0.05             # [E] case wall + insulation
        area = fs_kg / (RHO_GRAIN * length)            # annulus area of the remaining grain
        r_in = float(np.sqrt(max(r_out**2 - area / np.pi, 0.0)))
        segs.append(Segment("first_stage_grain", fs_kg, s["grain_fwd"], s["grain_aft"], r_out, r_in))
    for name, m, full, fwd, aft in (("lh2", lh2_kg, M_LH2, s["lh2_fwd"], s["lox_fwd"]),
                                    ("lox", lox_kg, M_LOX, s["lox_fwd"], s["lox_aft"])):
        if m > 0.0:  # settled at the aft end, height proportional to the mass remaining
            segs.append(Segment(name, m, aft - (aft - fwd) * m / full, aft, r_us))
    return segs


def mass_properties(segs: list[Segment]) -> tuple[float, float, np.ndarray]:
    """Mass (kg), CG station (m, structure x) and inertia about the CG in body axes
    ``[Ixx, Iyy, Izz, Ixy, Ixz, Iyz]`` (kg m^2) of a set of coaxial segments."""
    m = np.array([g.mass_kg for g in segs])
    x0 = np.array([g.x_fwd_m for g in segs])
    x1 = np.array([g.x_aft_m for g in segs])
    ro = np.array([g.r_out_m for g in segs])
    ri = np.array([g.r_in_m for g in segs])
    length, centre = x1 - x0, 0.5 * (x0 + x1)
    total = float(m.sum())
    cg = float(np.dot(m, centre) / total)
    r2 = ro**2 + ri**2
    ixx = float(np.dot(m, r2 / 2.0))
    itr = float(np.dot(m, r2 / 4.0 + length**2 / 12.0 + (centre - cg) ** 2))
    return total, cg, np.array([ixx, itr, itr, 0.0, 0.0, 0.0])


def upper_stage_loads(remaining_kg: float) -> tuple[float, float]:
    """LOX and LH2 left (kg) when ``remaining_kg`` of the total load is left, burning at
    the mixture ratio from the loaded masses until the limiting one is exhausted, then
    the other alone (the tables' drain order)."""
    used = M_LOX + M_LH2 - remaining_kg
    lox = M_LOX - used * MIXTURE_RATIO / (1.0 + MIXTURE_RATIO)
    lh2 = M_LH2 - used / (1.0 + MIXTURE_RATIO)
    if lox < 0.0:
        return 0.0, max(remaining_kg, 0.0)
    if lh2 < 0.0:
        return max(remaining_kg, 0.0), 0.0
    return lox, lh2


def configuration_segments(config: str, propellant_kg: float, lay: Layout = LAYOUT) -> list[Segment]:
    """All segments of ``config`` (stack, upper_les, upper) with ``propellant_kg`` of its
    burning stage's propellant remaining."""
    dry = dry_segments(lay)
    if config == "stack":
        return dry["les"] + dry["upper"] + dry["first_stage"] + propellant_segments(lay, propellant_kg, M_LOX, M_LH2)
    lox, lh2 = upper_stage_loads(propellant_kg)
    les = dry["les"] if config == "upper_les" else []
    return les + dry["upper"] + propellant_segments(lay, 0.0, lox, lh2)


def key_states(lay: Layout = LAYOUT) -> dict[str, tuple[float, float, np.ndarray]]:
    """Mass properties at the data file's four reference states."""
    return {
        "liftoff": mass_properties(configuration_segments("stack", M_FS_PROP, lay)),
        "fs_burnout": mass_properties(configuration_segments("stack", 0.0, lay)),
        "us_ignition": mass_properties(configuration_segments("upper_les", M_LOX + M_LH2, lay)),
        "us_burnout": mass_properties(configuration_segments("upper", 0.0, lay)),
    }


def _residuals(lay: Layout) -> np.ndarray:
    states = key_states(lay)
    out = []
    for state, qty, value in TARGETS:
        m, cg, inertia = states[state]
        got = LENGTH_M - cg if qty == "cg_above_exit_m" else inertia[1]
        out.append(got / value - 1.0)
    return np.array(out)


def fit_layout(regularization: float = 0.002) -> Layout:
    """Bounded least-squares fit of the free layout lengths to :data:`TARGETS`.

    Residuals are relative errors plus ``regularization`` times the relative distance
    from :data:`FIT_NOMINAL`, which makes the under-determined problem well posed.
    """
    names = list(FIT_BOUNDS)
    lo = np.array([FIT_BOUNDS[n][0] for n in names])
    hi = np.array([FIT_BOUNDS[n][1] for n in names])
    nominal = np.array([getattr(FIT_NOMINAL, n) for n in names])
    scale = hi - lo

    def fun(p: np.ndarray) -> np.ndarray:
        lay = Layout(**dict(zip(names, p)))
        return np.concatenate([_residuals(lay), regularization * (p - nominal) / scale])

    sol = least_squares(fun, np.clip(nominal, lo, hi), bounds=(lo, hi), x_scale=scale)
    return Layout(**dict(zip(names, sol.x)))


# ================================================================= tabulated models
def mass_table(config: str, lay: Layout = LAYOUT) -> np.ndarray:
    """Rows ``propellant_remaining_kg, mass_kg, cg_x_m, cg_y_m, cg_z_m, ixx..iyz`` in
    ascending propellant. Stack: first-stage propellant; upper configurations: LOX + LH2."""
    if config == "stack":
        props = np.linspace(0.0, M_FS_PROP, 33)
    else:
        # propellant left (all of the other tank) when the limiting one runs out
        residual = max(M_LH2 - M_LOX / MIXTURE_RATIO, M_LOX - MIXTURE_RATIO * M_LH2)
        props = np.linspace(0.0, M_LOX + M_LH2, 28)
        if residual > 1.0:  # off-ratio loads: a row where the limiting propellant runs out
            props = np.union1d(props, [residual])
    rows = []
    for p in props:
        m, cg, inertia = mass_properties(configuration_segments(config, float(p), lay))
        rows.append([p, m, cg, 0.0, 0.0, *inertia])
    return np.array(rows)


#: The stages whose own mass tables the generator writes (``mass_<stage>.csv``).
STAGES = ("first_stage", "upper_stage")


def stage_mass_table(stage: str, lay: Layout = LAYOUT) -> np.ndarray:
    """A stage's own mass properties (the ``mass_table`` of ``vehicle.stages.<stage>``, for
    configurations composed from their parts), rows as :func:`mass_table`'s against the
    stage's own propellant, at the propellant grid of the configuration it burns in."""
    dry = dry_segments(lay)
    rows = []
    for p in mass_table("stack" if stage == "first_stage" else "upper", lay)[:, 0]:
        if stage == "first_stage":
            segs = dry["first_stage"] + propellant_segments(lay, float(p), 0.0, 0.0)
        else:
            segs = dry["upper"] + propellant_segments(lay, 0.0, *upper_stage_loads(float(p)))
        m, cg, inertia = mass_properties(segs)
        rows.append([p, m, cg, 0.0, 0.0, *inertia])
    return np.array(rows)


def les_mass_properties(lay: Layout = LAYOUT) -> tuple[float, float, np.ndarray]:
    """The launch abort system's mass (kg), CG station (m) and inertia about it (body
    axes, ``[Ixx, Iyy, Izz, Ixy, Ixz, Iyz]`` kg m^2): the item's ``cg_m`` and ``inertia_kgm2``."""
    return mass_properties(dry_segments(lay)["les"])


def config_geometry(config: str, lay: Layout = LAYOUT) -> tuple[float, float]:
    """Nose station and length (m) of a configuration; its MRP is at the nose."""
    s = stations(lay)
    if config == "stack":
        return 0.0, LENGTH_M
    if config == "upper_les":
        return 0.0, s["us_aft"]
    return s["cm_fwd"], s["us_aft"] - s["cm_fwd"]


def aero_coefficients(mach: np.ndarray, alpha_rad: np.ndarray, beta_rad: np.ndarray, x_nose_m: float,
                      length_m: float, x_mrp_m: float) -> np.ndarray:
    """Body-axis coefficients ``(6, ...)`` = CA, CY, CN, Cl, Cm, Cn (moments about the
    MRP at structure station ``x_mrp_m``) of the slender-body stand-in; inputs broadcast."""
    mach, alpha, beta = np.broadcast_arrays(mach, alpha_rad, beta_rad)
    ca = np.interp(mach, CA_MACH, CA_TABLE)
    cna = np.interp(mach, CNA_MACH, CNA_TABLE)
    x_cp = x_nose_m + length_m * np.interp(mach, XCP_MACH, XCP_FRACTION)
    # C_Nt = CNa sin(alpha_t) against the crossflow (v, w)/V = (sin b, sin a cos b)
    cn = cna * np.sin(alpha) * np.cos(beta)
    cy = -cna * np.sin(beta)
    arm = (x_cp - x_mrp_m) / REF_LENGTH_M
    return np.stack([ca, cy, cn, np.zeros_like(ca), -cn * arm, -cy * arm])


def aero_table(config: str, lay: Layout = LAYOUT) -> np.ndarray:
    """Long-format rows ``mach, alpha_deg, beta_deg, CA, CY, CN, Cl, Cm, Cn`` on the full
    grid (Mach slowest, beta fastest)."""
    angles = STACK_ANGLES_DEG if config == "stack" else UPPER_ANGLES_DEG
    m, a, b = np.meshgrid(CA_MACH, angles, angles, indexing="ij")
    nose, length = config_geometry(config, lay)
    c = aero_coefficients(m, np.radians(a), np.radians(b), nose, length, nose)
    return np.column_stack([m.ravel(), a.ravel(), b.ravel(), c.reshape(6, -1).T])


def separation_time() -> float:
    """First time after the peak when the thrust falls below the separation fraction (s);
    the same rule as ``savant_cli.sim.build.predicted_separation_time``."""
    t = np.linspace(FS_THRUST_TIME_S[0], FS_THRUST_TIME_S[-1], 200001)
    f = np.interp(t, FS_THRUST_TIME_S, FS_THRUST_VAC_MN)
    ipk = int(np.argmax(f))
    below = np.nonzero(f[ipk:] < SEPARATION_THRUST_FRACTION * f[ipk])[0]
    return float(t[ipk + below[0]])


def j2x_startup() -> np.ndarray:
    """J-2X start transient [E]: rows ``time_s`` since the ignition command, thrust
    fraction; a smoothstep from 0.3 s to 2.8 s."""
    t = np.round(np.arange(0.0, 3.01, 0.1), 10)
    s = np.clip((t - 0.3) / 2.5, 0.0, 1.0)
    return np.column_stack([t, s * s * (3.0 - 2.0 * s)])


def point_mass_ascent(t_end: float = ASCENT_END_S) -> tuple[np.ndarray, ...]:
    """Two-dimensional point-mass ascent over a spherical non-rotating Earth.

    Vertical rise, fixed pitch kick, gravity turn; the first stage drops at the
    separation time, the J-2X starts after the coast with its start transient.

    Parameters
    ----------
    t_end : float
        Final time from liftoff, s.

    Returns
    -------
    tuple of numpy.ndarray
        Times (s), altitude (m), air speed (m/s), Mach, dynamic pressure (Pa) and
        configuration index (0 stack, 1 upper stage with LES, 2 without) on a 0.5 s grid
        plus the separation instant. Integration state: radius, range angle, radial and
        tangential velocity, mass.
    """
    from savant_cli.models.atmosphere import us76

    t_sep = separation_time()
    t_ign = t_sep + IGNITION_DELAY_S
    t_les = t_ign + LES_JETTISON_DELAY_S
    start = j2x_startup()
    f_tab = FS_THRUST_VAC_MN * 1e6
    kick = np.radians(90.0 - ASCENT_KICK_DEG)

    def rhs(t: float, y: np.ndarray) -> list[float]:
        r, _, vr, vt, m = y
        _, p, rho, a = us76(r - WGS84_A)
        v = float(np.hypot(vr, vt))
        q = 0.5 * rho * v * v
        mach = v / a
        if t < t_sep:
            fv = float(np.interp(t, FS_THRUST_TIME_S, f_tab))
            thrust, mdot = max(fv - FS_EXIT_AREA_M2 * p, 0.0), fv / (G0 * FS_ISP_VAC_S)
            a_base = FS_BASE_AREA_M2
        else:
            fv = US_THRUST_VAC_N * float(np.interp(t - t_ign, start[:, 0], start[:, 1], left=0.0))
            thrust, mdot = max(fv - US_EXIT_AREA_M2 * p, 0.0), fv / (G0 * US_ISP_VAC_S)
            a_base = REF_AREA_M2 - US_EXIT_AREA_M2
        drag = q * REF_AREA_M2 * float(np.interp(mach, CA_MACH, CA_TABLE)) \
            - float(np.interp(mach, CPB_MACH, CPB_TABLE)) * q * a_base
        if t < ASCENT_VERTICAL_S:
            ur, ut = 1.0, 0.0
        elif t < ASCENT_VERTICAL_S + ASCENT_KICK_HOLD_S:
            ur, ut = np.sin(kick), np.cos(kick)
        else:
            ur, ut = vr / v, vt / v
        dr, dt_ = (vr / v, vt / v) if v > 1.0 else (1.0, 0.0)
        ar = (thrust * ur - drag * dr) / m - MU_EARTH / r**2 + vt * vt / r
        at = (thrust * ut - drag * dt_) / m - vr * vt / r
        if r - WGS84_A < 1.0 and ar < 0.0:           # held on the pad until thrust > weight
            ar = 0.0
        return [vr, vt / r, ar, at, -mdot]

    m0 = mass_properties(configuration_segments("stack", M_FS_PROP))[0]
    sol1 = solve_ivp(rhs, (0.0, t_sep), [WGS84_A, 0.0, 0.0, 0.0, m0], max_step=0.5, rtol=1e-8,
                     atol=1e-6, dense_output=True)
    y_sep = sol1.y[:, -1].copy()
    y_sep[4] = mass_properties(configuration_segments("upper_les", M_LOX + M_LH2))[0]
    sol2 = solve_ivp(rhs, (t_sep, t_end), y_sep, max_step=0.5, rtol=1e-8, atol=1e-6, dense_output=True)
    t = np.union1d(np.arange(0.0, t_end + 1e-9, 0.5), [t_sep])
    y = np.where(t <= t_sep, sol1.sol(np.minimum(t, t_sep)), sol2.sol(np.maximum(t, t_sep)))
    alt = y[0] - WGS84_A
    atm = np.array([us76(h) for h in alt])
    v = np.hypot(y[2], y[3])
    config = np.where(t < t_sep, 0, np.where(t < t_les, 1, 2))
    return t, alt, v, v / atm[:, 3], 0.5 * atm[:, 2] * v * v, config


def base_force_tables() -> dict[str, np.ndarray]:
    """Rows ``time_s, base_force_N`` (time from liftoff) per configuration.

    Each table covers its configuration's flight window on the ascent (stack: liftoff to
    separation; upper stage with LES: separation to LES jettison; without: jettison to
    :data:`ASCENT_END_S`, where q is a few tens of Pa) every 2 s and at the window ends,
    then a final zero row at 1000 s.
    """
    t, _, _, mach, q, config = point_mass_ascent()
    t_sep = separation_time()
    t_les = t_sep + IGNITION_DELAY_S + LES_JETTISON_DELAY_S
    cpb = np.interp(mach, CPB_MACH, CPB_TABLE)
    a_us = REF_AREA_M2 - US_EXIT_AREA_M2
    spec = {"stack": (0.0, t_sep, FS_BASE_AREA_M2), "upper_les": (t_sep, t_les, a_us),
            "upper": (t_les, ASCENT_END_S, a_us)}
    out = {}
    for name, (t0, t1, area) in spec.items():
        tt = np.union1d(np.arange(np.ceil(t0 / 2.0) * 2.0, t1, 2.0), [t0, t1])
        f = np.interp(tt, t, cpb * q * area)
        out[name] = np.column_stack([np.append(tt, 1000.0), np.append(f, 0.0)])
    return out


# ========================================================================== writing
def write_csv(path: Path, header: list[str], rows: np.ndarray, comments: list[str], fmt: str = "%.10g") -> None:
    """``# `` comment lines, a header row, comma-separated rows; written atomically."""
    from savant_cli.io.atomic import atomic_path

    with atomic_path(path) as tmp:
        with open(tmp, "w") as f:
            for c in comments:
                f.write(f"# {c}\n")
            f.write(",".join(header) + "\n")
            np.savetxt(f, rows, delimiter=",", fmt=fmt)


MASS_HEADER = ["propellant_remaining_kg", "mass_kg", "cg_x_m", "cg_y_m", "cg_z_m", "ixx_kgm2", "iyy_kgm2",
               "izz_kgm2", "ixy_kgm2", "ixz_kgm2", "iyz_kgm2"]
AERO_HEADER = ["mach", "alpha_deg", "beta_deg", "CA", "CY", "CN", "Cl", "Cm", "Cn"]
CONFIGS = ("stack", "upper_les", "upper")


def derived_figures(lay: Layout = LAYOUT) -> dict[str, float]:
    """Scalars of ``conf/vehicle/ares_i.yaml`` that follow from the layout [D]."""
    s = stations(lay)
    j2x_cg = J2X_LENGTH_M / 2.0
    return {
        "first_stage.nozzle_exit_area_m2": FS_EXIT_AREA_M2,
        "first_stage.jettison_mass_kg": M_FS_INERT + M_INTERSTAGE,
        "first_stage.gimbal_x_m": s["fs_gimbal"],
        "upper_stage.gimbal_x_m": s["j2x_gimbal"],
        "upper_stage.engine.mass_kg": M_J2X,
        "upper_stage.engine.cg_from_gimbal_m": j2x_cg,
        "upper_stage.engine.inertia_about_gimbal_kgm2":
            M_J2X * (J2X_RADIUS_M**2 / 4.0 + J2X_LENGTH_M**2 / 12.0 + j2x_cg**2),
        "rcs.location_x_m": s["us_aft"] - 0.5,
        "sensors.imu_x_m": 0.5 * (s["us_fwd"] + s["lh2_fwd"]),
        # aft skirt, behind the first bending mode's antinode: its slope there has the
        # opposite sign to the upper stage's, so blending the two gyros can null the mode
        "sensors.rate_gyro_first_stage_x_m": s["fs_gimbal"] - 1.5,
        "configurations.upper.moment_reference_x_m": s["cm_fwd"],
        "items.les.cg_x_m": les_mass_properties(lay)[1],
        **{f"items.les.{k}_kgm2": v for k, v in zip(("ixx", "iyy"), les_mass_properties(lay)[2][:2])},
        "separation_time_s": separation_time(),
    }


def write_all(out: Path, lay: Layout = LAYOUT) -> None:
    """Write every CSV of the vehicle into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    src = "generated by `python -m savant_cli.datagen.ares_i_tables`; sources and marks in README.md"
    bases = base_force_tables()
    for config in CONFIGS:
        write_csv(out / f"mass_{config}.csv", MASS_HEADER, mass_table(config, lay),
               [src, f"{config}: [D] uniform-segment model; propellant_remaining of the burning stage, "
                     "CG in the structure frame (x aft of the nose tip), inertia about the CG in body axes"])
        nose, length = config_geometry(config, lay)
        write_csv(out / f"aero_{config}.csv", AERO_HEADER, aero_table(config, lay),
               [src, f"{config}: [E] slender-body stand-in (Atlas SLV-3D CA [P]); body-axis coefficients, "
                     f"moments about the MRP at station {nose:g} m (nose), l_ref {REF_LENGTH_M:g} m, "
                     f"S_ref {REF_AREA_M2:.2f} m2"], fmt="%.10g")
        write_csv(out / f"base_force_{config}.csv", ["time_s", "base_force_N"], bases[config],
               [src, f"{config}: [E] base force along body X (negative = drag) vs time from liftoff, "
                     "C_pb(M) q A_base along a 2-D point-mass ascent"], fmt="%.6g")
    for stage in STAGES:
        write_csv(out / f"mass_{stage}.csv", MASS_HEADER, stage_mass_table(stage, lay),
                  [src, f"{stage}: [D] the stage's own mass properties against its own propellant (uniform-segment "
                        "model), for configurations composed from their parts; CG in the structure frame, inertia "
                        "about the stage's CG in body axes"])
    write_csv(out / "first_stage_thrust.csv", ["time_s", "thrust_vac_N"],
           np.column_stack([FS_THRUST_TIME_S, FS_THRUST_VAC_MN * 1e6]),
           [src, "[D] first-stage vacuum thrust vs time from liftoff (data file curve, MN -> N)"])
    write_csv(out / "j2x_startup.csv", ["time_s", "thrust_fraction"], j2x_startup(),
           [src, "[E] J-2X start transient: fraction of rated vacuum thrust vs time since the ignition command"],
           fmt="%.6g")
    alt = np.array([0.0, 20000.0, 50000.0, 100000.0, 200000.0, 1000000.0])
    write_csv(out / "rcs_thrust.csv", ["altitude_m", "thrust_vac_N"],
           np.column_stack([alt, np.full_like(alt, RCS_THRUST_VAC_N)]),
           [src, "[E] roll-control jet vacuum thrust vs altitude (per jet); the simulation subtracts p * A_exit"])


def report(lay: Layout = LAYOUT) -> str:
    """Reference states vs the data file's figures, and the derived YAML scalars."""
    lines = []
    public = {"liftoff": (920e3, 33.9, 4.2e8), "fs_burnout": (272e3, 54.9, 1.4e8),
              "us_ignition": (181e3, None, 2.1e7), "us_burnout": (35.6e3, None, 3.7e6)}
    for name, (m, cg, inertia) in key_states(lay).items():
        pm, pcg, pi = public[name]
        cg_txt = f"CG {LENGTH_M - cg:5.1f} m above exit" + (f" ({pcg})" if pcg else "")
        lines.append(f"{name:12s} {m / 1e3:7.1f} t ({pm / 1e3:g})  {cg_txt:32s} "
                     f"Iyy {inertia[1]:.3g} ({pi:.2g}) kg m2  [{100 * (inertia[1] / pi - 1):+.1f} %]")
    lines += [f"{k} = {v:.6g}" for k, v in derived_figures(lay).items()]
    lines.append("stations: " + ", ".join(f"{k} {v:.2f}" for k, v in stations(lay).items()))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    """Command line: write the tables (default) or print a fresh layout fit (``--fit``)."""
    ap = argparse.ArgumentParser(description="Generate the ares_i vehicle tables from public figures.")
    ap.add_argument("--out", type=Path, default=None, help="output folder (default: the shipped conf/vehicle/ares_i)")
    ap.add_argument("--fit", action="store_true", help="refit the layout to the data file's figures and print it")
    args = ap.parse_args(argv)
    if args.fit:
        lay = fit_layout()
        print({k: round(v, 3) for k, v in asdict(lay).items()})
        print(report(lay))
        return
    from savant_cli.paths import shipped_config_dir

    out = args.out or shipped_config_dir() / "vehicle" / "ares_i"
    write_all(out)
    print(report())
    print(f"wrote {out}")


__all__ = ["Layout", "LAYOUT", "Segment", "fit_layout", "mass_table", "aero_table", "aero_coefficients",
           "base_force_tables", "point_mass_ascent", "write_all", "main"]

if __name__ == "__main__":
    main()
