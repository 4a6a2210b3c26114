"""Soil property sets: Bekker pressure-sinkage (n, k_c, k_phi), Mohr-Coulomb strength (c, phi) and the
Janosi-Hanamoto shear deformation modulus K, in SI units.

The built-in sets live in ``soils.csv`` beside this module (units, values and the source of every row in its
header). A user file has the same columns (``name,n,k_c,k_phi,c,phi,K`` in kN/m^(n+1), kN/m^(n+2), kPa, deg, m;
``source``, ``K_source`` and ``gamma`` [kN/m^3] optional, an empty gamma meaning unknown; ``#`` lines are comments):

    >>> from mftyre.soil import soil, read_soils
    >>> soil("paddy_soil").k_phi          # N/m^(n+2)
    96080.0
    >>> mine = read_soils("my_soils.csv")["field_7"]
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

from ..errors import DataError, ModelInputError
from ..files import TIR_MAX_BYTES, read_user_file

__all__ = ["Soil", "read_soils", "builtin_soils", "soil", "BUILTIN_FILE"]

BUILTIN_FILE = Path(__file__).with_name("soils.csv")
_COLUMNS = ("name", "n", "k_c", "k_phi", "c", "phi", "K")
#: Largest angle of internal friction [deg] and the range of the shear deformation modulus [m] of a soil the model
#: takes (within them every equation stays finite; beyond them no soil is).
MAX_PHI_DEG = 60.0
MIN_K, MAX_K = 1e-12, 1.0  # K -> 0 (1e-9) is the rigid-plastic limit; below 1e-150 the shear slip underflows
#: file unit -> SI factor of each numeric column (n and K need none, phi is converted to radians)
_TO_SI = {"k_c": 1e3, "k_phi": 1e3, "c": 1e3}


@dataclass(frozen=True)
class Soil:
    """One soil, SI units: n [-], k_c [N/m^(n+1)], k_phi [N/m^(n+2)], c [Pa], phi [rad], K [m].

    Pressure-sinkage (Bekker): p = (k_c / b + k_phi) z^n, b the smaller side of the loaded area.
    Shear strength (Mohr-Coulomb): tau_max = c + sigma tan(phi); shear stress (Janosi-Hanamoto):
    tau = tau_max (1 - exp(-j / K)), j the shear displacement. Unit weight gamma [N/m^3] (NaN: unknown), used
    only by the bulldozing option.
    """

    name: str
    n: float
    k_c: float
    k_phi: float
    c: float
    phi: float
    K: float
    source: str = ""
    gamma: float = math.nan

    def __post_init__(self):
        if not (isinstance(self.gamma, (int, float)) and (math.isnan(self.gamma) or
                                                          (math.isfinite(self.gamma) and self.gamma > 0))):
            raise ModelInputError(f"soil {self.name!r}: gamma (unit weight) must be a positive number in N/m^3 "
                                  f"or NaN (unknown), got {self.gamma!r}")
        for field, low in (("n", 0.0), ("k_c", 0.0), ("k_phi", 0.0), ("c", 0.0), ("phi", 0.0), ("K", 0.0)):
            value = getattr(self, field)
            if not (isinstance(value, (int, float)) and math.isfinite(value)):
                raise ModelInputError(f"soil {self.name!r}: {field} must be a finite number, got {value!r}")
        for field in ("n", "K"):
            if not getattr(self, field) > 0:
                raise ModelInputError(f"soil {self.name!r}: {field} must be positive, got {getattr(self, field)!r}")
        for field in ("k_c", "c"):
            if getattr(self, field) < 0:
                raise ModelInputError(f"soil {self.name!r}: {field} must be >= 0, got {getattr(self, field)!r}")
        if not 0 <= self.phi <= math.radians(MAX_PHI_DEG):  # soils: up to ~50 deg; N_gamma's tan(1.4 phi): 64.3 deg
            raise ModelInputError(f"soil {self.name!r}: phi must be in [0, {MAX_PHI_DEG:g}] deg (soils have up to about "
                                  f"50 deg; the bearing-capacity factors diverge before 65), got "
                                  f"{math.degrees(self.phi)!r} deg")
        if self.n < 0.1:  # soils.csv: n >= 0.11; below 0.1 the sinkage z = (p / k)^(1/n) overflows
            raise ModelInputError(f"soil {self.name!r}: n must be at least 0.1 (soils have 0.1 ... 1.5), got {self.n!r}")
        for field, high in (("n", 3.0), ("k_c", 1e9), ("k_phi", 1e10), ("c", 1e7)):
            if getattr(self, field) > high:  # soils.csv: n <= 1.1, k_c <= 1e5, k_phi <= 5.3e6, c <= 7e4 (SI)
                raise ModelInputError(f"soil {self.name!r}: {field} must be at most {high:g} (SI; no soil has more, and "
                                      f"the equations overflow far beyond), got {getattr(self, field)!r}")
        if not MIN_K <= self.K <= MAX_K:
            raise ModelInputError(f"soil {self.name!r}: K must be in [{MIN_K:g}, {MAX_K:g}] m (soils have 1 mm ... 10 cm; "
                                  f"a small K is the rigid-plastic limit), got {self.K!r} m")
        if not self.k_phi > 0 and not self.k_c > 0:
            raise ModelInputError(f"soil {self.name!r}: k_c and k_phi are both zero: the soil carries no load")
        if self.k_phi < 0:
            raise ModelInputError(f"soil {self.name!r}: k_phi must be >= 0, got {self.k_phi!r}")

    def modulus(self, b):
        """k_c / b + k_phi [N/m^(n+2)] for a loaded area of smaller side ``b`` [m]."""
        return self.k_c / b + self.k_phi


def read_soils(path) -> dict[str, Soil]:
    """The soils of a CSV file (see the module notes), keyed by name. Raises :class:`DataError` naming the file,
    line and column of a malformed, missing, negative or duplicate value."""
    path = Path(path)
    data = read_user_file(path, max_bytes=TIR_MAX_BYTES, what="soil CSV file", error=DataError)  # no FIFO, device
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: cannot read soil file: not UTF-8 text near byte {exc.start}") from None
    numbered = [(i, line) for i, line in enumerate(text.splitlines(), 1) if line.strip() and
                not line.lstrip().startswith("#")]
    if not numbered:
        raise DataError(f"{path}: no header line; expected columns {','.join(_COLUMNS)}")
    try:
        rows = list(csv.reader([line for _, line in numbered]))
    except csv.Error as exc:
        raise DataError(f"{path}: cannot read soil file as CSV: {exc}") from None
    header = [h.strip() for h in rows[0]]
    missing = [c for c in _COLUMNS if c not in header]
    if missing:
        raise DataError(f"{path}:{numbered[0][0]}: missing column(s) {', '.join(missing)}; expected "
                        f"{','.join(_COLUMNS)} (units kN/m^(n+1), kN/m^(n+2), kPa, deg, m), optional source")
    soils: dict[str, Soil] = {}
    for (line_no, _), row in zip(numbered[1:], rows[1:]):
        where = f"{path}:{line_no}"
        if len(row) != len(header):
            raise DataError(f"{where}: {len(row)} fields, the header has {len(header)}")
        record = dict(zip(header, (v.strip() for v in row)))
        name = record["name"]
        if not name:
            raise DataError(f"{where}: empty soil name")
        if name in soils:
            raise DataError(f"{where}: soil {name!r} defined twice")
        values = {}
        for column in _COLUMNS[1:]:
            try:
                value = float(record[column])
            except ValueError:
                raise DataError(f"{where}: column {column}: cannot read {record[column]!r} as a number") from None
            if not math.isfinite(value) or value < 0:
                raise DataError(f"{where}: column {column} of soil {name!r} must be a finite number >= 0, "
                                f"got {record[column]!r}")
            values[column] = value * _TO_SI.get(column, 1.0)
        values["phi"] = math.radians(values["phi"])
        gamma_text = record.get("gamma", "")
        if gamma_text:
            try:
                values["gamma"] = float(gamma_text) * 1e3
            except ValueError:
                raise DataError(f"{where}: column gamma: cannot read {gamma_text!r} as a number") from None
        source = "; K: ".join(s for s in (record.get("source", ""), record.get("K_source", "")) if s)
        try:
            soils[name] = Soil(name=name, source=source, **values)
        except ModelInputError as exc:
            raise DataError(f"{where}: {exc}") from None
    return soils


_BUILTIN: dict[str, Soil] | None = None


def builtin_soils() -> dict[str, Soil]:
    """The soils shipped with mftyre (``soils.csv``), keyed by name."""
    global _BUILTIN
    if _BUILTIN is None:
        _BUILTIN = read_soils(BUILTIN_FILE)
    return dict(_BUILTIN)


def soil(name: str, path=None) -> Soil:
    """The soil ``name`` from the built-in table, or from the CSV file ``path`` when given."""
    table = builtin_soils() if path is None else read_soils(path)
    if name not in table:
        where = "the built-in soils" if path is None else str(path)
        raise ModelInputError(f"unknown soil {name!r}; {where} define: {', '.join(sorted(table))}")
    return table[name]
