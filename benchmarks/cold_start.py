"""First contact: the cold first ``savant run`` and the warm second one (issue 27 item 9).

    python benchmarks/cold_start.py [--repeat 1] [--warm-repeat 3]

Each repetition makes a fresh, empty ``SAVANT_CACHE_DIR`` (so numba compiles the whole
plant), runs the README's first command ``savant run`` (plots, report and files included)
as a subprocess and times it, reads the run's ``compile_time_s`` (the kernels' compile or
cache load before the flight's first step, when the summary has it), then times the
second, warm whole run in the same cache ``--warm-repeat`` times. Medians where repeated.
Each run's CPU time (its own and its helpers') is printed beside its wall time: on a
loaded machine it is the steadier figure.
The machine's load average is printed before and after, so that a reader knows how
quiet it was: the reference machine has 2 cores and is shared.

Targets: the first result on a fresh install in under 60 s; a second whole run in under
3 s on a quiet machine.

Measured figures, with the commit and the machine's quiet, are recorded in
docs/architecture.md ("The cold compile"): at 4667790 the cold first run took 196 s
(``compile_time_s`` 174 s) and the warm second one 10 s, the first target not met.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import tempfile
import time
from pathlib import Path


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def _cpu() -> float:
    use = resource.getrusage(resource.RUSAGE_CHILDREN)
    return use.ru_utime + use.ru_stime


def _run(cache: Path, out: Path, extra: list[str]) -> tuple[float, float, dict]:
    """Wall and CPU time (s; the CPU of the process and the helpers it waited for) of one
    whole ``savant run``, and its summary."""
    env = dict(os.environ, SAVANT_CACHE_DIR=str(cache))
    env.pop("NUMBA_CACHE_DIR", None)
    cmd = ["savant", "run", f"hydra.run.dir={out}", "sim.progress=false", *extra]
    t0, c0 = time.perf_counter(), _cpu()
    subprocess.run(cmd, check=True, capture_output=True, env=env)
    wall, cpu = time.perf_counter() - t0, _cpu() - c0
    summary = json.loads((out / "summary.json").read_text())
    shutil.rmtree(out, ignore_errors=True)
    return wall, cpu, summary


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=1, help="cold first runs, each in a fresh cache")
    ap.add_argument("--warm-repeat", type=int, default=3, help="warm second runs after each cold one")
    ap.add_argument("overrides", nargs="*", help="extra overrides for both runs")
    args = ap.parse_args()
    print(f"load average before: {_load()} ({os.cpu_count()} cores)")
    cold, compile_s, warm, rtf = [], [], [], []
    with tempfile.TemporaryDirectory(prefix="savant-cold-") as tmp:
        for i in range(args.repeat):
            cache = Path(tmp) / f"cache{i}"
            wall, cpu, s = _run(cache, Path(tmp) / "run", args.overrides)
            cold.append(wall)
            compile_s.append(s.get("compile_time_s", float("nan")))
            print(f"cold first run {i + 1}: {wall:.1f} s whole ({cpu:.1f} s CPU), compile_time_s {compile_s[-1]:.1f} s, "
                  f"realtime_factor {s.get('realtime_factor', float('nan')):,.0f}x (load {_load()})")
            for j in range(args.warm_repeat):
                wall, cpu, s = _run(cache, Path(tmp) / "run", args.overrides)
                warm.append(wall)
                rtf.append(s.get("realtime_factor", float("nan")))
                print(f"  warm second run {j + 1}: {wall:.2f} s whole ({cpu:.1f} s CPU), "
                      f"realtime_factor {rtf[-1]:,.0f}x")
    print(f"cold first whole run: median {statistics.median(cold):.1f} s (of {len(cold)}); compile_time_s median "
          f"{statistics.median(compile_s):.1f} s")
    if warm:
        print(f"warm second whole run: median {statistics.median(warm):.2f} s (of {len(warm)}); "
              f"realtime_factor median {statistics.median(rtf):,.0f}x")
    print(f"load average after: {_load()}")


if __name__ == "__main__":
    main()
