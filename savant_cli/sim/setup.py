"""From a validated config to a ready-to-fly numeric model: find and load the data
files, then build. Every data problem surfaces here as a ConfigError, before any
computation."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from savant_cli.config import SavantConfig
from savant_cli.errors import ConfigError
from savant_cli.io.staging_state import read_staging_state
from savant_cli.io.guidance_file import read_guidance
from savant_cli.paths import hydra_search_dirs, resolve_data_path
from savant_cli.sim.build import SimModel, build_model
from savant_cli.vehicle import Vehicle, load_vehicle


@dataclass
class Prepared:
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
    model.x0, model.d0, model.u0, model.k0 = st.x, st.d, st.u, st.step
