"""TVC actuators: the third-order model and the simplex (electro-hydraulic) model.

One gimbal channel per engine axis: each engine of a stage has a pitch and a yaw
channel (a channel pair), each :data:`N_PER_CHANNEL` states, the pairs in engine order
from the offset ``P_CHANNEL_OFFSET`` in ``x`` (``models/layout.py``); the simplex model
adds a power-valve block ``[r, ṙ]`` per channel (offset ``P_VALVE_OFFSET``). The stages
share the channels (engine ``i`` of either stage drives pair ``i``): only one stage's
engines are live at a time, and every channel restarts at rest at separation. The
command of each channel (the mixer's, ``models/cluster.py``) is clipped to the stage's
gimbal limit.

Third order (``actuator=third_order``), states ``[δ, δ̇, δ̈]``::

    v = sat(ω_a (δ_c − δ), ±R)                 commanded rate
    δ⃛ = ω_n² (v − δ̇) − 2 ζ ω_n δ̈              second-order load

Unsaturated: δ/δ_c = ω_a ω_n² / (s (s² + 2ζω_n s + ω_n²) + ω_a ω_n²).

Simplex (``actuator=simplex``), states ``[δ, δ̇, θ_p]`` and ``[r, ṙ]``: position loop, power
valve, hydraulic ram and a compliant nozzle mount::

    v   = K_a (δ_c − δ_fb)                        position loop (valve command)
    r̈   = ω_v² (v − r) − 2 ζ_v ω_v ṙ,  |r| ≤ R     power valve: spool (flow as no-load
                                                   ram rate) against its stops
    θ̇_p = r − c_l K (θ_p − δ)                     ram: flow minus leakage
    J δ̈ = K (θ_p − δ) − C δ̇                       nozzle on a compliant mount

``δ_fb`` is the ram position (LVDT, ``feedback: piston``) or the nozzle angle. With
ω_v → ∞, c_l = 0 and nozzle feedback this is the third-order model with ω_a = K_a,
ω_n² = K/J, 2ζω_n = C/J.

Limits bound the hardware, not only the command (issue 12):

* **Rate limit.** The third-order nozzle rate δ̇ and the simplex spool r are integrator
  states held at ±R by a hard stop: while one sits at its limit and is driven outward its
  derivative is zero (so the third-order δ̈, and the tail-wags-dog load with it, is zero
  during a constant-rate slew), and after every plant step :func:`contain` puts it back
  on the limit and clears the outward rate of change it would carry (anti-windup:
  δ̈ for the third order, ṙ for the spool). The simplex nozzle may exceed R only through
  its mount compliance.
* **Gimbal stop.** δ is held at ±limit the same way for both models: at the stop the
  nozzle neither moves nor accelerates outward, and :func:`contain` clears an outward
  δ̇ (an inelastic stop, no run-through).

Source: SAVANT §III, "TVC actuator" (the paper's simplex model); ``docs/models.md``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.models import blocks
from savant_cli.models.configurations import ENGINE_FIRST

THIRD_ORDER = 0
SIMPLEX = 1
#: States of one gimbal channel: third order [δ, δ̇, δ̈], simplex [δ, δ̇, θ_piston]
#: (rad, rad/s, rad/s² or rad).
N_PER_CHANNEL = 3
#: Simplex power-valve states of one channel: [r, ṙ] (rad/s, rad/s²).
N_VALVE_PER_CHANNEL = 2

THIRD = blocks.Record(
    "third-order actuator",
    ("loop_gain", "rad/s", "position-loop gain ω_a"),
    ("natural_frequency", "rad/s", "load natural frequency ω_n"),
    ("damping", "1", "load damping ratio ζ"),
    ("rate_limit", "rad/s", "commanded-rate limit"),
)
T3_LOOP_GAIN, T3_NATURAL_FREQUENCY, T3_DAMPING, T3_RATE_LIMIT = THIRD.offsets
SPX = blocks.Record(
    "simplex actuator",
    ("loop_gain", "1/s", "position-loop gain K_a"),
    ("valve_frequency", "rad/s", "power-valve natural frequency ω_v"),
    ("valve_damping", "1", "power-valve damping ratio ζ_v"),
    ("rate_limit", "rad/s", "valve flow saturation as no-load ram rate"),
    ("stiffness", "N*m/rad", "mount stiffness K"),
    ("damping", "N*m*s/rad", "mount damping C"),
    ("load_inertia", "kg*m^2", "nozzle inertia about its gimbal J"),
    ("leakage", "rad/s/(N*m)", "leakage coefficient c_l"),
    ("nozzle_feedback", "1", "1: the loop feeds back the nozzle angle; 0: the ram LVDT"),
)
(SX_LOOP_GAIN, SX_VALVE_FREQUENCY, SX_VALVE_DAMPING, SX_RATE_LIMIT, SX_STIFFNESS, SX_DAMPING, SX_LOAD_INERTIA, SX_LEAKAGE,
 SX_NOZZLE_FEEDBACK) = SPX.offsets
STAGE = blocks.Record(
    "gimbal",
    ("limit", "rad", "gimbal angle limit, per axis"),
    ("bias_pitch", "rad", "nozzle null bias (thrust-line misalignment), pitch"),
    ("bias_yaw", "rad", "nozzle null bias, yaw"),
)
G_LIMIT, G_BIAS_PITCH, G_BIAS_YAW = STAGE.offsets

_PARAMS = blocks.PARAMETERS.block("actuator")
P_KIND = _PARAMS.scalar("kind", "1", "0 third order, 1 simplex")
P_VALVE_OFFSET = _PARAMS.scalar("valve_offset", "1", "offset of the simplex valve states in x (−1: none)")
P_CHANNEL_OFFSET = _PARAMS.scalar("channel_offset", "1",
                                  "offset in x of the first engine's pitch channel; its yaw channel and the other "
                                  "engines' pairs follow")
P_FS_GIMBAL = _PARAMS.record("first_stage", STAGE, "first-stage gimbal")
P_US_GIMBAL = _PARAMS.record("upper_stage", STAGE, "upper-stage gimbal")
P_FS_THIRD = _PARAMS.record("first_stage.third_order", THIRD, "first-stage third-order actuator")
P_US_THIRD = _PARAMS.record("upper_stage.third_order", THIRD, "upper-stage third-order actuator")
P_FS_SPX = _PARAMS.record("first_stage.simplex", SPX, "first-stage simplex actuator")
P_US_SPX = _PARAMS.record("upper_stage.simplex", SPX, "upper-stage simplex actuator")
P_N_CHANNELS = _PARAMS.scalar("channels", "1", "gimbal channels: two per engine of the stage with the most engines")
P_BOOSTER_CHANNEL = _PARAMS.scalar("booster_channel", "1", "the first gimbaled booster's pitch channel (its yaw "
                                   "channel and the other boosters' pairs follow; −1: no booster TVC)")
P_BOOSTER_GIMBAL = _PARAMS.record("boosters", STAGE, "the strap-on boosters' gimbals")
P_BOOSTER_THIRD = _PARAMS.record("boosters.third_order", THIRD, "the boosters' third-order actuators")
P_BOOSTER_SPX = _PARAMS.record("boosters.simplex", SPX, "the boosters' simplex actuators")
_AUX = blocks.DIAGNOSTICS.block("actuator")
# the first engine's (a cluster's other engines: their channels' states); null bias not included
A_ANGLES = _AUX.array("angles", 2, "rad", "engine gimbal angles (limited)",
                      blocks.Logged("gimbal_angle", ("pitch", "yaw"), "body"))
A_ACCEL = _AUX.array("accelerations", 2, "rad/s^2", "nozzle angular accelerations (zero while held at a gimbal stop)",
                     blocks.Logged("gimbal_acceleration", ("pitch", "yaw"), "body"))


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, pitch: float, yaw: float, pitch_accel: float, yaw_accel: float) -> None:
    """Write the limited actuator angles (rad) and the nozzle angular accelerations
    (rad/s²), pitch and yaw, into ``aux``."""
    aux[A_ANGLES] = pitch
    aux[A_ANGLES + 1] = yaw
    aux[A_ACCEL] = pitch_accel
    aux[A_ACCEL + 1] = yaw_accel


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """The ``actuator`` group (the record of its variant; ``kind`` selects it) and the
    vehicle's gimbal limits; the boosters' records with booster TVC only (zero, never
    read, otherwise)."""
    cfg, v = inputs.cfg, inputs.vehicle
    p[P_KIND] = SIMPLEX if cfg.actuator.name == "simplex" else THIRD_ORDER
    p[P_VALVE_OFFSET] = inputs.layout.valve
    p[P_CHANNEL_OFFSET] = inputs.layout.channel(0)
    p[P_N_CHANNELS] = len(inputs.layout.channels)
    p[P_BOOSTER_CHANNEL] = 2 * v.first_stage_engine_count if v.gimbaled_boosters else -1
    stages = [("first_stage", v.first_stage.gimbal_limit_rad, v.first_stage.engine, P_FS_GIMBAL, P_FS_THIRD, P_FS_SPX),
              ("upper_stage", v.upper_stage.gimbal_limit_rad, v.upper_stage.engine, P_US_GIMBAL, P_US_THIRD, P_US_SPX)]
    if v.gimbaled_boosters:
        stages.append(("boosters", v.boosters.gimbal_limit_rad, v.boosters.engine, P_BOOSTER_GIMBAL, P_BOOSTER_THIRD,
                       P_BOOSTER_SPX))
    for name, limit, engine, pg, p3, px in stages:
        a = getattr(cfg.actuator, name)
        p[pg + G_LIMIT] = limit
        p[pg + G_BIAS_PITCH], p[pg + G_BIAS_YAW] = np.radians(a.null_bias_deg)
        if cfg.actuator.name == "simplex":
            p[px:px + SPX.size] = (a.loop_gain_rad_s, 2.0 * np.pi * a.valve_frequency_hz, a.valve_damping,
                                   np.radians(a.rate_limit_deg_s), a.stiffness_Nm_per_rad, a.damping_Nms_per_rad,
                                   engine.inertia_about_gimbal_kgm2, a.leakage_rad_s_per_Nm,
                                   1.0 if a.feedback == "nozzle" else 0.0)
        else:
            p[p3 + T3_LOOP_GAIN] = a.loop_gain_rad_s
            p[p3 + T3_NATURAL_FREQUENCY] = 2.0 * np.pi * a.natural_frequency_hz
            p[p3 + T3_DAMPING] = a.damping
            p[p3 + T3_RATE_LIMIT] = np.radians(a.rate_limit_deg_s)


@njit(cache=True, error_model="numpy", inline="always")
def clip(x: float, lim: float) -> float:
    """``x`` limited to ``[−lim, lim]``."""
    if x > lim:
        return lim
    if x < -lim:
        return -lim
    return x


@njit(cache=True, error_model="numpy", inline="always")
def held(value: float, limit: float, push: float) -> bool:
    """Whether a state at ``value`` is held by its stop at ±``limit`` against a push of
    sign ``push`` (at or beyond the stop and driven outward)."""
    return (value >= limit and push > 0.0) or (value <= -limit and push < 0.0)


@njit(cache=True, error_model="numpy", inline="always")
def at_gimbal_stop(d: float, rate: float, acc: float, limit: float, out: np.ndarray, k: int) -> float:
    """The nozzle's ``δ̇``, ``δ̈`` into ``out[k]``, ``out[k + 1]``, each zero while the
    gimbal stop at ±``limit`` holds the nozzle against it; returns that δ̈ (rad/s²)."""
    if held(d, limit, rate):
        rate = 0.0
    if held(d, limit, acc):
        acc = 0.0
    out[k] = rate
    out[k + 1] = acc
    return acc


@njit(cache=True, error_model="numpy", inline="always")
def third_order(x: np.ndarray, k: int, cmd: float, p: np.ndarray, base: int, limit: float,
                out: np.ndarray) -> float:
    """Third-order actuator: states ``x[k:k+3] = [δ, δ̇, δ̈]``, derivatives into
    ``out[k:k+3]``; ``cmd`` is δ_c (rad), ``limit`` the gimbal stop (rad); ``p[base:]`` a
    :data:`THIRD` record. Returns the nozzle angular acceleration (rad/s²): δ̈, or 0 while
    the rate limit or the stop holds the nozzle."""
    wn = p[base + T3_NATURAL_FREQUENCY]
    rate_limit = p[base + T3_RATE_LIMIT]
    d, rate, acc = x[k], x[k + 1], x[k + 2]
    v = clip(p[base + T3_LOOP_GAIN] * (cmd - d), rate_limit)
    out[k + 2] = wn * wn * (v - rate) - 2.0 * p[base + T3_DAMPING] * wn * acc
    if held(rate, rate_limit, acc):
        acc = 0.0
    return at_gimbal_stop(d, rate, acc, limit, out, k)


@njit(cache=True, error_model="numpy", inline="always")
def simplex(x: np.ndarray, k: int, kv: int, cmd: float, p: np.ndarray, base: int, limit: float,
            out: np.ndarray) -> float:
    """Simplex actuator: states ``x[k:k+3] = [δ, δ̇, θ_p]`` and valve ``x[kv:kv+2] = [r, ṙ]``,
    derivatives into ``out``; ``limit`` the gimbal stop (rad); ``p[base:]`` a :data:`SPX`
    record. Returns the nozzle angular acceleration δ̈ (rad/s²; 0 while the stop holds it)."""
    d, rate, th = x[k], x[k + 1], x[k + 2]
    r, r_dot = x[kv], x[kv + 1]
    fb = d if p[base + SX_NOZZLE_FEEDBACK] > 0.5 else th
    rl = p[base + SX_RATE_LIMIT]
    v = p[base + SX_LOOP_GAIN] * (cmd - fb)
    wv = p[base + SX_VALVE_FREQUENCY]
    r_acc = wv * wv * (v - r) - 2.0 * p[base + SX_VALVE_DAMPING] * wv * r_dot
    if held(r, rl, r_dot):  # the spool on its stop: the flow holds at the limit
        r_dot = 0.0
    if held(r, rl, r_acc):
        r_acc = 0.0
    torque = p[base + SX_STIFFNESS] * (th - d)
    out[k + 2] = r - p[base + SX_LEAKAGE] * torque
    out[kv] = r_dot
    out[kv + 1] = r_acc
    return at_gimbal_stop(d, rate, (torque - p[base + SX_DAMPING] * rate) / p[base + SX_LOAD_INERTIA], limit, out, k)


@njit(cache=True, error_model="numpy", inline="always")
def _stop(x: np.ndarray, i: int, limit: float) -> bool:
    """Put ``x[i]`` back on its stop at ±``limit`` and clear an outward rate of change at
    ``x[i + 1]``; whether it was at the stop."""
    if x[i] >= limit:
        x[i] = limit
        if x[i + 1] > 0.0:
            x[i + 1] = 0.0
        return True
    if x[i] <= -limit:
        x[i] = -limit
        if x[i + 1] < 0.0:
            x[i + 1] = 0.0
        return True
    return False


@njit(cache=True, error_model="numpy", inline="always")
def limits(p: np.ndarray, engine: int) -> tuple[float, float]:
    """The stage's rate limit (rad/s: the third-order nozzle rate's, the simplex spool
    flow's) and gimbal limit (rad); the upper stage's from separation on."""
    first = engine == ENGINE_FIRST
    if int(p[P_KIND]) == SIMPLEX:
        rate = p[(P_FS_SPX if first else P_US_SPX) + SX_RATE_LIMIT]
    else:
        rate = p[(P_FS_THIRD if first else P_US_THIRD) + T3_RATE_LIMIT]
    return rate, p[gimbal_stage(engine) + G_LIMIT]


@njit(cache=True, error_model="numpy", inline="always")
def booster_limits(p: np.ndarray) -> tuple[float, float]:
    """The gimbaled boosters' rate limit (rad/s, as :func:`limits`) and gimbal limit (rad)."""
    if int(p[P_KIND]) == SIMPLEX:
        return p[P_BOOSTER_SPX + SX_RATE_LIMIT], p[P_BOOSTER_GIMBAL + G_LIMIT]
    return p[P_BOOSTER_THIRD + T3_RATE_LIMIT], p[P_BOOSTER_GIMBAL + G_LIMIT]


@njit(cache=True, error_model="numpy")
def contain(x: np.ndarray, p: np.ndarray, engine: int) -> None:
    """After a plant step: the active stage's gimbal stop on every channel's δ, and the
    rate stop (the third-order δ̇, the simplex spool r), each with its outward rate of
    change cleared; on the first stage the gimbaled boosters' channels
    (``P_BOOSTER_CHANNEL`` on) at the boosters' own stops."""
    rl, lim = limits(p, engine)
    k0 = int(p[P_CHANNEL_OFFSET])
    vo = int(p[P_VALVE_OFFSET])
    n = int(p[P_N_CHANNELS])
    boosted = n
    if engine == ENGINE_FIRST and p[P_BOOSTER_CHANNEL] >= 0.0:
        boosted = int(p[P_BOOSTER_CHANNEL])
    for c in range(n):
        if c == boosted:
            rl, lim = booster_limits(p)
        if int(p[P_KIND]) == SIMPLEX:
            _stop(x, vo + N_VALVE_PER_CHANNEL * c, rl)
            _stop(x, k0 + N_PER_CHANNEL * c, lim)
        else:
            k = k0 + N_PER_CHANNEL * c
            _stop(x, k + 1, rl)
            if _stop(x, k, lim) and x[k + 2] * x[k] > 0.0:
                x[k + 2] = 0.0  # no outward acceleration at the stop


@njit(cache=True, error_model="numpy")
def rest(x: np.ndarray, p: np.ndarray) -> None:
    """Every gimbal channel (and its power valve) at rest at null: the stages' engines
    change at separation."""
    k0 = int(p[P_CHANNEL_OFFSET])
    n = int(p[P_N_CHANNELS])
    x[k0:k0 + N_PER_CHANNEL * n] = 0.0
    vo = int(p[P_VALVE_OFFSET])
    if vo >= 0:
        x[vo:vo + N_VALVE_PER_CHANNEL * n] = 0.0


@njit(cache=True, error_model="numpy", inline="always")
def channels(p: np.ndarray) -> tuple[int, int]:
    """Indices in ``x`` of the first engine's pitch and yaw channel's first state (δ)."""
    k = int(p[P_CHANNEL_OFFSET])
    return k, k + N_PER_CHANNEL


@njit(cache=True, error_model="numpy", inline="always")
def gimbal_stage(engine: int) -> int:
    """Offset of the active stage's :data:`STAGE` record (upper stage from separation on)."""
    return P_FS_GIMBAL if engine == ENGINE_FIRST else P_US_GIMBAL


@njit(cache=True, error_model="numpy", inline="always")
def stage_actuator(p: np.ndarray, engine: int) -> tuple[int, int, int, int, float]:
    """The active stage's actuator: whether simplex (1) or third order (0), the offset of
    its parameter record in ``p``, the offsets of the first gimbal channel and of the
    first power valve in ``x`` (−1: none), and the gimbal limit (rad)."""
    first = engine == ENGINE_FIRST
    if int(p[P_KIND]) == SIMPLEX:
        kind, base = SIMPLEX, P_FS_SPX if first else P_US_SPX
    else:
        kind, base = THIRD_ORDER, P_FS_THIRD if first else P_US_THIRD
    return kind, base, int(p[P_CHANNEL_OFFSET]), int(p[P_VALVE_OFFSET]), p[gimbal_stage(engine) + G_LIMIT]


@njit(cache=True, error_model="numpy", inline="always")
def booster_actuator(p: np.ndarray) -> tuple[int, int, int, int, float]:
    """The gimbaled boosters' actuator, as :func:`stage_actuator` gives a stage's."""
    if int(p[P_KIND]) == SIMPLEX:
        kind, base = SIMPLEX, P_BOOSTER_SPX
    else:
        kind, base = THIRD_ORDER, P_BOOSTER_THIRD
    return kind, base, int(p[P_CHANNEL_OFFSET]), int(p[P_VALVE_OFFSET]), p[P_BOOSTER_GIMBAL + G_LIMIT]


@njit(cache=True, error_model="numpy", inline="always")
def channel_rates(x: np.ndarray, p: np.ndarray, stage: tuple[int, int, int, int, float], c: int, cmd: float,
                  xd: np.ndarray) -> float:
    """Write the derivatives of gimbal channel ``c`` (and of its power valve) into ``xd``
    for the command ``cmd`` (rad, clipped to the gimbal limit); ``stage`` is
    :func:`stage_actuator`'s. Returns the nozzle's angular acceleration (rad/s²; zero
    while a stop holds it), which is also ``xd`` of the channel's δ̇."""
    kind, base, k0, vo, lim = stage
    k = k0 + N_PER_CHANNEL * c
    if kind == SIMPLEX:
        return simplex(x, k, vo + N_VALVE_PER_CHANNEL * c, clip(cmd, lim), p, base, lim, xd)
    return third_order(x, k, clip(cmd, lim), p, base, lim, xd)


@njit(cache=True, error_model="numpy", inline="always")
def idle_channel(p: np.ndarray, c: int, xd: np.ndarray) -> None:
    """Zero derivatives for gimbal channel ``c`` (and its power valve): no engine of the
    active stage drives it, and it stays at rest."""
    k = int(p[P_CHANNEL_OFFSET]) + N_PER_CHANNEL * c
    xd[k:k + N_PER_CHANNEL] = 0.0
    vo = int(p[P_VALVE_OFFSET])
    if vo >= 0:
        xd[vo + N_VALVE_PER_CHANNEL * c:vo + N_VALVE_PER_CHANNEL * (c + 1)] = 0.0


@njit(cache=True, error_model="numpy", inline="always")
def gimbal_angles(x: np.ndarray, p: np.ndarray, engine: int) -> tuple[float, float, float, float]:
    """The first engine's limited actuator angles δp, δy and the active stage's null
    biases pitch, yaw (rad)."""
    g = gimbal_stage(engine)
    lim = p[g + G_LIMIT]
    kp, ky = channels(p)
    return clip(x[kp], lim), clip(x[ky], lim), p[g + G_BIAS_PITCH], p[g + G_BIAS_YAW]
