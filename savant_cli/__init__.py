"""savant: Stability Aerospace Vehicle ANalysis Tool.

A modular nonlinear six-degree-of-freedom launch-vehicle ascent simulation that
linearizes itself for frequency-domain stability analysis and runs dispersion and
design studies from Hydra configs.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("savant")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0+unknown"

from savant_cli import jit_cache as _jit_cache

_jit_cache.configure()
