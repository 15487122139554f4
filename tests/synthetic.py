"""A small synthetic plant (constant mass properties, no aerodynamics) for tests that
need the compiled dynamics without a vehicle's data."""

from __future__ import annotations

import numpy as np

from savant_cli import constants
from savant_cli.flex_slosh import FIRST_STAGE, UPPER_STAGE, default_plan
from savant_cli.models import (
    actuator, aero as aero_model, cluster, earth, flex, gravity, layout, propulsion, rcs, slosh
)
from savant_cli.models.atmosphere import upper_atmosphere_table
from savant_cli.sim.plant import PlantTables

#: The synthetic vehicle's tanks: the first stage's, then the upper stage's LOX and LH2.
TANKS = ("first_stage_propellant", "lox", "lh2")


def state_layout(slosh: bool = False, **optional) -> layout.StateLayout:
    """The synthetic vehicle's state layout with the optional blocks ``optional``
    (:class:`~savant_cli.models.layout.StateLayout`'s ``simplex``, ``n_modes``); ``slosh``:
    the LOX and LH2 tanks slosh."""
    return layout.StateLayout(tanks=TANKS, slosh_tanks=("lox", "lh2") if slosh else (), **optional)


#: The layout without optional blocks, and the indices tests address in it.
LAYOUT = state_layout()
FS, LOX, LH2 = (LAYOUT.tank(t) for t in TANKS)
ACT_P, ACT_Y = LAYOUT.channel(0), LAYOUT.channel(1)
RCS_POS = LAYOUT.rcs


def tables(mass: float = 1000.0, inertia=(100.0, 400.0, 400.0, 0.0, 0.0, 0.0),
           cg=(5.0, 0.0, 0.0)) -> PlantTables:
    """Constant mass properties in all three configurations, zero aerodynamic data."""
    row = np.array([mass, *cg, *inertia])
    mass_prop = np.tile(np.array([0.0, 1e6]), (3, 1))
    mass_data = np.tile(row, (3, 2, 1))
    ax = np.array([0.0, 1.0])
    atm_alt, atm_lnp, atm_lnrho = upper_atmosphere_table()
    return PlantTables(
        aero_mach=ax, aero_alpha=ax, aero_beta=ax, aero_coef=np.zeros((3, 6, 2, 2, 2)),
        aero_ref=np.tile(np.array([1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0]), (3, 1)),
        base_time=np.tile(ax, (3, 1)), base_force=np.zeros((3, 2)), base_len=np.array([2, 2, 2]),
        mass_prop=mass_prop, mass_data=mass_data, mass_len=np.array([2, 2, 2]),
        fs_time=ax, fs_thrust=np.zeros(2), us_start_time=ax, us_start_frac=np.ones(2), fs_start_time=ax,
        fs_start_frac=np.ones(2), fs_throttle_time=ax, fs_throttle=np.ones(2),
        rcs_alt=ax, rcs_thrust=np.zeros(2), atm_alt=atm_alt, atm_lnp=atm_lnp, atm_lnrho=atm_lnrho,
        wind_alt=ax, wind_north=np.zeros(2), wind_east=np.zeros(2),
        flex_freq=np.zeros((4, 1)), flex_zeta=np.zeros(1), flex_shape=np.zeros((4, 1, layout.N_POINTS, 6)),
        flex_set_map=default_plan((FIRST_STAGE, UPPER_STAGE, UPPER_STAGE)).table(),  # the stack, upper_les, upper
        slosh_level=np.tile(ax, (2, 1)), slosh_data=np.zeros((2, 2, 4)), slosh_len=np.array([2, 2]),  # two tanks
        mounts=MOUNTS, booster_time=ax, booster_thrust=np.zeros(2), booster_mount=np.zeros((1, 6)),
        booster_mass_prop=np.zeros((1, 1)), booster_mass_data=np.zeros((1, 1, 10)), booster_mass_len=np.ones(1, int),
        booster_burn_rate=np.ones(1), booster_cant=np.zeros((1, 2)), booster_full=np.zeros((1, 10)),
    )


def _one_engine_mounts() -> np.ndarray:
    """One engine a stage at its gimbal point, on channel pair 0, its mixer the identity."""
    rows = np.zeros((2, cluster.MOUNT_SIZE))
    rows[:, cluster.M_STAGE] = (0.0, 1.0)
    rows[:, cluster.M_SHARE] = 1.0
    rows[:, cluster.M_PITCH_PITCH] = rows[:, cluster.M_YAW_YAW] = 1.0
    return rows


MOUNTS = _one_engine_mounts()


def parameters(gravity_order: int = 0, aero: bool = False, thrust: bool = False,
               lay: layout.StateLayout = LAYOUT) -> np.ndarray:
    """Parameters of the synthetic plant, with the state offsets of ``lay``."""
    p = np.zeros(layout.N_PARAM)
    p[gravity.P_MU] = constants.MU_EARTH
    p[earth.P_RE] = constants.WGS84_A
    p[gravity.P_J2], p[gravity.P_J3], p[gravity.P_J4] = constants.EGM2008_J2, constants.EGM2008_J3, constants.EGM2008_J4
    p[earth.P_OMEGA_E] = constants.OMEGA_EARTH
    p[earth.P_E2] = constants.WGS84_E2
    p[propulsion.P_FS_ISP] = p[propulsion.P_US_ISP] = 300.0
    p[propulsion.P_US_MR] = 5.0
    p[propulsion.P_FS_FLOW_PER_THRUST] = 1.0 / (constants.G0 * p[propulsion.P_FS_ISP])  # F_vac = the table
    for g in (actuator.P_FS_GIMBAL, actuator.P_US_GIMBAL):
        p[g + actuator.G_LIMIT] = 0.1
    p[propulsion.P_FS_GIMBAL + propulsion.GIMBAL_X] = p[propulsion.P_US_GIMBAL + propulsion.GIMBAL_X] = 10.0
    p[rcs.P_RAMP_UP] = p[rcs.P_RAMP_DOWN] = 0.05
    for base in (actuator.P_FS_THIRD, actuator.P_US_THIRD):
        p[base + actuator.T3_LOOP_GAIN], p[base + actuator.T3_NATURAL_FREQUENCY] = 20.0, 60.0
        p[base + actuator.T3_DAMPING], p[base + actuator.T3_RATE_LIMIT] = 0.7, 1.0
    p[aero_model.P_ON] = 1.0 if aero else 0.0
    p[propulsion.P_ON] = 1.0 if thrust else 0.0
    p[gravity.P_ORDER] = gravity_order
    p[propulsion.P_FS_TANK], p[propulsion.P_US_OX_TANK], p[propulsion.P_US_FUEL_TANK] = (lay.tank(t) for t in TANKS)
    p[actuator.P_CHANNEL_OFFSET] = lay.channel(0)
    p[actuator.P_N_CHANNELS] = len(lay.channels)
    p[rcs.P_STATE_OFFSET] = lay.rcs
    p[actuator.P_VALVE_OFFSET], p[slosh.P_OFFSET], p[flex.P_OFFSET] = lay.valve, lay.slosh_offset, lay.flex
    p[propulsion.P_FS_PROP_FULL] = p[propulsion.P_US_PROP_FULL] = 1.0
    p[propulsion.P_FS_CONFIGS] = 1.0  # the stack, then the upper stage's configurations
    p[cluster.P_UPPER_FIRST] = 1.0  # tables(): one engine a stage
    p[slosh.P_FREQ_SCALE] = p[slosh.P_ZETA_SCALE] = 1.0
    p[slosh.P_N_TANKS], p[slosh.P_ROWS] = len(lay.slosh_tanks), 2  # tables(): two rows a tank
    for j, tank in enumerate(lay.slosh_tanks):  # aboard in every configuration
        base = slosh.P_TANKS + j * slosh.N_TANK_FIELDS
        p[base + slosh.K_AREF], p[base + slosh.K_LIQUID], p[base + slosh.K_CONFIGS] = 9.80665, lay.tank(tank), 3.0
    return p


def coast_inputs() -> np.ndarray:
    u = np.zeros(layout.N_INPUT)
    u[layout.U_CONFIG] = layout.CONFIG_UPPER
    u[layout.U_ENGINE] = layout.ENGINE_OFF
    return u
