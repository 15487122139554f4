"""Cost per plant step of an engine cluster and of strap-on boosters: the shipped ares_i
against the same vehicle with its first-stage motor split into a ring of six engines
(each a sixth of the thrust and of the moving mass, twelve gimbal channels through the
mixer), against docs/vehicles.md's strap-on booster example (two boosters, their
thrust and in-flight mass composition until their jettison) and against its booster-TVC
example (the same boosters' nozzles on four more gimbal channels, mixed with the
motor's), flown in turn in one process so the machine's drift falls on all alike.

    python benchmarks/cluster_speed.py [--rounds 7] [--engines 6] [overrides ...]

Each round flies each vehicle once, after one warm-up flight each (numba's cache loaded
or compiled). Prints the median wall time per plant step of each, the median real-time
factors, and the ratios of the medians to ares_i's.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import statistics
from pathlib import Path

import numpy as np
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf

from savant_cli.config import validate
from savant_cli.io.guidance_file import read_guidance
from savant_cli.paths import hydra_search_dirs, shipped_config_dir
from savant_cli.sim.build import build_model
from savant_cli.sim.run import simulate
from savant_cli.sim.setup import prepare
from savant_cli.vehicle import load_vehicle
from savant_cli.vehicle.tree import MovingMass
from savant_cli.vehicle.two_stage import Mount

RING_M = 1.5  # the ring's radius, m
PAGE = Path(__file__).resolve().parents[1] / "docs" / "vehicles.md"


def ring_first_stage(vehicle, n: int):
    """``vehicle`` with its first-stage motor split into ``n`` engines on a ring, each
    ``1/n`` of the moving mass."""
    fs = vehicle.first_stage
    theta = 2.0 * np.pi * np.arange(n) / n
    mounts = tuple(Mount(f"e{i}", np.array([0.0, RING_M * np.cos(t), RING_M * np.sin(t)]), np.zeros(2))
                   for i, t in enumerate(theta))
    moving = MovingMass(fs.engine.mass_kg / n, fs.engine.cg_from_gimbal_m, fs.engine.inertia_about_gimbal_kgm2 / n)
    return dataclasses.replace(vehicle, first_stage=dataclasses.replace(fs, engine=moving, mounts=mounts))


def strap_on_boosters(*more: str):
    """docs/vehicles.md's ``strap-on-boosters`` example over the shipped ares_i (its events
    replaced, as the page says), then the examples ``more`` written over it."""
    page = PAGE.read_text(encoding="utf-8")
    folder = shipped_config_dir() / "vehicle"
    node = OmegaConf.load(folder / "ares_i.yaml").vehicle
    OmegaConf.update(node, "events", {}, merge=False)
    for name in ("strap-on-boosters", *more):
        block = re.search(rf"```yaml\n# example: {name}\n(.*?)```", page, re.S)
        node = OmegaConf.merge(node, OmegaConf.create(block.group(1)))
    return load_vehicle(OmegaConf.to_container(node, resolve=True), folder / "ares_i")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--engines", type=int, default=6)
    ap.add_argument("overrides", nargs="*", help="config overrides for both vehicles")
    args = ap.parse_args()
    with initialize_config_dir(config_dir=str(shipped_config_dir()), version_base="1.3"):
        cfg = validate(compose(config_name="config", overrides=["sim.progress=false", *args.overrides]))
    prep = prepare(cfg, hydra_search_dirs())
    guidance = read_guidance(prep.command_file)
    models = {"ares_i": prep.model,
              f"{args.engines}-engine first stage": build_model(cfg, ring_first_stage(prep.vehicle, args.engines),
                                                               guidance),
              "two strap-on boosters": build_model(cfg, strap_on_boosters(), guidance),
              "two boosters with TVC": build_model(cfg, strap_on_boosters("booster-tvc"), guidance)}
    per_step = {name: [] for name in models}
    rtf = {name: [] for name in models}
    for model in models.values():
        simulate(model, progress=False)  # warm-up
    for _ in range(args.rounds):
        for name, model in models.items():
            res = simulate(model, progress=False)
            steps = res.t_final * cfg.sim.plant_rate_hz
            per_step[name].append(res.sim_wall_time_s / steps)
            rtf[name].append(res.t_final / res.sim_wall_time_s)
    for name in models:
        print(f"{name:24s} {1e6 * statistics.median(per_step[name]):7.2f} µs per plant step, "
              f"real-time factor {statistics.median(rtf[name]):7.0f}")
    single, *others = (statistics.median(v) for v in per_step.values())
    for name, cost in zip(list(models)[1:], others):
        print(f"cost per step, {name} / ares_i: {cost / single:.3f} (medians of {args.rounds} rounds)")


if __name__ == "__main__":
    main()
