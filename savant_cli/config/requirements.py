"""``requirements``: the stability-margin requirement set and its checks."""

from __future__ import annotations

import re
from dataclasses import asdict, dataclass, field, replace
from enum import StrEnum
from typing import Optional

from omegaconf import MISSING

from savant_cli.config.checks import non_negative, positive
from savant_cli.errors import ConfigError
from savant_cli.io.record import FAILURE_CLASSES


@dataclass
class RigidRequirement:
    """Rigid-body margins: the gain-increase margin of the phase crossover above the
    control bandwidth (dB), the gain-reduction margin below it where the vehicle has no
    aerodynamic instability (the integrator's conditional stability, dB), and the phase
    margin at the bandwidth (deg)."""

    gain_dB: float = MISSING
    gain_reduction_dB: float = MISSING
    phase_deg: float = MISSING


@dataclass
class AeroRequirement:
    """Gain-reduction margin of the aerodynamically unstable vehicle (dB)."""

    gain_dB: float = MISSING


@dataclass
class SloshRequirement:
    """Margins of the crossings a propellant-slosh mode makes (dB, deg)."""

    gain_dB: float = MISSING
    phase_deg: float = MISSING


class Stabilization(StrEnum):
    """How a bending mode is required to be stabilized (``linear/requirements.py``)."""

    gain = "gain"
    phase = "phase"
    either = "either"


#: A mission failure class (``savant_cli/sim/mission.py``), named as the record names it.
FailureClass = StrEnum("FailureClass", [(c, c) for c in FAILURE_CLASSES])
FailureClass.__doc__ = "A mission failure class (``savant_cli/sim/mission.py``; ``io/record.FAILURE_CLASSES``)."


@dataclass
class FlexModeRequirement:
    """One bending mode's requirement: ``gain``-stabilized (its loop peak at least
    ``gain_dB`` below 0 dB), ``phase``-stabilized (every crossing it makes: phase margin
    at least ``phase_deg``, gain margin at least ``gain_dB``) or ``either``."""

    stabilization: Stabilization = MISSING
    gain_dB: float = MISSING
    phase_deg: float = MISSING


@dataclass
class FlexModeOverride:
    """A bending mode's departures from its stage's ``default`` (``modes.flex_<n>``): each
    key given replaces the default's, each left out (None) keeps it."""

    stabilization: Optional[Stabilization] = None
    gain_dB: Optional[float] = None
    phase_deg: Optional[float] = None


@dataclass
class FlexStageRequirement:
    """A stage's bending-mode requirements: ``default`` for every mode, ``modes`` (keys
    ``flex_<n>``, the 1-based retained mode) for the modes that differ, key by key."""

    default: FlexModeRequirement = field(default_factory=FlexModeRequirement)
    modes: dict[str, FlexModeOverride] = field(default_factory=dict)

    def mode(self, mode: str) -> FlexModeRequirement:
        """The requirement of bending mode ``mode`` (``flex_<n>``): the default with the
        mode's own keys in place of the default's."""
        given = self.modes.get(mode)
        if given is None:
            return self.default
        return replace(self.default, **{k: v for k, v in asdict(given).items() if v is not None})


@dataclass
class FlexRequirement:
    """``requirements.flex``: the bending-mode requirements of each stage (dB, deg).

    Attributes
    ----------
    first_stage, upper_stage : FlexStageRequirement
        Each stage's default and per-mode requirements."""

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
    mission: a run succeeds when none of its classes is listed (the shipped sets list
    every class)."""

    failure_classes: list[FailureClass] = MISSING


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
        return getattr(self.flex, stage).mode(mode)

    def by_band(self) -> dict[str, tuple[float, float]]:
        """Band → (gain margin dB, phase margin deg) the charts mark: the rigid body's,
        the slosh modes' and the first stage's default bending-mode requirement."""
        fd = self.flex.first_stage.default
        return {"rigid/aero": (self.rigid.gain_dB, self.rigid.phase_deg),
                "slosh": (self.slosh.gain_dB, self.slosh.phase_deg), "flex": (fd.gain_dB, fd.phase_deg)}


def check_requirements(r: RequirementSet) -> None:
    """Margins are non-negative finite numbers; per-mode keys ``flex_<n>``; the failure
    classes each named once (their names and the stabilizations are typed by the schema)."""
    for key, value in (("rigid.gain_dB", r.rigid.gain_dB), ("rigid.gain_reduction_dB", r.rigid.gain_reduction_dB),
                       ("rigid.phase_deg", r.rigid.phase_deg), ("aero.gain_dB", r.aero.gain_dB),
                       ("slosh.gain_dB", r.slosh.gain_dB), ("slosh.phase_deg", r.slosh.phase_deg)):
        non_negative(f"requirements.{key}", value)
    for stage in ("first_stage", "upper_stage"):
        st = getattr(r.flex, stage)
        for name, m in [("default", st.default)] + [(f"modes.{k}", st.mode(k)) for k in st.modes]:
            key = f"requirements.flex.{stage}.{name}"
            if name != "default" and not re.fullmatch(r"modes\.flex_[1-9][0-9]*", name):
                raise ConfigError(key, name.split(".", 1)[1], "a bending mode is named flex_<n> (1-based retained mode)")
            non_negative(f"{key}.gain_dB", m.gain_dB)
            non_negative(f"{key}.phase_deg", m.phase_deg)
    for name in ("max_body_rate_deg_s", "max_attitude_error_deg", "max_qalpha_Pa_deg"):
        value = getattr(r.separation, name)
        if value is not None:
            positive(f"requirements.separation.{name}", value)
    if len(set(r.mission.failure_classes)) != len(r.mission.failure_classes):
        raise ConfigError("requirements.mission.failure_classes", list(r.mission.failure_classes),
                          "names each class at most once")
