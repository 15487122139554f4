"""A vehicle file of the old two-stage schema: refused on load naming the conversion
command, and converted by the installed ``savant convert-vehicle`` into a file that flies
the shipped vehicle bit for bit.

The fixture ``fixtures/old_schema/vehicle/old_small_launcher.yaml`` is the shipped
``small_launcher`` as it was written before the vehicle tree (savant 0.1), kept unchanged:
the same tables (found through the shipped tree's ``small_launcher/`` folder), names and
numbers.
"""

from __future__ import annotations

import dataclasses
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf

import savant_cli
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.hydra_compose import compose_config, task_config
from savant_cli.paths import shipped_config_dir
from savant_cli.sim.run import simulate
from savant_cli.sim.setup import prepare
from savant_cli.vehicle import load_vehicle
from savant_cli.vehicle.convert import convert_vehicle, is_old_schema
from savant_cli.vehicle.two_stage import Jettison, Mount

FIXTURE = Path(__file__).parent / "fixtures" / "old_schema"
OLD = FIXTURE / "vehicle" / "old_small_launcher.yaml"
DATA = shipped_config_dir() / "vehicle" / "small_launcher"


def _records_equal(a, b, path="vehicle") -> None:
    """Every number of the plant's records equal, array for array (the raw YAML sections,
    the refusal keys and the names the file gives aside)."""
    if dataclasses.is_dataclass(a):
        for f in dataclasses.fields(a):
            if f.name not in ("keys", "tree", "slosh_spec", "tanks", "names") \
                    and not (isinstance(a, (Mount, Jettison)) and f.name in ("name", "key")):  # (names are names)
                _records_equal(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}")
    elif isinstance(a, tuple):
        assert len(a) == len(b), path
        for k, (x, y) in enumerate(zip(a, b)):
            _records_equal(x, y, f"{path}[{k}]")
    elif isinstance(a, dict):
        assert list(a) == list(b), path
        for k in a:
            _records_equal(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and np.array_equal(a, b), path
    else:
        assert a == b, (path, a, b)


def test_the_fixture_is_the_old_schema():
    assert is_old_schema(OmegaConf.to_container(OmegaConf.load(OLD).vehicle))


def test_an_old_file_is_refused_naming_the_command(tmp_path):
    with pytest.raises(ConfigError) as info:
        savant_cli.run(["vehicle=old_small_launcher"], config_dir=FIXTURE, out_dir=tmp_path / "run", quiet=True)
    assert info.value.key == "vehicle.first_stage"
    assert "savant convert-vehicle" in str(info.value) and "old_small_launcher" not in info.value.key


def test_the_conversion_is_the_shipped_vehicle():
    """Converted in memory, the old file loads to the shipped small_launcher's records."""
    old = OmegaConf.to_container(OmegaConf.load(OLD).vehicle, resolve=True)
    shipped = OmegaConf.to_container(OmegaConf.load(shipped_config_dir() / "vehicle" / "small_launcher.yaml").vehicle,
                                     resolve=True)
    _records_equal(load_vehicle(convert_vehicle(old), DATA), load_vehicle(shipped, DATA))


@pytest.mark.slow
def test_the_converted_file_flies_the_shipped_vehicle_bit_for_bit(tmp_path):
    """The installed command converts a copy in place (the original kept as .v1); the
    converted vehicle's whole ascent equals the shipped one's, logged row for row."""
    conf = tmp_path / "conf"
    (conf / "vehicle").mkdir(parents=True)
    copy = conf / "vehicle" / OLD.name
    shutil.copy(OLD, copy)
    exe = Path(sys.executable).with_name("savant")
    done = subprocess.run([str(exe), "convert-vehicle", str(copy)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert (conf / "vehicle" / (OLD.name + ".v1")).read_text() == OLD.read_text()
    assert "stages" in OmegaConf.load(copy).vehicle
    again = subprocess.run([str(exe), "convert-vehicle", str(copy)], capture_output=True, text=True, timeout=120)
    assert again.returncode == 2 and "nothing to convert" in again.stderr

    def fly(vehicle: str, config_dir: Path | None):
        cfg = validate(task_config(compose_config([f"vehicle={vehicle}"], config_dir)))
        dirs = [config_dir, shipped_config_dir()] if config_dir else [shipped_config_dir()]
        return simulate(prepare(cfg, dirs).model, progress=False)

    converted, shipped = fly("old_small_launcher", conf), fly("small_launcher", None)
    assert converted.status == "complete" and converted.stop_reason == shipped.stop_reason
    assert np.array_equal(converted.log, shipped.log, equal_nan=True)
    assert np.array_equal(converted.events, shipped.events, equal_nan=True)
