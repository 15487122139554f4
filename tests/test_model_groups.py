"""The model groups (``config/savant.py::MODEL_GROUPS``; docs/architecture.md, "Adding a
model, step by step"): each declared once, with a field in the whole config, one option
file per schema, and its check run by ``validate``."""

from __future__ import annotations

import dataclasses

import pytest
from omegaconf import OmegaConf

from savant_cli.config import MODEL_GROUPS, SavantConfig, validate
from savant_cli.errors import ConfigError
from savant_cli.hydra_compose import compose_config, task_config
from savant_cli.paths import shipped_config_dir


def test_each_model_group_has_its_field_its_options_and_a_shipped_default():
    fields = {f.name: f for f in dataclasses.fields(SavantConfig)}
    names = [g.name for g in MODEL_GROUPS]
    assert len(set(names)) == len(names) == 5
    top = OmegaConf.load(shipped_config_dir() / "config.yaml")
    chosen = {k: v for d in top.defaults if isinstance(d, dict) or OmegaConf.is_dict(d) for k, v in d.items()}
    for g in MODEL_GROUPS:
        assert g.name in fields, f"SavantConfig has no field {g.name}"
        assert fields[g.name].default_factory()["name"] in g.variants  # the bare schema's option exists
        assert chosen[g.name] in g.variants  # conf/config.yaml's default is one of them
        files = {p.stem for p in (shipped_config_dir() / g.name).glob("*.yaml")}
        assert files == set(g.variants), f"conf/{g.name}/ holds {sorted(files)}, the schemas {sorted(g.variants)}"


@pytest.mark.parametrize("override, key", [
    ("actuator.first_stage.loop_gain_rad_s=-1", "actuator.first_stage.loop_gain_rad_s"),
    ("flex.n_modes=0", "flex.n_modes"),
    ("slosh.damping_scale=-1", "slosh.damping_scale"),
])
def test_validate_runs_each_model_groups_check(override, key):
    overrides = {"flex": ["flex=on"], "slosh": ["slosh=on"]}.get(key.split(".")[0], []) + [override]
    with pytest.raises(ConfigError) as exc:
        validate(task_config(compose_config(overrides, None)))
    assert exc.value.key == key
