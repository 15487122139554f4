"""What a dispersion acts on, and how one run's samples become its config, vehicle and
numeric model.

Four kinds of target (``dispersions.items.<name>.target``), and a fifth state:

``config``
    Any numeric leaf of the validated config, list elements by index:
    ``winds.scale``, ``flex.frequency_scale``, ``actuator.first_stage.natural_frequency_hz``,
    ``sensors.misalignment_deg.imu[1]``. Applied to a copy of the typed config, which is
    then checked like any config (a sample outside the allowed range fails that run with
    the usual message).
``vehicle``
    A numeric attribute of the loaded vehicle (``vehicle.upper_stage.isp_vac_s``,
    ``vehicle.first_stage.engine.inertia_about_gimbal_kgm2``), in the vehicle's SI units.
``tables``
    A vehicle-table quantity, see :data:`TABLE_TARGETS`.
``group``
    A config group whose option is drawn: ``winds`` (``dist: choice`` of option names).
``inactive``
    A config key of another option of its group than the one flown (``flex.damping``
    with ``flex=off``): drawn and recorded, applied to nothing.

The model of a run is built by :func:`savant_cli.sim.build.build_model` from the
dispersed config and vehicle (so every derived quantity, such as the separation time
of a faster-burning motor, follows); aerodynamic scales are applied to its tables.
"""

from __future__ import annotations

import copy
import dataclasses
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from omegaconf import OmegaConf

from savant_cli.config import GROUP_VARIANTS, ControllerConfig, SavantConfig, WindsConfig, check_physics, has_key
from savant_cli.errors import ConfigError
from savant_cli.sim.build import SimModel, build_model
from savant_cli.vehicle import AERO_COEFFICIENTS, MassTable, Vehicle

KINDS = ("config", "vehicle", "tables", "group")

#: Vehicle-table targets: name → (units of the sample, allowed ``apply``, what it does).
TABLE_TARGETS: dict[str, tuple[str, tuple[str, ...], str]] = {
    "tables.first_stage.burn_rate": ("1", ("scale",), "motor burn rate × k: thrust and mass flow × k on a time axis "
                                                      "÷ k; load and total impulse conserved, burn time ÷ k"),
    "tables.first_stage.propellant_load": ("1", ("scale",), "solid propellant load × k (density at a fixed grain): "
                                                            "mass flow and thrust × k at the same burn time and Isp"),
    "tables.upper_stage.lox_load": ("1", ("scale",), "LOX loaded × k (tank fill); the upper-stage mass tables "
                                                     "rescaled to the new total, the stack carries the difference"),
    "tables.upper_stage.lh2_load": ("1", ("scale",), "LH2 loaded × k (tank fill); as lox_load"),
    "tables.first_stage.dry_mass": ("kg", ("offset",), "mass added at the CG of the configurations flown with the "
                                                       "first stage"),
    "tables.boosters.burn_rate": ("1", ("scale",), "every strap-on booster's burn rate × k (their common propellant "
                                                   "temperature): as first_stage.burn_rate"),
    "tables.upper_stage.dry_mass": ("kg", ("offset",), "mass added at the CG of every configuration"),
    **{f"tables.{c}.cg_{ax}": ("m", ("offset",), f"CG shift along structure {ax} ({c})")
       for c in ("stack", "upper") for ax in "xyz"},
    **{f"tables.{c}.inertia": ("1", ("scale",), f"all inertia components × k ({c})") for c in ("stack", "upper")},
    **{f"tables.aero.{k}": ("1", ("scale",), f"aerodynamic coefficient {k} × k, every configuration")
       for k in AERO_COEFFICIENTS},
}
#: One booster's burn rate, ``tables.boosters.<booster>.burn_rate`` (its units, apply, what).
BOOSTER_BURN_RATE = re.compile(r"^tables\.boosters\.([A-Za-z_][A-Za-z0-9_]*)\.burn_rate$")
BOOSTER_BURN_RATE_TARGET = ("1", ("scale",), "one strap-on booster's burn rate × k (motor to motor), on top of "
                                             "tables.boosters.burn_rate: the thrust imbalance between boosters")
GROUP_TARGETS = ("winds",)
#: Targets that no longer exist, with why and what replaces them.
RETIRED_TARGETS = {
    "tables.first_stage.thrust": "retired: it scaled thrust and mass flow at a fixed burn time, so the motor ran out "
                                 "of propellant while its trace still thrust (k > 1) or ended with propellant unburned "
                                 "(k < 1); use tables.first_stage.burn_rate, tables.first_stage.propellant_load or "
                                 "vehicle.first_stage.isp_vac_s (docs/montecarlo.md)",
}

_PATH_RE = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)$")


@dataclass(frozen=True)
class Target:
    """A resolved dispersion target.

    Attributes
    ----------
    key : str
        As written in the spec.
    kind : str
        ``config``, ``vehicle``, ``tables``, ``group``, or ``inactive``: a key of a model
        variant that this configuration does not fly (``flex.damping`` with ``flex=off``,
        a third-order actuator key with ``actuator=simplex``). An inactive dispersion is
        drawn like the others (the streams of the rest do not depend on it) and recorded,
        but changes nothing; ``note`` says why.
    path : tuple
        Attribute names and list indices from the root (config and vehicle targets).
    nominal : float or None
        The nominal value (config and vehicle targets).
    units : str
        Units of the nominal and of ``value``/``offset`` samples.
    integer : bool
        The target holds an integer (only ``apply: value`` makes sense).
    choices : tuple
        Option names of a group target.
    """

    key: str
    kind: str
    path: tuple = ()
    nominal: float | None = None
    units: str = ""
    integer: bool = False
    choices: tuple = ()
    note: str = ""


def parse_path(key: str, text: str) -> tuple:
    """``a.b[2].c`` → ``("a", "b", 2, "c")``; a ConfigError naming ``key`` otherwise."""
    out: list = []
    for part in text.split("."):
        m = _PATH_RE.match(part)
        if not m:
            raise ConfigError(key, text, "must be a dotted path such as winds.scale or sensors.misalignment_deg.imu[1]")
        out.append(m.group(1))
        out.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
    return tuple(out)


def _get(obj: Any, element: Any) -> Any:
    if isinstance(element, int):
        return obj[element]
    if isinstance(obj, dict):
        return obj[element]
    if dataclasses.is_dataclass(obj):
        if element not in {f.name for f in dataclasses.fields(obj)}:
            raise KeyError(element)
        return getattr(obj, element)
    raise KeyError(element)


def _walk(root: Any, path: tuple) -> Any:
    obj = root
    for element in path:
        obj = _get(obj, element)
    return obj


def _units(name: str) -> str:
    for suffix, unit in (("_deg", "deg"), ("_hz", "Hz"), ("_kg", "kg"), ("_m", "m"), ("_s", "s"), ("_N", "N"),
                         ("_rad_s", "rad/s"), ("_kgm2", "kg m²")):
        if name.endswith(suffix):
            return unit
    return "1"


def table_target(name: str) -> tuple[str, tuple[str, ...], str] | None:
    """The units, allowed ``apply`` and description of the vehicle-table target
    ``name`` (None: not one)."""
    return TABLE_TARGETS.get(name) or (BOOSTER_BURN_RATE_TARGET if BOOSTER_BURN_RATE.match(name) else None)


def resolve(key: str, text: str, cfg: SavantConfig, vehicle: Vehicle, search_dirs: list[Path]) -> Target:
    """The target named ``text`` (``key``: the spec key named in errors)."""
    if text.startswith("tables.boosters.") and table_target(text) is not None:
        names = vehicle.boosters.names if vehicle.boosters is not None else ()
        match = BOOSTER_BURN_RATE.match(text)
        if not names or (match and match.group(1) not in names):
            known = ["tables.boosters.burn_rate", *(f"tables.boosters.{n}.burn_rate" for n in names)]
            raise ConfigError(key, text, ("one of " + ", ".join(known)) if names else
                              "none: this vehicle has no strap-on boosters")
    if table_target(text) is not None:
        return Target(text, "tables", units=table_target(text)[0])
    if text in RETIRED_TARGETS:
        raise ConfigError(key, text, RETIRED_TARGETS[text])
    if text.startswith("tables."):
        raise ConfigError(key, text, "unknown table target; known: " + ", ".join(TABLE_TARGETS)
                          + ", tables.boosters.<booster>.burn_rate")
    if text in GROUP_TARGETS:
        return Target(text, "group", choices=tuple(_group_options(text, search_dirs)))
    path = parse_path(key, text)
    kind, root, shown = ("vehicle", vehicle, path[1:]) if path[0] == "vehicle" else ("config", cfg, path)
    try:
        value = _walk(root, shown)
    except (KeyError, IndexError, TypeError):
        inactive = _inactive_variant_key(path, cfg)
        if inactive:
            name = next((e for e in reversed(path) if isinstance(e, str)), "")
            return Target(text, "inactive", tuple(shown), units=_units(name), note=inactive)
        where = "the loaded vehicle's attributes (see savant_cli/vehicle/two_stage.py)" if kind == "vehicle" else \
            "the config (see `savant run --cfg job`)"
        raise ConfigError(key, text, f"unknown target: no such key in {where}, and not a tables.* or group target") from None
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ConfigError(key, text, f"must name a number, not {type(value).__name__} ({value!r})")
    name = next((e for e in reversed(path) if isinstance(e, str)), "")
    return Target(text, kind, tuple(shown), float(value), _units(name), integer=isinstance(value, (int, np.integer)))


def _inactive_variant_key(path: tuple, cfg: SavantConfig) -> str:
    """Why a config path that the flown config lacks is a key of another option of its
    group (``""`` when it is not)."""
    group = path[0] if path and isinstance(path[0], str) else None
    if group not in GROUP_VARIANTS:
        return ""
    names = [e for e in path[1:] if isinstance(e, str)]
    flown = getattr(cfg, group).name
    where = [opt for opt, schema in GROUP_VARIANTS[group].items() if opt != flown and has_key(schema, names)]
    return f"a key of {' and '.join(f'{group}={w}' for w in where)}; this batch flies {group}={flown}" if where else ""


GROUP_SCHEMAS = {"winds": WindsConfig, "controller": ControllerConfig}


def group_options(group: str, search_dirs: list[Path]) -> list[str]:
    """The option names of a config group in the search path."""
    return _group_options(group, search_dirs)


def _group_options(group: str, search_dirs: list[Path]) -> list[str]:
    names: list[str] = []
    for d in search_dirs:
        for f in sorted((d / group).glob("*.yaml")):
            if f.stem not in names:
                names.append(f.stem)
    return names


def load_group_option(group: str, name: str, search_dirs: list[Path]) -> Any:
    """A config group option as its typed section (``winds`` → WindsConfig,
    ``controller`` → ControllerConfig)."""
    for d in search_dirs:
        f = d / group / f"{name}.yaml"
        if f.is_file():
            plain = OmegaConf.to_container(OmegaConf.load(f), resolve=True)  # e.g. yaw: ${.pitch}
            merged = OmegaConf.merge(OmegaConf.structured(GROUP_SCHEMAS[group]), plain)
            return OmegaConf.to_object(merged)
    raise ConfigError(group, name, f"no such option; known: {', '.join(_group_options(group, search_dirs))}")


# ------------------------------------------------------------------------ application


def combine(apply: str, nominal: float, sample: float) -> float:
    """The dispersed value of a numeric target."""
    if apply == "scale":
        return nominal * sample
    if apply == "offset":
        return nominal + sample
    return sample


def _set(obj: Any, path: tuple, value: Any) -> None:
    """Set a leaf of a mutable (deep-copied) typed config."""
    parent = _walk(obj, path[:-1])
    last = path[-1]
    if isinstance(last, int) or isinstance(parent, dict):
        parent[last] = value
    else:
        setattr(parent, last, value)


def _replace(obj: Any, path: tuple, value: Any) -> Any:
    """A copy of a frozen dataclass tree with one leaf replaced."""
    head, rest = path[0], path[1:]
    if isinstance(head, int):
        arr = np.array(obj, dtype=float, copy=True)
        arr[head] = value if not rest else _replace(arr[head], rest, value)
        return arr
    if isinstance(obj, dict):
        return {**obj, head: value if not rest else _replace(obj[head], rest, value)}
    return dataclasses.replace(obj, **{head: value if not rest else _replace(getattr(obj, head), rest, value)})


def first_stage_configurations(vehicle: Vehicle) -> tuple[str, ...]:
    """The configurations flown with the first stage attached (``stack``, and before it
    the configuration with the boosters): a ``stack`` target applies to each."""
    return tuple(vehicle.configurations)[:vehicle.first_stage_configurations]


def upper_configurations(vehicle: Vehicle) -> tuple[str, ...]:
    """The configurations flown after the separation (``upper_les``, any further one
    before the last item's jettison, ``upper``): an ``upper`` target applies to each."""
    return tuple(vehicle.configurations)[vehicle.first_stage_configurations:]


def _mass(vehicle: Vehicle, configs: tuple[str, ...], change) -> Vehicle:
    confs = dict(vehicle.configurations)
    for c in configs:
        confs[c] = dataclasses.replace(confs[c], mass=change(confs[c].mass))
    return dataclasses.replace(vehicle, configurations=confs)


def load_scaled(m: MassTable, k: float) -> MassTable:
    """The mass table of a burning stage whose propellant is × ``k`` at every burned
    fraction (the same grain or tank geometry, denser or fuller): the row at propellant
    ``p`` moves to ``k p`` with ``(k − 1) p`` more mass, placed at the propellant's own CG
    at that row, ``(m(p) cg(p) − m(0) cg(0)) / p`` (the dry part is the row at 0). The
    inertia is the nominal's at the same burned fraction (a ±0.3 % load changes it by
    less than 0.2 %, far inside the inertia dispersions)."""
    p = m.propellant_kg
    extra = (k - 1.0) * p
    first_moment = m.mass_kg[:, None] * m.cg_m + extra[:, None] * (
        (m.mass_kg[:, None] * m.cg_m - m.mass_kg[0] * m.cg_m[0]) / np.where(p > 0.0, p, 1.0)[:, None])
    mass = m.mass_kg + extra
    return dataclasses.replace(m, propellant_kg=k * p, mass_kg=mass,
                               cg_m=np.ascontiguousarray(first_moment / mass[:, None]))


def _upper_load(vehicle: Vehicle, name: str, k_tank: float) -> Vehicle:
    """One upper-stage tank's load × ``k_tank``. The upper
    configurations' tables (against LOX + LH2 remaining) are rescaled to the new total
    (:func:`load_scaled`: the extra spread like the propellant at each level); the stack,
    which carries the upper stage full, gains the extra at every row, at the upper-stage
    propellant's CG when full (the stack shares the structure frame)."""
    if not k_tank > 0.0:
        raise ConfigError(name, k_tank, "load factor must be positive")
    us = vehicle.upper_stage
    lox, lh2 = us.lox_kg, us.lh2_kg
    if name.endswith("lox_load"):
        lox *= k_tank
    else:
        lh2 *= k_tank
    delta_kg = lox + lh2 - us.lox_kg - us.lh2_kg
    k = (lox + lh2) / (us.lox_kg + us.lh2_kg)
    les = vehicle.configurations["upper_les"].mass
    full = les.propellant_kg[-1]
    cg_prop = (les.mass_kg[-1] * les.cg_m[-1] - les.mass_kg[0] * les.cg_m[0]) / full  # structure frame, m

    def stack(m: MassTable) -> MassTable:
        mass = m.mass_kg + delta_kg
        cg = (m.mass_kg[:, None] * m.cg_m + delta_kg * cg_prop[None, :]) / mass[:, None]
        return dataclasses.replace(m, mass_kg=mass, cg_m=np.ascontiguousarray(cg))

    vehicle = _mass(vehicle, upper_configurations(vehicle), lambda m: load_scaled(m, k))
    vehicle = _mass(vehicle, first_stage_configurations(vehicle), stack)
    return dataclasses.replace(vehicle, upper_stage=dataclasses.replace(us, lox_kg=lox, lh2_kg=lh2))


def _booster_rate(vehicle: Vehicle, name: str, v: float) -> Vehicle:
    """Every booster's burn rate × ``v`` (``tables.boosters.burn_rate``) or one's."""
    if not v > 0.0:
        raise ConfigError(name, v, "burn-rate factor must be positive")
    b = vehicle.boosters
    rate = np.ones(b.count) if b.burn_rate is None else np.array(b.burn_rate, float)
    match = BOOSTER_BURN_RATE.match(name)
    if match:
        rate[b.names.index(match.group(1))] *= v
    else:
        rate *= v
    return dataclasses.replace(vehicle, boosters=dataclasses.replace(b, burn_rate=rate))


def _apply_table(vehicle: Vehicle, name: str, v: float) -> Vehicle:
    """Vehicle-table dispersions applied before the build (aero is applied after)."""
    fs = vehicle.first_stage
    if fs.liquid is not None and name in ("tables.first_stage.burn_rate", "tables.first_stage.propellant_load"):
        raise ConfigError(name, v, "disperses a solid motor's trace or grain; this first stage is liquid (disperse "
                                   "its tanks' loads in the vehicle file)")
    if name.startswith("tables.boosters."):
        return _booster_rate(vehicle, name, v)
    if name == "tables.first_stage.burn_rate":
        if not v > 0.0:
            raise ConfigError(name, v, "burn-rate factor must be positive")
        return dataclasses.replace(vehicle, first_stage=dataclasses.replace(
            fs, thrust_time_s=fs.thrust_time_s / v, thrust_vac_N=fs.thrust_vac_N * v))
    if name == "tables.first_stage.propellant_load":
        if not v > 0.0:
            raise ConfigError(name, v, "propellant-load factor must be positive")
        vehicle = _mass(vehicle, first_stage_configurations(vehicle), lambda m: load_scaled(m, v))
        return dataclasses.replace(vehicle, first_stage=dataclasses.replace(fs, propellant_kg=fs.propellant_kg * v))
    if name in ("tables.upper_stage.lox_load", "tables.upper_stage.lh2_load"):
        return _upper_load(vehicle, name, v)
    if name.endswith("dry_mass"):
        upper = () if ".first_stage." in name else upper_configurations(vehicle)
        configs = first_stage_configurations(vehicle) + upper
        return _mass(vehicle, configs, lambda m: dataclasses.replace(m, mass_kg=m.mass_kg + v))
    config = name.split(".")[1]
    configs = first_stage_configurations(vehicle) if config == "stack" else upper_configurations(vehicle)
    if name.endswith("inertia"):
        if not v > 0.0:
            raise ConfigError(name, v, "inertia factor must be positive")
        return _mass(vehicle, configs, lambda m: dataclasses.replace(m, inertia_kgm2=m.inertia_kgm2 * v))
    axis = "xyz".index(name[-1])

    def shift(m):
        cg = m.cg_m.copy()
        cg[:, axis] += v
        return dataclasses.replace(m, cg_m=cg)

    return _mass(vehicle, configs, shift)


@dataclass
class Applied:
    """One run's dispersed inputs (what :func:`build_dispersed` flies)."""

    cfg: SavantConfig
    vehicle: Vehicle
    aero_scale: np.ndarray  # per coefficient (CA, CY, CN, Cl, Cm, Cn)


def apply_samples(cfg: SavantConfig, vehicle: Vehicle, items: list[tuple[Target, str, Any]],
                  groups: dict[str, Any]) -> Applied:
    """Apply ``(target, apply, sample)`` triples to copies of ``cfg`` and ``vehicle``.

    ``groups`` maps a group target's option name to its loaded typed section."""
    cfg = copy.deepcopy(cfg)
    aero = np.ones(len(AERO_COEFFICIENTS))
    for target, apply, sample in items:
        if target.kind == "group":
            setattr(cfg, target.key, copy.deepcopy(groups[sample]))
    for target, apply, sample in items:
        if target.kind == "config":
            value = combine(apply, target.nominal, float(sample))
            _set(cfg, target.path, int(round(value)) if target.integer else value)
        elif target.kind == "vehicle":
            value = combine(apply, target.nominal, float(sample))
            vehicle = _replace(vehicle, target.path, int(round(value)) if target.integer else value)
        elif target.kind == "tables":
            if target.key.startswith("tables.aero."):
                aero[AERO_COEFFICIENTS.index(target.key.rsplit(".", 1)[1])] *= float(sample)
            else:
                vehicle = _apply_table(vehicle, target.key, float(sample))
    check_physics(cfg)
    return Applied(cfg, vehicle, aero)


def build_dispersed(applied: Applied, guidance, staging=None) -> SimModel:
    """The numeric model of one run (``staging``: a callable starting it from a stored
    staging state, for ``phase=upper_stage`` batches)."""
    model = build_model(applied.cfg, applied.vehicle, guidance)
    if np.any(applied.aero_scale != 1.0):
        coef = model.tables.aero_coef * applied.aero_scale[None, :, None, None, None]
        model.tables = model.tables._replace(aero_coef=np.ascontiguousarray(coef))
    if staging is not None:
        staging(model, applied.cfg)
    return model
