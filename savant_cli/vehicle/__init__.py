"""Load a vehicle: its YAML config (``conf/vehicle/<name>.yaml``) and CSV tables, converted
to SI once, every bad value refused before any computation.

A vehicle is a tree of parts (:mod:`savant_cli.vehicle.tree`, read by
:mod:`savant_cli.vehicle.schema`; the YAML schema in ``docs/vehicles.md``). The plant flies
the two-stage records of :mod:`savant_cli.vehicle.two_stage`, derived from the tree. A
file in the old two-stage schema is refused naming ``savant convert-vehicle``
(:mod:`savant_cli.vehicle.convert`). Every refusal raises
:class:`savant_cli.errors.ConfigError` with the key (``vehicle.<path>`` or
``<folder>/<file>.csv:<column>``), the offending value and what is allowed.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from omegaconf import DictConfig, OmegaConf

from savant_cli.errors import ConfigError
from savant_cli.vehicle.convert import refuse_old_schema
from savant_cli.vehicle.schema import read_tree
from savant_cli.vehicle.tables import (
    AERO_COEFFICIENTS, TABLE_AXES, TABLE_COLUMNS, AeroTable, MassTable, read_aero, read_mass, read_table
)
from savant_cli.vehicle.tree import VehicleTree
from savant_cli.vehicle.two_stage import (
    CONFIG_NAMES, MASS_TOLERANCE_KG, Configuration, Engine, Events, FirstStage, Rcs, Sensors, UpperStage, Vehicle,
    check_consistency, two_stage_view
)

__all__ = ["AERO_COEFFICIENTS", "CONFIG_NAMES", "MASS_TOLERANCE_KG", "TABLE_AXES", "TABLE_COLUMNS", "AeroTable",
           "Configuration", "Engine", "Events", "FirstStage", "MassTable", "Rcs", "Sensors", "UpperStage", "Vehicle",
           "VehicleTree", "check_consistency", "load_vehicle", "read_aero", "read_mass", "read_table", "two_stage_view"]


def _to_plain(vehicle_cfg: Mapping) -> dict:
    """The vehicle section as plain Python containers (interpolations resolved)."""
    if isinstance(vehicle_cfg, DictConfig):
        return OmegaConf.to_container(vehicle_cfg, resolve=True)  # type: ignore[return-value]
    if not isinstance(vehicle_cfg, Mapping):
        raise ConfigError("vehicle", vehicle_cfg, "must be a mapping (the vehicle YAML)")
    return dict(vehicle_cfg)


def load_vehicle(vehicle_cfg: Mapping, data_dir: Path) -> Vehicle:
    """Load and check a vehicle.

    Parameters
    ----------
    vehicle_cfg : Mapping
        The ``vehicle`` config node (OmegaConf DictConfig or plain dict) of
        ``conf/vehicle/<name>.yaml``.
    data_dir : pathlib.Path
        Resolved folder of the vehicle's CSV tables.

    Returns
    -------
    Vehicle
        The plant's records (:func:`two_stage_view`) of the checked tree (its ``tree``):
        frozen dataclasses of float64 contiguous arrays, SI units (angles in rad,
        locations in the structure frame, inertias about the CG in body axes).

    Raises
    ------
    ConfigError
        A file in the old schema (naming the conversion command); unknown, missing or
        mistyped keys; names not unique or not found; an impossible event sequence or a
        configuration it does not reach; missing or malformed files; non-monotonic table
        axes; an aero grid that is not full and rectangular; negative mass, inertia,
        thrust or Isp; an inertia tensor that is not positive definite or violates the
        triangle inequality; mass tables inconsistent with the loads and the jettisoned
        masses; a vehicle shape the plant does not fly yet.
    """
    node = _to_plain(vehicle_cfg)
    refuse_old_schema(node)
    return two_stage_view(read_tree(node, Path(data_dir)))
