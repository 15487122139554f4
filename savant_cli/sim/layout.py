"""Index layout of the continuous state, the held inputs, the scalar parameters and the
per-derivative diagnostics of the compiled plant.

Module-level integer constants are compile-time constants for numba, so the kernels
address arrays by name at no cost. Python code uses the same names.

Continuous state ``x`` (SI):

=========  ======  ===========================================================
slice      units   meaning
=========  ======  ===========================================================
R          m       CG position, ECI
V          m/s     CG inertial velocity, ECI
Q          1       attitude quaternion q_b2i (body→ECI, scalar first)
W          rad/s   body angular rate relative to ECI, body axes
MFS        kg      first-stage propellant remaining
MLOX       kg      upper-stage LOX remaining
MLH2       kg      upper-stage LH2 remaining
ACT_P      rad...  pitch actuator states: third-order [δ, δ̇, δ̈]; simplex [δ, δ̇, θ_piston]
ACT_Y      rad...  yaw actuator states, as ACT_P
RCS_POS    1       thrust fraction of the positive-roll jets (0..1)
RCS_NEG    1       thrust fraction of the negative-roll jets (0..1)
=========  ======  ===========================================================

Optional blocks follow the 24 core states, in this order, only when their model is on
(their offsets are in ``p``, −1 when absent; :class:`StateLayout` builds them):

* simplex power valves: pitch [r, ṙ], yaw [r, ṙ] (valve flow as no-load piston rate, rad/s);
* slosh: LOX [y, z, ẏ, ż], LH2 [y, z, ẏ, ż] (slosh-mass lateral displacement from the tank
  centerline, body axes, m and m/s);
* flex: q₁ … q_N, then q̇₁ … q̇_N (modal coordinates, unit generalized mass in SI:
  √kg·m and √kg·m/s).
"""

from __future__ import annotations

# ---------------------------------------------------------------- continuous state
R = 0
V = 3
Q = 6
W = 10
MFS = 13
MLOX = 14
MLH2 = 15
ACT_P = 16
ACT_Y = 19
RCS_POS = 22
RCS_NEG = 23
N_STATE = 24  # the core (rigid-body) states; optional blocks follow
N_TANKS = 2  # slosh tanks: 0 LOX, 1 LH2
N_SLOSH_PER_TANK = 4
N_VALVE = 4

STATE_NAMES = (
    ["r_eci_x", "r_eci_y", "r_eci_z", "v_eci_x", "v_eci_y", "v_eci_z"]
    + ["q_w", "q_x", "q_y", "q_z", "p", "q", "r"]
    + ["prop_first_stage", "prop_lox", "prop_lh2"]
    + ["dp", "dp_dot", "dp_ddot", "dy", "dy_dot", "dy_ddot"]
    + ["rcs_pos", "rcs_neg"]
)



class StateLayout:
    """Size and offsets of the continuous state for one model set.

    Parameters
    ----------
    simplex : bool
        Simplex actuators (adds the 4 power-valve states).
    slosh : bool
        LOX and LH2 slosh (8 states).
    n_modes : int
        Retained flexible modes (2 states each).
    """

    def __init__(self, simplex: bool = False, slosh: bool = False, n_modes: int = 0) -> None:
        self.simplex, self.slosh, self.n_modes = bool(simplex), bool(slosh), int(n_modes)
        pos = N_STATE
        self.valve = pos if simplex else -1
        pos += N_VALVE if simplex else 0
        self.slosh_offset = pos if slosh else -1
        pos += N_TANKS * N_SLOSH_PER_TANK if slosh else 0
        self.flex = pos if n_modes > 0 else -1
        pos += 2 * n_modes
        self.n = pos

    def names(self) -> list[str]:
        """Names of every state, in order (also the staging-state file's keys)."""
        names = list(STATE_NAMES)
        if self.simplex:
            names[ACT_P + 2] = "dp_piston"
            names[ACT_Y + 2] = "dy_piston"
            names += ["valve_p", "valve_p_dot", "valve_y", "valve_y_dot"]
        if self.slosh:
            for tank in ("lox", "lh2"):
                names += [f"slosh_{tank}_y", f"slosh_{tank}_z", f"slosh_{tank}_y_dot", f"slosh_{tank}_z_dot"]
        names += [f"flex_q{i + 1}" for i in range(self.n_modes)]
        names += [f"flex_q{i + 1}_dot" for i in range(self.n_modes)]
        return names


# ------------------------------------------------------------------- held inputs u
U_DPC = 0  # pitch gimbal command, rad
U_DYC = 1  # yaw gimbal command, rad
U_RCS = 2  # roll jet command: +1, 0, -1
U_CONFIG = 3  # aero/mass configuration: 0 stack, 1 upper with LES, 2 upper
U_ENGINE = 4  # 0 first stage burning, 1 no thrust, 2 upper stage burning
U_T_IGN = 5  # J-2X ignition time, s (mission time)
U_GUST = 6  # gust velocity, body axes (3), m/s: the air moves with it (linear-analysis disturbance input)
N_INPUT = 9

CONFIG_STACK = 0
CONFIG_UPPER_LES = 1
CONFIG_UPPER = 2
ENGINE_FIRST = 0
ENGINE_OFF = 1
ENGINE_UPPER = 2

# --------------------------------------------------------------- scalar parameters p
P_MU = 0
P_RE = 1
P_J2 = 2
P_J3 = 3
P_J4 = 4
P_OMEGA_E = 5
P_E2 = 6
P_WIND_SCALE = 7  # 0 disables winds
P_FS_ISP_VAC = 8
P_FS_EXIT_AREA = 9
P_FS_THRUST_SCALE = 10
P_US_THRUST = 11
P_US_ISP = 12
P_US_MR = 13
P_US_EXIT_AREA = 14
P_FS_GIMBAL_LIMIT = 15
P_US_GIMBAL_LIMIT = 16
P_FS_GIMBAL_X = 17  # structure-frame gimbal location, m (x, y, z)
P_US_GIMBAL_X = 20
P_RCS_EXIT_AREA = 23
P_RCS_N = 24
P_RCS_ARM = 25
P_RCS_RAMP_UP = 26
P_RCS_RAMP_DOWN = 27
P_ACT_KIND = 28  # 0 third order
P_ACT_FS_WA = 29  # position-loop gain, rad/s
P_ACT_FS_WN = 30  # load natural frequency, rad/s
P_ACT_FS_ZETA = 31
P_ACT_FS_RATE = 32  # rate limit, rad/s
P_ACT_US_WA = 33
P_ACT_US_WN = 34
P_ACT_US_ZETA = 35
P_ACT_US_RATE = 36
P_AERO_ON = 37  # 0 disables aerodynamic force and moment
P_THRUST_ON = 38  # 0 disables thrust
P_GRAVITY_ORDER = 39  # 0 point mass ... 4 up to J4
P_FS_ISP_SL = 40
# optional-block offsets in x (−1: block absent) and model switches
P_VALVE_OFF = 41
P_SLOSH_OFF = 42
P_FLEX_OFF = 43
P_N_MODES = 44
P_FLEX_SWITCH = 45  # 0: liftoff set on the stack, ignition set after separation; 1: by propellant
P_FS_PROP_FULL = 46  # kg, for interpolation between modal sets
P_US_PROP_FULL = 47
P_TWD_ON = 48
P_FS_ENG_M = 49  # moving engine/nozzle: mass kg, gimbal→engine-CG m, inertia about gimbal kg m²
P_FS_ENG_L = 50
P_FS_ENG_I = 51
P_US_ENG_M = 52
P_US_ENG_L = 53
P_US_ENG_I = 54
P_SLOSH_AREF = 55  # reference acceleration of the slosh frequency tables, m/s²
P_TANK = 56  # per tank (LOX, LH2): radius m, bottom station m (structure x), liquid density kg/m³
P_SLOSH_FREQ_SCALE = 62
P_SLOSH_ZETA_SCALE = 63
P_SPX_FS = 64  # simplex parameters of the first stage (N_SPX), then of the upper stage
N_SPX = 9  # loop gain 1/s, valve ω rad/s, valve ζ, rate limit rad/s, stiffness N m/rad,
#            damping N m s/rad, load inertia kg m², leakage rad/s per N m, feedback (0 piston, 1 nozzle)
P_SPX_US = P_SPX_FS + N_SPX
# error sources (nominal 0; see docs/models.md "Gimbal null bias and sensor misalignment")
P_FS_GIMBAL_BIAS = P_SPX_US + N_SPX  # nozzle null bias (thrust-line misalignment), pitch, yaw, rad (2)
P_US_GIMBAL_BIAS = P_FS_GIMBAL_BIAS + 2
P_IMU_MISALIGN = P_US_GIMBAL_BIAS + 2  # mounting misalignment, small rotation vector body→sensor, rad (3)
P_GYRO_US_MISALIGN = P_IMU_MISALIGN + 3
P_GYRO_FS_MISALIGN = P_GYRO_US_MISALIGN + 3
N_PARAM = P_GYRO_FS_MISALIGN + 3
ACT_THIRD_ORDER = 0
ACT_SIMPLEX = 1

# ----------------------------------------------------- per-derivative diagnostics aux
A_ALT = 0  # geodetic altitude of the CG, m
A_LAT = 1
A_LON = 2
A_RHO = 3
A_PRES = 4
A_TEMP = 5
A_SOS = 6
A_MACH = 7
A_QBAR = 8
A_ALPHA = 9
A_BETA = 10
A_VREL = 11  # air-relative speed, m/s
A_WIND_N = 12
A_WIND_E = 13
A_WIND_D = 14
A_GRAV = 15  # gravity acceleration, ECI (3)
A_THRUST = 18  # thrust magnitude, N
A_MASS = 19
A_FAERO = 20  # aero force, body (3)
A_MAERO = 23  # aero moment about CG, body (3)
A_MTHRUST = 26  # thrust moment about CG, body (3)
A_RCS_TORQUE = 29
A_PROP = 30  # propellant remaining of the burning configuration, kg
A_CG = 31  # CG, structure frame (3)
A_DP = 34  # effective (limited) actuator gimbal angles, rad (the null bias not included)
A_DY = 35
A_VEARTH = 36  # Earth-relative speed (no wind), m/s
A_ACCEL = 37  # sensed (non-gravitational) acceleration, body (3)
A_TWD = 40  # tail-wags-dog moment about the CG, body (3)
A_DDP = 43  # gimbal angular acceleration, pitch, yaw, rad/s² (2)
A_SLOSH_W = 45  # slosh frequency per tank, rad/s (2)
A_LEVEL = 47  # liquid level per tank, m (2)
A_SLOSH_F = 49  # slosh force on the vehicle per tank, body (2 x 3)
A_FLEX_GIMBAL = 55  # flex rotation at the active gimbal, body (3)
N_AUX = 58

# ------------------------------------------------ discrete (flight software) state d
# guidance command smoother
D_QG = 0  # latest guidance quaternion q_c2i (4)
D_VG = 4  # guidance (eigenaxis) rate, command frame, rad/s (3)
D_TG = 7  # time of the latest guidance sample, s
D_QS = 8  # smoothed quaternion command (4)
D_VS = 12  # smoothed rate command, command frame, rad/s (3)
# rate gyros: 3 gyros (upper stage, IMU, first stage) x 3 axes x 2 filter states
D_GYRO_X = 15  # (18)
D_GYRO_Y = 33  # gyro outputs, body axes, rad/s: [gyro][axis] (9)
# flight control
D_ERR = 42  # attitude error roll, pitch, yaw, rad (3)
D_RATE_ERR = 45  # blended rate error, rad/s (3)
D_INT_ATT = 48  # integral of pitch, yaw attitude error, rad·s (2)
D_INT_RATE = 50  # integrated (gyro − command) rate, pitch, yaw, rad (2)
D_FILT = 52  # flex filter states: 2 axes x 2 paths x 2 sections x 4 (32)
D_ROLL_FILT = 84  # roll rate-error filter: 2 sections x 4 (8)
D_GAINS = 92  # scheduled Kp, Ki, Kd, Kir for pitch then yaw (8)
D_CMD_P = 100  # gimbal commands, rad
D_CMD_Y = 101
D_CMD_RCS = 102
D_RATE_CMD_B = 103  # rate command in body axes (3)
D_FLEX_NAV = 106  # flex rotation at the navigation unit, body, rad (3), added to the errors
N_DISC = 109

# ------------------------------------------------------------- flexible-body points
# Points where the plant and the sensors use mode shapes, and the vehicle YAML key
# (``flex.nodes.<key>``) of each; a point may average several nodes.
PT_IMU = 0  # navigation unit (its rotation enters the attitude errors) and IMU gyros
PT_GYRO_US = 1
PT_GYRO_FS = 2
PT_RCS = 3
PT_GIMBAL_FS = 4
PT_GIMBAL_US = 5
PT_SLOSH_LOX = 6
PT_SLOSH_LH2 = 7
N_POINTS = 8
POINT_KEYS = ("imu", "rate_gyro_upper_stage", "rate_gyro_first_stage", "rcs", "gimbal_first_stage",
              "gimbal_upper_stage", "slosh_lox", "slosh_lh2")
FIRST_STAGE_POINTS = (PT_GYRO_FS, PT_GIMBAL_FS)  # absent from the upper-stage modal sets
# modal data sets, in this order in the packed tables
FLEX_SETS = ("first_stage_liftoff", "first_stage_burnout", "second_stage_ignition", "second_stage_burnout")
GYRO_POINTS = (PT_GYRO_US, PT_IMU, PT_GYRO_FS)  # in the FCS gyro order: upper, IMU, first
GYRO_MISALIGN = (P_GYRO_US_MISALIGN, P_IMU_MISALIGN, P_GYRO_FS_MISALIGN)  # same order
