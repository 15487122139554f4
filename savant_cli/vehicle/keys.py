"""The key checks of the vehicle YAML: unknown, missing and mistyped keys refused with
their path, the value and what is allowed (:class:`savant_cli.errors.ConfigError`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from savant_cli.errors import ConfigError
from savant_cli.vehicle.tables import is_number

#: Value kinds of a key (besides ``float``, ``int``, ``str`` and a nested schema dict).
VEC3 = "vec3"  # [x, y, z], finite numbers
VEC2 = "vec2"  # [pitch, yaw], finite numbers
VEC6 = "vec6"  # [Ixx, Iyy, Izz, Ixy, Ixz, Iyz], finite numbers
VECTORS = {VEC3: (3, "[x, y, z] (structure frame, m)"), VEC2: (2, "[pitch, yaw]"),
           VEC6: (6, "[Ixx, Iyy, Izz, Ixy, Ixz, Iyz] (kg m^2, about the CG, body axes)")}
ROWS3 = "rows3"  # a list of rows of 3 finite numbers
NAMES = "names"  # a list of names (strings)
NAMED = "named"  # a mapping of name → section, each checked by its own reader
MAPPING = "mapping"  # a free-form mapping checked by its own reader


class Key:
    """One key of a section: its kind and whether it may be left out."""

    def __init__(self, kind: Any, optional: bool = False) -> None:
        self.kind = kind
        self.optional = optional


def opt(kind: Any) -> Key:
    """An optional key."""
    return Key(kind, optional=True)


def check_keys(node: Any, schema: Mapping[str, Any], path: str) -> None:
    """Refuse unknown, missing and mistyped keys of ``node`` against ``schema`` (key →
    kind or :class:`Key`); nested schema dicts are checked in turn."""
    if not isinstance(node, Mapping):
        raise ConfigError(path, node, "must be a mapping with keys " + ", ".join(schema))
    for key in node:
        if key not in schema:
            raise ConfigError(f"{path}.{key}", node[key], f"unknown key; allowed: {', '.join(schema)}")
    for key, spec in schema.items():
        spec = spec if isinstance(spec, Key) else Key(spec)
        full = f"{path}.{key}"
        if key not in node or node[key] is None:
            if spec.optional:
                continue
            raise ConfigError(full, None, "missing")
        check_value(full, node[key], spec.kind)


def check_value(key: str, value: Any, kind: Any) -> None:
    """Refuse a value of the wrong kind (see :func:`check_keys`)."""
    if isinstance(kind, Mapping):
        check_keys(value, kind, key)
    elif kind in (NAMED, MAPPING):
        if not isinstance(value, Mapping):
            raise ConfigError(key, value, "must be a mapping" + (" of name: section" if kind == NAMED else ""))
    elif kind is float:
        if not is_number(value):
            raise ConfigError(key, value, "must be a finite number")
    elif kind is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(key, value, "must be an integer")
    elif kind in VECTORS:
        n, what = VECTORS[kind]
        if not isinstance(value, (list, tuple)) or len(value) != n or not all(is_number(v) for v in value):
            raise ConfigError(key, value, f"must be a list of {n} finite numbers {what}")
    elif kind == ROWS3:
        rows_ok = isinstance(value, (list, tuple)) and len(value) > 0 and all(
            isinstance(r, (list, tuple)) and len(r) == 3 and all(is_number(v) for v in r) for r in value)
        if not rows_ok:
            raise ConfigError(key, value, "must be a list of rows of 3 finite numbers")
    elif kind == NAMES:
        if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
            raise ConfigError(key, value, "must be a list of names")
    elif kind is str and not isinstance(value, str):
        raise ConfigError(key, value, "must be a string")
