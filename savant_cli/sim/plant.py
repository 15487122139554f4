"""The compiled continuous plant: the composition of the physical models.

``derivative`` is the one function the time simulation integrates and the linearization
differentiates. It reads top to bottom: environment → mass → forces and moments →
equations of motion → auxiliary states, each step one call into the model that owns it
(``savant_cli/models/``). Each model then writes its own diagnostics into ``aux``
(its ``write_diagnostics``, beside the fields it declares), so the logger reports exactly
what the dynamics used.

The tables reach the compiled code packed into one flat array (:func:`pack_tables`):
numba increments and decrements a reference count for every array argument of every
call, and two dozen arrays made those atomic operations a quarter of the run time.
Python code uses :class:`PlantTables`, the same arrays by name.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba import njit

from savant_cli.models import (
    actuator, aero, atmosphere, blocks, boosters, cluster, earth, flex, gravity, mass as mass_model, propulsion,
    quaternion as qt, rcs, rigid_body, slosh, throttle, twd, winds
)
from savant_cli.models.configurations import ENGINE_FIRST
from savant_cli.models.layout import (
    U_CONFIG, U_DPC, U_DYC, U_ENGINE, U_FS_T_CUT, U_GUST, U_PY_JETS, U_RCS, U_ROLL, U_T_CUT, U_T_IGN, U_THROTTLE,
    U_US_THROTTLE, Q, R, V, W
)

#: Tabular data of the plant by name (SI, contiguous arrays); the fields are the tables
#: the models declare, in field-number order (``blocks.TABLES``).
PlantTables = namedtuple("PlantTables", blocks.TABLES.names())
N_AUX = blocks.DIAGNOSTICS.size


def pack_tables(tb: PlantTables) -> np.ndarray:
    """One flat float64 array holding every table of ``tb`` (see :class:`blocks.Tables`)."""
    return blocks.pack(list(tb))


@njit(cache=True, error_model="numpy")
def derivative(t: float, x: np.ndarray, u: np.ndarray, p: np.ndarray, tb: np.ndarray,
               aux: np.ndarray, xd: np.ndarray) -> None:
    """Time derivative of the continuous state into ``xd`` and every diagnostic into
    ``aux`` (see :func:`compose` for the arguments)."""
    compose(t, x, u, p, tb, aux, xd, np.bool_(True))  # a run-time flag: a literal compiles compose per value


@njit(cache=True, error_model="numpy")
def derivative_state(t: float, x: np.ndarray, u: np.ndarray, p: np.ndarray, tb: np.ndarray,
                     aux: np.ndarray, xd: np.ndarray) -> None:
    """:func:`derivative` without the diagnostics only a log reads (latitude, longitude,
    Earth-relative speed): ``xd`` is bit for bit the same; of ``aux`` only the altitude
    (the engine's ground check) and the sloshing tanks' entries the slosh model hands
    from the mass properties to the loads are written."""
    compose(t, x, u, p, tb, aux, xd, np.bool_(False))


@njit(cache=True, error_model="numpy", inline="always")
def mass_state(x: np.ndarray, p: np.ndarray, tb: np.ndarray, config: int, aux: np.ndarray):
    """Mass properties of ``config`` in state ``x``.

    Returns
    -------
    tuple
        ``(propellant kg, (mass kg, CG x, y, z m) of the whole vehicle, (mass, CG x, y, z,
        Ixx, Iyy, Izz, Ixy, Ixz, Iyz) of the rigid part)``: CGs in structure axes, inertia
        about the rigid part's CG in body axes (tensor elements); the rigid part leaves the
        slosh masses out when slosh is on (else it is the whole vehicle), and each
        sloshing tank's mode at its level goes into ``aux``
        (:func:`~savant_cli.models.slosh.tank_modes`). In the liftoff configuration of a
        vehicle with strap-on boosters each booster's full-load row is exchanged for its
        row at its own propellant (:func:`~savant_cli.models.boosters.exchange`).
    """
    prop = propulsion.propellant_remaining(x, p, config)
    mass, cgx, cgy, cgz, ixx, iyy, izz, ixy, ixz, iyz = mass_model.mass_properties(tb, config, prop)
    if config == 0 and p[boosters.P_N_BOOSTERS] > 0.0:  # the boosters burn their own propellant
        mass, cgx, cgy, cgz, ixx, iyy, izz, ixy, ixz, iyz = boosters.exchange(
            x, p, tb, mass, cgx, cgy, cgz, ixx, iyy, izz, ixy, ixz, iyz)
    whole = (mass, cgx, cgy, cgz)
    if slosh.tank_count(p) > 0:  # the rigid part leaves the slosh masses out
        slosh.tank_modes(x, p, tb, config, aux)
        mass, cgx, cgy, cgz, ixx, iyy, izz, ixy, ixz, iyz = slosh.rigid_part(
            p, aux, mass, cgx, cgy, cgz, ixx, iyy, izz, ixy, ixz, iyz)
    return prop, whole, (mass, cgx, cgy, cgz, ixx, iyy, izz, ixy, ixz, iyz)


@njit(cache=True, error_model="numpy")
def reference_cg(x: np.ndarray, p: np.ndarray, tb: np.ndarray, config: int) -> tuple[float, float, float]:
    """The state's reference point in configuration ``config``: the CG (structure axes,
    m) of the rigid part (:func:`mass_state`)."""
    rigid = mass_state(x, p, tb, config, np.zeros(N_AUX))[2]
    return rigid[1], rigid[2], rigid[3]


@njit(cache=True, error_model="numpy")
def compose(t: float, x: np.ndarray, u: np.ndarray, p: np.ndarray, tb: np.ndarray,
            aux: np.ndarray, xd: np.ndarray, diagnostics: bool) -> None:
    """Time derivative of the continuous state, written into ``xd``.

    Parameters
    ----------
    t : float
        Mission time, s (0 at liftoff).
    x : ndarray (n_state,)
        Continuous state (see :mod:`savant_cli.models.layout`).
    u : ndarray (N_INPUT,)
        Held inputs from the discrete flight software and the event logic.
    p : ndarray (N_PARAM,)
        Scalar parameters.
    tb : ndarray
        Tabular data packed by :func:`pack_tables`.
    aux : ndarray (N_AUX,)
        Filled with diagnostics of this evaluation.
    xd : ndarray (n_state,)
        Output: the state derivative.
    diagnostics : bool
        Fill every entry of ``aux`` (False: only the altitude).

    Notes
    -----
    The models are compiled inline and pass scalars: this function runs four times per
    plant step, and heap temporaries would dominate its cost. It is itself compiled once,
    as its own function, not inlined into :func:`derivative` and
    :func:`derivative_state`: inlined, the whole plant compiled twice on a cold cache
    (about half the first run's compile time), for a run time a few percent shorter.
    """
    config = int(u[U_CONFIG])
    engine = int(u[U_ENGINE])
    rx, ry, rz = x[R], x[R + 1], x[R + 2]
    vx, vy, vz = x[V], x[V + 1], x[V + 2]
    q0, q1, q2, q3 = x[Q], x[Q + 1], x[Q + 2], x[Q + 3]
    wx, wy, wz = x[W], x[W + 1], x[W + 2]
    m00, m01, m02, m10, m11, m12, m20, m21, m22 = qt.dcm_xyz(q0, q1, q2, q3)  # body → ECI

    # ------------------------------------------------------------ environment
    alt, sin_lat, cos_lat, sin_lon, cos_lon, cos_et, sin_et, x_ecef, y_ecef, lat_num, lat_den = earth.geodetic_of_eci(
        t, rx, ry, rz, p)
    temp, pres, rho, sos = atmosphere.air_at(alt, tb)
    gx, gy, gz = gravity.gravity_at(rx, ry, rz, p, p[earth.P_RE])
    ex, ey, ez = earth.earth_relative_velocity(rx, ry, vx, vy, vz, p)
    air_x, air_y, air_z, wind_n, wind_e, wind_d = winds.air_relative_velocity(
        t, alt, sin_lat, cos_lat, sin_lon, cos_lon, cos_et, sin_et, ex, ey, ez, tb, p)
    # air-relative velocity in body axes (Rᵀ v), less the gust the air moves with
    ub = m00 * air_x + m10 * air_y + m20 * air_z - u[U_GUST]
    vb = m01 * air_x + m11 * air_y + m21 * air_z - u[U_GUST + 1]
    wb = m02 * air_x + m12 * air_y + m22 * air_z - u[U_GUST + 2]
    vair, alpha, beta, mach, qbar = aero.air_data(ub, vb, wb, rho, sos)

    # ------------------------------------------------------- mass properties
    prop, whole, rigid = mass_state(x, p, tb, config, aux)
    mass_total, cgx_t, cgy_t, cgz_t = whole
    mass, cgx, cgy, cgz, ixx, iyy, izz, ixy, ixz, iyz = rigid

    # ------------------------------------------------- forces and moments
    fax, fay, faz, max_, may, maz = aero.aero_loads(tb, p, config, t, mach, alpha, beta, qbar, cgx, cgy, cgz)
    ddp, ddy = cluster.gimbal_rates(x, p, tb, engine, config, u[U_ROLL], u[U_DPC], u[U_DYC], xd)
    rcs_pos_rate, rcs_neg_rate = rcs.jet_rates(x, p, u[U_RCS])
    jets = int(p[rcs.P_STATE_OFFSET])
    xd[jets] = rcs_pos_rate
    xd[jets + 1] = rcs_neg_rate
    gimbal_pt = flex.PT_GIMBAL_FS if engine == ENGINE_FIRST else flex.PT_GIMBAL_US
    tgx, tgy, tgz = flex.rotation_at(x, config, p, tb, gimbal_pt, False)  # follower thrust
    setting = throttle.held(u[U_THROTTLE], p)
    us_setting = throttle.held_upper(u[U_US_THROTTLE], p)
    thrust, mdot_fs, mdot_us, thrust_vac = propulsion.thrust_and_flow(x, tb, p, engine, t, u[U_T_IGN], u[U_T_CUT],
                                                                      setting, u[U_FS_T_CUT], pres, us_setting)
    dp, dy, bias_p, bias_y = actuator.gimbal_angles(x, p, engine)
    rgx, rgy, rgz = propulsion.gimbal_arm(p, engine, cgx, cgy, cgz)
    dgx, dgy, dgz = flex.displacement_at(x, config, p, tb, gimbal_pt)  # the structure moves the gimbal
    rgx, rgy, rgz = rgx + dgx, rgy + dgy, rgz + dgz
    thrust_part, twd_part, couple = cluster.cluster_loads(tb, p, x, xd, engine, config, thrust, dp + bias_p - tgy,
                                                  dy + bias_y - tgz, ddp, ddy, bias_p, bias_y, tgy, tgz, rgx, rgy, rgz)
    ftx, fty, ftz, mtx, mty, mtz = thrust_part
    fwx, fwy, fwz, twy, twz, mwx, mwy, mwz = twd_part
    rcs_torque = rcs.roll_torque(x, tb, p, alt, pres)
    fex, fey, fez = fax + ftx, fay + fty, faz + ftz  # external, non-gravitational
    fjy = fjz = mjy = mjz = 0.0  # the pitch and yaw jets' force and moment (coasts)
    if u[U_PY_JETS] != 0.0 or u[U_PY_JETS + 1] != 0.0:
        fjy, fjz, mjy, mjz = rcs.pitch_yaw_loads(p, u[U_PY_JETS], u[U_PY_JETS + 1], cgx)
        fey, fez = fey + fjy, fez + fjz
    booster_thrust = 0.0
    if p[boosters.P_N_BOOSTERS] > 0.0:  # strap-on boosters: their thrust, moment and nozzles' reaction join in
        booster_thrust, fbx, fby, fbz, mbx, mby, mbz, wbx, wby, wbz = boosters.loads(x, tb, p, t, pres, config == 0,
                                                                                   cgx, cgy, cgz, xd, aux)
        fex, fey, fez = fex + fbx, fey + fby, fez + fbz
        mtx, mty, mtz = mtx + mbx, mty + mby, mtz + mbz
        mwx, mwy, mwz = mwx + wbx, mwy + wby, mwz + wbz
    # the rigid part carries the slosh masses' forces too
    frx, fry, frz, msx, msy, msz = slosh.add_loads(x, p, aux, fex, fey, fez, mass_total, (cgx, cgy, cgz))

    # ------------------------------------------------------- equations of motion
    abx = frx / mass
    aby = fry / mass
    abz = frz / mass
    dvx, dvy, dvz = rigid_body.inertial_acceleration(m00, m01, m02, m10, m11, m12, m20, m21, m22,
                                                     abx, aby, abz, gx, gy, gz)
    dq0, dq1, dq2, dq3 = qt.rate_xyz(q0, q1, q2, q3, wx, wy, wz)
    alx, aly, alz = rigid_body.angular_acceleration(
        (ixx, iyy, izz, ixy, ixz, iyz), (wx, wy, wz),
        (max_ + mtx + mwx + msx + rcs_torque, may + mty + mwy + msy + mjy, maz + mtz + mwz + msz + mjz))
    dm_fs, dm_fs_fuel, dm_lox, dm_lh2 = propulsion.propellant_rates(p, mdot_fs, mdot_us)
    # (one store per element: a tuple unpacked into array items compiles to slower code)
    xd[R] = vx
    xd[R + 1] = vy
    xd[R + 2] = vz
    xd[V] = dvx
    xd[V + 1] = dvy
    xd[V + 2] = dvz
    xd[Q] = dq0
    xd[Q + 1] = dq1
    xd[Q + 2] = dq2
    xd[Q + 3] = dq3
    xd[W] = alx
    xd[W + 1] = aly
    xd[W + 2] = alz
    xd[int(p[propulsion.P_FS_TANK])] = dm_fs
    if p[propulsion.P_FS_LIQUID] != 0.0:
        xd[int(p[propulsion.P_FS_FUEL_TANK])] = dm_fs_fuel
    xd[int(p[propulsion.P_US_OX_TANK])] = dm_lox
    xd[int(p[propulsion.P_US_FUEL_TANK])] = dm_lh2

    # ------------------------------------------------------- auxiliary states
    if slosh.tank_count(p) > 0:
        motion = slosh.RigidMotion((cgx, cgy, cgz), (aby, abz), (wx, wy, wz), (alx, aly, alz))
        slosh.rates(x, p, aux, config, motion, xd)
    loads = flex.StructuralLoads((ftx + fwx, fty + fwy, ftz + fwz), (twy, twz), rcs_torque, (fjy, fjz), couple)
    flex.modal_rates(x, config, p, tb, gimbal_pt, loads, aux, boosters.A_NOZZLE_LOADS, xd)

    # ------------------------------------------------------------ diagnostics
    earth.write_altitude(aux, alt)
    if not diagnostics:
        return
    earth.write_diagnostics(aux, x_ecef, y_ecef, lat_num, lat_den, ex, ey, ez)
    atmosphere.write_diagnostics(aux, rho, pres, temp, sos)
    aero.write_diagnostics(aux, mach, qbar, alpha, beta, vair, fax, fay, faz, max_, may, maz)
    winds.write_diagnostics(aux, wind_n, wind_e, wind_d)
    gravity.write_diagnostics(aux, gx, gy, gz)
    propulsion.write_diagnostics(aux, thrust, thrust_vac, mtx, mty, mtz)
    boosters.write_diagnostics(aux, booster_thrust, x, p, config == 0)
    mass_model.write_diagnostics(aux, mass_total, prop, cgx_t, cgy_t, cgz_t)
    rcs.write_diagnostics(aux, rcs_torque)
    throttle.write_diagnostics(aux, setting, us_setting)
    actuator.write_diagnostics(aux, dp, dy, ddp, ddy)
    rigid_body.write_diagnostics(aux, abx, aby, abz)
    twd.write_diagnostics(aux, mwx, mwy, mwz)
    slosh.write_diagnostics(aux, p)
    flex.write_diagnostics(aux, tgx, tgy, tgz)
