"""savant: Stability Aerospace Vehicle ANalysis Tool.

A modular nonlinear six-degree-of-freedom launch-vehicle ascent simulation that
linearizes itself for frequency-domain stability analysis and runs dispersion and
design studies from Hydra configs.
"""

import os

# One BLAS thread per process unless the user says otherwise: savant's linear algebra is
# on matrices of at most a few hundred rows, where OpenBLAS threads cost more than they
# give (the linear study runs ~1.5x faster single-threaded on 2 cores), and batch studies
# parallelize over processes. Effective when savant is imported before numpy (the CLI).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from savant_cli import jit_cache as _jit_cache
from savant_cli.version import __version__  # noqa: F401  (savant_cli.__version__)

_jit_cache.configure()


def __getattr__(name: str):
    """``savant_cli.run``, ``savant_cli.load``, ``savant_cli.Result``: the Python API
    (savant_cli/api.py, docs/api.md), imported on first use so that the command line
    does not pay for it."""
    if name in ("run", "load", "Result"):
        from savant_cli import api

        return getattr(api, name)
    raise AttributeError(f"module 'savant_cli' has no attribute {name!r}")
