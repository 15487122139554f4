"""A staging-state file written before the tanks were named (savant 0.1: ``prop_first_stage``,
``prop_lox``, ``prop_lh2``) still starts a run: its propellant states are read as the
vehicle's three tanks in order (``sim/setup.py::staging_vector``)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from savant_cli.errors import ConfigError
from savant_cli.models import layout
from savant_cli.paths import shipped_config_dir
from savant_cli.sim.setup import LEGACY_TANK_STATES, staging_vector
from savant_cli.sim.staging_state import read_staging_state

SHIPPED = shipped_config_dir() / "phase" / "ares_i_peg_staging_state.json"
ARES_I = layout.StateLayout(tanks=("grain", "lox", "lh2"))


def _rewritten(tmp_path, rename: dict[str, str]):
    doc = json.loads(SHIPPED.read_text())
    doc["state"] = {rename.get(k, k): v for k, v in doc["state"].items()}
    path = tmp_path / "staging.json"
    path.write_text(json.dumps(doc))
    return read_staging_state(path), path


def test_old_tank_names_read_as_the_vehicles_tanks(tmp_path):
    current = read_staging_state(SHIPPED)
    want = staging_vector(current, ARES_I, "k", SHIPPED)
    old, path = _rewritten(tmp_path, dict(zip(("prop_grain", "prop_lox", "prop_lh2"), LEGACY_TANK_STATES)))
    assert "prop_grain" not in old.names and "prop_first_stage" in old.names
    got = staging_vector(old, ARES_I, "k", path)
    assert np.array_equal(got, want)
    assert got[ARES_I.tank("grain")] == json.loads(SHIPPED.read_text())["state"]["prop_grain"]


def test_a_file_without_the_tank_is_refused_naming_it(tmp_path):
    st, path = _rewritten(tmp_path, {"prop_grain": "prop_something_else"})
    with pytest.raises(ConfigError, match="has no state 'prop_grain'"):
        staging_vector(st, ARES_I, "phase.staging_state_file", path)
