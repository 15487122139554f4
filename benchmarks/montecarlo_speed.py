"""Speed and memory of ``study=montecarlo`` (issue 5 and 13 targets, full-fidelity plant).

    python benchmarks/montecarlo_speed.py [--runs 1000] [--small 100] [--workers 0]

Flies a batch of full-fidelity runs (flex 4 modes, slosh, TWD; histories and plots
off) through the installed ``savant`` command line, twice: ``--small`` runs and
``--runs`` runs, and prints runs per minute, the peak resident memory of the largest
process of each, and where the wall time goes: each run's stages as its journal records
them (``montecarlo/batch.py::RUN_STAGES``: build, simulate, assess, margins, histories;
summed over the runs and divided by the worker count) and the rest, outside the runs
(the command's start-up and the reference flight, the worker pool, journaling, the
collection and the output files). Targets: 1000 runs in at most 200 s on the 2-core
reference machine (issue 13); peak memory the same for both batch sizes (it must not
grow with n_runs).
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

FIDELITY = ["flex=on", "flex.n_modes=4", "slosh=on", "twd=on"]


def batch(n: int, workers: int) -> tuple[float, float, np.ndarray]:
    """Wall time (s), peak RSS (MiB) and the runs' summed stage times (s) of one batch of
    ``n`` runs, in a fresh process."""
    from savant_cli.montecarlo.batch import RUN_STAGES, read_outcome

    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "savant_cli.cli", "run", "study=montecarlo", *FIDELITY, f"study.n_runs={n}",
               f"study.workers={workers}", "study.histories.signals=[]", "output.plots=false", "sim.progress=false",
               f"hydra.run.dir={tmp}/mc"]
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        wall = time.perf_counter() - t0
        stages = np.zeros(len(RUN_STAGES))
        for path in sorted(Path(tmp, "mc", "runs").glob("run_*.npz")):
            stages += read_outcome(path).stage_wall_s
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0
    return wall, peak, stages


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--small", type=int, default=100)
    ap.add_argument("--workers", type=int, default=0)
    args = ap.parse_args()
    from savant_cli.montecarlo.batch import RUN_STAGES
    from savant_cli.processes import default_workers

    workers = args.workers or default_workers()
    batch(2, 1)  # compile / load the cache
    for n in (args.small, args.runs):
        wall, peak, stages = batch(n, args.workers)
        inside = stages / min(workers, n)
        print(f"{n:5d} full-fidelity runs: {wall:6.1f} s = {60 * n / wall:6.1f} runs/min; "
              f"peak memory of the largest process so far {peak:.0f} MiB")
        parts = ", ".join(f"{name} {t:.1f} s" for name, t in zip(RUN_STAGES, inside))
        print(f"      in the runs ({workers} workers): {parts}; outside the runs {wall - inside.sum():.1f} s")
    print("target: 1000 runs in 200 s (300 runs/min); peak memory independent of the run count")


if __name__ == "__main__":
    main()
