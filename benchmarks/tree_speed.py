"""Real-time factor of the rigid nominal flight in this checkout against a reference
commit, the two flown in turn in their own processes (``PYTHONPATH`` set to each source
tree, as ``bitwise_regression.py`` does), so the machine's drift falls on both alike.

    python benchmarks/tree_speed.py --ref 14d677f [--rounds 4] [overrides ...]

Each round flies one process per tree: a warm-up flight (loads or compiles that tree's
numba cache), then three timed flights. Prints the medians and their ratio. What it is
for: showing that a change which should cost nothing when switched off (issue 15's
gusts and loop perturbation) costs nothing measurable.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CHILD = r"""
import json, sys
from hydra import compose, initialize_config_dir
from savant_cli.config import validate
from savant_cli.paths import hydra_search_dirs, shipped_config_dir
from savant_cli.sim.run import simulate
from savant_cli.sim.setup import prepare
with initialize_config_dir(config_dir=str(shipped_config_dir()), version_base="1.3"):
    cfg = validate(compose(config_name="config", overrides=sys.argv[1:]))
model = prepare(cfg, hydra_search_dirs()).model
simulate(model, progress=False)
rtf = []
for _ in range(3):
    res = simulate(model, progress=False)
    rtf.append(res.t_final / res.sim_wall_time_s)
print(json.dumps(rtf))
"""


def flights(tree: Path, overrides: list[str]) -> list[float]:
    """Three real-time factors of one process of ``tree``."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    proc = subprocess.run([sys.executable, "-c", CHILD, *overrides], env=env, capture_output=True, text=True,
                          cwd=tempfile.gettempdir(), check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ref", required=True, help="reference commit (checked out in a temporary git worktree)")
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("overrides", nargs="*", help="config overrides for both trees")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as work:
        ref = Path(work) / "ref_tree"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(ref), args.ref], check=True,
                       capture_output=True)
        try:
            rtf: dict[str, list[float]] = {"ref": [], "this": []}
            for _ in range(args.rounds):
                rtf["ref"] += flights(ref, args.overrides)
                rtf["this"] += flights(ROOT, args.overrides)
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(ref)], capture_output=True)
    med = {k: statistics.median(v) for k, v in rtf.items()}
    flight = "nominal flight" + (f" ({' '.join(args.overrides)})" if args.overrides else " (rigid)")
    print(f"{flight}, medians of {len(rtf['ref'])}: {args.ref} {med['ref']:,.0f}x, this checkout "
          f"{med['this']:,.0f}x real time; ratio {med['this'] / med['ref']:.3f}")


if __name__ == "__main__":
    main()
