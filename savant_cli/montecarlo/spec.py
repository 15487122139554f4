"""The dispersion spec of ``study=montecarlo``: checked against the model before anything
runs, then sampled run by run.

Sampling. Every (run, dispersion) pair has its own stream,
``SeedSequence(seed, spawn_key=(run, h(name)))`` with ``h`` a stable hash of the
dispersion's name, so a run's draws depend only on the master seed, the run number and
the names: not on the worker, the shard, the order of the spec or on which other
dispersions exist. Each stream gives one standard normal ``z``; a correlated group mixes
its members' ``z`` with a square root of its correlation matrix (a Gaussian copula), and
each distribution maps ``u = Φ(z)`` through its inverse CDF (normal: ``mean + σ z``
exactly). Run 0 is the nominal: nothing is applied.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.special import ndtr, ndtri

from savant_cli.config import DispersionApply, DispersionDist, DispersionSetConfig, DispersionSpec, SavantConfig
from savant_cli.errors import ConfigError
from savant_cli.montecarlo.targets import Target, apply_samples, load_group_option, resolve, table_target
from savant_cli.vehicle import Vehicle

APPLY = tuple(DispersionApply)
DISTS = tuple(DispersionDist)
#: fields each distribution reads (any other field set away from its default is refused)
DIST_FIELDS = {"normal": ("mean", "sigma", "truncate_sigma"), "uniform": ("low", "high"),
               "triangular": ("low", "mode", "high"), "choice": ("values", "weights"), "constant": ("value",)}


def _stream_key(name: str) -> int:
    return int.from_bytes(hashlib.sha256(name.encode()).digest()[:4], "little")


@dataclass(frozen=True)
class Dispersion:
    """One checked dispersion."""

    name: str
    target: Target
    apply: str
    dist: str
    mean: float = 0.0
    sigma: float = 0.0
    truncate: float = 0.0
    low: float = 0.0
    high: float = 0.0
    mode: float = 0.0
    values: tuple = ()
    cum_weights: tuple = ()
    constant: Any = None
    source: str = ""

    def draw(self, z: float) -> Any:
        """The sample for a standard normal ``z`` (choice: the chosen value)."""
        if self.dist == "normal":
            if self.truncate > 0.0:
                lo, hi = ndtr(-self.truncate), ndtr(self.truncate)
                z = float(ndtri(lo + ndtr(z) * (hi - lo)))
            return self.mean + self.sigma * z
        u = float(ndtr(z))
        if self.dist == "uniform":
            return self.low + u * (self.high - self.low)
        if self.dist == "triangular":
            a, c, b = self.low, self.mode, self.high
            if b == a:
                return a
            fc = (c - a) / (b - a)
            return a + math.sqrt(u * (b - a) * (c - a)) if u < fc else b - math.sqrt((1 - u) * (b - a) * (b - c))
        if self.dist == "choice":
            return self.values[min(int(np.searchsorted(self.cum_weights, u, side="right")), len(self.values) - 1)]
        return self.constant

    def center(self) -> Any:
        """A central sample (mean, mode, mid-range, first choice) for the trial application."""
        return {"normal": self.mean, "uniform": 0.5 * (self.low + self.high), "triangular": self.mode,
                "constant": self.constant}.get(self.dist, self.values[0] if self.values else None)

    def as_number(self, sample: Any) -> float:
        """The sample as a float for the tables (a group option: its index in ``values``)."""
        if self.target.kind == "group":
            return float(self.values.index(sample)) if self.values else 0.0
        return float(sample)

    @property
    def nominal_number(self) -> float:
        """What run 0 records: 1 for a scale, 0 for an offset, NaN for a value."""
        return {"scale": 1.0, "offset": 0.0}.get(self.apply, float("nan"))


@dataclass
class DispersionSet:
    """The checked spec: dispersions in spec order, correlated groups, master seed."""

    seed: int
    items: list[Dispersion]
    groups: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)  # (indices, square-root factor)
    group_sections: dict[str, Any] = field(default_factory=dict)

    @property
    def names(self) -> list[str]:
        return [d.name for d in self.items]

    def normals(self, run: int) -> np.ndarray:
        """The (correlated) standard normals of one run, one per dispersion."""
        z = np.array([np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(run, _stream_key(d.name))))
                      .standard_normal() for d in self.items])
        for idx, factor in self.groups:
            z[idx] = factor @ z[idx]
        return z

    def sample(self, run: int) -> list[Any]:
        """The samples of run ``run`` (run 0: none, see :meth:`numbers`)."""
        if run == 0:
            return []
        return [d.draw(float(zi)) for d, zi in zip(self.items, self.normals(run))]

    def numbers(self, run: int, samples: list[Any]) -> np.ndarray:
        """Samples as floats for the dispersion table; run 0's nominal markers."""
        if run == 0:
            return np.array([d.nominal_number for d in self.items])
        return np.array([d.as_number(s) for d, s in zip(self.items, samples)])

    def triples(self, samples: list[Any]) -> list[tuple[Target, str, Any]]:
        return [(d.target, d.apply, s) for d, s in zip(self.items, samples)]


def _number(key: str, value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ConfigError(key, value, f"must be a finite number ({what})")
    return float(value)


def _check_fields(key: str, spec: DispersionSpec) -> None:
    default = DispersionSpec()
    used = DIST_FIELDS[spec.dist]
    for f in ("mean", "sigma", "truncate_sigma", "low", "high", "mode", "values", "weights", "value"):
        if f not in used and getattr(spec, f) != getattr(default, f):
            raise ConfigError(f"{key}.{f}", getattr(spec, f),
                              f"is not used by dist {spec.dist} (it reads {', '.join(used)})")


def _one(key: str, spec: DispersionSpec, target: Target) -> Dispersion:
    if spec.apply not in APPLY:
        raise ConfigError(f"{key}.apply", spec.apply, f"must be one of {', '.join(APPLY)}")
    if spec.dist not in DISTS:
        raise ConfigError(f"{key}.dist", spec.dist, f"must be one of {', '.join(DISTS)}")
    _check_fields(key, spec)
    if target.kind == "tables" and spec.apply not in table_target(target.key)[1]:
        raise ConfigError(f"{key}.apply", spec.apply,
                          f"{target.key} takes apply: {' or '.join(table_target(target.key)[1])}")
    if target.kind == "group" and (spec.apply != "value" or spec.dist not in ("choice", "constant")):
        raise ConfigError(f"{key}.dist", spec.dist, f"the group {target.key} takes apply: value with dist choice or "
                          f"constant of its options ({', '.join(target.choices)})")
    if target.integer and spec.apply != "value":
        raise ConfigError(f"{key}.apply", spec.apply, f"{target.key} is an integer: use apply: value")
    kw: dict[str, Any] = {"name": key.rsplit(".", 1)[1], "target": target, "apply": spec.apply, "dist": spec.dist,
                          "source": spec.source}
    if spec.dist == "normal":
        mean = spec.mean if spec.mean is not None else {"scale": 1.0, "offset": 0.0}.get(spec.apply)
        if mean is None:
            raise ConfigError(f"{key}.mean", None, "is required with apply: value")
        kw["mean"] = _number(f"{key}.mean", mean, "the mean")
        kw["sigma"] = _number(f"{key}.sigma", spec.sigma, "σ")
        if kw["sigma"] < 0.0:
            raise ConfigError(f"{key}.sigma", spec.sigma, "must be zero or positive")
        kw["truncate"] = _number(f"{key}.truncate_sigma", spec.truncate_sigma, "k σ")
        if kw["truncate"] < 0.0:
            raise ConfigError(f"{key}.truncate_sigma", spec.truncate_sigma, "must be 0 (no truncation) or positive")
    elif spec.dist in ("uniform", "triangular"):
        lo = _number(f"{key}.low", spec.low, "the lower bound")
        hi = _number(f"{key}.high", spec.high, "the upper bound")
        if lo > hi:
            raise ConfigError(f"{key}.low", spec.low, f"must not exceed high ({spec.high})")
        kw.update(low=lo, high=hi)
        if spec.dist == "triangular":
            mode = _number(f"{key}.mode", spec.mode, "the mode")
            if not lo <= mode <= hi:
                raise ConfigError(f"{key}.mode", spec.mode, f"must lie in [low, high] = [{lo}, {hi}]")
            kw["mode"] = mode
    elif spec.dist == "choice":
        values = list(spec.values)
        if not values:
            raise ConfigError(f"{key}.values", values, "must list at least one value")
        if target.kind == "group":
            bad = [v for v in values if v not in target.choices]
            if bad:
                raise ConfigError(f"{key}.values", bad, f"unknown {target.key} options; known: {', '.join(target.choices)}")
        else:
            values = [_number(f"{key}.values", v, "each choice") for v in values]
        weights = list(spec.weights) or [1.0] * len(values)
        if len(weights) != len(values) or any(not (w >= 0.0 and math.isfinite(w)) for w in weights) or sum(weights) <= 0:
            raise ConfigError(f"{key}.weights", list(spec.weights),
                              f"must be {len(values)} non-negative numbers with a positive sum (or empty: equal)")
        cum = np.cumsum(weights) / sum(weights)
        kw.update(values=tuple(values), cum_weights=tuple(cum[:-1]))
    else:
        if spec.value is None:
            raise ConfigError(f"{key}.value", None, "is required with dist: constant")
        if target.kind == "group":
            if spec.value not in target.choices:
                raise ConfigError(f"{key}.value", spec.value, f"unknown {target.key} option; known: {', '.join(target.choices)}")
            kw["constant"] = spec.value
        else:
            kw["constant"] = _number(f"{key}.value", spec.value, "the constant")
    return Dispersion(**kw)


def _correlations(dispersions: DispersionSetConfig, items: list[Dispersion]) -> list[tuple[np.ndarray, np.ndarray]]:
    index = {d.name: i for i, d in enumerate(items)}
    seen: set[str] = set()
    out = []
    for g, group in enumerate(dispersions.correlations):
        key = f"dispersions.correlations[{g}]"
        names = list(group.names)
        for n in names:
            if n not in index:
                raise ConfigError(f"{key}.names", n, f"is not a dispersion; known: {', '.join(index)}")
            if items[index[n]].dist not in ("normal", "uniform", "triangular"):
                raise ConfigError(f"{key}.names", n, "only normal, uniform and triangular dispersions can be correlated")
            if n in seen:
                raise ConfigError(f"{key}.names", n, "is already in another correlated group")
            seen.add(n)
        m = np.asarray(group.matrix, dtype=float)
        if m.shape != (len(names), len(names)):
            raise ConfigError(f"{key}.matrix", group.matrix, f"must be {len(names)} x {len(names)} (one row per name)")
        if not np.all(np.isfinite(m)) or not np.allclose(m, m.T, atol=1e-12) or not np.allclose(np.diag(m), 1.0) \
                or np.abs(m).max() > 1.0:
            raise ConfigError(f"{key}.matrix", group.matrix,
                              "must be a symmetric correlation matrix: unit diagonal, entries in [-1, 1]")
        lam, vec = np.linalg.eigh(m)
        if lam.min() < -1e-10:
            raise ConfigError(f"{key}.matrix", group.matrix,
                              f"must be positive semi-definite (smallest eigenvalue {lam.min():.3g})")
        out.append((np.array([index[n] for n in names]), vec @ np.diag(np.sqrt(np.clip(lam, 0.0, None))) @ vec.T))
    return out


def parse(dispersions: DispersionSetConfig, seed: int, cfg: SavantConfig, vehicle: Vehicle,
          search_dirs: list[Path]) -> DispersionSet:
    """Check the whole spec against the config and the loaded vehicle.

    Raises
    ------
    ConfigError
        Unknown target, σ < 0, low > high, bad weights, a correlation matrix that is not
        positive semi-definite, a field the distribution does not read, …
    """
    items = []
    for name, spec in dispersions.items.items():
        key = f"dispersions.items.{name}"
        if not spec.target:
            raise ConfigError(f"{key}.target", spec.target, "must name what to disperse")
        target = resolve(f"{key}.target", spec.target, cfg, vehicle, search_dirs)
        items.append(_one(key, spec, target))
    sections = {}
    for d in items:
        if d.target.kind == "group":
            for option in (d.values or (d.constant,)):
                sections[option] = load_group_option(d.target.key, option, search_dirs)
    dset = DispersionSet(seed=seed, items=items, groups=_correlations(dispersions, items), group_sections=sections)
    # one trial application with every dispersion at a central value, so a target that
    # cannot take a value fails here rather than in every run
    if items:
        apply_samples(cfg, vehicle, dset.triples([d.center() for d in items]), sections)
    return dset
