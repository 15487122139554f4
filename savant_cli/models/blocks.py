"""Named blocks of the flat vectors the compiled plant reads.

The plant sees four flat float64 vectors: the continuous state ``x`` (its rigid-body part), the
scalar parameters ``p``, the per-evaluation diagnostics ``aux`` and the packed tables
``tb``; the flight software keeps its discrete state in a fifth, ``d``. Each physical model declares, in its own file, the fields it owns in them::

    PARAMS = blocks.PARAMETERS.block("rcs")
    P_ARM = PARAMS.scalar("moment_arm", "m", "roll moment arm of each jet")

``scalar``/``array``/``record`` return the field's index as a plain ``int``: assigned to a
module-level name it is a compile-time constant for numba, so the kernels address the
vectors by name at no cost. Indices are handed out in declaration order. The order is
fixed because :mod:`savant_cli.models` imports every model in one documented order
before any of them can be used (a package's ``__init__`` always runs first), and the
numba cache is keyed on the sources (:mod:`savant_cli.jit_cache`), so a compiled kernel
can never see indices other than the ones it was compiled with.

A :class:`Record` is the layout of a repeated group (one stage's actuator, one tank, one
row of a table): its field offsets are named constants too, so a kernel writes
``p[stage + ACT_RATE_LIMIT]`` or ``tb[row + SLOSH_DAMPING]`` instead of ``p[base + 3]``.
Every field carries its units and a description; ``docs/models.md`` lists them and a
test checks that each one is documented there.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from savant_cli.config import SavantConfig
    from savant_cli.vehicle import Vehicle


@dataclass(frozen=True)
class Logged:
    """A diagnostic logged as a named time history (``sim/run.py::signals``, the dataset
    ``time_history/<name>`` of ``savant.h5``), with the field's units and description.

    Attributes
    ----------
    name : str
        The signal's name.
    columns : tuple of str
        Names of the columns of a field of more than one entry.
    frame : str
        Reference frame of a vector (``"body"``, ``"ECI"``, ``"NED"``); empty for scalars.
    when : callable or None
        ``when(model)`` (the built :class:`savant_cli.sim.build.SimModel`) is true when
        the field means something in the run (its model is on); None: always logged.
    columns_of : callable or None
        ``columns_of(model)``: the columns of a field sized for the most a vehicle may
        have (one per sloshing tank, say), of which a run logs the first
        ``len(columns_of(model))``; None: ``columns``.
    """

    name: str
    columns: tuple[str, ...] = ()
    frame: str = ""
    when: Callable[[Any], bool] | None = None
    columns_of: Callable[[Any], tuple[str, ...]] | None = None


@dataclass(frozen=True)
class Field:
    """One named field of a vector: ``size`` consecutive entries from ``index``; a
    diagnostic with ``logged`` set is a time history of every run."""

    vector: str
    model: str
    name: str
    index: int
    size: int
    units: str
    description: str
    logged: Logged | None = None

    @property
    def key(self) -> str:
        """``model.name``, the field's documented name."""
        return f"{self.model}.{self.name}"


class Record:
    """Field layout of a repeated group of entries (offsets relative to its start).

    Parameters
    ----------
    name : str
        What one record is (e.g. ``"actuator stage"``).
    fields : tuple of (name, units, description)
        The entries, in order; each is one float64.
    """

    def __init__(self, name: str, *fields: tuple[str, str, str]) -> None:
        self.name = name
        self.fields = tuple(fields)
        self.offsets = tuple(range(len(fields)))
        self.size = len(fields)

    def names(self) -> tuple[str, ...]:
        return tuple(f[0] for f in self.fields)


class Vector:
    """One flat vector of the plant and the fields declared in it, in index order."""

    def __init__(self, name: str, description: str, start: int = 0) -> None:
        self.name = name
        self.description = description
        self.fields: list[Field] = []
        self.size = start

    def block(self, model: str) -> "Block":
        """The fields of ``model`` in this vector (declared through the returned block)."""
        return Block(self, model)

    def _add(self, model: str, name: str, size: int, units: str, description: str,
             logged: Logged | None = None) -> int:
        if not units:
            raise ValueError(f"{self.name}: field {model}.{name} needs units ('1' when dimensionless)")
        if any(f.model == model and f.name == name for f in self.fields):
            raise ValueError(f"{self.name}: field {model}.{name} declared twice")
        if logged is not None and logged.columns_of is None and len(logged.columns) != (0 if size == 1 else size):
            raise ValueError(f"{self.name}: field {model}.{name} of {size} entries logged with columns "
                             f"{logged.columns}")
        index = self.size
        self.fields.append(Field(self.name, model, name, index, size, units, description, logged))
        self.size += size
        return index

    def field(self, key: str) -> Field:
        """The field named ``model.name``."""
        for f in self.fields:
            if f.key == key:
                return f
        raise KeyError(f"{self.name} has no field {key!r}")


class Block:
    """The fields one model declares in one :class:`Vector`."""

    def __init__(self, vector: Vector, model: str) -> None:
        self.vector = vector
        self.model = model

    def scalar(self, name: str, units: str, description: str, logged: Logged | None = None) -> int:
        """One entry; returns its index. ``logged``: a time history of every run."""
        return self.vector._add(self.model, name, 1, units, description, logged)

    def array(self, name: str, size: int, units: str, description: str, logged: Logged | None = None) -> int:
        """``size`` consecutive entries of one quantity; returns the first index.
        ``logged``: a time history of every run."""
        return self.vector._add(self.model, name, size, units, description, logged)

    def record(self, name: str, layout: Record, description: str) -> int:
        """One :class:`Record`; returns its first index (add the record's offsets)."""
        start = self.vector.size
        for fname, units, desc in layout.fields:
            self.vector._add(self.model, f"{name}.{fname}", 1, units, f"{description}: {desc}")
        return start


class Tables:
    """The packed tables: named arrays of any size, one field number each.

    The packed array starts with a header of two entries per field (offset of the
    field's C-ordered data in the flat array, element count), then the data (see
    :func:`pack`). A field's number is its position in the header.
    """

    def __init__(self) -> None:
        self.fields: list[Field] = []

    def block(self, model: str) -> "TableBlock":
        return TableBlock(self, model)

    def names(self) -> tuple[str, ...]:
        """Field names, in field-number order (the fields of ``PlantTables``)."""
        return tuple(f.name for f in self.fields)


class TableBlock:
    """The tables one model declares."""

    def __init__(self, tables: Tables, model: str) -> None:
        self.tables = tables
        self.model = model

    def table(self, name: str, units: str, description: str) -> int:
        """A table field; returns its field number (``T_*``)."""
        if not units:
            raise ValueError(f"table {self.model}.{name} needs units")
        number = len(self.tables.fields)
        self.tables.fields.append(Field("tb", self.model, name, number, 0, units, description))
        return number


@dataclass
class ModelInputs:
    """What a model's ``build(inputs, p, tables)`` reads: the validated config, the
    loaded vehicle, and data loaded once per run by the vehicle-data layer
    (``savant_cli.flex_slosh``: ``slosh``, the slosh tables when slosh is on; ``flex``, the
    modal data at the plant's points when flex is on); ``layout``: the run's state layout."""

    cfg: "SavantConfig"
    vehicle: "Vehicle"
    layout: Any
    slosh: Any = None
    flex: Any = None


def pack(arrays: list[np.ndarray]) -> np.ndarray:
    """One flat float64 array holding ``arrays`` (the :class:`Tables` layout): a header of
    (offset, element count) per array, then each array's C-ordered data."""
    parts = [np.ascontiguousarray(a, dtype=np.float64).ravel() for a in arrays]
    n_header = 2 * len(parts)
    out = np.empty(n_header + sum(a.size for a in parts))
    pos = n_header
    for f, a in enumerate(parts):
        out[2 * f] = pos
        out[2 * f + 1] = a.size
        out[pos:pos + a.size] = a
        pos += a.size
    return out


def stack_padded(arrays: list[np.ndarray], fill: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Pad 1-D or 2-D arrays along axis 0 to a common length and stack them; return
    (stacked, valid lengths). Padding repeats the last row (keeps axes monotone)."""
    n = max(a.shape[0] for a in arrays)
    out = np.full((len(arrays), n) + arrays[0].shape[1:], fill)
    for i, a in enumerate(arrays):
        out[i, : a.shape[0]] = a
        out[i, a.shape[0]:] = a[-1]
    return np.ascontiguousarray(out), np.array([a.shape[0] for a in arrays], dtype=np.int64)


#: Core continuous states (optional model blocks follow them; see models/layout.py).
STATE = Vector("x", "core continuous state")
#: Scalar parameters.
PARAMETERS = Vector("p", "scalar parameters")
#: Diagnostics filled by every derivative evaluation (logged on logged steps).
DIAGNOSTICS = Vector("aux", "per-derivative diagnostics")
#: Discrete flight-software state (guidance smoother, gyro filters, flight control).
DISCRETE = Vector("d", "discrete flight-software state")
#: Held plant inputs (gimbal and jet commands, configuration, engine phase, gust).
INPUTS = Vector("u", "held plant inputs")
#: Packed tabular data.
TABLES = Tables()
