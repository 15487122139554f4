"""Speed of the flight-control design search (issue 13): what one candidate costs.

    python benchmarks/design_speed.py [--repeats 20]

Flies the default vehicle at full fidelity (flex 4 modes, slosh, TWD), freezes the plant
at 55 s (stack) and 180 s (upper stage), and times ``linear/evaluate.py::judge_controller``
of the shipped controller on each, pitch loop only as the search does (the median of
``--repeats`` calls after a warm-up), next to the full ``study=linear`` analysis of the
same point (linearization included). A candidate of the default ``study=fcs_design``
costs one judgement per design point and corner: 13 stack points x 3 corners, 21 upper-
stage points x 3 corners. Target: the whole default study within 15 minutes on this machine.
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings

import savant_cli  # noqa: F401  (first: sets one BLAS thread per process, as the CLI does)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=20)
    args = ap.parse_args()
    from hydra import compose, initialize_config_dir

    from savant_cli.config import linear_settings, validate
    from savant_cli.linear.evaluate import freeze, judge_controller
    from savant_cli.linear.point_analysis import analyse
    from savant_cli.paths import shipped_config_dir
    from savant_cli.studies import flight as flight_mod

    with initialize_config_dir(config_dir=str(shipped_config_dir()), version_base="1.3"):
        cfg = validate(compose(config_name="config", overrides=["flex=on", "flex.n_modes=4", "slosh=on", "twd=on",
                                                                 "sim.progress=false"]))
    times = [55.0, 180.0]
    flight = flight_mod.fly(cfg, snapshot_steps=flight_mod.control_steps(cfg, times))
    model, res = flight.prep.model, flight.result
    dt = model.rates.dt * model.rates.n_fcs
    warnings.simplefilter("ignore")
    for k, snap in sorted(res.snapshots.items()):
        point = freeze(model, snap, dt)
        judge_controller(point, model.fcs, dt, cfg.requirements, axes=("pitch",))  # warm-up
        judge, full = [], []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            judge_controller(point, model.fcs, dt, cfg.requirements, axes=("pitch",))
            judge.append(time.perf_counter() - t0)
        for _ in range(max(3, args.repeats // 4)):
            t0 = time.perf_counter()
            analyse(model, snap, linear_settings([snap.t]), dt, cfg.requirements)
            full.append(time.perf_counter() - t0)
        print(f"t = {snap.t:5.1f} s ({point.phase_name}, {point.plant.nstates} plant states): "
              f"judge_controller {1e3 * statistics.median(judge):.1f} ms (median of {len(judge)}), "
              f"study=linear point {1e3 * statistics.median(full):.1f} ms")


if __name__ == "__main__":
    main()
