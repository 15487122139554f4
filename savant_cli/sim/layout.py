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
ACT_P      rad...  pitch actuator states [δ, δ̇, δ̈]
ACT_Y      rad...  yaw actuator states [δ, δ̇, δ̈]
RCS_POS    1       thrust fraction of the positive-roll jets (0..1)
RCS_NEG    1       thrust fraction of the negative-roll jets (0..1)
=========  ======  ===========================================================
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
N_STATE = 24

STATE_NAMES = (
    ["r_eci_x", "r_eci_y", "r_eci_z", "v_eci_x", "v_eci_y", "v_eci_z"]
    + ["q_w", "q_x", "q_y", "q_z", "p", "q", "r"]
    + ["prop_first_stage", "prop_lox", "prop_lh2"]
    + ["dp", "dp_dot", "dp_ddot", "dy", "dy_dot", "dy_ddot"]
    + ["rcs_pos", "rcs_neg"]
)

# ------------------------------------------------------------------- held inputs u
U_DPC = 0  # pitch gimbal command, rad
U_DYC = 1  # yaw gimbal command, rad
U_RCS = 2  # roll jet command: +1, 0, -1
U_CONFIG = 3  # aero/mass configuration: 0 stack, 1 upper with LES, 2 upper
U_ENGINE = 4  # 0 first stage burning, 1 no thrust, 2 upper stage burning
U_T_IGN = 5  # J-2X ignition time, s (mission time)
N_INPUT = 6

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
N_PARAM = 41

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
A_DP = 34  # effective (limited) gimbal angles, rad
A_DY = 35
A_VEARTH = 36  # Earth-relative speed (no wind), m/s
A_ACCEL = 37  # sensed (non-gravitational) acceleration, body (3)
N_AUX = 40

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
N_DISC = 106
