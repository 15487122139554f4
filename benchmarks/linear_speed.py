"""Speed of the linear study (issue 4 targets, full-fidelity plant).

    python benchmarks/linear_speed.py [--points 20]

Prints the time to linearize, assemble and take every margin per point, the time to
compute the chart data (frequency responses, root loci, time responses) and to draw the
charts, and the whole batch of points, after the time run and compilation.
Targets: ≤ 0.2 s per point for models and margins; 20 points with charts ≤ 30 s.
"""

from __future__ import annotations

import argparse
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

import savant_cli  # noqa: F401  (first: sets one BLAS thread per process, as the CLI does)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--points", type=int, default=20)
    args = ap.parse_args()
    from hydra import compose, initialize_config_dir

    from savant_cli.config import validate
    from savant_cli.linear.charts import point_charts
    from savant_cli.linear.point_analysis import analyse
    from savant_cli.paths import shipped_config_dir
    from savant_cli.plots.linear import plot_linear_point
    from savant_cli.sim.run import simulate
    from savant_cli.sim.setup import prepare

    overrides = ["study=linear", "flex=on", "flex.n_modes=4", "slosh=on", "twd=on"]
    with initialize_config_dir(config_dir=str(shipped_config_dir()), version_base="1.3"):
        cfg = validate(compose(config_name="config", overrides=overrides))
    model = prepare(cfg).model
    rt = model.rates
    times = np.linspace(20.0, 120.0, args.points // 2).tolist() + np.linspace(150.0, 500.0, args.points - args.points // 2).tolist()
    steps = tuple(int(round(t / (rt.dt * rt.n_fcs))) * rt.n_fcs for t in times)
    simulate(model, progress=False)  # compile / load the cache
    t0 = time.perf_counter()
    res = simulate(model, progress=False, snapshot_steps=steps)
    t_run = time.perf_counter() - t0
    dt = rt.dt * rt.n_fcs
    warnings.simplefilter("ignore")
    analyse(model, res.snapshots[steps[0]], cfg.study, dt)  # warm-up (imports)
    t0 = time.perf_counter()
    results = [analyse(model, res.snapshots[k], cfg.study, dt) for k in steps]
    t_models = time.perf_counter() - t0
    t0 = time.perf_counter()
    charts = [point_charts(pt.time_s, pt.loops, pt.closed, rows) for pt, rows in ((a.point, a.rows) for a in results)]
    t_data = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        for c, a in zip(charts, results):
            plot_linear_point(c, a.rows, Path(tmp))
        t_draw = time.perf_counter() - t0
    t_plots = t_data + t_draw
    n = len(steps)
    print(f"plant states: {results[0].point.plant_continuous.nstates}, loop states: {results[0].point.loops['pitch'].nstates}")
    print(f"time run with {n} snapshots: {t_run:.2f} s")
    print(f"models and margins: {t_models:.2f} s for {n} points = {t_models / n:.3f} s per point (target 0.2)")
    print(f"charts: {t_plots:.2f} s (data {t_data:.2f} s, drawing {t_draw:.2f} s); points with charts: {t_models + t_plots:.1f} s (target 30 s for 20)")


if __name__ == "__main__":
    main()
