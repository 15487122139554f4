"""Staging-state files: the complete simulation state at first-stage separation, so an
upper-stage phase (``phase=upper_stage``) can start there without flying the first stage.

A ``phase=first_stage`` run writes ``staging_state.json`` into its output folder. The
state is taken at the plant step where separation triggers, *before* it is applied, so
a run resumed from it separates on its first step exactly as the full ascent does.

JSON layout: ``format`` ("savant-staging-state"), ``format_version``, ``vehicle``,
``guidance``, ``dt_s`` (plant step), ``step`` (plant step index), ``time_s``, ``state``
(name → value, SI, the names of :meth:`savant_cli.models.layout.StateLayout.names`: the
rigid body, the vehicle's tanks, gimbal channels and roll jets, then the optional models
that were on), ``discrete`` and ``inputs``
(flight-software state and held inputs, as lists).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from savant_cli.errors import ConfigError
from savant_cli.io.atomic import write_json_atomic
from savant_cli.models import layout

FORMAT = "savant-staging-state"
FORMAT_VERSION = 1


@dataclass(frozen=True)
class StagingState:
    """The simulation state at the plant step where separation triggers.

    Attributes
    ----------
    vehicle, guidance : str
        The vehicle and guidance config names the state was flown with (a resumed run
        must match them).
    dt_s : float
        Plant step, s.
    step : int
        Plant step index; the mission time is ``step * dt_s`` s.
    x : ndarray
        Continuous state (SI, ECI position and velocity, attitude quaternion body → ECI),
        in the order of ``names``.
    d : ndarray
        Discrete flight-software state (``layout.N_DISC`` values).
    u : ndarray
        Held plant inputs (``layout.N_INPUT`` values).
    names : tuple of str
        One name per element of ``x`` (:meth:`savant_cli.models.layout.StateLayout.names`).
    """

    vehicle: str
    guidance: str
    dt_s: float
    step: int
    x: np.ndarray
    d: np.ndarray
    u: np.ndarray
    names: tuple[str, ...] = tuple(layout.STATE_NAMES)  # one per element of x


def write_staging_state(path: Path, state: StagingState) -> None:
    """Write a staging-state file atomically."""
    write_json_atomic(path, {
        "format": FORMAT, "format_version": FORMAT_VERSION, "vehicle": state.vehicle, "guidance": state.guidance,
        "dt_s": state.dt_s, "step": int(state.step), "time_s": state.step * state.dt_s,
        "state": dict(zip(state.names, map(float, state.x), strict=True)),
        "discrete": [float(v) for v in state.d], "inputs": [float(v) for v in state.u],
    })


def read_staging_state(path: Path, key: str = "phase.staging_state_file") -> StagingState:
    """Read and check a staging-state file (ConfigError on anything malformed)."""
    try:
        doc = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise ConfigError(key, str(path), f"unreadable staging-state file ({exc})") from None
    if doc.get("format") != FORMAT or doc.get("format_version") != FORMAT_VERSION:
        raise ConfigError(key, str(path), f"not a {FORMAT} file of version {FORMAT_VERSION}")
    names = list(doc.get("state", {}))
    if names[:layout.N_STATE] != list(layout.STATE_NAMES):
        raise ConfigError(key, str(path), f"the state must start with the rigid-body states {list(layout.STATE_NAMES)}")
    d = np.asarray(doc["discrete"], float)
    u = np.asarray(doc["inputs"], float)
    if d.size > layout.N_DISC or u.size > layout.N_INPUT:
        raise ConfigError(key, str(path), f"needs at most {layout.N_DISC} discrete and {layout.N_INPUT} input values")
    # discrete fields and inputs are only ever appended (models/__init__.py, models/layout.py):
    # those a file was written without start at their initial zero (the throttle at 1)
    d = np.concatenate([d, np.zeros(layout.N_DISC - d.size)])
    written = u.size
    u = np.concatenate([u, np.zeros(layout.N_INPUT - u.size)])
    if written <= layout.U_THROTTLE:  # written before the throttle: its vehicle burned at rated thrust
        u[layout.U_THROTTLE] = 1.0
    x = np.array([doc["state"][n] for n in names], float)
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(d)) and np.all(np.isfinite(u))):
        raise ConfigError(key, str(path), "all values must be finite")
    return StagingState(vehicle=str(doc["vehicle"]), guidance=str(doc["guidance"]), dt_s=float(doc["dt_s"]),
                        step=int(doc["step"]), x=x, d=d, u=u, names=tuple(names))
