"""The generic validators of config values and vehicle data: each raises
:class:`savant_cli.errors.ConfigError` naming the key, the value and what is allowed."""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from savant_cli.errors import ConfigError


def positive(key: str, value: float) -> float:
    """``value`` must be a positive finite number; returned as a float."""
    if not (value > 0.0 and np.isfinite(value)):
        raise ConfigError(key, value, "must be a positive finite number")
    return float(value)


def non_negative(key: str, value: float) -> float:
    """``value`` must be zero or a positive finite number; returned as a float."""
    if not (value >= 0.0 and np.isfinite(value)):
        raise ConfigError(key, value, "must be zero or positive")
    return float(value)


def no_negative_entries(key: str, values: np.ndarray, what: str) -> None:
    """No entry of the array ``values`` may be negative; the first one that is is named."""
    if np.any(values < 0.0):
        raise ConfigError(key, float(values[np.argmax(values < 0.0)]), f"{what} must not be negative")


#: OmegaConf's refusal of a value (or dict key) outside a choice's ``Enum`` type.
_ENUM_REFUSAL = re.compile(r"^(?:Invalid value '.*', expected one of|Key '.*' is incompatible with the enum type "
                           r"'\w+', valid:) \[(?P<allowed>[^\]]*)\]")


def allowed_of(message: str) -> str:
    """What is allowed, from the first line of an OmegaConf merge error: a choice (an
    ``Enum``-typed key) refused reads ``must be one of a, b`` as :func:`one_of` words
    it; any other message is returned as it is."""
    m = _ENUM_REFUSAL.match(message)
    if not m:
        return message
    subject = "its keys " if message.startswith("Key ") else ""  # a dict keyed by a choice
    return f"{subject}must be one of {m.group('allowed')}"


def one_of(key: str, value: Any, allowed: tuple) -> None:
    """``value`` must be one of ``allowed`` (the message lists them)."""
    if value not in allowed:
        raise ConfigError(key, value, f"must be one of {', '.join(map(str, allowed))}")


def small_angles(key: str, values: list[float], n: int, limit_deg: float, axes: str) -> None:
    """``values`` must be ``n`` finite angles (deg), each of magnitude at most ``limit_deg``."""
    vals = list(values)
    if len(vals) != n:
        raise ConfigError(key, vals, f"must list {n} angles in deg ({axes})")
    for i, v in enumerate(vals):
        if not (np.isfinite(v) and abs(v) <= limit_deg):
            raise ConfigError(f"{key}[{i}]", v, f"must be a finite angle within ±{limit_deg} deg")


def increasing(key: str, values: list[float]) -> None:
    """A table axis given as a YAML list: at least 2 finite numbers, strictly increasing as
    written; the first element out of order is named ``key[i]`` (refused, never sorted)."""
    arr = np.asarray(values, dtype=float)
    if arr.size < 2:
        raise ConfigError(key, list(values), "must be a strictly increasing list of at least 2 numbers")
    for i in range(arr.size):
        if not np.isfinite(arr[i]):
            raise ConfigError(f"{key}[{i}]", float(arr[i]), "must be a finite number")
        if i and arr[i] <= arr[i - 1]:
            raise ConfigError(f"{key}[{i}]", float(arr[i]), f"the list must be strictly increasing, and it follows "
                                                            f"{arr[i - 1]:g} at [{i - 1}]; put it in order (savant "
                                                            f"never sorts a table)")


def finite(key: str, value: float) -> None:
    """``value`` must be a finite number."""
    if not np.isfinite(value):
        raise ConfigError(key, value, "must be a finite number")
