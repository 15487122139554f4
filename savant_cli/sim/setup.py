"""From a validated config to a ready-to-fly numeric model: find and load the data
files, then build. Every data problem surfaces here as a ConfigError, before any
computation."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from savant_cli.config import SavantConfig
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
    return Prepared(model=build_model(cfg, vehicle, table), vehicle=vehicle, vehicle_dir=vdir, command_file=cmd)
