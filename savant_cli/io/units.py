"""The unit suffixes of vehicle data: a column name ``<quantity>_<unit>`` (``thrust_vac_N``,
``alpha_deg``, ``level_ft``) carries its unit, converted to SI once on load.

One table for every vehicle data file: the vehicle tables (:func:`savant_cli.vehicle.read_table`,
also the slosh tables) and the modal data files (:mod:`savant_cli.io.modal_data`).
"""

from __future__ import annotations

import numpy as np

from savant_cli.constants import FT, IN, LBF, LBM, SLUG

#: unit suffix -> (dimension, factor to SI)
UNITS: dict[str, tuple[str, float]] = {
    "m": ("length", 1.0), "km": ("length", 1000.0), "ft": ("length", FT), "in": ("length", IN),
    "kg": ("mass", 1.0), "lbm": ("mass", LBM), "slug": ("mass", SLUG),
    "N": ("force", 1.0), "kN": ("force", 1e3), "MN": ("force", 1e6), "lbf": ("force", LBF),
    "s": ("time", 1.0),
    "deg": ("angle", np.pi / 180.0), "rad": ("angle", 1.0),
    "kgm2": ("inertia", 1.0), "slugft2": ("inertia", SLUG * FT**2),
    "m2": ("area", 1.0), "ft2": ("area", FT**2),
    "Pa": ("pressure", 1.0), "psf": ("pressure", LBF / FT**2),
    "mps": ("speed", 1.0), "fps": ("speed", FT),
    "hz": ("frequency", 1.0), "Hz": ("frequency", 1.0),
    # compound units of a (force, length, second) system, as structural models write lumped
    # masses (force·s²/length) and rotary inertias (force·length·s²)
    "lbf_s2_per_in": ("mass", LBF / IN), "lbf_s2_per_ft": ("mass", LBF / FT), "N_s2_per_m": ("mass", 1.0),
    "lbf_in_s2": ("inertia", LBF * IN), "lbf_ft_s2": ("inertia", LBF * FT), "N_m_s2": ("inertia", 1.0),
}
#: The suffixes made of several ``_``-separated words, longest first (matched before the last word).
_COMPOUND = sorted((u for u in UNITS if "_" in u), key=len, reverse=True)


def split_unit(name: str) -> tuple[str, str | None]:
    """Split a column name into its quantity and its unit suffix.

    Parameters
    ----------
    name : str
        A column name, e.g. ``thrust_vac_N``.

    Returns
    -------
    base : str
        The name without its unit (``thrust_vac``), or the whole name when it has none.
    unit : str or None
        The suffix when it is a key of :data:`UNITS` (a compound one such as
        ``lbf_s2_per_in`` whole, else the word after the last ``_``), else ``None``.
    """
    for unit in _COMPOUND:
        if name.endswith("_" + unit) and len(name) > len(unit) + 1:
            return name[:-len(unit) - 1], unit
    base, sep, unit = name.rpartition("_")
    if sep and base and unit in UNITS:
        return base, unit
    return name, None


def units_of(dimension: str) -> list[str]:
    """The accepted suffixes of one dimension (``"length"`` → ``m, km, ft, in``)."""
    return [u for u, (d, _) in UNITS.items() if d == dimension]
