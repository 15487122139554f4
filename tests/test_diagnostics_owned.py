"""Each model writes its own diagnostics (issue 28 item 7): every field of the plant's
``aux`` vector is written by the ``write_diagnostics`` of the model that declares it, the
plant composes those calls and writes none by hand, and one full-fidelity evaluation
fills every entry."""

from __future__ import annotations

import importlib
import inspect
import re

import numpy as np

import savant_cli.models  # noqa: F401  (declares every field)
from conftest import compose_config
from savant_cli.config import validate
from savant_cli.models import blocks, layout, slosh
from savant_cli.paths import hydra_search_dirs
from savant_cli.sim import plant
from savant_cli.sim.setup import prepare


def test_every_model_with_diagnostics_writes_them_and_the_plant_writes_none():
    owners = {f.model for f in blocks.DIAGNOSTICS.fields}
    for model in owners:
        module = importlib.import_module(f"savant_cli.models.{model}")
        assert callable(getattr(module, "write_diagnostics", None)), f"models/{model}.py has no write_diagnostics"
    source = inspect.getsource(plant)
    assert not re.search(r"\baux\[", source), "sim/plant.py writes a diagnostic by hand"
    for model in owners:
        assert f"{'mass_model' if model == 'mass' else model}.write_diagnostics(aux" in source, model


def test_one_evaluation_fills_every_diagnostic_and_the_state_only_path_only_the_altitude():
    """aux starts as NaN: after one full-fidelity derivative no entry is left unwritten
    (a field no model writes would stay NaN); the state-only derivative writes the
    altitude and, of the rest, only the sloshing tanks' entries the slosh model hands from
    the mass properties to the loads (their mode, frequency, level and force), and the
    same state derivative."""
    prep = prepare(validate(compose_config(["flex=on", "flex.n_modes=2", "slosh=on", "twd=on"])),
                   hydra_search_dirs())
    model = prep.model
    tb = model.packed_tables
    x = model.x0.copy()
    aux = np.full(layout.N_AUX, np.nan)
    xd = np.zeros(x.size)
    plant.derivative(0.5, x, model.u0, model.p, tb, aux, xd)
    unwritten = [f.key for f in blocks.DIAGNOSTICS.fields if not np.all(np.isfinite(aux[f.index:f.index + f.size]))]
    assert not unwritten, unwritten

    aux_state = np.full(layout.N_AUX, np.nan)
    xd_state = np.zeros(x.size)
    plant.derivative_state(0.5, x, model.u0, model.p, tb, aux_state, xd_state)
    written = np.flatnonzero(np.isfinite(aux_state))
    altitude = blocks.DIAGNOSTICS.field("earth.altitude").index
    n = len(model.layout.slosh_tanks)
    handed = [blocks.DIAGNOSTICS.field(f"slosh.{name}").index + k for name, per in (
        ("frequency", 1), ("level", 1), ("force", 3), ("mode", slosh.N_MODE)) for k in range(per * n)]
    assert written.tolist() == sorted([altitude] + handed)
    np.testing.assert_array_equal(aux_state[written], aux[written])
    assert np.array_equal(xd_state, xd)


def _short_flight(overrides):
    from savant_cli.sim.run import signals, simulate

    prep = prepare(validate(compose_config(overrides + ["sim.max_time_s=2", "sim.progress=false"])), hydra_search_dirs())
    result = simulate(prep.model, progress=False)
    return prep.model, result, signals(result, prep.model)


def test_a_logged_diagnostic_is_a_signal_of_every_run_where_its_model_is_on():
    """Each field declared with ``blocks.Logged`` is a time history with the field's units
    and description, the declaration's columns and frame, and the logged ``aux`` entries
    as data (a per-tank field's first entries, one per column ``columns_of`` gives: the
    run's sloshing tanks); a field whose model is off (``when`` false: slosh, flex, boosters
    with fixed nozzles or none, an unthrottled upper stage) is left out."""
    from savant_cli.sim.run import _split

    logged = [f for f in blocks.DIAGNOSTICS.fields if f.logged is not None]
    assert {"dynamic_pressure", "wind_ned", "twd_moment", "liquid_level", "flex_gimbal_rotation"} <= \
        {f.logged.name for f in logged}
    model, result, sig = _short_flight(["flex=on", "flex.n_modes=2", "slosh=on", "twd=on"])
    aux = _split(result.log, model.layout.n)[2]
    for f in logged:
        if f.logged.when is not None and not f.logged.when(model):
            assert f.logged.name not in sig
            continue
        s = sig[f.logged.name]
        columns = f.logged.columns if f.logged.columns_of is None else f.logged.columns_of(model)
        declared = (f.units, f.description, columns, f.logged.frame)
        assert (s.units, s.description, s.columns, s.frame) == declared
        size = f.size if f.logged.columns_of is None else len(columns)
        assert np.array_equal(s.data, aux[:, f.index] if f.size == 1 else aux[:, f.index:f.index + size])
    assert sig["liquid_level"].columns == ("lox", "lh2") and sig["slosh_force"].columns[-1] == "lh2_z"
    _, _, rigid = _short_flight([])
    conditional = {f.logged.name for f in logged if f.logged.when is not None}
    assert conditional == {"liquid_level", "slosh_force", "flex_gimbal_rotation", "booster_gimbal_angle",
                           "upper_stage_throttle"}
    assert not conditional & set(rigid) and {f.logged.name for f in logged} - conditional <= set(rigid)


def test_a_logged_field_needs_one_column_name_per_entry():
    import pytest

    vec = blocks.Vector("aux_test", "a scratch vector")
    with pytest.raises(ValueError, match="columns"):
        vec.block("m").array("v", 3, "m/s", "a vector", blocks.Logged("v", ("x", "y")))
    with pytest.raises(ValueError, match="columns"):
        vec.block("m").scalar("s", "m", "a scalar", blocks.Logged("s", ("x",)))
