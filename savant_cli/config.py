"""Configuration schema (structured dataclasses) and physical validation.

Hydra composes the YAML tree in ``conf/``; :func:`validate` then merges the result onto
the schema, which refuses unknown keys and wrong types, and checks physical sense
(rates that divide each other, positive frequencies, blending weights summing to 1 …).
Every refusal is a :class:`savant_cli.errors.ConfigError` naming the key, the value and
what is allowed; the command line turns it into exit status 2. Nothing here imports
Hydra: the schema is put in Hydra's ConfigStore by
:func:`savant_cli.hydra_compose.register_schema`, which the entry points call.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np
from omegaconf import DictConfig, OmegaConf
from omegaconf.errors import OmegaConfBaseException

from savant_cli.errors import ConfigError

# --------------------------------------------------------------------------- schema


@dataclass
class HealthConfig:
    """``sim.health``: when a run that flew to its end is not a clean ``complete``
    (``savant_cli/sim/health.py``)."""

    max_saturation_s: float = 1.0  # s on a rate limit or gimbal stop (per stage) → "saturated"
    min_amplitude_deg: float = 0.1  # limit cycle, slow divergence: smallest amplitude (gimbal angle, attitude error)
    min_periods: float = 5.0  # limit cycle: the oscillation holds for at least this many periods
    tonal_fraction: float = 0.5  # limit cycle: share of the detrended variance in the periodic part
    max_damping_ratio: float = 0.005  # limit cycle: an envelope decaying (or growing) this fast is not sustained
    event_quiet_s: float = 20.0  # limit cycle, slow divergence: s left out after each event
    divergence_growth: float = 10.0  # slow divergence: attitude-error envelope growth (–) to the stage's end
    divergence_min_amplitude_deg: float = 1.0  # slow divergence: ... reaching this (deg): 1/10 of the LOC bound
    max_attitude_error_deg: float = 10.0  # loss of control: pitch/yaw attitude-error magnitude bound
    max_alpha_deg: Optional[float] = None  # loss of control: total angle-of-attack bound (None: off)
    alpha_min_dynamic_pressure_Pa: float = 1000.0  # the α bound applies from this dynamic pressure on


@dataclass
class SimConfig:
    plant_rate_hz: float = 200.0
    sensor_rate_hz: float = 200.0
    fcs_rate_hz: float = 50.0
    guidance_rate_hz: float = 1.0
    log_rate_hz: float = 50.0
    max_time_s: float = 800.0
    chunk_s: float = 10.0
    progress: bool = True
    max_body_rate_deg_s: float = 60.0
    health: HealthConfig = field(default_factory=HealthConfig)


@dataclass
class EnvironmentConfig:
    gravity_order: int = 4
    aero: bool = True
    thrust: bool = True


@dataclass
class OutputConfig:
    hdf5: bool = True
    plots: bool = True
    console: str = "full"  # full | summary | quiet (savant_cli.io.console.CONSOLE_MODES)


@dataclass
class PhaseConfig:
    name: str = "ascent"
    start: str = "liftoff"  # liftoff | staging (from staging_state_file)
    stop_at: str = "cutoff"
    staging_state_file: str = ""


@dataclass
class StudyConfig:
    """``study=nominal``: one flight."""

    name: str = "nominal"


@dataclass
class RigidRequirement:
    """Rigid-body margins: the gain-increase margin of the phase crossover above the
    control bandwidth (dB), the gain-reduction margin below it where the vehicle has no
    aerodynamic instability (the integrator's conditional stability, dB), and the phase
    margin at the bandwidth (deg)."""

    gain_dB: float = 6.0
    gain_reduction_dB: float = 6.0
    phase_deg: float = 30.0


@dataclass
class AeroRequirement:
    """Gain-reduction margin of the aerodynamically unstable vehicle (dB)."""

    gain_dB: float = 6.0


@dataclass
class SloshRequirement:
    """Margins of the crossings a propellant-slosh mode makes (dB, deg)."""

    gain_dB: float = 6.0
    phase_deg: float = 30.0


#: How a bending mode is required to be stabilized (``linear/requirements.py``).
STABILIZATIONS = ("gain", "phase", "either")


@dataclass
class FlexModeRequirement:
    """One bending mode's requirement: ``gain``-stabilized (its loop peak at least
    ``gain_dB`` below 0 dB), ``phase``-stabilized (every crossing it makes: phase margin
    at least ``phase_deg``, gain margin at least ``gain_dB``) or ``either``."""

    stabilization: str = "either"
    gain_dB: float = 6.0
    phase_deg: float = 30.0


@dataclass
class FlexStageRequirement:
    """A stage's bending-mode requirements: ``default`` for every mode, ``modes`` (keys
    ``flex_<n>``, the 1-based retained mode) for the modes that differ."""

    default: FlexModeRequirement = field(default_factory=FlexModeRequirement)
    modes: dict[str, FlexModeRequirement] = field(default_factory=dict)


@dataclass
class FlexRequirement:
    first_stage: FlexStageRequirement = field(default_factory=FlexStageRequirement)
    upper_stage: FlexStageRequirement = field(default_factory=FlexStageRequirement)


@dataclass
class SeparationRequirement:
    """The vehicle's state at first-stage separation (``requirements.separation``),
    judged in every flight: the largest body-rate magnitude (deg/s), pitch/yaw
    attitude-error magnitude (deg) and total q·α (Pa·deg) at the separation step; None:
    not judged. A run outside falls in the mission class ``separation_state``."""

    max_body_rate_deg_s: Optional[float] = None
    max_attitude_error_deg: Optional[float] = None
    max_qalpha_Pa_deg: Optional[float] = None


@dataclass
class MissionRequirement:
    """Which mission failure classes (``savant_cli/sim/mission.py``) count as a failed
    mission: a run succeeds when none of its classes is listed. All, by default."""

    failure_classes: list[str] = field(default_factory=lambda: list(_failure_classes()))


def _failure_classes() -> tuple[str, ...]:
    from savant_cli.io.record import FAILURE_CLASSES

    return FAILURE_CLASSES


@dataclass
class RequirementSet:
    """The stability-margin requirement set (group ``requirements``, selected by the
    vehicle config): what every linear margin, point and study is judged against
    (``savant_cli/linear/requirements.py``)."""

    name: str = "none"
    source: str = ""
    rigid: RigidRequirement = field(default_factory=RigidRequirement)
    aero: AeroRequirement = field(default_factory=AeroRequirement)
    slosh: SloshRequirement = field(default_factory=SloshRequirement)
    flex: FlexRequirement = field(default_factory=FlexRequirement)
    separation: SeparationRequirement = field(default_factory=SeparationRequirement)
    mission: MissionRequirement = field(default_factory=MissionRequirement)

    def flex_mode(self, stage: str, mode: str) -> FlexModeRequirement:
        """The requirement of bending mode ``mode`` (``flex_<n>``) in ``stage``
        (``first_stage`` or ``upper_stage``)."""
        st = getattr(self.flex, stage)
        return st.modes.get(mode, st.default)

    def by_band(self) -> dict[str, tuple[float, float]]:
        """Band → (gain margin dB, phase margin deg) the charts mark: the rigid body's,
        the slosh modes' and the first stage's default bending-mode requirement."""
        fd = self.flex.first_stage.default
        return {"rigid/aero": (self.rigid.gain_dB, self.rigid.phase_deg),
                "slosh": (self.slosh.gain_dB, self.slosh.phase_deg), "flex": (fd.gain_dB, fd.phase_deg)}


def check_requirements(r: RequirementSet) -> None:
    """Margins are non-negative finite numbers; stabilizations one of
    :data:`STABILIZATIONS`; per-mode keys ``flex_<n>``."""
    for key, value in (("rigid.gain_dB", r.rigid.gain_dB), ("rigid.gain_reduction_dB", r.rigid.gain_reduction_dB),
                       ("rigid.phase_deg", r.rigid.phase_deg), ("aero.gain_dB", r.aero.gain_dB),
                       ("slosh.gain_dB", r.slosh.gain_dB), ("slosh.phase_deg", r.slosh.phase_deg)):
        _non_negative(f"requirements.{key}", value)
    for stage in ("first_stage", "upper_stage"):
        st = getattr(r.flex, stage)
        for name, m in [("default", st.default)] + [(f"modes.{k}", v) for k, v in st.modes.items()]:
            key = f"requirements.flex.{stage}.{name}"
            if name != "default" and not re.fullmatch(r"modes\.flex_[1-9][0-9]*", name):
                raise ConfigError(key, name.split(".", 1)[1], "a bending mode is named flex_<n> (1-based retained mode)")
            _one_of(f"{key}.stabilization", m.stabilization, STABILIZATIONS)
            _non_negative(f"{key}.gain_dB", m.gain_dB)
            _non_negative(f"{key}.phase_deg", m.phase_deg)
    for name in ("max_body_rate_deg_s", "max_attitude_error_deg", "max_qalpha_Pa_deg"):
        value = getattr(r.separation, name)
        if value is not None:
            _positive(f"requirements.separation.{name}", value)
    allowed = _failure_classes()
    for i, c in enumerate(r.mission.failure_classes):
        _one_of(f"requirements.mission.failure_classes[{i}]", c, allowed)
    if len(set(r.mission.failure_classes)) != len(r.mission.failure_classes):
        raise ConfigError("requirements.mission.failure_classes", list(r.mission.failure_classes),
                          "names each class at most once")


@dataclass
class FrozenTimeSpec:
    """``study.frozen_time``: the first-stage tail-off window, where frozen-time margins
    are analysed and reported but not judged, and the time domain judges instead
    (``linear/frozen_time.py``, ``timedomain/tailoff.py``; docs/requirements.md)."""

    # period: crossover period >= time to separation; control_power: the control power
    # falls within one period by the rigid gain requirement; []: no window, judge every point
    criteria: list[str] = field(default_factory=lambda: ["period", "control_power"])
    scan_s: float = 20.0  # s before the flown separation scanned for the criteria
    step_s: float = 0.5  # s between scan points
    excitation_deg: float = 0.5  # time-domain checks: doublet at the gimbal command, deg ...
    excitation_s: float = 0.4  # ... and its duration, s


@dataclass
class LinearStudyConfig:
    """``study=linear``: frozen-time linearization and stability margins."""

    name: str = "linear"
    times: list[float] = field(default_factory=lambda: [55.0, 130.0, 180.0, 230.0])
    every: float = 0.0  # > 0: points every `every` s over the whole flight instead of `times`
    event_clearance_s: float = 0.1  # a time this close to an event is refused (skipped with `every`)
    # the first-stage tail-off window: points in it are analysed and reported but judged
    # in the time domain (separation state with the required margins inserted)
    frozen_time: FrozenTimeSpec = field(default_factory=FrozenTimeSpec)
    jacobian: str = "auto"  # auto: per-state steps; fixed: one user step
    jacobian_step: float = 1e-6  # the fixed step, as an attitude perturbation in rad
    charts: str = "auto"  # all | none | auto (per-point charts up to 20 points)
    exclusion_zones: bool = True  # Nichols exclusion zones


@dataclass
class DispersionSpec:
    """One dispersed quantity of ``study=montecarlo`` (see docs/montecarlo.md).

    ``target``: a config path (``winds.scale``, ``sensors.misalignment_deg.imu[1]``), a
    loaded-vehicle attribute (``vehicle.upper_stage.isp_vac_s``), a vehicle-table
    quantity (``tables.first_stage.thrust`` …) or the config group ``winds``.
    ``apply``: the sample multiplies (``scale``), is added to (``offset``) or replaces
    (``value``) the nominal."""

    target: str = ""
    apply: str = "scale"  # scale | offset | value
    dist: str = "normal"  # normal | uniform | triangular | choice | constant
    mean: Any = None  # normal; default 1 for scale, 0 for offset
    sigma: float = 0.0  # normal
    truncate_sigma: float = 0.0  # normal: > 0 truncates at ± this many σ
    low: Any = None  # uniform, triangular
    high: Any = None  # uniform, triangular
    mode: Any = None  # triangular
    values: list[Any] = field(default_factory=list)  # choice
    weights: list[float] = field(default_factory=list)  # choice (default equal)
    value: Any = None  # constant
    source: str = ""  # where the numbers come from


@dataclass
class CorrelationGroup:
    """Dispersions drawn with a correlation matrix (Gaussian copula)."""

    names: list[str] = field(default_factory=list)
    matrix: list[list[float]] = field(default_factory=list)


@dataclass
class DispersionSetConfig:
    """A vehicle's dispersion set (the ``dispersions`` group, selected by the vehicle
    config): what ``study=montecarlo`` and ``study=flyoff`` disperse. Other studies fly
    the nominal vehicle and do not read it."""

    name: str = "none"
    items: dict[str, DispersionSpec] = field(default_factory=dict)
    correlations: list[CorrelationGroup] = field(default_factory=list)


@dataclass
class HistoriesSpec:
    """Decimated time histories kept for every run (empty list: none)."""

    signals: list[str] = field(default_factory=list)
    rate_hz: float = 5.0


@dataclass
class ReliabilitySpec:
    """The success probability a batch demonstrates (``montecarlo/reliability.py``)."""

    confidence: float = 0.9  # one-sided confidence level of the demonstrated probability
    target_probability: float = 0.9973  # the success probability the batch is to demonstrate
    # the flight-performance reserve covers this fraction of dispersed flights, at
    # ``confidence`` (montecarlo/insertion.py): 99.865 %, the 3-sigma-low flight
    reserve_probability: float = 0.99865


@dataclass
class MonteCarloStudyConfig:
    """``study=montecarlo``: dispersed full-fidelity ascents."""

    name: str = "montecarlo"
    n_runs: int = 1000  # run 0 is the nominal
    seed: int = 20261123  # master seed; run i uses SeedSequence(seed).spawn(n)[i]
    workers: int = 0  # processes; 0: all cores
    shards: int = 1  # split the batch into this many shards …
    shard: int = 0  # … and fly this one (Hydra multirun: study.shard='range(0,N)')
    histories: HistoriesSpec = field(default_factory=HistoriesSpec)
    linear_times: list[float] = field(default_factory=list)  # s: margins of every run at these times
    reliability: ReliabilitySpec = field(default_factory=ReliabilitySpec)


@dataclass
class FlyoffStudyConfig(MonteCarloStudyConfig):
    """``study=flyoff``: two or more controllers fly the same nominal and the same
    dispersed runs (the Monte Carlo keys apply to each), compared metric by metric."""

    name: str = "flyoff"
    controllers: list[str] = field(default_factory=lambda: ["msfc_pid", "larc_pd"])


@dataclass
class ModeRetentionStudyConfig:
    """``study=mode_retention``: add bending modes lowest first until the response and
    the margins stop changing."""

    name: str = "mode_retention"
    times: list[float] = field(default_factory=lambda: [55.0, 180.0, 230.0])
    step: int = 1  # modes added per step (2: a bending mode in both planes)
    max_modes: int = 0  # 0: as many as the modal data and the plant rate allow
    response_duration_s: float = 5.0  # closed-loop attitude-command step responses compared
    response_tolerance: float = 0.05  # of the response's peak
    margin_tolerance_dB: float = 0.5
    margin_tolerance_deg: float = 2.0


@dataclass
class FlexSweepStudyConfig:
    """``study=flex_sweep``: margins and Nichols charts with the bending frequencies, and
    separately the mode-shape magnitudes, scaled over a grid (the GVT decision study)."""

    name: str = "flex_sweep"
    times: list[float] = field(default_factory=lambda: [55.0, 130.0, 180.0, 230.0])
    parameters: list[str] = field(default_factory=lambda: ["frequency", "shape"])  # frequency | shape
    levels: list[float] = field(default_factory=lambda: [0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.3])
    modes: list[int] = field(default_factory=list)  # 1-based retained modes varied; empty: all
    chart_axes: list[str] = field(default_factory=lambda: ["pitch"])  # loops overlaid in the Nichols charts
    event_clearance_s: float = 0.1
    exclusion_zones: bool = True


@dataclass
class DesignParameter:
    """One free parameter of ``study=fcs_design``: its starting value (``None``: the design
    rules' own) and bounds."""

    initial: Any = None
    low: float = 0.0
    high: float = 0.0


@dataclass
class ScheduleParameters:
    """The tuned parameters of one gain schedule (``null``: not tuned;
    ``savant_cli/design/parameters.py``)."""

    omega: Optional[DesignParameter] = None  # rad/s, pole-placement natural frequency (first breakpoint)
    omega_end: Optional[DesignParameter] = None  # rad/s, at the last breakpoint (linear in between)
    zeta: Optional[DesignParameter] = None  # pole-placement damping
    integral_ratio: Optional[DesignParameter] = None  # integral gain / (omega x attitude stiffness)
    kir_share: Optional[DesignParameter] = None  # attitude stiffness in the integrated-rate path
    lowpass_hz: Optional[DesignParameter] = None  # Butterworth corner of the rate paths, Hz
    notch1_hz: Optional[DesignParameter] = None
    notch1_q: Optional[DesignParameter] = None
    notch2_hz: Optional[DesignParameter] = None
    notch2_q: Optional[DesignParameter] = None
    blend_first: Optional[DesignParameter] = None  # stack only: first-stage gyro weight in the rate blend
    tailoff_kp_cap: Optional[DesignParameter] = None  # stack only: tail-off attitude-stiffness cap (x last regular)
    tailoff_kd_cap: Optional[DesignParameter] = None  # stack only: tail-off rate-gain cap (x last regular)


#: Design parameters only the stack schedule has, and why.
STACK_ONLY_PARAMETERS = {"blend_first": "only the stack blends its gyros",
                         "tailoff_kp_cap": "only the first stage has a thrust tail-off",
                         "tailoff_kd_cap": "only the first stage has a thrust tail-off"}


@dataclass
class DesignParameters:
    stack: ScheduleParameters = field(default_factory=ScheduleParameters)
    upper: ScheduleParameters = field(default_factory=ScheduleParameters)


@dataclass
class DesignOptimizer:
    """The search of ``study=fcs_design`` (``scipy.optimize.minimize``)."""

    method: str = "nelder-mead"  # nelder-mead (goal attainment, then max-min) | cobyla (margins as constraints)
    max_evaluations: int = 300  # per schedule
    tolerance: float = 1e-3  # on the normalized parameters and the ratio
    initial_step: float = 0.1  # first simplex / trust radius, fraction of each parameter's range
    stop_ratio: float = 0.0  # > 0: stop a schedule's search once every point's ratio reaches it
    restarts: int = 2  # fresh starts from the best point after a search converges (budget permitting)


@dataclass
class FcsDesignStudyConfig:
    """``study=fcs_design``: tune the flight control's free parameters against the
    requirement set at frozen points over the flight and the uncertainty corners, and
    write the controller config (docs/design_studies.md)."""

    name: str = "fcs_design"
    design: str = "msfc_pid"  # design rules it starts from (savant_cli/datagen/fcs_gains.py CONTROLLERS)
    controller_name: str = ""  # name of the controller written ("": <design>_tuned, or <design> with install)
    install: bool = False  # also write conf/controller/<name>.yaml of the shipped config tree
    schedules: list[str] = field(default_factory=lambda: ["stack", "upper"])  # tuned in turn
    every_s: dict[str, float] = field(default_factory=lambda: {"stack": 10.0, "upper": 30.0})  # design points
    verify_every_s: float = 5.0  # the before/after envelope
    event_window_s: float = 2.0  # points this close to an event are skipped
    axes: list[str] = field(default_factory=lambda: ["pitch"])  # loops judged in the search (both verified)
    workers: int = 0  # processes judging a candidate's points; 0: all cores
    corners: dict[str, dict[str, Any]] = field(default_factory=dict)  # name → {config key: value}
    parameters: DesignParameters = field(default_factory=DesignParameters)
    optimizer: DesignOptimizer = field(default_factory=DesignOptimizer)


#: The time-domain margins a study measures: gain raised, gain lowered (dB) and delay added (ms).
MARGIN_KINDS = ("gain_high", "gain_low", "delay")


@dataclass
class TimeMarginsStudyConfig:
    """``study=time_margins``: gain and delay margins measured in the nonlinear time
    simulation, beside the frequency-domain ones (docs/design_studies.md)."""

    name: str = "time_margins"
    times: list[float] = field(default_factory=lambda: [55.0, 130.0, 180.0, 230.0])
    axes: list[str] = field(default_factory=lambda: ["pitch", "yaw"])
    kinds: list[str] = field(default_factory=lambda: list(MARGIN_KINDS))
    lead_s: float = 10.0  # the perturbation starts this long before the point
    window_s: float = 20.0  # and is held this long
    min_periods: float = 3.0  # the window stretched to hold this many periods of the frequency-domain crossing
    max_window_s: float = 60.0  # longest stretched window
    event_clearance_s: float = 0.2  # the window keeps this far from events
    gain_bound_dB: float = 20.0  # search bound of the gain margins
    delay_bound_ms: float = 1000.0  # search bound of the delay margin
    gain_tolerance_dB: float = 0.1  # bisection tolerance
    delay_tolerance_ms: float = 2.0
    scan_points: int = 8  # coarse scan before the bisection
    excitation_deg: float = 0.5  # doublet amplitude at the gimbal command
    excitation_s: float = 0.4  # doublet duration
    settle_s: float = 2.0  # left out of the growth analysis after the window starts
    min_damping_ratio: float = 0.01  # stable only when the envelope decays per period as a mode of this damping
    workers: int = 0  # processes; 0: all cores
    jacobian: str = "auto"  # of the frequency-domain side (as study=linear)
    jacobian_step: float = 1e-6


STUDY_SCHEMAS: dict[str, type] = {"nominal": StudyConfig, "linear": LinearStudyConfig,
                                  "montecarlo": MonteCarloStudyConfig, "flex_sweep": FlexSweepStudyConfig,
                                  "flyoff": FlyoffStudyConfig, "mode_retention": ModeRetentionStudyConfig,
                                  "fcs_design": FcsDesignStudyConfig, "time_margins": TimeMarginsStudyConfig}


@dataclass
class WindProfile:
    altitude_m: list[float] = field(default_factory=list)
    north_mps: list[float] = field(default_factory=list)
    east_mps: list[float] = field(default_factory=list)


#: ``winds.gust.onset``, ``winds.gust.frame`` and ``winds.shear.shape`` options.
GUST_ONSETS = ("altitude", "time")
GUST_FRAMES = ("ned", "flight_path")
SHEAR_SHAPES = ("linear", "cosine")


@dataclass
class GustConfig:
    """``winds.gust``: a discrete 1 − cos gust (``models/winds.py``, docs/models.md)."""

    enabled: bool = False
    amplitude_mps: float = 9.0  # peak speed A, reached at mid-length
    onset: str = "altitude"  # altitude | time: what the gust coordinate s runs in
    onset_altitude_m: float = 12000.0  # onset: altitude: where the gust starts (geodetic)
    length_m: float = 240.0  # onset: altitude: full thickness d (build-up d/2, peak at d/2)
    onset_time_s: float = 60.0  # onset: time: when the gust starts (mission time)
    duration_s: float = 1.0  # onset: time: full duration d
    frame: str = "flight_path"  # ned: horizontal toward direction_deg; flight_path: across the path
    direction_deg: float = 0.0  # ned: azimuth from north; flight_path: clock angle (0 up: +alpha, 90 left: +beta)


@dataclass
class ShearConfig:
    """``winds.shear``: a build-up of the horizontal wind by ``delta_mps`` over an altitude band."""

    enabled: bool = False
    delta_mps: float = 0.0  # Δv over the band (m/s, may be negative)
    base_altitude_m: float = 9000.0  # bottom of the band (geodetic)
    thickness_m: float = 1000.0  # band thickness Δh
    return_thickness_m: float = 0.0  # > 0: Δv is removed again over this thickness above the band
    shape: str = "linear"  # linear | cosine ramp
    direction_deg: float = 90.0  # azimuth the added wind blows toward, from north


@dataclass
class WindsConfig:
    name: str = "none"
    enabled: bool = False
    scale: float = 1.0
    profile: WindProfile = field(default_factory=WindProfile)
    gust: GustConfig = field(default_factory=GustConfig)
    shear: ShearConfig = field(default_factory=ShearConfig)


@dataclass
class ActuatorStageCommon:
    """Keys of one stage's TVC actuator common to both variants."""

    loop_gain_rad_s: float = 25.0
    rate_limit_deg_s: float = 10.0
    # thrust-line misalignment from the actuator null, pitch and yaw, deg
    null_bias_deg: list[float] = field(default_factory=lambda: [0.0, 0.0])


@dataclass
class ThirdOrderStage(ActuatorStageCommon):
    """``actuator=third_order``: position loop of gain ``loop_gain_rad_s`` driving a
    second-order load."""

    natural_frequency_hz: float = 12.0
    damping: float = 0.6


@dataclass
class SimplexStage(ActuatorStageCommon):
    """``actuator=simplex``: power valve, hydraulic ram and compliant nozzle mount (load
    inertia: the vehicle's engine inertia about the gimbal)."""

    valve_frequency_hz: float = 50.0
    valve_damping: float = 0.7
    stiffness_Nm_per_rad: float = 1.99e8  # the first stage's: ω_n = 12 Hz with J = 35,000 kg m²
    damping_Nms_per_rad: float = 3.17e6  # ζ = C / (2 √(K J)) = 0.6 with that J
    leakage_rad_s_per_Nm: float = 0.0
    feedback: str = "piston"  # piston (ram LVDT) | nozzle


@dataclass
class ThirdOrderActuatorConfig:
    name: str = "third_order"
    first_stage: ThirdOrderStage = field(default_factory=ThirdOrderStage)
    upper_stage: ThirdOrderStage = field(default_factory=ThirdOrderStage)


@dataclass
class SimplexActuatorConfig:
    name: str = "simplex"
    first_stage: SimplexStage = field(default_factory=SimplexStage)
    upper_stage: SimplexStage = field(default_factory=SimplexStage)


def check_actuator(a: ThirdOrderActuatorConfig | SimplexActuatorConfig, plant_rate_hz: float) -> None:
    """Physical checks of the ``actuator`` group (either variant)."""
    for stage in ("first_stage", "upper_stage"):
        st = getattr(a, stage)
        names = ["loop_gain_rad_s", "rate_limit_deg_s"]
        names += ["natural_frequency_hz", "damping"] if a.name == "third_order" else [
            "valve_frequency_hz", "valve_damping", "stiffness_Nm_per_rad", "damping_Nms_per_rad"]
        for name in names:
            _positive(f"actuator.{stage}.{name}", getattr(st, name))
        _small_angles(f"actuator.{stage}.null_bias_deg", st.null_bias_deg, 2, 2.0, "pitch, yaw")
        if a.name == "simplex":
            _non_negative(f"actuator.{stage}.leakage_rad_s_per_Nm", st.leakage_rad_s_per_Nm)
            _one_of(f"actuator.{stage}.feedback", st.feedback, ("piston", "nozzle"))
            # the valve is integrated by the plant's RK4: keep it well inside its stability
            nyq = 0.25 * plant_rate_hz
            if st.valve_frequency_hz >= nyq:
                raise ConfigError(f"actuator.{stage}.valve_frequency_hz", st.valve_frequency_hz,
                                  f"must be below a quarter of sim.plant_rate_hz ({nyq} Hz) for RK4 stability")


@dataclass
class FlexOffConfig:
    """``flex=off``: the rigid vehicle."""

    name: str = "off"
    enabled: bool = False


@dataclass
class FlexOnConfig:
    """``flex=on``: retained bending modes from the vehicle's modal data."""

    name: str = "on"
    enabled: bool = True
    n_modes: int = 4  # retained modes, lowest first
    damping: float = 0.005  # structural damping ratio of every retained mode
    damping_per_mode: list[float] = field(default_factory=list)  # overrides `damping` when given
    switching: str = "separation"  # separation | propellant
    frequency_scale: float = 1.0
    shape_scale: float = 1.0


def check_flex(f: FlexOffConfig | FlexOnConfig) -> None:
    """Physical checks of the ``flex`` group."""
    if not f.enabled:
        return
    if f.n_modes < 1:
        raise ConfigError("flex.n_modes", f.n_modes, "must be at least 1 when flex is on (flex=off turns it off)")
    _non_negative("flex.damping", f.damping)
    for i, z in enumerate(f.damping_per_mode):
        _non_negative(f"flex.damping_per_mode[{i}]", z)
    if f.damping_per_mode and len(f.damping_per_mode) < f.n_modes:
        raise ConfigError("flex.damping_per_mode", list(f.damping_per_mode),
                          f"must give at least flex.n_modes = {f.n_modes} values, or be empty")
    _one_of("flex.switching", f.switching, ("separation", "propellant"))
    _positive("flex.frequency_scale", f.frequency_scale)
    _non_negative("flex.shape_scale", f.shape_scale)


@dataclass
class SloshOffConfig:
    """``slosh=off``: no propellant slosh."""

    name: str = "off"
    enabled: bool = False


@dataclass
class SloshOnConfig:
    """``slosh=on``: LOX and LH2 spring-mass slosh from the vehicle's tables."""

    name: str = "on"
    enabled: bool = True
    frequency_scale: float = 1.0
    damping_scale: float = 1.0


def check_slosh(s: SloshOffConfig | SloshOnConfig) -> None:
    """Physical checks of the ``slosh`` group."""
    if s.enabled:
        _positive("slosh.frequency_scale", s.frequency_scale)
        _non_negative("slosh.damping_scale", s.damping_scale)


@dataclass
class TwdOffConfig:
    """``twd=off``: no engine-inertia reaction."""

    name: str = "off"
    enabled: bool = False


@dataclass
class TwdOnConfig:
    """``twd=on``: the engine-inertia reaction (data: the vehicle's engines)."""

    name: str = "on"
    enabled: bool = True


@dataclass
class NavigationPerfectConfig:
    """``navigation=perfect``: the flight software reads the true state (the source paper's
    §III.H assumption), apart from the navigation unit's mounting misalignment
    (``sensors.misalignment_deg.imu``)."""

    name: str = "perfect"


@dataclass
class GyroErrorsConfig:
    """The IMU gyro triad's errors (body x, y, z)."""

    bias_deg_per_h: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    scale_factor_ppm: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    misalignment_arcsec: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])


@dataclass
class AccelerometerErrorsConfig:
    """The IMU accelerometer triad's errors (body x, y, z)."""

    bias_micro_g: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    scale_factor_ppm: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    misalignment_arcsec: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])


@dataclass
class NavigationInertialConfig:
    """``navigation=inertial``: strapdown inertial navigation from an IMU with errors
    (``models/navigation.py``); nominal errors zero, their spread in the dispersion set."""

    name: str = "inertial"
    gyro: GyroErrorsConfig = field(default_factory=GyroErrorsConfig)
    accelerometer: AccelerometerErrorsConfig = field(default_factory=AccelerometerErrorsConfig)
    alignment_arcsec: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])


#: Bounds of the inertial-navigation errors, ``key: (limit, units)``. The error model is
#: first order in the errors (small-angle attitude error, scale factors ≪ 1): a 1°
#: (3600 arcsec) attitude error keeps the neglected second-order terms below 1 % of the
#: first-order ones, and the bias bounds keep a 10-minute ascent's attitude drift (10 deg/h:
#: 1.7°) and tilt-equivalent (10,000 µg = 0.57°) within that regime. The bounds span
#: navigation to tactical grade; a worse IMU is outside what this model represents.
NAVIGATION_BOUNDS: dict[str, tuple[float, str]] = {
    "gyro.bias_deg_per_h": (10.0, "deg/h"),
    "gyro.scale_factor_ppm": (10000.0, "ppm"),
    "gyro.misalignment_arcsec": (3600.0, "arcsec"),
    "accelerometer.bias_micro_g": (10000.0, "µg"),
    "accelerometer.scale_factor_ppm": (10000.0, "ppm"),
    "accelerometer.misalignment_arcsec": (3600.0, "arcsec"),
    "alignment_arcsec": (3600.0, "arcsec"),
}


def check_navigation(n: NavigationPerfectConfig | NavigationInertialConfig) -> None:
    """Physical checks of the ``navigation`` group: three finite values per error, each
    within :data:`NAVIGATION_BOUNDS`."""
    if n.name != "inertial":
        return
    for path, (limit, units) in NAVIGATION_BOUNDS.items():
        node: Any = n
        for part in path.split("."):
            node = getattr(node, part)
        vals = list(node)
        key = f"navigation.{path}"
        if len(vals) != 3:
            raise ConfigError(key, vals, f"must list 3 values in {units} (body x, y, z)")
        for i, v in enumerate(vals):
            if not (isinstance(v, (int, float)) and np.isfinite(v) and abs(v) <= limit):
                raise ConfigError(f"{key}[{i}]", v, f"must be a finite value within ±{limit:g} {units} (the first-order "
                                                    "error model's range, config.NAVIGATION_BOUNDS)")


#: The schema of each option of the groups whose options carry different keys.
GROUP_VARIANTS: dict[str, dict[str, type]] = {
    "actuator": {"third_order": ThirdOrderActuatorConfig, "simplex": SimplexActuatorConfig},
    "flex": {"off": FlexOffConfig, "on": FlexOnConfig},
    "slosh": {"off": SloshOffConfig, "on": SloshOnConfig},
    "twd": {"off": TwdOffConfig, "on": TwdOnConfig},
    "navigation": {"perfect": NavigationPerfectConfig, "inertial": NavigationInertialConfig},
}


@dataclass
class RateGyroConfig:
    natural_frequency_hz: float = 25.0
    damping: float = 0.7


@dataclass
class SensorMisalignment:
    """Mounting misalignment of each sensor package: a small rotation vector from the body
    axes to the sensor's axes (x, y, z body axes, deg)."""

    imu: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    rate_gyro_upper_stage: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    rate_gyro_first_stage: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])


@dataclass
class SensorsConfig:
    name: str = "ares_i_gyros"
    rate_gyro: RateGyroConfig = field(default_factory=RateGyroConfig)
    misalignment_deg: SensorMisalignment = field(default_factory=SensorMisalignment)


@dataclass
class FilterSection:
    b: list[float] = field(default_factory=list)
    a: list[float] = field(default_factory=list)


@dataclass
class FilterSet:
    rate: list[FilterSection] = field(default_factory=list)
    integrated_rate: list[FilterSection] = field(default_factory=list)
    roll: list[FilterSection] = field(default_factory=list)


@dataclass
class FilterSets:
    stack: FilterSet = field(default_factory=FilterSet)
    upper: FilterSet = field(default_factory=FilterSet)


@dataclass
class Blending:
    stack: list[float] = field(default_factory=list)
    upper: list[float] = field(default_factory=list)


@dataclass
class AxisGains:
    kp: list[float] = field(default_factory=list)
    ki: list[float] = field(default_factory=list)
    kd: list[float] = field(default_factory=list)
    kir: list[float] = field(default_factory=list)


@dataclass
class GainTable:
    schedule: str = "altitude_m"
    breakpoints: list[float] = field(default_factory=list)
    pitch: AxisGains = field(default_factory=AxisGains)
    yaw: AxisGains = field(default_factory=AxisGains)


@dataclass
class GainTables:
    stack: GainTable = field(default_factory=GainTable)
    coast: GainTable = field(default_factory=GainTable)
    upper: GainTable = field(default_factory=GainTable)


@dataclass
class RollControl:
    attitude_deadband_deg: float = 1.0
    rate_deadband_deg_s: float = 1.0
    lead_time_s: float = 1.0


@dataclass
class IgnitionFade:
    """``controller.ignition_fade``: the upper-stage loop's engagement at the J-2X start
    (``models/fcs.py::engagement``). The gains fade linearly from the coast table to the
    upper-stage table from ``start_s`` to ``end_s`` after the ignition command (s); the
    integrators are held until ``start_s``. The design rules write the engine's thrust
    build-up: its last zero-thrust time and the time it reaches rated thrust."""

    start_s: float = 0.3
    end_s: float = 2.8


@dataclass
class ControllerDesign:
    """How a controller file was made: the design rules (``datagen/fcs_gains.py``) and the
    values ``study=fcs_design`` tuned (schedule → parameter → value; empty: the rules'
    own values). Provenance only: the flight uses the tables."""

    rules: str = ""
    parameters: dict[str, dict[str, float]] = field(default_factory=dict)


@dataclass
class ControllerConfig:
    name: str = "msfc_pid"
    vehicle: str = ""  # the vehicle the design is for ("": any); another is refused ...
    allow_other_vehicle: bool = False  # ... unless this is true
    blending: Blending = field(default_factory=Blending)
    flex_filters: FilterSets = field(default_factory=FilterSets)
    gains: GainTables = field(default_factory=GainTables)
    roll: RollControl = field(default_factory=RollControl)
    ignition_fade: IgnitionFade = field(default_factory=IgnitionFade)
    # transport delay from the sensor sample to the actuator command (s): a whole number
    # of plant steps, shorter than the control period; the same in the time run and the
    # linear model
    delay_s: float = 0.005
    design: ControllerDesign = field(default_factory=ControllerDesign)


@dataclass
class LaunchSite:
    latitude_deg: float = 28.627
    longitude_deg: float = -80.621
    base_altitude_m: float = 0.0
    pad_heading_deg: float = 0.0


@dataclass
class InsertionTolerance:
    """``guidance.target.tolerance``: the largest |error| of the cut-off orbit against the
    target that is still a successful insertion (mission class ``insertion_tolerance``).
    Defaults: the 3σ LEO injection accuracies launcher users' guides quote (e.g. ±10 km
    in each apsis altitude, ±0.1° in inclination) [E]."""

    perigee_km: float = 10.0
    apogee_km: float = 10.0
    inclination_deg: float = 0.1


@dataclass
class OrbitTarget:
    """``guidance.target``: the insertion orbit (apsis altitudes above the WGS84
    equatorial radius) and the cutoff altitude on it; every key is required. The plane
    has the inclination and passes through the launch site, northbound, at
    ``in_plane_time_s`` after liftoff (its node follows from the site and that time)."""

    perigee_altitude_km: Optional[float] = None
    apogee_altitude_km: Optional[float] = None
    inclination_deg: Optional[float] = None
    cutoff_altitude_km: Optional[float] = None
    in_plane_time_s: float = 0.0
    tolerance: InsertionTolerance = field(default_factory=InsertionTolerance)


@dataclass
class PegConfig:
    """``guidance.peg``: closed-loop upper-stage guidance (``models/peg.py``)."""

    enabled: bool = False
    start_after_ignition_s: float = 40.0  # engages this long after upper-stage ignition
    isp_vac_s: Optional[float] = None  # guidance's value of the engine's Isp (an I-load), s
    convergence_tolerance: float = 0.01  # largest relative change of t_go of a converged cycle
    terminal_time_to_go_s: float = 10.0  # steering frozen below this time to go
    max_iterations: int = 50  # passes allowed at engagement
    steering_tolerance_deg: float = 0.01  # engagement: thrust-direction change between passes of a converged solution
    blend_s: float = 10.0  # the command turns from the stored profile to PEG's over this time
    max_unconverged_cycles: int = 5  # consecutive unconverged cycles that stop the run
    gravity_steps: int = 20  # RK4 steps of the gravity prediction over the time to go
    # the nominal engine shutdown impulse in seconds of rated thrust, I_sd / F_vac (an I-load):
    # the cutoff is commanded this much before t_go runs out, so the tail-off completes the burn
    shutdown_impulse_time_s: float = 0.0


@dataclass
class SmootherConfig:
    damping: float = 0.8
    natural_frequency_rad_s: float = 1.0


@dataclass
class GuidanceConfig:
    name: str = ""
    vehicle: str = ""  # the vehicle the command file was generated for ("": any); another is refused ...
    allow_other_vehicle: bool = False  # ... unless this is true
    command_file: str = ""
    launch_site: LaunchSite = field(default_factory=LaunchSite)
    target: OrbitTarget = field(default_factory=OrbitTarget)
    smoother: SmootherConfig = field(default_factory=SmootherConfig)
    generator: dict[str, Any] = field(default_factory=dict)
    first_stage_schedule: str = "time"  # the stored profile's index in the first stage: time | relative_velocity
    peg: PegConfig = field(default_factory=PegConfig)


@dataclass
class SavantConfig:
    vehicle: Any = None  # validated by savant_cli.vehicle.load_vehicle (tables and keys)
    phase: PhaseConfig = field(default_factory=PhaseConfig)
    # typed per option in validate() (GROUP_VARIANTS)
    actuator: Any = field(default_factory=lambda: {"name": "third_order"})
    flex: Any = field(default_factory=lambda: {"name": "off"})
    slosh: Any = field(default_factory=lambda: {"name": "off"})
    twd: Any = field(default_factory=lambda: {"name": "off"})
    navigation: Any = field(default_factory=lambda: {"name": "perfect"})
    winds: WindsConfig = field(default_factory=WindsConfig)
    controller: ControllerConfig = field(default_factory=ControllerConfig)
    guidance: GuidanceConfig = field(default_factory=GuidanceConfig)
    sensors: SensorsConfig = field(default_factory=SensorsConfig)
    dispersions: DispersionSetConfig = field(default_factory=DispersionSetConfig)
    requirements: RequirementSet = field(default_factory=RequirementSet)
    study: Any = field(default_factory=lambda: {"name": "nominal"})  # typed per study in validate()
    sim: SimConfig = field(default_factory=SimConfig)
    environment: EnvironmentConfig = field(default_factory=EnvironmentConfig)
    output: OutputConfig = field(default_factory=OutputConfig)


# ------------------------------------------------------------------------ validation


def _strict_merge(cfg: DictConfig) -> DictConfig:
    """Merge ``cfg`` onto the schema; unknown keys and wrong types raise ConfigError."""
    schema = OmegaConf.structured(SavantConfig)
    plain = OmegaConf.to_container(cfg, resolve=True)
    plain.pop("hydra", None)
    try:
        merged = OmegaConf.merge(schema, plain)
    except OmegaConfBaseException as exc:
        key = getattr(exc, "full_key", None) or "?"
        value = getattr(exc, "value", None)
        msg = str(exc).splitlines()[0]
        if "not in struct" in msg or "Key '" in msg and "not in" in msg:
            allowed = "unknown key; see `savant run --cfg job` for the known keys"
        else:
            allowed = msg
        raise ConfigError(key, value, allowed) from None
    return merged


def _positive(key: str, value: float) -> None:
    if not (value > 0.0 and np.isfinite(value)):
        raise ConfigError(key, value, "must be a positive finite number")


def _non_negative(key: str, value: float) -> None:
    if not (value >= 0.0 and np.isfinite(value)):
        raise ConfigError(key, value, "must be zero or positive")


def _one_of(key: str, value: Any, allowed: tuple) -> None:
    if value not in allowed:
        raise ConfigError(key, value, f"must be one of {', '.join(map(str, allowed))}")


def _small_angles(key: str, values: list[float], n: int, limit_deg: float, axes: str) -> None:
    """``values`` must be ``n`` finite angles (deg), each of magnitude at most ``limit_deg``."""
    vals = list(values)
    if len(vals) != n:
        raise ConfigError(key, vals, f"must list {n} angles in deg ({axes})")
    for i, v in enumerate(vals):
        if not (np.isfinite(v) and abs(v) <= limit_deg):
            raise ConfigError(f"{key}[{i}]", v, f"must be a finite angle within ±{limit_deg} deg")


def _increasing(key: str, values: list[float]) -> None:
    """A table axis given as a YAML list: at least 2 finite numbers, strictly increasing as
    written; the first element out of order is named ``key[i]`` (refused, never sorted)."""
    arr = np.asarray(values, dtype=float)
    if arr.size < 2:
        raise ConfigError(key, list(values), "must be a strictly increasing list of at least 2 numbers")
    for i in range(arr.size):
        if not np.isfinite(arr[i]):
            raise ConfigError(f"{key}[{i}]", float(arr[i]), "must be a finite number")
        if i and arr[i] <= arr[i - 1]:
            raise ConfigError(f"{key}[{i}]", float(arr[i]), f"the list must be strictly increasing, and it follows "
                                                            f"{arr[i - 1]:g} at [{i - 1}]; put it in order (savant "
                                                            f"never sorts a table)")


#: Documented bounds of the ``sim`` rates (Hz) and times (s): beyond them a run would not
#: finish in reasonable time or memory (the log holds max_time_s × log_rate_hz rows).
SIM_BOUNDS = {"plant_rate_hz": (20.0, 10000.0), "sensor_rate_hz": (1.0, 10000.0), "fcs_rate_hz": (1.0, 1000.0),
              "guidance_rate_hz": (0.01, 100.0), "log_rate_hz": (0.1, 1000.0), "max_time_s": (1.0, 3600.0)}

#: Most rows of a run's time history, ``sim.max_time_s × sim.log_rate_hz``: the history is
#: allocated whole before the flight, about 280 columns of 8 bytes at full fidelity, so
#: 500,000 rows are about 1.1 GB in memory and again in ``savant.h5`` (ten times the
#: default log rate over the default flight; docs/outputs.md, "Bounds").
MAX_LOG_ROWS = 500_000

#: Largest ``winds.scale``: the shipped strong-jet profile peaks at 53 m/s, five times it
#: at 266 m/s, more than twice the fastest jet-stream winds measured (about 110 m/s);
#: beyond that the profile is no longer a wind but a modelling error (docs/outputs.md).
MAX_WINDS_SCALE = 5.0

#: Most runs of a Monte Carlo batch. A batch without a failure demonstrates a success
#: probability of 1 − 2.3/n at 90 % confidence: a million runs show 0.9999977, beyond any
#: crew-vehicle requirement; they take about 50 h at the measured 328 runs/min on the
#: 2-core machine (docs/montecarlo.md), and the batch's tables hold about 1.2 kB per run
#: in memory (1.2 GB). ``study.n_runs=1000000000000`` is refused before anything is built.
MAX_N_RUNS = 1_000_000

#: Most shards of a batch: each is one scheduler job and one folder ``savant collect``
#: reads; 10,000 shards of the largest batch are 100 runs each (SLURM's default job-array
#: limit, MaxArraySize, is 1,001).
MAX_SHARDS = 10_000

#: Most history samples of one signal over a batch, ``study.n_runs × sim.max_time_s ×
#: study.histories.rate_hz``: the envelope plots read one signal of every run at once,
#: 4 bytes a sample, so 2.5e8 samples are 1 GB in memory (the default batch: 4e6).
MAX_HISTORY_SAMPLES = 250_000_000

#: Most worker processes of a study: each holds a copy of the built model and its
#: compiled plant, about 170 MB measured, so 256 are about 43 GB; a machine with more cores
#: is better used by shards.
MAX_WORKERS = 256
WORKERS_ALLOWED = f"must be 0 (all cores) or a process count up to {MAX_WORKERS} (about 170 MB each)"


def _check_rates(sim: SimConfig) -> None:
    for name, (low, high) in SIM_BOUNDS.items():
        value = getattr(sim, name)
        _positive(f"sim.{name}", value)
        if not low <= value <= high:
            raise ConfigError(f"sim.{name}", value, f"must lie between {low:g} and {high:g}")
    rows = sim.max_time_s * sim.log_rate_hz
    if rows > MAX_LOG_ROWS:
        raise ConfigError("sim.log_rate_hz", sim.log_rate_hz,
                          f"with sim.max_time_s = {sim.max_time_s:g} s the history would hold {rows:,.0f} rows; at most "
                          f"{MAX_LOG_ROWS:,} (about 1.1 GB): allowed up to {MAX_LOG_ROWS / sim.max_time_s:g} Hz, or a "
                          "shorter sim.max_time_s")
    for name in ("sensor_rate_hz", "fcs_rate_hz", "guidance_rate_hz", "log_rate_hz"):
        ratio = sim.plant_rate_hz / getattr(sim, name)
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ConfigError(f"sim.{name}", getattr(sim, name),
                              f"must divide sim.plant_rate_hz = {sim.plant_rate_hz} into a whole number of steps")
    _positive("sim.chunk_s", sim.chunk_s)
    _positive("sim.max_body_rate_deg_s", sim.max_body_rate_deg_s)
    _check_health(sim)


def _check_health(sim: SimConfig) -> None:
    h = sim.health
    for name in ("max_saturation_s", "event_quiet_s", "alpha_min_dynamic_pressure_Pa"):
        _non_negative(f"sim.health.{name}", getattr(h, name))
    for name in ("min_amplitude_deg", "max_damping_ratio"):
        _positive(f"sim.health.{name}", getattr(h, name))
    if not (np.isfinite(h.min_periods) and h.min_periods >= 2.0):
        raise ConfigError("sim.health.min_periods", h.min_periods,
                          "must be a finite number of periods of at least 2 (a sustained oscillation repeats)")
    if not 0.0 < h.tonal_fraction <= 1.0:
        raise ConfigError("sim.health.tonal_fraction", h.tonal_fraction, "must lie in (0, 1]")
    if not (np.isfinite(h.divergence_growth) and h.divergence_growth > 1.0):
        raise ConfigError("sim.health.divergence_growth", h.divergence_growth,
                          "must be a finite envelope growth ratio above 1")
    if not (np.isfinite(h.max_attitude_error_deg) and 0.0 < h.max_attitude_error_deg < 180.0):
        raise ConfigError("sim.health.max_attitude_error_deg", h.max_attitude_error_deg,
                          "must be an angle between 0 and 180 deg (exclusive)")
    if not 0.0 < h.divergence_min_amplitude_deg <= h.max_attitude_error_deg:
        raise ConfigError("sim.health.divergence_min_amplitude_deg", h.divergence_min_amplitude_deg,
                          f"must be positive and at most sim.health.max_attitude_error_deg "
                          f"({h.max_attitude_error_deg} deg): a divergence is flagged before it is a loss of control")
    if h.max_alpha_deg is not None and not (np.isfinite(h.max_alpha_deg) and 0.0 < h.max_alpha_deg < 180.0):
        raise ConfigError("sim.health.max_alpha_deg", h.max_alpha_deg,
                          "must be null (no bound) or an angle between 0 and 180 deg (exclusive)")


def _check_controller(c: ControllerConfig) -> None:
    for name in ("stack", "upper"):
        weights = list(getattr(c.blending, name))
        key = f"controller.blending.{name}"
        if len(weights) != 3:
            raise ConfigError(key, weights, "must list 3 weights: upper-stage gyro, IMU, first-stage gyro")
        if any(w < 0 for w in weights) or abs(sum(weights) - 1.0) > 1e-9:
            raise ConfigError(key, weights, "weights must be non-negative and sum to 1")
        fs = getattr(c.flex_filters, name)
        for path in ("rate", "integrated_rate", "roll"):
            sections = getattr(fs, path)
            key = f"controller.flex_filters.{name}.{path}"
            if len(sections) != 2:
                raise ConfigError(key, len(sections), "must hold exactly 2 fourth-order sections")
            for i, sec in enumerate(sections):
                for coef in ("b", "a"):
                    vals = list(getattr(sec, coef))
                    if len(vals) != 5:
                        raise ConfigError(f"{key}[{i}].{coef}", vals, "must hold 5 coefficients (4th order)")
                if sec.a[0] == 0.0:
                    raise ConfigError(f"{key}[{i}].a", list(sec.a), "a[0] must be non-zero")
                roots = np.roots(np.asarray(sec.a, float) / sec.a[0])
                if np.any(np.abs(roots) >= 1.0):
                    raise ConfigError(f"{key}[{i}].a", list(sec.a), "filter must be stable (poles inside the unit circle)")
    for name, sched in (("stack", "altitude_m"), ("coast", "velocity_mps"), ("upper", "velocity_mps")):
        table = getattr(c.gains, name)
        key = f"controller.gains.{name}"
        _one_of(f"{key}.schedule", table.schedule, (sched,))
        _increasing(f"{key}.breakpoints", list(table.breakpoints))
        n = len(table.breakpoints)
        for axis in ("pitch", "yaw"):
            for g in ("kp", "ki", "kd", "kir"):
                vals = list(getattr(getattr(table, axis), g))
                if len(vals) != n:
                    raise ConfigError(f"{key}.{axis}.{g}", vals, f"must have one value per breakpoint ({n})")
    _non_negative("controller.roll.attitude_deadband_deg", c.roll.attitude_deadband_deg)
    _non_negative("controller.roll.rate_deadband_deg_s", c.roll.rate_deadband_deg_s)
    _non_negative("controller.roll.lead_time_s", c.roll.lead_time_s)
    fade = c.ignition_fade
    _non_negative("controller.ignition_fade.start_s", fade.start_s)
    if not (np.isfinite(fade.end_s) and fade.end_s >= fade.start_s):
        raise ConfigError("controller.ignition_fade.end_s", fade.end_s,
                          f"must be finite and at least controller.ignition_fade.start_s = {fade.start_s} s "
                          "(the fade from the coast gains to the upper-stage gains after the ignition command)")


def check_vehicle_match(cfg: SavantConfig) -> None:
    """Guidance and flight control generated for another vehicle are refused unless the
    user says so (``guidance.allow_other_vehicle``, ``controller.allow_other_vehicle``)."""
    flown = (cfg.vehicle or {}).get("name", "") if isinstance(cfg.vehicle, dict) else ""
    for group, node, fix in (("guidance", cfg.guidance, "its command file"), ("controller", cfg.controller, "its gains")):
        if node.vehicle and flown and node.vehicle != flown and not node.allow_other_vehicle:
            raise ConfigError(f"{group}.vehicle", node.vehicle,
                              f"{group}={node.name} was generated for vehicle {node.vehicle} ({fix} fit that vehicle "
                              f"only) but this run flies vehicle={flown}: choose the {group} of {flown} (its vehicle "
                              f"config selects it by default), or set {group}.allow_other_vehicle=true to fly it anyway")


def check_delay(delay_s: float, sim: SimConfig) -> None:
    """``controller.delay_s``: 0 or more, a whole number of plant steps, below one
    flight-control period."""
    _non_negative("controller.delay_s", delay_s)
    steps = delay_s * sim.plant_rate_hz
    if abs(steps - round(steps)) > 1e-6:
        raise ConfigError("controller.delay_s", delay_s,
                          f"must be a whole number of plant steps (1 / sim.plant_rate_hz = {1.0 / sim.plant_rate_hz:g} s)")
    if delay_s >= 1.0 / sim.fcs_rate_hz - 1e-12:
        raise ConfigError("controller.delay_s", delay_s,
                          f"must be shorter than the flight-control period (1 / sim.fcs_rate_hz = {1.0 / sim.fcs_rate_hz:g} s)")


def check_physics(cfg: SavantConfig) -> None:
    """Physical checks of a typed config (every group); raises ConfigError naming the key."""
    check_vehicle_match(cfg)
    _check_rates(cfg.sim)
    _one_of("environment.gravity_order", cfg.environment.gravity_order, (0, 2, 3, 4))
    _one_of("phase.stop_at", cfg.phase.stop_at, ("cutoff", "separation"))
    _one_of("phase.start", cfg.phase.start, ("liftoff", "staging"))
    _one_of("output.console", cfg.output.console, ("full", "summary", "quiet"))
    if cfg.phase.start == "staging" and cfg.phase.stop_at == "separation":
        raise ConfigError("phase.stop_at", cfg.phase.stop_at, "a phase starting at staging must stop at cutoff")
    if cfg.phase.start == "staging" and not cfg.phase.staging_state_file:
        raise ConfigError("phase.staging_state_file", "", "must name a staging-state file when phase.start = staging")
    check_actuator(cfg.actuator, cfg.sim.plant_rate_hz)
    check_delay(cfg.controller.delay_s, cfg.sim)
    check_flex(cfg.flex)
    check_slosh(cfg.slosh)
    check_navigation(cfg.navigation)
    check_requirements(cfg.requirements)
    _positive("sensors.rate_gyro.natural_frequency_hz", cfg.sensors.rate_gyro.natural_frequency_hz)
    _positive("sensors.rate_gyro.damping", cfg.sensors.rate_gyro.damping)
    for name in ("imu", "rate_gyro_upper_stage", "rate_gyro_first_stage"):
        _small_angles(f"sensors.misalignment_deg.{name}", getattr(cfg.sensors.misalignment_deg, name), 3, 1.0,
                      "about body x, y, z")
    nyquist = 0.5 * cfg.sim.sensor_rate_hz
    if cfg.sensors.rate_gyro.natural_frequency_hz >= nyquist:
        raise ConfigError("sensors.rate_gyro.natural_frequency_hz", cfg.sensors.rate_gyro.natural_frequency_hz,
                          f"must be below the sensor Nyquist frequency {nyquist} Hz")
    w = cfg.winds
    if not (np.isfinite(w.scale) and 0.0 <= w.scale <= MAX_WINDS_SCALE):
        raise ConfigError("winds.scale", w.scale, f"must lie between 0 and {MAX_WINDS_SCALE:g} (five times the "
                          "strongest shipped profile is already twice the fastest jet stream measured)")
    check_study_times(cfg)
    if w.enabled:
        _increasing("winds.profile.altitude_m", list(w.profile.altitude_m))
        n = len(w.profile.altitude_m)
        for comp in ("north_mps", "east_mps"):
            vals = list(getattr(w.profile, comp))
            if len(vals) != n:
                raise ConfigError(f"winds.profile.{comp}", vals, f"must have one value per altitude ({n})")
    check_gust_shear(w)
    _check_controller(cfg.controller)
    g = cfg.guidance
    if not g.command_file:
        raise ConfigError("guidance.command_file", g.command_file, "must name a guidance command file (CSV or HDF5)")
    ls = g.launch_site
    if not -90.0 <= ls.latitude_deg <= 90.0:
        raise ConfigError("guidance.launch_site.latitude_deg", ls.latitude_deg, "must be within [-90, 90]")
    if not -180.0 <= ls.longitude_deg <= 360.0:
        raise ConfigError("guidance.launch_site.longitude_deg", ls.longitude_deg, "must be within [-180, 360]")
    check_target(g)
    _one_of("guidance.first_stage_schedule", g.first_stage_schedule, ("time", "relative_velocity"))
    check_peg(g.peg, cfg.sim)
    _positive("guidance.smoother.damping", g.smoother.damping)
    _positive("guidance.smoother.natural_frequency_rad_s", g.smoother.natural_frequency_rad_s)


def check_study_times(cfg: SavantConfig) -> None:
    """Flight times a study asks for must lie inside ``sim.max_time_s`` (the flight can
    reach no later), and ``study.every`` must not be finer than the flight-control cycle
    the study's snapshots land on; refused before anything flies. Times beyond the end
    of the flight itself are refused as soon as the flight has flown (``study=linear``
    says the flight's end)."""
    s, sim = cfg.study, cfg.sim
    lists = [("study.times", getattr(s, "times", None))] if not getattr(s, "every", 0.0) else []
    lists.append(("study.linear_times", getattr(s, "linear_times", None)))
    for key, times in lists:
        for i, t in enumerate(times or []):
            if not t < sim.max_time_s:
                raise ConfigError(f"{key}[{i}]", t, f"must be earlier than sim.max_time_s = {sim.max_time_s:g} s "
                                  "(the flight stops there)")
    every = getattr(s, "every", 0.0)
    if every > 0.0:
        cycle = 1.0 / sim.fcs_rate_hz
        if every < cycle - 1e-12:
            raise ConfigError("study.every", every, f"must be at least one flight-control cycle (1 / "
                              f"sim.fcs_rate_hz = {cycle:g} s): the points land on control cycles")
        if every >= sim.max_time_s:
            raise ConfigError("study.every", every, f"must be shorter than sim.max_time_s = {sim.max_time_s:g} s")
    if isinstance(s, MonteCarloStudyConfig):
        h = s.histories
        if h.signals and h.rate_hz > sim.log_rate_hz:
            raise ConfigError("study.histories.rate_hz", h.rate_hz,
                              f"must be at most sim.log_rate_hz = {sim.log_rate_hz:g} Hz (a decimation of the log)")
        samples = s.n_runs * sim.max_time_s * h.rate_hz
        if h.signals and samples > MAX_HISTORY_SAMPLES:
            raise ConfigError("study.histories.rate_hz", h.rate_hz,
                              f"{s.n_runs:,} runs × {sim.max_time_s:g} s would keep {samples:.3g} samples per signal; "
                              f"at most {MAX_HISTORY_SAMPLES:.3g} (1 GB, read at once by the envelope plots): allowed "
                              f"up to {MAX_HISTORY_SAMPLES / (s.n_runs * sim.max_time_s):.3g} Hz, fewer runs, or no "
                              "histories (study.histories.signals=[])")


def _finite(key: str, value: float) -> None:
    if not np.isfinite(value):
        raise ConfigError(key, value, "must be a finite number")


def check_gust_shear(w: WindsConfig) -> None:
    """``winds.gust`` and ``winds.shear`` (checked whether enabled or not, so a switched-off
    gust is ready to fly): options from their lists, a gust amplitude within ±50 m/s, a
    positive length (``onset: altitude``) or duration (``onset: time``), an onset above
    the ground or after liftoff, a shear of at most ±100 m/s over a positive band."""
    g = w.gust
    _one_of("winds.gust.onset", g.onset, GUST_ONSETS)
    _one_of("winds.gust.frame", g.frame, GUST_FRAMES)
    if not (np.isfinite(g.amplitude_mps) and abs(g.amplitude_mps) <= 50.0):
        raise ConfigError("winds.gust.amplitude_mps", g.amplitude_mps, "must be a finite speed within ±50 m/s")
    _finite("winds.gust.direction_deg", g.direction_deg)
    if g.onset == "altitude":
        _non_negative("winds.gust.onset_altitude_m", g.onset_altitude_m)
        _positive("winds.gust.length_m", g.length_m)
    else:
        _non_negative("winds.gust.onset_time_s", g.onset_time_s)
        _positive("winds.gust.duration_s", g.duration_s)
    s = w.shear
    _one_of("winds.shear.shape", s.shape, SHEAR_SHAPES)
    if not (np.isfinite(s.delta_mps) and abs(s.delta_mps) <= 100.0):
        raise ConfigError("winds.shear.delta_mps", s.delta_mps, "must be a finite speed within ±100 m/s")
    _finite("winds.shear.base_altitude_m", s.base_altitude_m)
    _positive("winds.shear.thickness_m", s.thickness_m)
    _non_negative("winds.shear.return_thickness_m", s.return_thickness_m)
    _finite("winds.shear.direction_deg", s.direction_deg)


def check_target(g: GuidanceConfig) -> None:
    """``guidance.target``: present and reachable from the launch site."""
    t = g.target
    for name in ("perigee_altitude_km", "apogee_altitude_km", "inclination_deg", "cutoff_altitude_km"):
        if getattr(t, name) is None:
            raise ConfigError(f"guidance.target.{name}", None,
                              f"is required: guidance={g.name or '?'} flies to (and cuts off on) its target orbit")
    _positive("guidance.target.perigee_altitude_km", t.perigee_altitude_km)
    if t.apogee_altitude_km < t.perigee_altitude_km:
        raise ConfigError("guidance.target.apogee_altitude_km", t.apogee_altitude_km,
                          f"must be at least the perigee altitude ({t.perigee_altitude_km} km)")
    if not t.perigee_altitude_km <= t.cutoff_altitude_km <= t.apogee_altitude_km:
        raise ConfigError("guidance.target.cutoff_altitude_km", t.cutoff_altitude_km,
                          f"must lie on the target orbit, between its perigee ({t.perigee_altitude_km} km) and "
                          f"apogee ({t.apogee_altitude_km} km)")
    lat = abs(g.launch_site.latitude_deg)
    if not lat <= t.inclination_deg <= 180.0 - lat:
        raise ConfigError("guidance.target.inclination_deg", t.inclination_deg,
                          f"is unreachable from the launch latitude {g.launch_site.latitude_deg} deg without a plane "
                          f"change: allowed [{lat:g}, {180.0 - lat:g}]")
    if not -86400.0 <= t.in_plane_time_s <= 86400.0:
        raise ConfigError("guidance.target.in_plane_time_s", t.in_plane_time_s, "must be within one day of liftoff")
    for name in ("perigee_km", "apogee_km", "inclination_deg"):
        _positive(f"guidance.target.tolerance.{name}", getattr(t.tolerance, name))


def check_peg(peg: PegConfig, sim: SimConfig) -> None:
    """``guidance.peg``: its I-loads and tunings (checked only when enabled)."""
    if not peg.enabled:
        return
    if peg.start_after_ignition_s < 0.0:
        raise ConfigError("guidance.peg.start_after_ignition_s", peg.start_after_ignition_s,
                          "PEG cannot start before upper-stage ignition: must be >= 0 s after it")
    if peg.isp_vac_s is None:
        raise ConfigError("guidance.peg.isp_vac_s", None, "is required: PEG's value of the engine's Isp (s)")
    _positive("guidance.peg.isp_vac_s", peg.isp_vac_s)
    _non_negative("guidance.peg.shutdown_impulse_time_s", peg.shutdown_impulse_time_s)
    if not 0.0 < peg.convergence_tolerance < 0.5:
        raise ConfigError("guidance.peg.convergence_tolerance", peg.convergence_tolerance, "must be within (0, 0.5)")
    _non_negative("guidance.peg.terminal_time_to_go_s", peg.terminal_time_to_go_s)
    _positive("guidance.peg.steering_tolerance_deg", peg.steering_tolerance_deg)
    _non_negative("guidance.peg.blend_s", peg.blend_s)
    for name, low in (("max_iterations", 1), ("max_unconverged_cycles", 1), ("gravity_steps", 1)):
        if getattr(peg, name) < low:
            raise ConfigError(f"guidance.peg.{name}", getattr(peg, name), f"must be at least {low}")
    if peg.terminal_time_to_go_s < 1.0 / sim.guidance_rate_hz:
        raise ConfigError("guidance.peg.terminal_time_to_go_s", peg.terminal_time_to_go_s,
                          f"must be at least one guidance cycle (1 / sim.guidance_rate_hz = {1.0 / sim.guidance_rate_hz:g} s)")


def validate(cfg: DictConfig) -> SavantConfig:
    """Merge a composed config onto the schema and check it.

    Returns
    -------
    SavantConfig
        A typed (OmegaConf structured) view of the validated config.

    Raises
    ------
    ConfigError
        Naming the key, the value and what is allowed.
    """
    merged = _strict_merge(cfg)
    typed = OmegaConf.to_object(merged)
    typed.study = _study(typed.study)
    for group in GROUP_VARIANTS:
        setattr(typed, group, group_option(group, getattr(typed, group)))
    check_physics(typed)
    return typed


def has_key(schema: type, path: list[str]) -> bool:
    """Whether the dotted ``path`` names a field of the dataclass ``schema``."""
    node: Any = schema
    for part in path:
        fields = {f.name: f for f in dataclasses.fields(node)} if dataclasses.is_dataclass(node) else {}
        if part not in fields:
            return False
        default = fields[part].default_factory() if fields[part].default_factory is not dataclasses.MISSING \
            else fields[part].default
        node = type(default) if dataclasses.is_dataclass(default) else None
    return True


def group_option(group: str, node: Any) -> Any:
    """The section of a group with per-option schemas (:data:`GROUP_VARIANTS`), merged onto
    its option's schema: a key of another option, or of a model that is switched off, is
    refused naming the options where it exists."""
    variants = GROUP_VARIANTS[group]
    if dataclasses.is_dataclass(node):
        node = OmegaConf.to_container(OmegaConf.structured(node))
    name = node.get("name") if isinstance(node, dict) else None
    if name not in variants:
        raise ConfigError(f"{group}.name", name, f"must be one of {', '.join(variants)}")
    try:
        merged = OmegaConf.merge(OmegaConf.structured(variants[name]), node)
    except OmegaConfBaseException as exc:
        sub = str(getattr(exc, "full_key", None) or "?")
        key = f"{group}.{sub}"
        msg = str(exc).splitlines()[0]
        if "not in struct" in msg or ("Key '" in msg and "not in" in msg):
            where = [opt for opt, schema in variants.items() if opt != name and has_key(schema, sub.split("."))]
            allowed = (f"not a key of {group}={name}; it belongs to {' and '.join(f'{group}={w}' for w in where)}"
                       if where else f"not a key of {group}={name} (nor of any other {group} option)")
        else:
            allowed = msg
        value = node
        for part in sub.split("."):
            value = value.get(part) if isinstance(value, dict) else None
        raise ConfigError(key, value, allowed) from None
    return OmegaConf.to_object(merged)


def _study(node: Any) -> Any:
    """The study section merged onto its own study's schema (unknown keys refused)."""
    name = node.get("name") if isinstance(node, dict) else None
    if name not in STUDY_SCHEMAS:
        raise ConfigError("study.name", name, f"must be one of {', '.join(STUDY_SCHEMAS)}")
    try:
        merged = OmegaConf.merge(OmegaConf.structured(STUDY_SCHEMAS[name]), node)
    except OmegaConfBaseException as exc:
        key = "study." + str(getattr(exc, "full_key", None) or "?")
        msg = str(exc).splitlines()[0]
        allowed = "unknown key; see `savant run --cfg job`" if "not in" in msg else msg
        raise ConfigError(key, getattr(exc, "value", None), allowed) from None
    study = OmegaConf.to_object(merged)
    if isinstance(study, LinearStudyConfig):
        _check_linear(study)
    if isinstance(study, MonteCarloStudyConfig):
        _check_montecarlo(study)
    if isinstance(study, FlyoffStudyConfig) and len(set(study.controllers)) < 2:
        raise ConfigError("study.controllers", list(study.controllers), "must name at least two different controllers")
    if isinstance(study, FlexSweepStudyConfig):
        _check_flex_sweep(study)
    if isinstance(study, ModeRetentionStudyConfig):
        _check_mode_retention(study)
    if isinstance(study, FcsDesignStudyConfig):
        _check_fcs_design(study)
    if isinstance(study, TimeMarginsStudyConfig):
        _check_time_margins(study)
    return study


#: The gain schedules ``study=fcs_design`` tunes.
DESIGN_SCHEDULES = ("stack", "upper")


def design_controller_name(s: FcsDesignStudyConfig) -> str:
    """The name ``study=fcs_design`` writes its controller under: ``study.controller_name``,
    else the design's own with ``study.install`` and ``<design>_tuned`` without."""
    return s.controller_name or (s.design if s.install else f"{s.design}_tuned")


def _check_fcs_design(s: FcsDesignStudyConfig) -> None:
    from savant_cli.paths import shipped_config_dir

    name = design_controller_name(s)
    if not s.install and (shipped_config_dir() / "controller" / f"{name}.yaml").is_file():
        # Hydra searches the shipped config tree before --config-dir: the copy would be shadowed
        raise ConfigError("study.controller_name", name,
                          "names a shipped controller, which would shadow the run folder's copy "
                          "(--config-dir is searched after the shipped configs): choose another name, "
                          "or set study.install=true to replace the shipped file")
    for i, name in enumerate(s.schedules):
        _one_of(f"study.schedules[{i}]", name, DESIGN_SCHEDULES)
    for name, step in s.every_s.items():
        _one_of("study.every_s", name, DESIGN_SCHEDULES)
        _positive(f"study.every_s.{name}", step)
    for name in s.schedules:
        if name not in s.every_s:
            raise ConfigError("study.every_s", dict(s.every_s), f"must give the design-point spacing of {name}")
    _positive("study.verify_every_s", s.verify_every_s)
    _non_negative("study.event_window_s", s.event_window_s)
    if not 0 <= s.workers <= MAX_WORKERS:
        raise ConfigError("study.workers", s.workers, WORKERS_ALLOWED)
    for i, axis in enumerate(s.axes):
        _one_of(f"study.axes[{i}]", axis, ("pitch", "yaw"))
    if not s.axes:
        raise ConfigError("study.axes", [], "must name at least one loop (pitch, yaw)")
    for sched in DESIGN_SCHEDULES:
        params = getattr(s.parameters, sched)
        for name, why in STACK_ONLY_PARAMETERS.items():
            if sched != "stack" and getattr(params, name) is not None:
                raise ConfigError(f"study.parameters.{sched}.{name}", "set", why)
        for f in dataclasses.fields(params):
            prm = getattr(params, f.name)
            if prm is None:
                continue
            key = f"study.parameters.{sched}.{f.name}"
            if not (np.isfinite(prm.low) and np.isfinite(prm.high) and prm.low < prm.high):
                raise ConfigError(f"{key}.high", prm.high, f"must be finite and above low = {prm.low}")
            if prm.initial is not None and not prm.low <= prm.initial <= prm.high:
                raise ConfigError(f"{key}.initial", prm.initial, f"must lie within [{prm.low}, {prm.high}]")
    o = s.optimizer
    _one_of("study.optimizer.method", o.method, ("nelder-mead", "cobyla"))
    if o.max_evaluations < 1:
        raise ConfigError("study.optimizer.max_evaluations", o.max_evaluations, "must be a positive count")
    _positive("study.optimizer.tolerance", o.tolerance)
    if not 0.0 < o.initial_step <= 1.0:
        raise ConfigError("study.optimizer.initial_step", o.initial_step, "must lie in (0, 1]")
    _non_negative("study.optimizer.stop_ratio", o.stop_ratio)
    if o.restarts < 0:
        raise ConfigError("study.optimizer.restarts", o.restarts, "must be 0 or a positive count")


def _flight_times(times: list[float]) -> None:
    """``study.times``: at least one positive, finite flight time (s)."""
    if not times:
        raise ConfigError("study.times", list(times), "must list at least one flight time (s)")
    for i, t in enumerate(times):
        if not (t > 0.0 and np.isfinite(t)):
            raise ConfigError(f"study.times[{i}]", t, "must be a positive flight time in s")


def _check_time_margins(s: TimeMarginsStudyConfig) -> None:
    _flight_times(s.times)
    if not s.axes:
        raise ConfigError("study.axes", [], "must name at least one loop (pitch, yaw)")
    for i, axis in enumerate(s.axes):
        _one_of(f"study.axes[{i}]", axis, ("pitch", "yaw"))
    if not s.kinds:
        raise ConfigError("study.kinds", [], f"must name at least one of {', '.join(MARGIN_KINDS)}")
    for i, kind in enumerate(s.kinds):
        _one_of(f"study.kinds[{i}]", kind, MARGIN_KINDS)
    for key in ("window_s", "max_window_s", "gain_bound_dB", "delay_bound_ms", "gain_tolerance_dB",
                "delay_tolerance_ms", "excitation_deg", "excitation_s"):
        _positive(f"study.{key}", getattr(s, key))
    for key in ("lead_s", "min_periods", "event_clearance_s", "settle_s"):
        _non_negative(f"study.{key}", getattr(s, key))
    if s.lead_s > s.window_s:
        raise ConfigError("study.lead_s", s.lead_s, f"must not exceed study.window_s ({s.window_s} s)")
    if s.max_window_s < s.window_s:
        raise ConfigError("study.max_window_s", s.max_window_s, f"must be at least study.window_s ({s.window_s} s)")
    if s.settle_s >= s.window_s:
        raise ConfigError("study.settle_s", s.settle_s, f"must be shorter than study.window_s ({s.window_s} s)")
    if s.scan_points < 1:
        raise ConfigError("study.scan_points", s.scan_points, "must be a positive count")
    if not 0.0 < s.min_damping_ratio < 1.0:
        raise ConfigError("study.min_damping_ratio", s.min_damping_ratio,
                          "must lie in (0, 1): the damping ratio whose decay per period a stable response must "
                          "reach (0 would leave the verdict on a neutral oscillation to round-off)")
    if not 0 <= s.workers <= MAX_WORKERS:
        raise ConfigError("study.workers", s.workers, WORKERS_ALLOWED)
    _one_of("study.jacobian", s.jacobian, ("auto", "fixed"))
    _positive("study.jacobian_step", s.jacobian_step)


def _check_mode_retention(s: ModeRetentionStudyConfig) -> None:
    _flight_times(s.times)
    if s.step < 1:
        raise ConfigError("study.step", s.step, "must be a positive number of modes")
    if s.max_modes < 0:
        raise ConfigError("study.max_modes", s.max_modes, "must be 0 (as many as allowed) or a positive count")
    _positive("study.response_duration_s", s.response_duration_s)
    _positive("study.response_tolerance", s.response_tolerance)
    _positive("study.margin_tolerance_dB", s.margin_tolerance_dB)
    _positive("study.margin_tolerance_deg", s.margin_tolerance_deg)


def _check_flex_sweep(s: FlexSweepStudyConfig) -> None:
    _flight_times(s.times)
    if not s.parameters:
        raise ConfigError("study.parameters", list(s.parameters), "must list frequency and/or shape")
    for i, prm in enumerate(s.parameters):
        _one_of(f"study.parameters[{i}]", prm, ("frequency", "shape"))
    if not s.levels:
        raise ConfigError("study.levels", list(s.levels), "must list at least one scale factor")
    for i, v in enumerate(s.levels):
        if not (v > 0.0 and np.isfinite(v)):
            raise ConfigError(f"study.levels[{i}]", v, "must be a positive scale factor (1.0 = nominal)")
    for i, m in enumerate(s.modes):
        if m < 1:
            raise ConfigError(f"study.modes[{i}]", m, "must be a mode number, 1 = the lowest retained mode")
    for i, a in enumerate(s.chart_axes):
        _one_of(f"study.chart_axes[{i}]", a, ("pitch", "yaw"))
    _non_negative("study.event_clearance_s", s.event_clearance_s)


def _check_montecarlo(s: MonteCarloStudyConfig) -> None:
    """Counts and sharding; the dispersion spec is checked against the model by
    :func:`savant_cli.montecarlo.spec.parse` before anything runs."""
    if not 1 <= s.n_runs <= MAX_N_RUNS:
        raise ConfigError("study.n_runs", s.n_runs, f"must be between 1 (run 0 is the nominal) and {MAX_N_RUNS:,} "
                          "(a million runs without a failure demonstrate 0.9999977 at 90 % confidence)")
    if not 0 <= s.workers <= MAX_WORKERS:
        raise ConfigError("study.workers", s.workers, WORKERS_ALLOWED)
    if s.shards < 1 or s.shards > min(s.n_runs, MAX_SHARDS):
        raise ConfigError("study.shards", s.shards, f"must be between 1 and {min(s.n_runs, MAX_SHARDS):,} "
                          f"(study.n_runs = {s.n_runs}, and at most {MAX_SHARDS:,} scheduler jobs)")
    if not 0 <= s.shard < s.shards:
        raise ConfigError("study.shard", s.shard, f"must be between 0 and study.shards - 1 ({s.shards - 1})")
    if s.seed < 0:
        raise ConfigError("study.seed", s.seed, "must be a non-negative integer")
    _positive("study.histories.rate_hz", s.histories.rate_hz)
    for i, t in enumerate(s.linear_times):
        if not (t > 0.0 and np.isfinite(t)):
            raise ConfigError(f"study.linear_times[{i}]", t, "must be a positive flight time in s")
    r = s.reliability
    for key, value in (("confidence", r.confidence), ("target_probability", r.target_probability),
                       ("reserve_probability", r.reserve_probability)):
        if not 0.0 < value < 1.0:
            raise ConfigError(f"study.reliability.{key}", value, "must be a probability strictly between 0 and 1")


def check_frozen_time(f: FrozenTimeSpec, key: str) -> None:
    """Criteria among ``period``, ``control_power`` (each once); positive scan span and
    step, the step at most the span; a positive excitation."""
    for i, c in enumerate(f.criteria):
        _one_of(f"{key}.criteria[{i}]", c, ("period", "control_power"))
    if len(set(f.criteria)) != len(f.criteria):
        raise ConfigError(f"{key}.criteria", list(f.criteria), "names each criterion at most once")
    _positive(f"{key}.scan_s", f.scan_s)
    _positive(f"{key}.step_s", f.step_s)
    if f.step_s > f.scan_s:
        raise ConfigError(f"{key}.step_s", f.step_s, f"must be at most {key}.scan_s ({f.scan_s} s)")
    _positive(f"{key}.excitation_deg", f.excitation_deg)
    _positive(f"{key}.excitation_s", f.excitation_s)


def _check_linear(s: LinearStudyConfig) -> None:
    if s.every < 0:
        raise ConfigError("study.every", s.every, "must be zero (use study.times) or a positive interval in s")
    if s.every == 0:
        _flight_times(s.times)
    _non_negative("study.event_clearance_s", s.event_clearance_s)
    check_frozen_time(s.frozen_time, "study.frozen_time")
    _one_of("study.jacobian", s.jacobian, ("auto", "fixed"))
    _positive("study.jacobian_step", s.jacobian_step)
    _one_of("study.charts", s.charts, ("auto", "all", "none"))

