"""One shared way to fly, record and write a run, for every study.

:func:`fly` loads the data, builds the model and flies it (with the snapshots a study
asks for), then names the signals and computes the summary; :func:`record` packages a
flight as a :class:`~savant_cli.io.record.RunRecord` (events, resolved config,
provenance, completion status); :func:`write` writes a record as a nominal run is
written: ``savant.h5`` (with the study's own groups), ``summary.json`` and the ascent
plots.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from omegaconf import DictConfig, OmegaConf

from savant_cli import lifecycle
from savant_cli.config import SavantConfig
from savant_cli.io.atomic import write_json_atomic
from savant_cli.io.hdf5 import write_run
from savant_cli.io.provenance import collect_provenance
from savant_cli.io.record import FLOWN, RunRecord, Signal
from savant_cli.sim.build import rates
from savant_cli.sim.engine import EVENT_NAMES
from savant_cli.sim.run import SimResult, signals, simulate
from savant_cli.sim.run_summary import run_summary
from savant_cli.sim.setup import Prepared, prepare


@dataclass
class Flight:
    """A flown run: the prepared model, the raw result, named signals and summary."""

    prep: Prepared
    result: SimResult
    signals: dict[str, Signal]
    summary: dict[str, Any]


def fly(cfg: SavantConfig, progress: bool | None = None, snapshot_steps: tuple[int, ...] = (),
        keep_partial: bool = False) -> Flight:
    """Prepare and fly ``cfg`` (``progress``: the bar, default ``sim.progress``), keeping the
    state at ``snapshot_steps`` (plant steps). A Ctrl-C in flight propagates, unless
    ``keep_partial``: then the flight so far comes back with status ``interrupted``."""
    lifecycle.stage("prepare")
    prep = prepare(cfg)
    result = simulate(prep.model, progress=cfg.sim.progress if progress is None else progress,
                      chunk_s=cfg.sim.chunk_s, snapshot_steps=snapshot_steps, keep_partial=keep_partial)
    lifecycle.stage("analysis")
    sig = signals(result, prep.model)
    summary = run_summary(result, sig, prep.model, cfg, prep.vehicle.qalpha_limit_Pa_deg)
    return Flight(prep=prep, result=result, signals=sig, summary=summary)


def write_then_show(write: Callable[[], None], show: Callable[[], None]) -> None:
    """``write()`` a study's files, then ``show()`` its console summary; the summary is
    shown too when a file cannot be written (:class:`~savant_cli.errors.OutputWriteError`,
    raised again after it)."""
    from savant_cli.errors import OutputWriteError

    try:
        write()
    except OutputWriteError:
        show()
        raise
    show()


def control_steps(cfg: SavantConfig, times: list[float]) -> tuple[int, ...]:
    """Plant steps of the flight-control cycles nearest to ``times`` (s): where a study
    takes its snapshots."""
    rt = rates(cfg)
    return tuple(int(round(t / (rt.dt * rt.n_fcs))) * rt.n_fcs for t in times)


def events_of(result: SimResult) -> list[tuple[str, float]]:
    """The events that happened, in the order they did: ``(name, mission time s)``."""
    return sorted(((name, float(t)) for name, t in zip(EVENT_NAMES, result.events) if t == t), key=lambda e: e[1])


def record(result: SimResult, sig: dict[str, Signal], summary: dict[str, Any], raw_cfg: DictConfig,
           wall_time_s: float | None = None) -> RunRecord:
    """A flight as a :class:`RunRecord`: its events, the resolved config, provenance
    (with the study's wall time when given) and its completion status."""
    return RunRecord(signals=sig, events=events_of(result), summary=summary,
                     config_yaml=OmegaConf.to_yaml(raw_cfg, resolve=True),
                     provenance=collect_provenance(wall_time_s=wall_time_s),
                     complete=result.status in FLOWN, status=result.status, message=result.message)


def write(out_dir: Path, rec: RunRecord, cfg: SavantConfig, json_summary: dict[str, Any] | None = None,
          extra: Callable | None = None, plots: bool = True) -> None:
    """Write a record into ``out_dir``: ``savant.h5`` (``extra(h5file)`` adds a study's
    groups) unless ``output.hdf5`` is off, ``summary.json`` (``json_summary``, default the
    record's) and the ascent plots unless ``output.plots`` is off or ``plots`` is False. A
    file that cannot be written raises :class:`~savant_cli.errors.OutputWriteError` (the
    ones before it stay whole)."""
    lifecycle.stage("writing")
    if cfg.output.hdf5:  # atomic_path makes out_dir (an OutputWriteError when it cannot)
        write_run(out_dir / "savant.h5", rec, extra=extra)
    write_json_atomic(out_dir / "summary.json", rec.summary if json_summary is None else json_summary)
    if cfg.output.plots and plots:
        lifecycle.stage("plots")
        from savant_cli.plots.ascent import plot_ascent

        plot_ascent(rec, out_dir / "plots")
