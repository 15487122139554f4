"""The configuration schema (structured dataclasses) and its physical validation, one
module per concern; this package's public API is every name below.

Hydra composes the YAML tree in ``conf/``; :func:`validate` then merges the result onto
the schema, which refuses unknown keys and wrong types, and checks physical sense
(rates that divide each other, positive frequencies, blending weights summing to 1 …).
Every refusal is a :class:`savant_cli.errors.ConfigError` naming the key, the value and
what is allowed; the command line turns it into exit status 2. Nothing here imports
Hydra: the schema is put in Hydra's ConfigStore by
:func:`savant_cli.hydra_compose.register_schema`, which the entry points call.

Where things are: ``run`` (sim, environment, phase), ``output``, ``requirements``,
``dispersions``, one module per model group (``actuator``, ``flex``, ``slosh``, ``twd``,
``navigation``, ``winds``, ``sensors``, ``controller``, ``guidance``), ``study/`` (one
module per study), ``savant`` (the whole config), ``checks`` (the generic validators)
and ``validation`` (:func:`validate`). Each schema's checks follow it in its module.
"""

from __future__ import annotations

from savant_cli.config.actuator import (
    ActuatorStageCommon, SimplexActuatorConfig, SimplexFeedback, SimplexStage, ThirdOrderActuatorConfig,
    ThirdOrderStage, check_actuator
)
from savant_cli.config.controller import (
    AxisGains, Blending, ControllerConfig, ControllerDesign, FilterSection, FilterSet, FilterSets, GainTable,
    GainTables, IgnitionFade, RollControl, check_delay
)
from savant_cli.config.dispersions import (
    CorrelationGroup, DispersionApply, DispersionDist, DispersionSetConfig, DispersionSpec
)
from savant_cli.config.flex import FlexOffConfig, FlexOnConfig, FlexSwitching, check_flex
from savant_cli.config.guidance import (
    FirstStageSchedule, GuidanceConfig, InsertionTolerance, LaunchSite, OrbitTarget, PegConfig, SmootherConfig,
    check_peg, check_target
)
from savant_cli.config.model_group import ModelGroup
from savant_cli.config.navigation import (
    NAVIGATION_BOUNDS, AccelerometerErrorsConfig, GyroErrorsConfig, NavigationInertialConfig, NavigationPerfectConfig,
    check_navigation
)
from savant_cli.config.output import OutputConfig
from savant_cli.config.requirements import (
    AeroRequirement, FailureClass, FlexModeOverride, FlexModeRequirement, FlexRequirement, FlexStageRequirement,
    MissionRequirement, RequirementSet, RigidRequirement, SeparationRequirement, SloshRequirement, Stabilization,
    check_requirements
)
from savant_cli.config.run import (
    MAX_LOG_ROWS, SIM_BOUNDS, EnvironmentConfig, HealthConfig, PhaseConfig, PhaseStart, PhaseStop, SimConfig
)
from savant_cli.config.savant import GROUP_VARIANTS, MODEL_GROUPS, SavantConfig, check_vehicle_match
from savant_cli.config.sensors import RateGyroConfig, SensorMisalignment, SensorsConfig
from savant_cli.config.shipped import linear_settings, shipped_option
from savant_cli.config.slosh import SloshOffConfig, SloshOnConfig, check_slosh
from savant_cli.config.study import STUDY_SCHEMAS, check_study_times
from savant_cli.config.study.common import MAX_WORKERS, WORKERS_ALLOWED, Jacobian, LoopAxis
from savant_cli.config.study.fcs_design import (
    STACK_ONLY_PARAMETERS, DesignOptimizer, DesignParameter, DesignParameters, DesignSchedule, FcsDesignStudyConfig,
    OptimizerMethod, ScheduleParameters, design_controller_name
)
from savant_cli.config.study.flex_sweep import FlexSweepStudyConfig, SweepParameter
from savant_cli.config.study.flyoff import FlyoffStudyConfig
from savant_cli.config.study.linear import (
    ChartMode, FrozenTimeCriterion, FrozenTimeSpec, LinearStudyConfig, check_frozen_time
)
from savant_cli.config.study.mode_retention import ModeRetentionStudyConfig
from savant_cli.config.study.montecarlo import (
    MAX_HISTORY_SAMPLES, MAX_N_RUNS, MAX_SHARDS, HistoriesSpec, MonteCarloStudyConfig, ReliabilitySpec
)
from savant_cli.config.study.nominal import StudyConfig
from savant_cli.config.study.time_margins import MarginKind, TimeMarginsStudyConfig
from savant_cli.config.twd import TwdOffConfig, TwdOnConfig
from savant_cli.config.validation import check_physics, group_option, has_key, validate
from savant_cli.config.winds import (
    MAX_WINDS_SCALE, GustConfig, GustFrame, GustOnset, ShearConfig, ShearShape, WindProfile, WindsConfig,
    check_gust_shear
)

__all__ = [
    "AccelerometerErrorsConfig", "ActuatorStageCommon", "AeroRequirement", "AxisGains", "Blending", "ChartMode",
    "ControllerConfig", "ControllerDesign", "CorrelationGroup", "DesignOptimizer", "DesignParameter",
    "DesignParameters", "DesignSchedule", "DispersionApply", "DispersionDist", "DispersionSetConfig",
    "DispersionSpec", "EnvironmentConfig", "FailureClass", "FcsDesignStudyConfig", "FilterSection", "FilterSet",
    "FilterSets", "FirstStageSchedule", "FlexModeOverride", "FlexModeRequirement", "FlexOffConfig", "FlexOnConfig",
    "FlexRequirement", "FlexStageRequirement", "FlexSweepStudyConfig", "FlexSwitching", "FlyoffStudyConfig",
    "FrozenTimeCriterion", "FrozenTimeSpec", "GROUP_VARIANTS", "GainTable", "GainTables", "GuidanceConfig",
    "GustConfig", "GustFrame", "GustOnset", "GyroErrorsConfig", "HealthConfig", "HistoriesSpec", "IgnitionFade",
    "InsertionTolerance", "Jacobian", "LaunchSite", "LinearStudyConfig", "LoopAxis", "MAX_HISTORY_SAMPLES",
    "MAX_LOG_ROWS", "MAX_N_RUNS", "MAX_SHARDS", "MAX_WINDS_SCALE", "MAX_WORKERS", "MODEL_GROUPS", "MarginKind",
    "MissionRequirement", "ModeRetentionStudyConfig", "ModelGroup", "MonteCarloStudyConfig", "NAVIGATION_BOUNDS",
    "NavigationInertialConfig", "NavigationPerfectConfig", "OptimizerMethod", "OrbitTarget", "OutputConfig",
    "PegConfig", "PhaseConfig", "PhaseStart", "PhaseStop", "RateGyroConfig", "ReliabilitySpec", "RequirementSet",
    "RigidRequirement", "RollControl", "SIM_BOUNDS", "STACK_ONLY_PARAMETERS", "STUDY_SCHEMAS", "SavantConfig",
    "ScheduleParameters", "SensorMisalignment", "SensorsConfig", "SeparationRequirement", "ShearConfig", "ShearShape",
    "SimConfig", "SimplexActuatorConfig", "SimplexFeedback", "SimplexStage", "SloshOffConfig", "SloshOnConfig",
    "SloshRequirement", "SmootherConfig", "Stabilization", "StudyConfig", "SweepParameter",
    "ThirdOrderActuatorConfig", "ThirdOrderStage", "TimeMarginsStudyConfig", "TwdOffConfig", "TwdOnConfig",
    "WORKERS_ALLOWED", "WindProfile", "WindsConfig", "check_actuator", "check_delay", "check_flex",
    "check_frozen_time", "check_gust_shear", "check_navigation", "check_peg", "check_physics", "check_requirements",
    "check_slosh", "check_study_times", "check_target", "check_vehicle_match", "design_controller_name",
    "group_option", "has_key", "linear_settings", "shipped_option", "validate",
]
