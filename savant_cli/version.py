"""The installed package's version, in a module of the bottom floor so that provenance,
the command line and the report read it without importing the package's API."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("savant")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0+unknown"
