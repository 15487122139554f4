"""A shipped option file's settings, typed (:func:`shipped_option`).

A default lives in the YAML, the schema says ``MISSING`` (docs/architecture.md, "Where a
new config option goes"), so a schema class cannot be built bare. Code that needs a
group's settings outside the run that composed them (the Monte Carlo's per-run margins
use ``study=linear``'s settings; mode retention's ``flex=on`` when the run flies
``flex=off``) and tests that judge against the shipped thresholds read them here, from
the same file an analyst reads and edits.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from omegaconf import OmegaConf
from omegaconf.errors import InterpolationResolutionError

from savant_cli.config.savant import GROUP_VARIANTS, SavantConfig
from savant_cli.config.study import STUDY_SCHEMAS
from savant_cli.config.study.linear import LinearStudyConfig
from savant_cli.paths import shipped_config_dir


def _schema(group: str, option: str | None) -> type:
    if group == "study":
        return STUDY_SCHEMAS[option]
    if group in GROUP_VARIANTS:
        return GROUP_VARIANTS[group][option]
    f = {f.name: f for f in dataclasses.fields(SavantConfig)}[group]
    default = f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default
    if not dataclasses.is_dataclass(default):
        raise ValueError(f"config group {group!r} has no schema of its own (savant_cli.config.SavantConfig)")
    return type(default)


def shipped_option(group: str, option: str | None = None) -> Any:
    """The settings of the shipped ``conf/<group>/<option>.yaml`` merged onto the group's
    schema (or, with ``option`` None, the section ``group`` of ``conf/config.yaml``).

    Parameters
    ----------
    group : str
        The config group (``study``, ``flex``, ``requirements``, …) or, with ``option``
        None, a top-level section (``sim``, ``environment``, ``output``).
    option : str or None
        The option file's name (``linear``, ``on``, ``ares_i``, …).

    Returns
    -------
    dataclass
        The typed settings (``LinearStudyConfig``, ``FlexOnConfig``, ``RequirementSet``,
        ``SimConfig``, …), unchecked beyond their types: the shipped files pass
        :func:`savant_cli.config.validate` (``tests/test_config_defaults.py``).

    Raises
    ------
    ValueError
        The option file takes its keys from another option of its group (a ``defaults``
        entry naming it) or interpolates keys of other groups (``${guidance.name}``):
        that needs Hydra's composition, not this reader. Or the group has no schema of
        its own (``vehicle``, checked by ``savant_cli.vehicle``).
    """
    conf = shipped_config_dir()
    if option is None:
        node = OmegaConf.load(conf / "config.yaml")[group]
    else:
        path = conf / group / f"{option}.yaml"
        node = OmegaConf.load(path)
        parents = [d for d in node.get("defaults", []) if isinstance(d, str) and d != "_self_"]
        if parents:
            raise ValueError(f"{path} takes its keys from {parents}: compose it with Hydra")
        if path.read_text().startswith("# @package _global_"):
            node = node[group]
        node = OmegaConf.masked_copy(node, [k for k in node if k != "defaults"])
    schema = _schema(group, option)
    try:  # the option's own interpolations (``yaw: ${.pitch}``), as validate resolves them
        plain = OmegaConf.to_container(node, resolve=True)
    except InterpolationResolutionError as exc:
        raise ValueError(f"{group}/{option}.yaml interpolates the composed config ({exc}): "
                         "compose it with Hydra") from exc
    return OmegaConf.to_object(OmegaConf.merge(OmegaConf.structured(schema), plain))


def linear_settings(times) -> LinearStudyConfig:
    """The shipped ``study=linear`` settings (``conf/study/linear.yaml``: the Jacobian, the
    tail-off window criteria …) at the flight times ``times`` (s): how another study
    analyses its points as ``study=linear`` would."""
    return dataclasses.replace(shipped_option("study", "linear"), times=[float(t) for t in times])
