"""Real-time factor of the nominal ascent.

Prints (1) the compiled simulation alone — simulated seconds per wall second of the
compiled loop, after a warm-up run that loads (or compiles) the numba cache — and
(2) the whole second `savant run` process, plots and files included, timed as a
subprocess.

    python benchmarks/nominal_speed.py [--repeat 3]

Targets: ≥ 1500× real time for the rigid simulation on one core and a whole second
`savant run` in under 10 s on the 2-core reference machine (issue 2); ≥ 1000× for full
fidelity — 4 flex modes, both slosh tanks, tail-wags-dog, third-order actuators (issue 3).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time


FULL_FIDELITY = ["flex=on", "flex.n_modes=4", "slosh=on", "twd=on", "actuator=third_order"]


def simulation_only(repeat: int, overrides: list[str] | None = None, label: str = "rigid") -> None:
    from hydra import compose, initialize_config_dir

    from savant_cli.config import validate
    from savant_cli.paths import hydra_search_dirs, shipped_config_dir
    from savant_cli.sim.run import simulate
    from savant_cli.sim.setup import prepare

    with initialize_config_dir(config_dir=str(shipped_config_dir()), version_base="1.3"):
        cfg = validate(compose(config_name="config", overrides=overrides or []))
    t0 = time.perf_counter()
    prep = prepare(cfg, hydra_search_dirs())
    t_prep = time.perf_counter() - t0
    t0 = time.perf_counter()
    warm = simulate(prep.model, progress=False)
    t_first = time.perf_counter() - t0
    print(f"setup (load vehicle, build model): {t_prep:.3f} s")
    print(f"first run (cache load or compile):  {t_first:.2f} s wall, {warm.message}")
    best = None
    for i in range(repeat):
        res = simulate(prep.model, progress=False)
        rtf = res.t_final / res.sim_wall_time_s
        best = rtf if best is None else max(best, rtf)
        print(f"run {i + 1}: {res.t_final:.1f} s simulated in {res.sim_wall_time_s:.3f} s -> {rtf:,.0f}x real time")
    print(f"simulation real-time factor, {label} (best of {repeat}): {best:,.0f}x")


def whole_process() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "savant_cli.cli", "run", f"hydra.run.dir={tmp}/run", "sim.progress=false"]
        env = dict(os.environ)
        subprocess.run(cmd, check=True, capture_output=True, env=env)  # warm the cache
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True, env=env)
        wall = time.perf_counter() - t0
    print(f"whole `savant run` (second run, plots included): {wall:.2f} s")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    simulation_only(args.repeat)
    simulation_only(args.repeat, FULL_FIDELITY, "full fidelity (" + " ".join(FULL_FIDELITY) + ")")
    whole_process()


if __name__ == "__main__":
    main()
