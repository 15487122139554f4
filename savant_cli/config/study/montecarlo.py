"""``study=montecarlo``: dispersed full-fidelity ascents."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from omegaconf import MISSING

from savant_cli.config.checks import positive
from savant_cli.config.study.common import MAX_WORKERS, WORKERS_ALLOWED
from savant_cli.errors import ConfigError


@dataclass
class HistoriesSpec:
    """Decimated time histories kept for every run (empty list: none)."""

    signals: list[str] = field(default_factory=list)
    rate_hz: float = MISSING


@dataclass
class ReliabilitySpec:
    """The success probability a batch demonstrates (``montecarlo/reliability.py``)."""

    confidence: float = MISSING  # one-sided confidence level of the demonstrated probability
    target_probability: float = MISSING  # the success probability the batch is to demonstrate
    # the flight-performance reserve covers this fraction of dispersed flights, at
    # ``confidence`` (montecarlo/insertion.py): 99.865 %, the 3-sigma-low flight
    reserve_probability: float = MISSING


#: Most runs of a Monte Carlo batch. A batch without a failure demonstrates a success
#: probability of 1 − 2.3/n at 90 % confidence: a million runs show 0.9999977, beyond any
#: crew-vehicle requirement; they take about 50 h at the measured 328 runs/min on the
#: 2-core machine (docs/montecarlo.md), and the batch's tables hold about 1.2 kB per run
#: in memory (1.2 GB). ``study.n_runs=1000000000000`` is refused before anything is built.
MAX_N_RUNS = 1_000_000

#: Most shards of a batch: each is one scheduler job and one folder ``savant collect``
#: reads; 10,000 shards of the largest batch are 100 runs each (SLURM's default job-array
#: limit, MaxArraySize, is 1,001).
MAX_SHARDS = 10_000

#: Most history samples of one signal over a batch, ``study.n_runs × sim.max_time_s ×
#: study.histories.rate_hz``: the envelope plots read one signal of every run at once,
#: 4 bytes a sample, so 2.5e8 samples are 1 GB in memory (the default batch: 4e6).
MAX_HISTORY_SAMPLES = 250_000_000


@dataclass
class MonteCarloStudyConfig:
    """``study=montecarlo``: dispersed full-fidelity ascents."""

    name: str = "montecarlo"
    n_runs: int = MISSING  # run 0 is the nominal
    seed: int = MISSING  # master seed; run i uses SeedSequence(seed).spawn(n)[i]
    workers: int = MISSING  # processes; 0: all cores
    shards: int = MISSING  # split the batch into this many shards …
    shard: int = MISSING  # … and fly this one (Hydra multirun: study.shard='range(0,N)')
    histories: HistoriesSpec = field(default_factory=HistoriesSpec)
    linear_times: list[float] = MISSING  # s: margins of every run at these times
    reliability: ReliabilitySpec = field(default_factory=ReliabilitySpec)


def check_montecarlo(s: MonteCarloStudyConfig) -> None:
    """Counts and sharding; the dispersion spec is checked against the model by
    :func:`savant_cli.montecarlo.spec.parse` before anything runs."""
    if not 1 <= s.n_runs <= MAX_N_RUNS:
        raise ConfigError("study.n_runs", s.n_runs, f"must be between 1 (run 0 is the nominal) and {MAX_N_RUNS:,} "
                          "(a million runs without a failure demonstrate 0.9999977 at 90 % confidence)")
    if not 0 <= s.workers <= MAX_WORKERS:
        raise ConfigError("study.workers", s.workers, WORKERS_ALLOWED)
    if s.shards < 1 or s.shards > min(s.n_runs, MAX_SHARDS):
        raise ConfigError("study.shards", s.shards, f"must be between 1 and {min(s.n_runs, MAX_SHARDS):,} "
                          f"(study.n_runs = {s.n_runs}, and at most {MAX_SHARDS:,} scheduler jobs)")
    if not 0 <= s.shard < s.shards:
        raise ConfigError("study.shard", s.shard, f"must be between 0 and study.shards - 1 ({s.shards - 1})")
    if s.seed < 0:
        raise ConfigError("study.seed", s.seed, "must be a non-negative integer")
    positive("study.histories.rate_hz", s.histories.rate_hz)
    for i, t in enumerate(s.linear_times):
        if not (t > 0.0 and np.isfinite(t)):
            raise ConfigError(f"study.linear_times[{i}]", t, "must be a positive flight time in s")
    r = s.reliability
    for key, value in (("confidence", r.confidence), ("target_probability", r.target_probability),
                       ("reserve_probability", r.reserve_probability)):
        if not 0.0 < value < 1.0:
            raise ConfigError(f"study.reliability.{key}", value, "must be a probability strictly between 0 and 1")
