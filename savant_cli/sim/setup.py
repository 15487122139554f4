"""From a validated config to a ready-to-fly numeric model: find and load the data
files, then build. Every data problem surfaces here as a ConfigError, before any
computation."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from savant_cli.config import SavantConfig
from savant_cli.errors import ConfigError
from savant_cli.io.guidance_file import read_guidance
from savant_cli.paths import hydra_search_dirs, resolve_data_path
from savant_cli.sim.build import SimModel, build_model
from savant_cli.sim.staging_state import read_staging_state
from savant_cli.vehicle import Vehicle, load_vehicle

log = logging.getLogger(__name__)


@dataclass
class Prepared:
    """One run made ready to fly (:func:`prepare`).

    Attributes
    ----------
    model : SimModel
        The numeric model (parameters, tables, schedules and the pad state, SI).
    vehicle : Vehicle
        The loaded vehicle data (SI).
    vehicle_dir : Path
        The folder the vehicle data was read from.
    command_file : Path
        The guidance command file read.
    """

    model: SimModel
    vehicle: Vehicle
    vehicle_dir: Path
    command_file: Path


def prepare(cfg: SavantConfig, search_dirs: list[Path] | None = None) -> Prepared:
    """Load the vehicle and the guidance commands named by ``cfg`` and build the model."""
    dirs = search_dirs or hydra_search_dirs()
    vcfg = cfg.vehicle
    vdir = resolve_data_path("vehicle.data_dir", "vehicle", str(vcfg.get("data_dir", "")), dirs, must_be_dir=True)
    vehicle = load_vehicle(vcfg, vdir)
    cmd = resolve_data_path("guidance.command_file", "guidance", cfg.guidance.command_file, dirs)
    table = read_guidance(cmd)
    model = build_model(cfg, vehicle, table)
    if cfg.phase.start == "staging":
        start_from_staging(model, cfg, resolve_data_path("phase.staging_state_file", "phase",
                                                         cfg.phase.staging_state_file, dirs))
    return Prepared(model=model, vehicle=vehicle, vehicle_dir=vdir, command_file=cmd)


def start_from_staging(model: SimModel, cfg: SavantConfig, path: Path) -> None:
    """Replace the model's pad start by a stored staging state (checked for the same
    vehicle, guidance and plant step)."""
    st = read_staging_state(path)
    key = "phase.staging_state_file"
    if st.vehicle != cfg.vehicle["name"]:
        raise ConfigError(key, str(path), f"was written for vehicle {st.vehicle!r}, not {cfg.vehicle['name']!r}")
    if st.guidance != cfg.guidance.name:
        raise ConfigError(key, str(path), f"was written for guidance {st.guidance!r}, not {cfg.guidance.name!r}")
    if abs(st.dt_s - model.rates.dt) > 1e-12:
        raise ConfigError(key, str(path), f"was written with a plant step of {st.dt_s} s; sim.plant_rate_hz gives {model.rates.dt} s")
    model.x0 = staging_vector(st, model.layout, key, path)
    model.d0, model.u0, model.k0 = st.d, st.u, st.step


#: The propellant states' names before the tanks were named (savant 0.1): the two-stage
#: vehicle's first-stage, LOX and LH2 tanks, in the order of ``Vehicle.tanks``.
LEGACY_TANK_STATES = ("prop_first_stage", "prop_lox", "prop_lh2")


def staging_vector(st, layout, key: str, path: Path) -> np.ndarray:
    """The model's state vector from a staging state, by name.

    States of models the file was written without start at rest: exact for the flex
    modes and the actuators (all restart at separation) and an approximation for
    slosh (logged). A model the file has but the config has off is ignored. A file
    written before the tanks were named gives the propellant states by their old names
    (:data:`LEGACY_TANK_STATES`), read as the vehicle's three tanks in order.
    """
    have = dict(zip(st.names, st.x, strict=True))
    if len(layout.tanks) == len(LEGACY_TANK_STATES):
        for old, tank in zip(LEGACY_TANK_STATES, layout.tanks):
            if old in have:
                have.setdefault(f"prop_{tank}", have[old])
    x = np.zeros(layout.n)
    missing_slosh = False
    for i, name in enumerate(layout.names()):
        if name in have:
            x[i] = have[name]
        elif name.startswith(("flex_", "valve_")) or name.endswith(("_piston", "_ddot")):
            x[i] = 0.0  # reset at separation anyway
        elif name.startswith("slosh_"):
            missing_slosh = True
        else:
            raise ConfigError(key, str(path), f"has no state {name!r}")
    if missing_slosh:
        log.warning("%s was written without slosh: the slosh masses start at rest at separation", path)
    return x
