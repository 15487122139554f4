"""The two-stage vehicle schema of savant 0.1 (``first_stage``, ``upper_stage``, ``rcs``,
``slosh.lox``/``lh2``, ``events`` as three numbers) converted to the vehicle tree's schema.

``savant convert-vehicle FILE [--out NEW]`` converts a vehicle file once: the file's
leading comment lines and its ``defaults`` list are kept, the ``vehicle`` section is
written in the new schema (comments inside it are not carried over). The result flies
the same vehicle: the same tables, numbers and event rules, bit for bit
(``tests/test_vehicle_convert.py`` flies a kept copy of ``small_launcher`` in the old
schema against the shipped one). A vehicle YAML in the old schema is refused on load
naming this command (:func:`refuse_old_schema`).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import yaml

from savant_cli.errors import ConfigError
from savant_cli.io.atomic import write_text_atomic

#: Keys only the old schema has.
OLD_KEYS = ("first_stage", "upper_stage", "rcs", "slosh")
COMMAND = "savant convert-vehicle"
#: Names the conversion gives the old schema's implicit parts.
FIRST, UPPER, ITEM = "first_stage", "upper_stage", "les"
FIRST_ENGINE, UPPER_ENGINE = "first_stage_engine", "upper_stage_engine"
GRAIN, OXIDIZER, FUEL = "first_stage_propellant", "lox", "lh2"


def is_old_schema(node: Mapping) -> bool:
    """Whether a vehicle section is written in the old two-stage schema."""
    return "stages" not in node and any(k in node for k in OLD_KEYS)


def refuse_old_schema(node: Mapping) -> None:
    """A ConfigError naming the conversion command, for a vehicle in the old schema."""
    if is_old_schema(node):
        key = next(k for k in OLD_KEYS if k in node)
        name = node.get("name", "<name>")
        raise ConfigError(f"vehicle.{key}", "(the two-stage schema of savant 0.1)",
                          f"vehicles are a tree of stages, tanks, engines and events now; convert this file once with "
                          f"`{COMMAND} <config dir>/vehicle/{name}.yaml` (docs/vehicles.md, \"Converting an older "
                          f"vehicle file\")")


def _moving_mass(engine: Mapping) -> dict:
    return {k: engine[k] for k in ("mass_kg", "cg_from_gimbal_m", "inertia_about_gimbal_kgm2")}


def convert_vehicle(old: Mapping) -> dict:
    """The old schema's ``vehicle`` section (plain containers) in the new schema."""
    old = copy.deepcopy(dict(old))
    for key in ("first_stage", "upper_stage", "rcs", "events", "configurations", "sensors"):
        if not isinstance(old.get(key), Mapping):
            raise ConfigError(f"vehicle.{key}", old.get(key), "missing: not a vehicle in the old two-stage schema")
    fs, us, ev = old["first_stage"], old["upper_stage"], old["events"]
    slosh = old.get("slosh") or {}

    def tank(load: Any, name: str) -> dict:
        out = {"propellant_kg": load}
        if slosh.get(name):
            out["slosh"] = {**slosh[name], "reference_accel_mps2": slosh.get("reference_accel_mps2")}
        return out

    new: dict[str, Any] = {k: old[k] for k in ("name", "description", "data_dir", "length_m") if k in old}
    new["stages"] = {
        FIRST: {
            "inert_mass_kg": fs["jettison_mass_kg"],
            "tanks": {GRAIN: {"propellant_kg": fs["propellant_kg"]}},
            "engines": {FIRST_ENGINE: {
                "source": "trace", "tanks": [GRAIN], "thrust_table": fs["thrust_table"], "isp_vac_s": fs["isp_vac_s"],
                "isp_sl_s": fs["isp_sl_s"], "nozzle_exit_area_m2": fs["nozzle_exit_area_m2"],
                "gimbal_m": fs["gimbal_m"],
                "gimbal_limit_deg": fs["gimbal_limit_deg"], "moving_mass": _moving_mass(fs["engine"])}},
        },
        UPPER: {
            "tanks": {OXIDIZER: tank(us["lox_kg"], "lox"), FUEL: tank(us["lh2_kg"], "lh2")},
            "engines": {UPPER_ENGINE: {
                "source": "liquid", "tanks": [OXIDIZER, FUEL], "thrust_vac_N": us["thrust_vac_N"],
                "isp_vac_s": us["isp_vac_s"], "mixture_ratio": us["mixture_ratio"],
                "startup_table": us["startup_table"], "shutdown_impulse_Ns": us["shutdown_impulse_Ns"],
                "nozzle_exit_area_m2": us["nozzle_exit_area_m2"], "gimbal_m": us["gimbal_m"],
                "gimbal_limit_deg": us["gimbal_limit_deg"], "moving_mass": _moving_mass(us["engine"])}},
            "roll_jets": old["rcs"],
        },
    }
    new["items"] = {ITEM: {"mass_kg": us["les_mass_kg"], "attached_to": UPPER}}
    parts = {"stack": [FIRST, UPPER, ITEM], "upper_les": [UPPER, ITEM], "upper": [UPPER]}
    tanks = {"stack": [GRAIN], "upper_les": [OXIDIZER, FUEL], "upper": [OXIDIZER, FUEL]}
    new["configurations"] = {name: {"parts": parts[name], **section, "mass_tanks": tanks[name]}
                             for name, section in old["configurations"].items()}
    new["events"] = {
        "separation": {"when": {"quantity": "thrust_fraction", "of": FIRST_ENGINE,
                                "below": ev["separation_thrust_fraction"]}, "jettison": [FIRST]},
        "upper_stage_ignition": {"after": "separation", "delay_s": ev["ignition_delay_s"], "ignite": [UPPER_ENGINE]},
        "les_jettison": {"after": "upper_stage_ignition", "delay_s": ev["les_jettison_delay_s"], "jettison": [ITEM]},
    }
    new["sensors"] = old["sensors"]
    for key in ("flex", "loads"):
        if old.get(key) is not None:
            new[key] = old[key]
    return new


class _Dumper(yaml.SafeDumper):
    """Block style for mappings, flow style for short lists of scalars ([x, y, z])."""


def _represent_list(dumper: yaml.SafeDumper, data: list):
    flow = all(not isinstance(v, (list, dict)) for v in data)
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


_Dumper.add_representer(list, _represent_list)


def convert_file(path: Path, out: Path | None = None) -> Path:
    """Convert the vehicle file ``path`` (old schema) and write it to ``out`` (default:
    in place, the original kept beside it as ``<file>.v1``). Returns the written path."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ConfigError(str(path), None, f"cannot read the vehicle file: {exc.strerror}") from None
    doc = yaml.safe_load(text)
    node = doc.get("vehicle") if isinstance(doc, Mapping) else None
    if not isinstance(node, Mapping):
        raise ConfigError(f"{path}:vehicle", None, "missing: a vehicle file holds a `vehicle:` section")
    if not is_old_schema(node):
        raise ConfigError(f"{path}:vehicle", "(the current schema)", "is not in the old two-stage schema: nothing to "
                                                                     "convert")
    header = []
    for line in text.splitlines():
        if not line.startswith("#"):
            break
        header.append(line)
    header.append(f"# Converted from the two-stage schema by `{COMMAND}` (docs/vehicles.md).")
    body = {k: v for k, v in doc.items() if k != "vehicle"}
    body["vehicle"] = convert_vehicle(node)
    dumped = yaml.dump(body, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=4096)
    target = Path(out) if out is not None else path
    if out is None:
        write_text_atomic(path.with_name(path.name + ".v1"), text)
    write_text_atomic(target, "\n".join(header) + "\n" + dumped)
    return target
