"""Engine clusters: the burning stage's thrust shared over its engines, each at its own
gimbal point and cant, on its own gimbal channels, with its own tail-wags-dog reaction.

A stage's engines are identical (``vehicle/two_stage.py``): the propulsion model
computes the stage's thrust (the engines' sum), and each of the ``n`` engines carries
``F/n`` along its own thrust line, at its own arm from the CG::

    F_i = (F/n) (cos θp cos θy, −sin θy, sin θp cos θy),   θ = δ_i + bias + cant_i − flex rotation
    r_i = r_cg→gimbal + diag(−1, 1, −1) Δ_i,               M = Σ r_i × F_i

with ``δ_i`` engine ``i``'s own gimbal angles (its channel pair, ``models/actuator.py``)
and ``Δ_i`` its gimbal offset from the stage's mean gimbal point (structure frame). Each
engine's moving mass reacts on the vehicle at its own gimbal with its own nozzle
accelerations (``models/twd.py``). The flexible body sees the stage's engines at the
stage's one gimbal node, through a rigid thrust structure: the engines' forces summed
and their couple about the node, ``Σ Δ_i × F_i``.

The control mixer (``models/mixer.py``) gives each channel its command from the flight
control's three: the equivalent-engine pitch and yaw angles ``δp``, ``δy`` and the roll
command ``δr`` (rad)::

    δ_channel = k_roll δr + k_pitch δp + k_yaw δy

The coefficients are the mixer's limit-weighted pseudo-inverse allocation ``K`` for the
stage's engines at unit thrust, at the arms from the stage's CG at ignition (the
configuration's mass table at full load): the pitch and yaw columns give the moment
of the equivalent engine (every engine moved together, for a symmetric cluster), and
the roll column is ``K``'s scaled so that its largest channel deflection is ``δr``
(the *equivalent roll angle*: 1 rad of ``δr`` puts the most-deflected nozzle at 1 rad).
A stage whose engines cannot make a roll moment (``B`` of rank below 3: one engine, or
all on the roll axis) gets a zero roll column; a stage of one engine is the equivalent
engine itself (``k_pitch = (1, 0)``, ``k_yaw = (0, 1)``), bit for bit the single-engine
plant. The mixer is the flight software's static map of its held commands, evaluated
where the plant consumes them. Its coefficients are computed once per stage: the roll
column depends on the engines' lateral arms, which the CG's travel along the axis does
not change, and the pitch and yaw columns on the engines' arms only through the
differences between them.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.errors import ConfigError
from savant_cli.models import actuator, blocks, mixer, propulsion, twd
from savant_cli.models.configurations import ENGINE_FIRST
from savant_cli.models.interp import tab
from savant_cli.vehicle import CONFIG_NAMES

MOUNT = blocks.Record(
    "engine mount",
    ("stage", "1", "0 first stage, 1 upper stage"),
    ("share", "1", "the engine's share of its stage's thrust (1/n of n identical engines)"),
    ("dx", "m", "gimbal offset from the stage's gimbal point, structure x"),
    ("dy", "m", "gimbal offset, structure y"),
    ("dz", "m", "gimbal offset, structure z"),
    ("cant_pitch", "rad", "nozzle cant at null, pitch (added to the thrust-line angle)"),
    ("cant_yaw", "rad", "nozzle cant at null, yaw"),
    ("pair", "1", "the engine's gimbal channel pair (its order in the stage)"),
    ("pitch_roll", "1", "mixer: pitch channel per rad of roll command δr"),
    ("pitch_pitch", "1", "mixer: pitch channel per rad of pitch command δp"),
    ("pitch_yaw", "1", "mixer: pitch channel per rad of yaw command δy"),
    ("yaw_roll", "1", "mixer: yaw channel per rad of roll command δr"),
    ("yaw_pitch", "1", "mixer: yaw channel per rad of pitch command δp"),
    ("yaw_yaw", "1", "mixer: yaw channel per rad of yaw command δy"),
    ("booster", "1", "0: an engine of the stage; i + 1: gimbaled booster i's nozzle (its thrust, actuator and "
                     "moving mass are the booster's: models/boosters.py)"),
)
(M_STAGE, M_SHARE, M_DX, M_DY, M_DZ, M_CANT_PITCH, M_CANT_YAW, M_PAIR, M_PITCH_ROLL, M_PITCH_PITCH, M_PITCH_YAW,
 M_YAW_ROLL, M_YAW_PITCH, M_YAW_YAW, M_BOOSTER) = MOUNT.offsets
MOUNT_SIZE = MOUNT.size

_PARAMS = blocks.PARAMETERS.block("cluster")
P_UPPER_FIRST = _PARAMS.scalar("upper_stage_first_mount", "1",
                               "the upper stage's first mount record (the first stage's engines come before)")
P_BOOSTED_END = _PARAMS.scalar("boosted_mounts", "1",
                               "the mount records mixed while gimbaled boosters are attached: the first stage's "
                               "engines, then the boosters' nozzles (0: no booster TVC); the first stage's own "
                               "records follow them")
_TABLES = blocks.TABLES.block("cluster")
T_MOUNTS = _TABLES.table("mounts", "1", f"one {MOUNT_SIZE}-element engine-mount record per engine, stage by stage")


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """Each stage's engine mounts and mixing coefficients (a stage without ``mounts``: one
    engine at its gimbal), with gimbaled boosters the first stage's engines and the
    boosters' nozzles mixed together first; roll-by-gimbal gains on a stage whose engines
    (with its gimbaled boosters) cannot roll the vehicle are refused."""
    boosted = boosted_mounts(inputs.vehicle)
    mounts = np.concatenate([boosted, mount_table(inputs.vehicle)])
    p[P_BOOSTED_END] = boosted.shape[0]
    p[P_UPPER_FIRST] = np.count_nonzero(mounts[:, M_STAGE] == 0.0)
    tables.update(mounts=mounts)
    gimbal = inputs.cfg.controller.roll.gimbal
    for stage, (phase, name) in enumerate((("stack", "first stage"), ("upper", "upper stage"))):
        gains = getattr(gimbal, phase)
        rows = mounts[mounts[:, M_STAGE] == stage]  # the first stage's with and without the boosters
        if (gains.kp, gains.ki, gains.kd) != (0.0, 0.0, 0.0) and not np.any(rows[:, [M_PITCH_ROLL, M_YAW_ROLL]]):
            raise ConfigError(f"controller.roll.gimbal.{phase}", {"kp": gains.kp, "ki": gains.ki, "kd": gains.kd},
                              f"the {name}'s engines cannot roll the vehicle (one engine, or all on the roll axis): "
                              "its gains must be 0")


def stage_geometry(vehicle, stage: int) -> tuple:
    """A stage's engines for the mixer: the stage's gimbal point, each engine's offset and
    cant, the reference CG (the stage's configuration at full load; structure frame, m,
    rad) and the gimbal limit (rad)."""
    record, config = ((vehicle.first_stage, CONFIG_NAMES[0]), (vehicle.upper_stage, CONFIG_NAMES[-1]))[stage]
    mounts = record.mounts or (None,)
    offsets = np.array([np.zeros(3) if m is None else m.offset_m for m in mounts], float)
    cants = np.array([np.zeros(2) if m is None else m.cant_rad for m in mounts], float)
    mass = vehicle.configurations[config].mass
    cg = np.asarray(mass.cg_m, float)[int(np.argmax(mass.propellant_kg))]  # at ignition: full load
    return np.asarray(record.gimbal_m, float), offsets, cants, cg, float(record.gimbal_limit_rad)


def mount_table(vehicle) -> np.ndarray:
    """The :data:`MOUNT` records of the vehicle's engines, ``(n_engines, MOUNT.size)``; a
    stage's own ``mixing_matrix`` replaces the mixer's allocation once
    :func:`check_given_mixer` finds it gives the same moments."""
    rows = []
    for stage, name in enumerate(("first_stage", "upper_stage")):
        gimbal, offsets, cants, cg, limit = stage_geometry(vehicle, stage)
        coefficients = stage_mixer(gimbal, offsets, cants, cg, limit)
        given = getattr(vehicle, name).mixing_matrix
        if given is not None:
            key = vehicle.keys.get(f"mixing_matrix.{name}", f"vehicle.{name}.mixing_matrix")
            failures = check_given_mixer(given, gimbal, offsets, cants, cg, limit)
            if failures:
                raise ConfigError(key, np.asarray(given).tolist(), "must give the moments of the mixer's own "
                                  "allocation (docs/models.md, \"Control mixer\"): " + "; ".join(failures))
            coefficients = np.asarray(given, float).reshape(-1, 6)
        n = offsets.shape[0]
        for i in range(n):
            rows.append([float(stage), 1.0 / n, *offsets[i], *cants[i], float(i), *coefficients[i], 0.0])
    return np.array(rows, dtype=float)


def boosted_mounts(vehicle) -> np.ndarray:
    """The :data:`MOUNT` records mixed while gimbaled boosters are attached: the first
    stage's engines (pairs 0 … n − 1), then each booster's nozzle (pair n + i, its
    offset from the first stage's gimbal point, ``booster`` i + 1), with the mixer's
    allocation over all of their channels (:func:`boosted_mixer`); none (``(0,
    MOUNT.size)``) without booster TVC."""
    if not vehicle.gimbaled_boosters:
        return np.zeros((0, MOUNT_SIZE))
    gimbal, offsets, cants, _, _ = stage_geometry(vehicle, 0)
    b = vehicle.boosters
    coefficients = boosted_mixer(vehicle)
    n = offsets.shape[0]
    rows = [[0.0, 1.0 / n, *offsets[i], *cants[i], float(i), *coefficients[i], 0.0] for i in range(n)]
    rows += [[0.0, 0.0, *(b.nozzle_m[i] - gimbal), *b.cant_rad[i], float(n + i), *coefficients[n + i], float(i + 1)]
             for i in range(b.count)]
    return np.array(rows, dtype=float)


def boosted_mixer(vehicle) -> np.ndarray:
    """The mixing coefficients ``(n + n_boosters, 6)`` (as :func:`stage_mixer`'s) of the
    first stage's engines and the gimbaled boosters' nozzles together: the allocation
    over all of their channels with each engine at its rated vacuum thrust (the peak of
    its trace; a booster at its own, a stage's engine at an equal share of the stage's),
    the arms from the liftoff configuration's CG at full load, each channel weighted by
    its own gimbal limit."""
    gimbal, offsets, cants, _, limit = stage_geometry(vehicle, 0)
    b = vehicle.boosters
    n = offsets.shape[0]
    mass = vehicle.configurations["boosted"].mass
    cg = np.asarray(mass.cg_m, float)[int(np.argmax(mass.propellant_kg))]
    points = np.concatenate([gimbal + offsets, b.nozzle_m])
    thrust = np.concatenate([np.full(n, float(np.max(vehicle.first_stage.thrust_vac_N)) / n),
                             np.full(b.count, float(np.max(b.thrust_vac_N)))])
    limits = np.repeat(np.concatenate([np.full(n, limit), np.full(b.count, b.gimbal_limit_rad)]), 2)
    return allocation(points, np.concatenate([cants, b.cant_rad]), thrust, cg, limits)


def _effectiveness(gimbal_m: np.ndarray, offsets_m: np.ndarray, cants_rad: np.ndarray,
                   cg_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``B`` (3 × 2n, N·m/rad per N of the stage's thrust, body axes; each engine's pitch
    then yaw channel) of a stage's engines sharing its thrust, and the channels' axes."""
    n = offsets_m.shape[0]
    return effectiveness(gimbal_m + offsets_m, cants_rad, np.full(n, 1.0 / n), cg_m)


def effectiveness(points_m: np.ndarray, cants_rad: np.ndarray, thrust_N: np.ndarray,
                  cg_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``B`` (3 × 2n, N·m/rad, body axes; each engine's pitch then yaw channel) of n
    engines at their gimbal points ``points_m`` (structure frame, m) with their cants
    (rad) and thrusts (N), about the CG ``cg_m`` (structure frame, m), and the channels'
    axes."""
    n = points_m.shape[0]
    structure = points_m - cg_m
    arms = np.ascontiguousarray(np.column_stack([-structure[:, 0], structure[:, 1], -structure[:, 2]]))  # body axes
    engine = np.repeat(np.arange(n, dtype=np.int64), 2)
    axis = np.tile(np.array([mixer.AXIS_PITCH, mixer.AXIS_YAW], np.int64), n)
    return mixer.moment_effectiveness(arms, np.ascontiguousarray(cants_rad), np.ascontiguousarray(thrust_N, float),
                                      engine, axis), axis


def allocation(points_m: np.ndarray, cants_rad: np.ndarray, thrust_N: np.ndarray, cg_m: np.ndarray,
               limits_rad: np.ndarray) -> np.ndarray:
    """The mixing coefficients ``(n, 6)`` of n engines (:func:`effectiveness`'s
    arguments; ``limits_rad`` each channel's gimbal limit, ``(2 n,)``): the mixer's
    allocation with its roll column scaled so that the most-deflected channel moves by
    ``δr``, or zero where the engines cannot roll the vehicle (``B`` of rank below 3)."""
    b, axis = effectiveness(points_m, cants_rad, thrust_N, cg_m)
    k = mixer.mixing_matrix(b, np.ascontiguousarray(limits_rad, float), axis)
    roll = k[:, mixer.ROLL]
    if np.linalg.matrix_rank(b) < 3:  # the engines cannot roll the vehicle
        k[:, mixer.ROLL] = 0.0
    else:
        k[:, mixer.ROLL] = roll / np.max(np.abs(roll))
    return k.reshape(points_m.shape[0], 6)


def stage_mixer(gimbal_m: np.ndarray, offsets_m: np.ndarray, cants_rad: np.ndarray, cg_m: np.ndarray,
                limit_rad: float) -> np.ndarray:
    """The mixing coefficients of a stage's engines (module notes).

    Parameters
    ----------
    gimbal_m : ndarray (3,)
        The stage's gimbal point, structure frame, m.
    offsets_m : ndarray (n, 3)
        Each engine's gimbal offset from it, structure frame, m.
    cants_rad : ndarray (n, 2)
        Each nozzle's cant at null, pitch and yaw, rad.
    cg_m : ndarray (3,)
        The reference CG, structure frame, m.
    limit_rad : float
        The engines' gimbal limit, rad.

    Returns
    -------
    ndarray (n, 6)
        Per engine: its pitch channel's coefficients of ``(δr, δp, δy)``, then its yaw
        channel's.
    """
    n = offsets_m.shape[0]
    if n == 1:
        return np.array([[0.0, 1.0, 0.0, 0.0, 0.0, 1.0]])
    return allocation(gimbal_m + offsets_m, cants_rad, np.full(n, 1.0 / n), cg_m, np.full(2 * n, float(limit_rad)))


def check_given_mixer(given: np.ndarray, gimbal_m: np.ndarray, offsets_m: np.ndarray, cants_rad: np.ndarray,
                      cg_m: np.ndarray, limit_rad: float, rtol: float = 1e-6) -> list[str]:
    """What a stage's own mixing matrix (``(2 n, 3)``, rows the channels of
    :func:`stage_mixer`, columns ``δr``, ``δp``, ``δy``) fails to do: each command must
    give the moment :func:`stage_mixer`'s does, within ``rtol`` of that moment's largest
    component (``mixer.check_mixing_matrix``); on a stage whose engines cannot roll the
    vehicle the roll column must be 0. An empty list: it is accepted."""
    n = offsets_m.shape[0]
    given = np.asarray(given, float)
    if given.shape != (2 * n, 3):
        return [f"has shape {list(given.shape)}, not [{2 * n}, 3]"]
    own = stage_mixer(gimbal_m, offsets_m, cants_rad, cg_m, limit_rad).reshape(2 * n, 3)
    b, axis = _effectiveness(gimbal_m, offsets_m, cants_rad, cg_m)
    roll_moment = float(b[0] @ own[:, mixer.ROLL])  # per rad of δr: the gains' convention
    if roll_moment == 0.0:
        if np.any(given[:, mixer.ROLL] != 0.0):
            return ["its roll column must be 0: the stage's engines cannot roll the vehicle"]
        roll_moment = 1.0
    # in the mixer's own units (roll in N·m) the allocation check applies as it is
    as_moment = given.copy()
    as_moment[:, mixer.ROLL] = given[:, mixer.ROLL] / roll_moment
    return mixer.check_mixing_matrix(as_moment, b, np.full(2 * n, float(limit_rad)), axis, rtol)


def roll_effectiveness(vehicle, stage: int) -> float:
    """The roll moment of one radian of the roll command ``δr`` per newton of the stage's
    thrust (N·m/rad/N = m/rad, about body x, at the mixer's reference CG); 0 for a stage
    whose engines cannot roll the vehicle. ``stage``: 0 first, 1 upper."""
    gimbal, offsets, cants, cg, limit = stage_geometry(vehicle, stage)
    if offsets.shape[0] == 1:
        return 0.0
    b, _ = _effectiveness(gimbal, offsets, cants, cg)
    k = stage_mixer(gimbal, offsets, cants, cg, limit).reshape(-1, 3)
    return float(b[0] @ k[:, mixer.ROLL])


@njit(cache=True, error_model="numpy", inline="always")
def stage_mounts(tb: np.ndarray, p: np.ndarray, engine: int, config: int) -> tuple[int, int]:
    """The active mount records: the offsets in ``tb`` of the first and past the last
    (the upper stage's from separation on; on the first stage with gimbaled boosters,
    the boosted records while they are attached, configuration 0, then the stage's own)."""
    o, n = tab(tb, T_MOUNTS)
    split = o + int(p[P_UPPER_FIRST]) * MOUNT_SIZE
    if engine != ENGINE_FIRST:
        return split, o + n
    end = o + int(p[P_BOOSTED_END]) * MOUNT_SIZE  # o without booster TVC
    return (o, end) if config == 0 and end > o else (end, split)


@njit(cache=True, error_model="numpy", inline="always")
def gimbal_rates(x: np.ndarray, p: np.ndarray, tb: np.ndarray, engine: int, config: int, roll: float, pitch: float,
                 yaw: float, xd: np.ndarray) -> tuple[float, float]:
    """Mix the flight control's commands to the active stage's channels (and the
    gimbaled boosters' while they are attached) and write every gimbal channel's
    derivatives into ``xd`` (the channels no active engine drives stay at rest).

    Parameters
    ----------
    engine, config : int
        The engine phase and the configuration (:func:`stage_mounts`).
    roll, pitch, yaw : float
        The equivalent roll angle δr and the equivalent engine's pitch and yaw angles
        δp, δy commanded (rad).

    Returns
    -------
    tuple of float
        The first engine's nozzle angular accelerations, pitch and yaw (rad/s²).
    """
    first, stop = stage_mounts(tb, p, engine, config)
    stage = actuator.stage_actuator(p, engine)
    cmd_p = tb[first + M_PITCH_ROLL] * roll + tb[first + M_PITCH_PITCH] * pitch + tb[first + M_PITCH_YAW] * yaw
    cmd_y = tb[first + M_YAW_ROLL] * roll + tb[first + M_YAW_PITCH] * pitch + tb[first + M_YAW_YAW] * yaw
    acc_p = actuator.channel_rates(x, p, stage, 0, cmd_p, xd)  # the first engine: pair 0
    acc_y = actuator.channel_rates(x, p, stage, 1, cmd_y, xd)
    n_ch = int(p[actuator.P_N_CHANNELS])
    if n_ch == 2:  # every stage of one engine: the compiled code keeps this path free of the loops
        return acc_p, acc_y
    used = 2
    boosters = actuator.booster_actuator(p)
    for b in range(first + MOUNT_SIZE, stop, MOUNT_SIZE):  # a cluster's other engines, the gimbaled boosters
        c = 2 * int(tb[b + M_PAIR])
        cmd_p = tb[b + M_PITCH_ROLL] * roll + tb[b + M_PITCH_PITCH] * pitch + tb[b + M_PITCH_YAW] * yaw
        cmd_y = tb[b + M_YAW_ROLL] * roll + tb[b + M_YAW_PITCH] * pitch + tb[b + M_YAW_YAW] * yaw
        act = stage if tb[b + M_BOOSTER] == 0.0 else boosters
        actuator.channel_rates(x, p, act, c, cmd_p, xd)
        actuator.channel_rates(x, p, act, c + 1, cmd_y, xd)
        used += 2
    for c in range(used, n_ch):
        actuator.idle_channel(p, c, xd)
    return acc_p, acc_y


@njit(cache=True, error_model="numpy", inline="always")
def cluster_loads(tb: np.ndarray, p: np.ndarray, x: np.ndarray, xd: np.ndarray, engine: int, config: int,
                  thrust: float, pitch: float, yaw: float, ddp: float, ddy: float, bias_p: float, bias_y: float,
                  flex_p: float, flex_y: float, rgx: float, rgy: float, rgz: float):
    """Thrust and tail-wags-dog loads of the active stage's engines (a gimbaled booster's
    are its own: ``boosters.loads``).

    Parameters
    ----------
    x, xd : ndarray
        The state and its derivative, the gimbal channels' written by
        :func:`gimbal_rates` (a cluster's other engines' angles and nozzle accelerations
        are read there).
    engine, config : int
        The engine phase (the upper stage's engines from separation on) and the
        configuration.
    thrust : float
        The stage's delivered thrust, N.
    pitch, yaw : float
        The first engine's thrust-line angles (its limited actuator angles + the null
        bias − the flex rotation at the gimbal node), rad.
    ddp, ddy : float
        The first engine's nozzle accelerations, rad/s².
    bias_p, bias_y : float
        The stage's nozzle null biases, rad.
    flex_p, flex_y : float
        The flex rotation at the stage's gimbal node about body y and z, rad
        (subtracted: the follower thrust).
    rgx, rgy, rgz : float
        ``r_cg→gimbal`` of the stage's gimbal point, body axes, m.

    Returns
    -------
    tuple of float
        ``(Fx, Fy, Fz, Mx, My, Mz)`` the thrust force (N) and its moment about the CG
        (N·m), then ``(Fx, Fy, Fz, Ty, Tz, Mx, My, Mz)`` the engines' tail-wags-dog force
        and torque at the gimbal and moment about the CG (as ``twd.twd_loads``), then
        ``(Cx, Cy, Cz)`` the couple about the stage's gimbal point of the engines' forces
        (thrust and tail-wags-dog) at their own gimbals, ``Σ Δ_i × F_i`` (N·m; zero for
        one engine), body axes: with the forces' sum, the load a rigid thrust structure
        hands the flexible body at the stage's gimbal node.
    """
    first, stop = stage_mounts(tb, p, engine, config)
    thrust_part, twd_part = engine_loads(tb, p, first, engine, thrust, pitch, yaw, ddp, ddy, rgx, rgy, rgz)
    if stop - first == MOUNT_SIZE:  # one engine: the compiled code keeps this path free of the loop
        return thrust_part, twd_part, (0.0, 0.0, 0.0)
    ftx, fty, ftz, mtx, mty, mtz = thrust_part
    fwx, fwy, fwz, twy, twz, mwx, mwy, mwz = twd_part
    cx, cy, cz = _couple(tb, first, ftx + fwx, fty + fwy, ftz + fwz)
    lim = p[actuator.gimbal_stage(engine) + actuator.G_LIMIT]
    k0 = int(p[actuator.P_CHANNEL_OFFSET])
    for b in range(first + MOUNT_SIZE, stop, MOUNT_SIZE):  # a cluster's other engines
        if tb[b + M_BOOSTER] != 0.0:
            continue  # a gimbaled booster's loads are its own (boosters.loads)
        kp = k0 + 2 * actuator.N_PER_CHANNEL * int(tb[b + M_PAIR])
        ky = kp + actuator.N_PER_CHANNEL
        (fx, fy, fz, mx, my, mz), (wx, wy, wz, ty, tz, nx, ny, nz) = engine_loads(
            tb, p, b, engine, thrust, actuator.clip(x[kp], lim) + bias_p - flex_p,
            actuator.clip(x[ky], lim) + bias_y - flex_y, xd[kp + 1], xd[ky + 1], rgx, rgy, rgz)
        ex, ey, ez = _couple(tb, b, fx + wx, fy + wy, fz + wz)
        cx += ex
        cy += ey
        cz += ez
        ftx += fx
        fty += fy
        ftz += fz
        mtx += mx
        mty += my
        mtz += mz
        fwx += wx
        fwy += wy
        fwz += wz
        twy += ty
        twz += tz
        mwx += nx
        mwy += ny
        mwz += nz
    return (ftx, fty, ftz, mtx, mty, mtz), (fwx, fwy, fwz, twy, twz, mwx, mwy, mwz), (cx, cy, cz)


@njit(cache=True, error_model="numpy", inline="always")
def _couple(tb: np.ndarray, b: int, fx: float, fy: float, fz: float) -> tuple[float, float, float]:
    """``Δ × F`` (N·m, body axes) of the force ``F`` (N, body axes) at the gimbal of the
    engine whose mount record is at ``tb[b]``, about its stage's gimbal point (``Δ``: its
    gimbal offset, structure → body)."""
    ox, oy, oz = -tb[b + M_DX], tb[b + M_DY], -tb[b + M_DZ]
    return oy * fz - oz * fy, oz * fx - ox * fz, ox * fy - oy * fx


@njit(cache=True, error_model="numpy", inline="always")
def engine_loads(tb: np.ndarray, p: np.ndarray, b: int, engine: int, thrust: float, pitch: float, yaw: float,
                 ddp: float, ddy: float, rgx: float, rgy: float, rgz: float):
    """One engine's thrust and tail-wags-dog loads (:func:`cluster_loads`): its mount
    record at ``tb[b]``, its thrust-line angles before its cant (rad) and its nozzle
    accelerations (rad/s²)."""
    ex, ey, ez = rgx - tb[b + M_DX], rgy + tb[b + M_DY], rgz - tb[b + M_DZ]  # structure → body offset
    loads = propulsion.thrust_loads(tb[b + M_SHARE] * thrust, pitch + tb[b + M_CANT_PITCH],
                                    yaw + tb[b + M_CANT_YAW], ex, ey, ez)
    return loads, twd.twd_loads(p, engine, ddp, ddy, ex, ey, ez)
