"""The assembled vectors of the plant: sizes, the continuous-state layout with its
optional blocks, and the held inputs.

Every field of the state ``x``, the parameters ``p``, the diagnostics ``aux``, the
discrete flight-software state ``d`` and the packed tables is declared by the model that
owns it (``savant_cli/models/*.py``, through :mod:`savant_cli.models.blocks`); this
module declares the held inputs ``u``, adds the vectors up and re-exports the state and
discrete-state indices that the engine, the linearization and the tests address.

Continuous state ``x`` (SI): the rigid body ``R V Q W`` (compile-time indices), then the
blocks a vehicle and a model set size, in this order (:class:`StateLayout` builds them; the
compiled models read their offsets from ``p``):

* propellant: one state per tank of the vehicle, in the vehicle file's order (kg);
* gimbal channels: ``[δ, δ̇, δ̈]`` (third order) or ``[δ, δ̇, θ_piston]`` (simplex) per
  channel (rad, rad/s, rad/s² or rad), a pitch and a yaw channel per engine of the stage
  with the most engines; engines whose gimbals are never live together (engine ``i`` of
  each stage) share a channel pair (``models/actuator.py``);
* roll jets: the thrust fractions of the positive and negative jets (1);
* simplex power valves: ``[r, ṙ]`` per channel (valve flow as no-load piston rate, rad/s),
  only with the simplex actuator;
* slosh: ``[y, z, ẏ, ż]`` per sloshing tank, in the order of the propellant states
  (slosh-mass lateral displacement from the tank centerline, body axes, m and m/s), only
  with slosh on;
* flex: q₁ … q_N, then q̇₁ … q̇_N (modal coordinates, unit generalized mass in SI:
  √kg·m and √kg·m/s), only with flex on.
"""

from __future__ import annotations

from savant_cli.flex_slosh import FLEX_SETS  # noqa: F401  (the modal sets, in table order)
from savant_cli.models import blocks
from savant_cli.models.actuator import N_PER_CHANNEL, N_VALVE_PER_CHANNEL  # noqa: F401
from savant_cli.models.configurations import (  # noqa: F401
    CONFIG_STACK, CONFIG_UPPER, CONFIG_UPPER_LES, ENGINE_FIRST, ENGINE_OFF, ENGINE_UPPER
)
from savant_cli.models.fcs import (  # noqa: F401  (discrete-state indices)
    D_CMD_P, D_CMD_PY, D_CMD_RCS, D_CMD_Y, D_ERR, D_FILT, D_FLEX_NAV, D_GAINS, D_INT_ATT, D_INT_RATE, D_RATE_CMD_B,
    D_RATE_ERR, D_ROLL_FILT
)
from savant_cli.models.flex import (  # noqa: F401
    FIRST_STAGE_POINTS, N_POINTS, POINT_KEYS, PT_GIMBAL_FS, PT_GIMBAL_US, PT_GYRO_FS, PT_GYRO_US, PT_IMU, PT_RCS,
    PT_SLOSH
)
from savant_cli.models.guidance import D_QG, D_QS, D_TG, D_VG, D_VS  # noqa: F401
from savant_cli.models.rcs import N_JET_STATES, STATE_NAMES as _RCS_NAMES  # noqa: F401
from savant_cli.models.rigid_body import STATE_NAMES as _RIGID_NAMES, Q, R, V, W  # noqa: F401
from savant_cli.models.sensors import D_GYRO_X, D_GYRO_Y, GYRO_MISALIGN, GYRO_POINTS  # noqa: F401
from savant_cli.models.slosh import N_PER_TANK as N_SLOSH_PER_TANK  # noqa: F401

N_STATE = blocks.STATE.size  # the rigid body; the vehicle's and the optional blocks follow
N_PARAM = blocks.PARAMETERS.size
N_AUX = blocks.DIAGNOSTICS.size
N_DISC = blocks.DISCRETE.size
STATE_NAMES = list(_RIGID_NAMES)
assert len(STATE_NAMES) == N_STATE, "every rigid-body state needs a name"
#: The gimbal channels of a vehicle whose stages each gimbal one engine in pitch and yaw.
PITCH_YAW = ("p", "y")


def channel_names(n_engines: int) -> tuple[str, ...]:
    """The gimbal channels' names for stages of at most ``n_engines`` engines: ``p``, ``y``
    for the first engine, then ``p2``, ``y2``, ``p3``, … (the states ``dp``, ``dy``, ``dp2`` …)."""
    return PITCH_YAW + tuple(f"{axis}{i}" for i in range(2, n_engines + 1) for axis in PITCH_YAW)


class StateLayout:
    """Size and offsets of the continuous state for one vehicle and model set.

    Parameters
    ----------
    tanks : sequence of str
        The vehicle's tanks, one propellant state each, in order.
    channels : sequence of str
        The gimbal channels' names (``p``, ``y``: the states ``dp``, ``dy`` …), in order.
    simplex : bool
        Simplex actuators (adds 2 power-valve states per channel).
    slosh_tanks : sequence of str
        The sloshing tanks (4 states each), in the order of ``tanks``; empty: slosh off.
    n_modes : int
        Retained flexible modes (2 states each).
    """

    def __init__(self, tanks: tuple[str, ...] | list[str] = (), channels: tuple[str, ...] | list[str] = PITCH_YAW,
                 simplex: bool = False, slosh_tanks: tuple[str, ...] | list[str] = (), n_modes: int = 0) -> None:
        self.tanks, self.channels, self.slosh_tanks = tuple(tanks), tuple(channels), tuple(slosh_tanks)
        self.simplex, self.slosh, self.n_modes = bool(simplex), bool(self.slosh_tanks), int(n_modes)
        pos = N_STATE + len(self.tanks)
        self.channel_offset = pos
        pos += N_PER_CHANNEL * len(self.channels)
        self.rcs = pos
        pos += N_JET_STATES
        self.n_core = pos  # the states every run of this vehicle has
        self.valve = pos if simplex else -1
        pos += N_VALVE_PER_CHANNEL * len(self.channels) if simplex else 0
        self.slosh_offset = pos if self.slosh else -1
        pos += len(self.slosh_tanks) * N_SLOSH_PER_TANK
        self.flex = pos if n_modes > 0 else -1
        pos += 2 * n_modes
        self.n = pos

    def tank(self, name: str) -> int:
        """The index in ``x`` of tank ``name``'s propellant state (kg)."""
        return N_STATE + self.tanks.index(name)

    def channel(self, k: int) -> int:
        """The index in ``x`` of gimbal channel ``k``'s first state (its angle δ, rad)."""
        return self.channel_offset + N_PER_CHANNEL * k

    def names(self) -> list[str]:
        """Names of every state, in order (also the staging-state file's keys)."""
        names = list(STATE_NAMES) + [f"prop_{t}" for t in self.tanks]
        third = "piston" if self.simplex else "ddot"
        for c in self.channels:
            names += [f"d{c}", f"d{c}_dot", f"d{c}_{third}"]
        names += list(_RCS_NAMES)
        if self.simplex:
            for c in self.channels:
                names += [f"valve_{c}", f"valve_{c}_dot"]
        for tank in self.slosh_tanks:
            names += [f"slosh_{tank}_y", f"slosh_{tank}_z", f"slosh_{tank}_y_dot", f"slosh_{tank}_z_dot"]
        names += [f"flex_q{i + 1}" for i in range(self.n_modes)]
        names += [f"flex_q{i + 1}_dot" for i in range(self.n_modes)]
        return names


# ------------------------------------------------------------------- held inputs u
# Set by the flight software and the event logic, held over a plant step.
_INPUTS = blocks.INPUTS.block("engine")
U_DPC = _INPUTS.scalar("pitch_command", "rad", "pitch gimbal command δp (the equivalent engine's)")
U_DYC = _INPUTS.scalar("yaw_command", "rad", "yaw gimbal command δy (the equivalent engine's)")
U_RCS = _INPUTS.scalar("roll_jet_command", "1", "roll jet command +1, 0, −1")
U_CONFIG = _INPUTS.scalar("configuration", "1", "aero/mass configuration (models/configurations.py)")
U_ENGINE = _INPUTS.scalar("engine_phase", "1", "engine phase (models/configurations.py)")
U_T_IGN = _INPUTS.scalar("ignition_time", "s", "upper-stage ignition time, mission time")
U_T_CUT = _INPUTS.scalar("cutoff_command_time", "s",
                         "upper-stage cutoff command time, mission time (0: none yet; never at liftoff)")
U_GUST = _INPUTS.array("gust", 3, "m/s", "gust velocity, body axes: the air moves with it (linear-analysis input)")
U_ROLL = _INPUTS.scalar("roll_gimbal_command", "rad",
                       "roll command δr to the engines' gimbals: the most-deflected nozzle's angle")
U_THROTTLE = _INPUTS.scalar("first_stage_throttle", "1", "the first stage's throttle setting, fraction of rated "
                           "thrust (read only when it is throttled: models/throttle.py)")
U_FS_T_CUT = _INPUTS.scalar("first_stage_cutoff_command_time", "s",
                            "a liquid first stage's cutoff command time, mission time (0: none yet; never at liftoff)")
U_US_THROTTLE = _INPUTS.scalar("upper_stage_throttle", "1", "the upper stage's throttle setting, fraction of rated "
                              "thrust (read only when it is throttled: models/throttle.py)")
U_PY_JETS = _INPUTS.array("pitch_yaw_jet_command", 2, "1", "the pitch and yaw jets' commands +1, 0, −1 (the coasts "
                                                           "only: models/rcs.py)")
N_INPUT = blocks.INPUTS.size


def all_fields() -> list[blocks.Field]:
    """Every declared field of every vector of the plant, the held inputs included.

    Returns
    -------
    list of blocks.Field
        The fields of ``x``, ``p``, ``aux``, ``d``, ``u`` and the packed tables, each
        vector in declaration order (importing this module imports every model first).
    """
    return [*blocks.STATE.fields, *blocks.PARAMETERS.fields, *blocks.DIAGNOSTICS.fields, *blocks.DISCRETE.fields,
            *blocks.INPUTS.fields, *blocks.TABLES.fields]
