"""The study schemas by name (:data:`STUDY_SCHEMAS`), a study section merged onto its
own schema and checked (:func:`study_option`), and the study times checked against the
flight (:func:`check_study_times`)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from omegaconf import OmegaConf
from omegaconf.errors import OmegaConfBaseException

from savant_cli.config.checks import allowed_of
from savant_cli.config.savant import SavantConfig
from savant_cli.config.study.fcs_design import FcsDesignStudyConfig, check_fcs_design
from savant_cli.config.study.flex_sweep import FlexSweepStudyConfig, check_flex_sweep
from savant_cli.config.study.flyoff import FlyoffStudyConfig, check_flyoff
from savant_cli.config.study.linear import LinearStudyConfig, check_linear
from savant_cli.config.study.mode_retention import ModeRetentionStudyConfig, check_mode_retention
from savant_cli.config.study.montecarlo import MAX_HISTORY_SAMPLES, MonteCarloStudyConfig, check_montecarlo
from savant_cli.config.study.nominal import StudyConfig
from savant_cli.config.study.time_margins import TimeMarginsStudyConfig, check_time_margins
from savant_cli.errors import ConfigError

#: Each study's physical checks, by name (``nominal`` has none).
STUDY_CHECKS: dict[str, Callable[[Any], None]] = {
    "nominal": lambda s: None, "linear": check_linear, "montecarlo": check_montecarlo, "flex_sweep": check_flex_sweep,
    "flyoff": check_flyoff, "mode_retention": check_mode_retention, "fcs_design": check_fcs_design,
    "time_margins": check_time_margins}

#: Each study's schema, by name.
STUDY_SCHEMAS: dict[str, type] = {"nominal": StudyConfig, "linear": LinearStudyConfig,
                                  "montecarlo": MonteCarloStudyConfig, "flex_sweep": FlexSweepStudyConfig,
                                  "flyoff": FlyoffStudyConfig, "mode_retention": ModeRetentionStudyConfig,
                                  "fcs_design": FcsDesignStudyConfig, "time_margins": TimeMarginsStudyConfig}


def study_option(node: Any) -> Any:
    """The study section merged onto its own study's schema (unknown keys refused)."""
    name = node.get("name") if isinstance(node, dict) else None
    if name not in STUDY_SCHEMAS:
        raise ConfigError("study.name", name, f"must be one of {', '.join(STUDY_SCHEMAS)}")
    try:
        study = OmegaConf.to_object(OmegaConf.merge(OmegaConf.structured(STUDY_SCHEMAS[name]), node))
    except OmegaConfBaseException as exc:
        key = "study." + str(getattr(exc, "full_key", None) or "?")
        msg = str(exc).splitlines()[0]
        if "missing mandatory value" in msg.lower():
            allowed = (f"is required: study={name} has no default for it (the shipped conf/study/{name}.yaml "
                       f"gives one)")
        else:
            allowed = "unknown key; see `savant run --cfg job`" if "not in" in msg else allowed_of(msg)
        raise ConfigError(key, getattr(exc, "value", None), allowed) from None
    STUDY_CHECKS[name](study)
    return study


def check_study_times(cfg: SavantConfig) -> None:
    """Flight times a study asks for must lie inside ``sim.max_time_s`` (the flight can
    reach no later), and ``study.every`` must not be finer than the flight-control cycle
    the study's snapshots land on; refused before anything flies. Times beyond the end
    of the flight itself are refused as soon as the flight has flown (``study=linear``
    says the flight's end)."""
    s, sim = cfg.study, cfg.sim
    lists = [("study.times", getattr(s, "times", None))] if not getattr(s, "every", 0.0) else []
    lists.append(("study.linear_times", getattr(s, "linear_times", None)))
    for key, times in lists:
        for i, t in enumerate(times or []):
            if not t < sim.max_time_s:
                raise ConfigError(f"{key}[{i}]", t, f"must be earlier than sim.max_time_s = {sim.max_time_s:g} s "
                                  "(the flight stops there)")
    every = getattr(s, "every", 0.0)
    if every > 0.0:
        cycle = 1.0 / sim.fcs_rate_hz
        if every < cycle - 1e-12:
            raise ConfigError("study.every", every, f"must be at least one flight-control cycle (1 / "
                              f"sim.fcs_rate_hz = {cycle:g} s): the points land on control cycles")
        if every >= sim.max_time_s:
            raise ConfigError("study.every", every, f"must be shorter than sim.max_time_s = {sim.max_time_s:g} s")
    if isinstance(s, MonteCarloStudyConfig):
        h = s.histories
        if h.signals and h.rate_hz > sim.log_rate_hz:
            raise ConfigError("study.histories.rate_hz", h.rate_hz,
                              f"must be at most sim.log_rate_hz = {sim.log_rate_hz:g} Hz (a decimation of the log)")
        samples = s.n_runs * sim.max_time_s * h.rate_hz
        if h.signals and samples > MAX_HISTORY_SAMPLES:
            raise ConfigError("study.histories.rate_hz", h.rate_hz,
                              f"{s.n_runs:,} runs × {sim.max_time_s:g} s would keep {samples:.3g} samples per signal; "
                              f"at most {MAX_HISTORY_SAMPLES:.3g} (1 GB, read at once by the envelope plots): allowed "
                              f"up to {MAX_HISTORY_SAMPLES / (s.n_runs * sim.max_time_s):.3g} Hz, fewer runs, or no "
                              "histories (study.histories.signals=[])")
