"""One nominal flight of the configured vehicle: time histories, summary, plots."""

from __future__ import annotations

import time
from pathlib import Path

from omegaconf import DictConfig

from savant_cli.config import SavantConfig
from savant_cli.io.console import print_run_summary, study_console
from savant_cli.io.record import RunRecord
from savant_cli.io.staging_state import StagingState, write_staging_state
from savant_cli.sim.engine import STOP_SEPARATION
from savant_cli.studies import flight as flight_mod


def fly(cfg: SavantConfig, raw_cfg: DictConfig, progress: bool | None = None) -> tuple[RunRecord, StagingState | None]:
    """Fly one run and package it as a :class:`RunRecord` (nothing written), plus the
    staging state when the run stopped at separation."""
    t_start = time.perf_counter()
    flight = flight_mod.fly(cfg, progress)
    result, summary = flight.result, flight.summary
    summary["study_wall_time_s"] = time.perf_counter() - t_start
    staging = None
    if result.stop_code == STOP_SEPARATION:
        staging = StagingState(vehicle=cfg.vehicle["name"], guidance=cfg.guidance.name,
                               dt_s=flight.prep.model.rates.dt, step=result.k_final, x=result.x, d=result.d,
                               u=result.u, names=tuple(flight.prep.model.layout.names()))
    return flight_mod.record(result, flight.signals, summary, raw_cfg, summary["study_wall_time_s"]), staging


def run(cfg: SavantConfig, raw_cfg: DictConfig, out_dir: Path) -> int:
    """Fly, write ``savant.h5``, ``summary.json`` and plots into ``out_dir``; 0 on success."""
    console = study_console(cfg.output.console)
    record, staging = fly(cfg, raw_cfg)
    out_dir.mkdir(parents=True, exist_ok=True)
    if staging is not None:
        write_staging_state(out_dir / "staging_state.json", staging)
    flight_mod.write(out_dir, record, cfg)
    print_run_summary(record.summary, record.status, record.message, console, cfg.output.console)
    console.print(f"outputs: {out_dir}")
    return 0 if record.complete else 1
