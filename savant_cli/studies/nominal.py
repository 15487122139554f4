"""One nominal flight of the configured vehicle: time histories, summary, plots."""

from __future__ import annotations

import time
from pathlib import Path

from omegaconf import DictConfig, OmegaConf
from rich.console import Console

from savant_cli.config import SavantConfig
from savant_cli.io.console import print_run_summary
from savant_cli.io.atomic import write_json_atomic
from savant_cli.io.hdf5 import write_run
from savant_cli.io.provenance import collect_provenance
from savant_cli.io.record import RunRecord
from savant_cli.sim.run import simulate, signals
from savant_cli.sim.setup import prepare
from savant_cli.sim.summary import summarize
from savant_cli.io.staging_state import StagingState, write_staging_state
from savant_cli.sim.engine import EVENT_NAMES, STOP_SEPARATION


def fly(cfg: SavantConfig, raw_cfg: DictConfig, progress: bool | None = None) -> tuple[RunRecord, StagingState | None]:
    """Fly one run and package it as a :class:`RunRecord` (nothing written), plus the
    staging state when the run stopped at separation."""
    t_start = time.perf_counter()
    prep = prepare(cfg)
    result = simulate(prep.model, progress=cfg.sim.progress if progress is None else progress,
                      chunk_s=cfg.sim.chunk_s)
    sig = signals(result, prep.model)
    summary = summarize(result, sig)
    events = [(name, float(t)) for name, t in zip(EVENT_NAMES, result.events) if t == t]
    summary["study_wall_time_s"] = time.perf_counter() - t_start
    staging = None
    if result.stop_code == STOP_SEPARATION:
        staging = StagingState(vehicle=cfg.vehicle["name"], guidance=cfg.guidance.name, dt_s=prep.model.rates.dt,
                               step=result.k_final, x=result.x, d=result.d, u=result.u,
                               names=tuple(prep.model.layout.names()))
    return RunRecord(
        signals=sig, events=events, summary=summary,
        config_yaml=OmegaConf.to_yaml(raw_cfg, resolve=True),
        provenance=collect_provenance(wall_time_s=summary["study_wall_time_s"]),
        complete=result.status == "complete", status=result.status, message=result.message,
    ), staging


def run(cfg: SavantConfig, raw_cfg: DictConfig, out_dir: Path) -> int:
    """Fly, write ``savant.h5``, ``summary.json`` and plots into ``out_dir``; 0 on success."""
    console = Console()
    record, staging = fly(cfg, raw_cfg)
    out_dir.mkdir(parents=True, exist_ok=True)
    if staging is not None:
        write_staging_state(out_dir / "staging_state.json", staging)
    if cfg.output.hdf5:
        write_run(out_dir / "savant.h5", record)
    write_json_atomic(out_dir / "summary.json", record.summary)
    if cfg.output.plots:
        from savant_cli.plots.ascent import plot_ascent

        plot_ascent(record, out_dir / "plots")
    print_run_summary(record.summary, record.status, record.message, console)
    console.print(f"outputs: {out_dir}")
    return 0 if record.complete else 1
