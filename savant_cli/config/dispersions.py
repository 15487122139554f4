"""``dispersions``: a vehicle's Monte Carlo dispersion set (checked against the model by
:func:`savant_cli.montecarlo.spec.parse`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any


class DispersionApply(StrEnum):
    """``apply``: the sample multiplies (``scale``), is added to (``offset``) or replaces
    (``value``) the nominal."""

    scale = "scale"
    offset = "offset"
    value = "value"


class DispersionDist(StrEnum):
    """``dist``: the distribution a dispersion is drawn from (docs/montecarlo.md)."""

    normal = "normal"
    uniform = "uniform"
    triangular = "triangular"
    choice = "choice"
    constant = "constant"


@dataclass
class DispersionSpec:
    """One dispersed quantity of ``study=montecarlo`` (see docs/montecarlo.md).

    ``target``: a config path (``winds.scale``, ``sensors.misalignment_deg.imu[1]``), a
    loaded-vehicle attribute (``vehicle.upper_stage.isp_vac_s``), a vehicle-table
    quantity (``tables.first_stage.thrust`` …) or the config group ``winds``.
    ``apply``: the sample multiplies (``scale``), is added to (``offset``) or replaces
    (``value``) the nominal."""

    target: str = ""
    apply: DispersionApply = DispersionApply.scale
    dist: DispersionDist = DispersionDist.normal
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
