"""Speed and memory of ``study=montecarlo`` (issue 5 targets, full-fidelity plant).

    python benchmarks/montecarlo_speed.py [--runs 1000] [--small 100] [--workers 0]

Flies a batch of full-fidelity runs (flex 4 modes, slosh, TWD; histories and plots
off) through the installed ``savant`` command line, twice: ``--small`` runs and
``--runs`` runs, and prints runs per minute and the peak resident memory of the largest
process of each. Targets: 1000 runs in at most 5 min on the 2-core reference machine;
peak memory the same for both batch sizes (it must not grow with n_runs).
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time

FIDELITY = ["flex=on", "flex.n_modes=4", "slosh=on", "twd=on"]


def batch(n: int, workers: int) -> tuple[float, float]:
    """Wall time (s) and peak RSS (MiB) of one batch of ``n`` runs, in a fresh process."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "savant_cli.cli", "run", "study=montecarlo", *FIDELITY, f"study.n_runs={n}",
               f"study.workers={workers}", "study.histories.signals=[]", "output.plots=false", "sim.progress=false",
               f"hydra.run.dir={tmp}/mc"]
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        wall = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0
    return wall, peak


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--small", type=int, default=100)
    ap.add_argument("--workers", type=int, default=0)
    args = ap.parse_args()
    batch(2, 1)  # compile / load the cache
    for n in (args.small, args.runs):
        wall, peak = batch(n, args.workers)
        print(f"{n:5d} full-fidelity runs: {wall:6.1f} s = {60 * n / wall:6.1f} runs/min; "
              f"peak memory of the largest process so far {peak:.0f} MiB")
    print("target: 1000 runs in 300 s (200 runs/min); peak memory independent of the run count")


if __name__ == "__main__":
    main()
