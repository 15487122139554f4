"""One nominal flight of the configured vehicle: time histories, summary, plots."""

from __future__ import annotations

import time
from pathlib import Path

from omegaconf import DictConfig

from savant_cli.config import SavantConfig
from savant_cli.errors import RunInterrupted
from savant_cli.io.console import print_run_summary, study_console
from savant_cli.io.record import RunRecord
from savant_cli.sim.engine import STOP_SEPARATION
from savant_cli.sim.staging_state import StagingState, write_staging_state
from savant_cli.studies import flight as flight_mod


def fly(cfg: SavantConfig, raw_cfg: DictConfig, progress: bool | None = None,
        keep_partial: bool = False) -> tuple[RunRecord, StagingState | None]:
    """Fly one run and package it as a :class:`RunRecord` (nothing written), plus the
    staging state when the run stopped at separation (``keep_partial``: a Ctrl-C in
    flight returns the flight so far, status ``interrupted``)."""
    t_start = time.perf_counter()
    flight = flight_mod.fly(cfg, progress, keep_partial=keep_partial)
    result, summary = flight.result, flight.summary
    summary["study_wall_time_s"] = time.perf_counter() - t_start
    staging = None
    if result.stop_code == STOP_SEPARATION:
        staging = StagingState(vehicle=cfg.vehicle["name"], guidance=cfg.guidance.name,
                               dt_s=flight.prep.model.rates.dt, step=result.k_final, x=result.x, d=result.d,
                               u=result.u, names=tuple(flight.prep.model.layout.names()))
    return flight_mod.record(result, flight.signals, summary, raw_cfg, summary["study_wall_time_s"]), staging


def run(cfg: SavantConfig, raw_cfg: DictConfig, out_dir: Path) -> int:
    """Fly, print the summary, write ``savant.h5``, ``summary.json`` and plots into
    ``out_dir``; 0 on success. The summary is printed before the files are written, so
    it reaches the console when they cannot be (disk full: ``OutputWriteError``)."""
    console = study_console(cfg.output.console)
    record, staging = fly(cfg, raw_cfg, keep_partial=True)
    if record.status == "interrupted":
        # what was computed is written (the data, not the figures), then the interrupt
        # goes on to the command, which marks the folder and says this in one line
        flight_mod.write(out_dir, record, cfg, plots=False)
        raise RunInterrupted("flight", f"the flight to t = {record.summary.get('final_time_s', float('nan')):.2f} s "
                             f"is in savant.h5 and summary.json (status interrupted); `savant report {out_dir}` "
                             "draws its plots")
    # whether or not the disk takes the files
    print_run_summary(record.summary, record.status, record.message, console, cfg.output.console)
    if staging is not None:
        write_staging_state(out_dir / "staging_state.json", staging)
    flight_mod.write(out_dir, record, cfg)
    console.print(f"outputs: {out_dir}")
    return 0 if record.complete else 1
