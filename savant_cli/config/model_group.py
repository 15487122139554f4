"""A config group whose options carry different keys (:class:`ModelGroup`): a physical
model's group (``actuator``, ``flex``, ``slosh``, ``twd``, ``navigation``), declared once
in its schema module and listed in :data:`savant_cli.config.savant.MODEL_GROUPS`."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class ModelGroup:
    """One model's config group: what :func:`savant_cli.config.validate` types and checks.

    Attributes
    ----------
    name : str
        The group (``conf/<name>/``, ``cfg.<name>``).
    variants : Mapping[str, type]
        Option name → its schema dataclass (an ``off`` option with no keys of the
        others); ``validate`` types the section by the option its ``name`` says.
    check : Callable[[Any, Any], None]
        ``check(section, cfg)``: the section's physical checks, with the whole typed
        config for the keys of other groups it is judged against (a rate, a vehicle);
        raises :class:`savant_cli.errors.ConfigError` naming the key.
    """

    name: str
    variants: Mapping[str, type]
    check: Callable[[Any, Any], None]
