"""Speed of the default controller fly-off (issue 6 target: 2 controllers x 100
dispersed runs, margins at two times, in at most 3 min on the 2-core reference machine).

    python benchmarks/flyoff_speed.py

Runs ``savant run study=flyoff`` (plots included) after a warm-up that loads the
compiled plant, and prints the wall time.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time


def main() -> None:
    base = [sys.executable, "-m", "savant_cli.cli", "run", "study=flyoff", "sim.progress=false"]
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run(base + ["study.n_runs=1", f"hydra.run.dir={tmp}/warm"], check=True, stdout=subprocess.DEVNULL)
        t0 = time.perf_counter()
        subprocess.run(base + [f"hydra.run.dir={tmp}/flyoff"], check=True, stdout=subprocess.DEVNULL)
        wall = time.perf_counter() - t0
    print(f"default fly-off (2 controllers x 101 runs, margins at 55 and 180 s, plots): {wall:.1f} s (target 180 s)")


if __name__ == "__main__":
    main()
