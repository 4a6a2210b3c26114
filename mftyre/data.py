"""Measured tyre data: :class:`TyreData`, CSV and TYDEX readers, a TYDEX writer, preparation helpers and a
synthetic test-trailer programme.

Channels (canonical names, SI units, ISO-W / TYDEX W axes, as the model's inputs and outputs)
------------------------------------------------------------------------------------------------
=========  ==========  ========================================  ==============================
channel    unit        meaning                                   model input / output
=========  ==========  ========================================  ==============================
FX FY FZ   N           forces in the contact point (W axes)      fx fy, fz (input)
MX MY MZ   N m         overturning, rolling-resistance, aligning mx my mz
SL         -           longitudinal slip kappa                   kappa
SA         rad         slip angle alpha                          alpha
IA         rad         inclination (camber) angle gamma          gamma
PHIT       1/m         turn slip                                 phit
VX         m/s         longitudinal speed of the wheel centre    vx
P          Pa          inflation pressure                        p
OMEGA      rad/s       wheel spin                                omega
RL RHO RE  m           loaded radius, deflection, eff. radius    rl rho re
=========  ==========  ========================================  ==============================

:class:`TyreData` holds a ``pandas.DataFrame`` (``.frame``) with these columns (a subset of them) plus any
extra columns (e.g. ``SWEEP``, a sweep number, and ``TEST``, the kind of test) and metadata: ``tyre``,
``source``, ``units`` (channel -> unit as read), ``constants`` (TYDEX constants, SI where the unit is known)
and ``history`` (what the preparation helpers did, outliers rejected included).

Required channels: ``FZ``, ``SA``, ``SL``, ``VX`` and ``P`` (every row, numeric, no NaN). ``IA`` and
``PHIT`` default to 0 when absent (recorded in ``history``). A reader may also take a missing input from a
constant (``constants`` of a TYDEX file, ``defaults=`` of the readers). Measured outputs (FX ... RE) may be
absent or NaN in rows where they were not measured.

CSV (:func:`read_csv`)
    Comma separated, one header row. Columns with canonical names are read as SI as they are. Otherwise pass
    ``columns={"file column": "CHANNEL"}`` and ``units={"CHANNEL": "unit"}`` (e.g. ``"deg"``, ``"kN"``,
    ``"kPa"``, ``"km/h"``, ``"%"``, ``"N*m"``, ``"rpm"``, ``"mm"``); see :data:`UNITS`.

TYDEX (:func:`read_tydex`, :func:`write_tydex`): the subset of TYDEX 1.3 (Unrau & Zamow, *TYDEX-Format:
Description and Reference Manual, Release 1.3*, 1997) used for steady-state measurements:

* blocks opened by lines ``**HEADER``, ``**COMMENTS``, ``**CONSTANTS``, ``**MEASURCHANNELS``,
  ``**MEASURDATA`` and closed by ``**END``; lines starting with ``!`` are comments; blank lines ignored.
* ``**HEADER`` and ``**CONSTANTS`` lines are fixed-format: name in columns 1-10, description 11-40, unit
  41-50, value from column 51 (a number, or text for header entries such as ``MEASID``).
* ``**MEASURCHANNELS`` lines: name 1-10, description 11-40, unit 41-50, then (whitespace separated from
  column 51) the conversion factor and up to two offsets (``meas. offset``, ``phys. offset``):
  value in ``unit`` = factor * raw + meas. offset + phys. offset (absent offsets are 0).
* ``**MEASURDATA``: one row per sample, whitespace-separated numbers, one per channel in channel order.
* Channel keywords (W axis system) read, with the first one written: FX: ``FXW`` ``FX``; FY: ``FYW``
  ``FY``; FZ: ``FZW`` ``FZ``; MX: ``MXW`` ``MX``; MY: ``MYW`` ``MY``; MZ: ``MZW`` ``MZ``; SL: ``LONGSLIP``;
  SA: ``SLIPANGL``; IA: ``INCLANGL``; P: ``INFLPRES``; VX: ``LONGVEL`` ``RUNSPEED``; OMEGA: ``WHROTSPD``;
  PHIT: ``TURNSLIP``; RL: ``RLOADED`` ``RSTAT``; RHO: ``DEFLECT``; RE: ``REFFECT`` ``RDYNAM``. (FXW ...
  MZW, LONGSLIP, SLIPANGL, INCLANGL, INFLPRES, LONGVEL and WHROTSPD are TYDEX 1.3 keywords; the names used
  for turn slip and the three radii are mftyre's choice, not checked against the manual.) Other channels
  are kept as extra columns under their TYDEX name, unconverted.
* Constants read as channel values when the channel is absent: ``INFLPRES``, ``INCLANGL``, ``LONGVEL``;
  tyre constants ``FNOMIN``, ``NOMPRES``, ``RFREE`` (unloaded radius), ``NOMWIDTH`` are converted to SI and
  used as the tyre's dimensions by :func:`mftyre.fit.start_parameters`.
* The writer writes SI units with factor 1 and offsets 0, so data round-trip exactly (17 significant
  digits); numeric extra columns (e.g. ``SWEEP``) are written as further channels, text columns (``TEST``)
  are not written.

Every malformed input raises :class:`mftyre.errors.DataError` naming the file, the line (and column or
channel) and the reason: missing channel, unknown unit, non-numeric value, wrong number of values, NaN in a
required channel.
"""
from __future__ import annotations

import datetime as _dt
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .errors import DataError
from .tir import UNIT_FACTORS

__all__ = [
    "CHANNELS", "REQUIRED", "INPUTS", "OUTPUTS", "UNITS", "TyreData", "read_csv", "read_tydex", "write_tydex",
    "unit_to_si", "levels", "split_conditions", "split_sweeps", "bin_sweeps", "resample_sweeps",
    "reject_outliers", "trailer_programme", "NOISE",
]

#: channel -> (physical kind, meaning)
CHANNELS: dict[str, tuple[str, str]] = {
    "FX": ("force", "longitudinal force"),
    "FY": ("force", "lateral force"),
    "FZ": ("force", "vertical load"),
    "MX": ("moment", "overturning moment"),
    "MY": ("moment", "rolling-resistance moment"),
    "MZ": ("moment", "self-aligning moment"),
    "SL": ("ratio", "longitudinal slip kappa"),
    "SA": ("angle", "slip angle alpha"),
    "IA": ("angle", "inclination angle gamma"),
    "PHIT": ("curvature", "turn slip phit"),
    "VX": ("speed", "longitudinal speed"),
    "P": ("pressure", "inflation pressure"),
    "OMEGA": ("angular_speed", "wheel spin"),
    "RL": ("length", "loaded radius"),
    "RHO": ("length", "vertical deflection"),
    "RE": ("length", "effective rolling radius"),
}
#: Input channels of the model, in the order of :meth:`mftyre.MFModel.evaluate`.
INPUTS = ("FZ", "SL", "SA", "IA", "PHIT", "VX", "P")
REQUIRED = ("FZ", "SA", "SL", "VX", "P")
OUTPUTS = ("FX", "FY", "MX", "MY", "MZ", "OMEGA", "RL", "RHO", "RE")
_ZERO_DEFAULT = ("IA", "PHIT")
_SI_NAME = {"force": "N", "moment": "N*m", "ratio": "-", "angle": "rad", "curvature": "1/m", "speed": "m/s",
            "pressure": "Pa", "angular_speed": "rad/s", "length": "m"}


def _unit_table() -> dict[str, dict[str, float]]:
    """kind -> unit spelling (lower case, no blanks) -> factor to SI."""
    def simple(key):
        return {k: float(v) for k, v in UNIT_FACTORS[key].items()}

    length, force, angle, pressure, time = (simple(k) for k in ("LENGTH", "FORCE", "ANGLE", "PRESSURE", "TIME"))
    moment = {}
    for f, ff in force.items():
        for ln, fl in length.items():
            for sep in ("*", ".", "", "-"):
                moment[f"{f}{sep}{ln}"] = ff * fl
    speed = {f"{ln}/{t}": fl / ft for ln, fl in length.items() for t, ft in time.items()}
    speed.update({"kph": 1 / 3.6, "mph": 0.44704, "km/hr": 1 / 3.6})
    angular = {f"{a}/{t}": fa / ft for a, fa in angle.items() for t, ft in time.items()}
    angular.update({"rpm": 2 * math.pi / 60, "1/min": 2 * math.pi / 60, "1/s": 1.0, "u/min": 2 * math.pi / 60})
    curvature = {f"1/{ln}": 1 / fl for ln, fl in length.items()}
    curvature.update({f"{a}/{ln}": fa / fl for a, fa in angle.items() for ln, fl in length.items()})
    ratio = {"-": 1.0, "": 1.0, "1": 1.0, "%": 0.01, "percent": 0.01}
    return {"force": force, "moment": moment, "ratio": ratio, "angle": angle, "curvature": curvature,
            "speed": speed, "pressure": pressure, "angular_speed": angular, "length": length}


#: Accepted unit spellings per kind (case-insensitive, blanks ignored) -> factor to SI.
UNITS: dict[str, dict[str, float]] = _unit_table()


def unit_to_si(channel: str, unit: str) -> float:
    """Factor that converts values of ``channel`` in ``unit`` to SI; ValueError naming the accepted units."""
    kind = CHANNELS[channel][0]
    key = str(unit).strip().lower().replace(" ", "")
    table = UNITS[kind]
    if key not in table:
        examples = ", ".join(list(dict.fromkeys(table))[:10])
        raise ValueError(f"unknown unit {unit!r} for {channel} ({kind}); e.g. {examples}")
    return table[key]


# --------------------------------------------------------------------------------------------- TyreData
@dataclass
class TyreData:
    """Measured or synthetic tyre data: ``frame`` (pandas, canonical channels in SI) and metadata."""

    frame: pd.DataFrame
    tyre: str = ""
    source: str = ""
    units: dict = field(default_factory=dict)
    constants: dict = field(default_factory=dict)
    history: list = field(default_factory=list)

    def __post_init__(self):
        self.frame = self.frame.reset_index(drop=True)
        where = self.source or "<data>"
        missing = [c for c in REQUIRED if c not in self.frame.columns]
        if missing:
            raise DataError(f"{where}: missing channel(s) {', '.join(missing)}; required: {', '.join(REQUIRED)}")
        for name in _ZERO_DEFAULT:
            if name not in self.frame.columns:
                self.frame[name] = 0.0
                self.history.append(f"{name} absent: set to 0")
        for name in CHANNELS:
            if name in self.frame.columns:
                col = pd.to_numeric(self.frame[name], errors="coerce").astype(float)
                bad = col.isna() & self.frame[name].notna()
                if bad.any():
                    row = int(np.flatnonzero(bad.to_numpy())[0])
                    raise DataError(f"{where}: row {row}: channel {name}: non-numeric value "
                                    f"{self.frame[name].iloc[row]!r}")
                self.frame[name] = col
        for name in (*REQUIRED, *_ZERO_DEFAULT):
            nan = self.frame[name].isna().to_numpy()
            if nan.any():
                raise DataError(f"{where}: row {int(np.flatnonzero(nan)[0])}: channel {name}: NaN in a required "
                                f"channel ({int(nan.sum())} rows)")

    # -- table access --------------------------------------------------------------------------------
    def __len__(self) -> int:
        return len(self.frame)

    def __getitem__(self, name):
        return self.frame[name]

    def __contains__(self, name) -> bool:
        return name in self.frame.columns

    @property
    def channels(self) -> tuple[str, ...]:
        """The canonical channels present."""
        return tuple(c for c in CHANNELS if c in self.frame.columns)

    def has(self, name: str) -> bool:
        """True when ``name`` is present with at least one finite value."""
        return name in self.frame.columns and bool(np.isfinite(self.frame[name].to_numpy(float)).any())

    def array(self, name: str) -> np.ndarray:
        return self.frame[name].to_numpy(dtype=float)

    def select(self, mask, note: str | None = None) -> "TyreData":
        """The rows where ``mask`` (boolean array) is true, metadata kept."""
        sub = self.frame.loc[np.asarray(mask, dtype=bool)]
        hist = list(self.history) + ([note] if note else [])
        return TyreData(sub.copy(), self.tyre, self.source, dict(self.units), dict(self.constants), hist)

    def with_frame(self, frame: pd.DataFrame, note: str) -> "TyreData":
        return TyreData(frame, self.tyre, self.source, dict(self.units), dict(self.constants),
                        list(self.history) + [note])

    @staticmethod
    def concat(parts: list["TyreData"]) -> "TyreData":
        first = parts[0]
        frame = pd.concat([p.frame for p in parts], ignore_index=True)
        return TyreData(frame, first.tyre, first.source, dict(first.units), dict(first.constants),
                        list(first.history))

    def inputs(self) -> dict:
        """Keyword arguments fz kappa alpha gamma phit vx p for :meth:`mftyre.MFModel.evaluate`."""
        return dict(fz=self.array("FZ"), kappa=self.array("SL"), alpha=self.array("SA"), gamma=self.array("IA"),
                    phit=self.array("PHIT"), vx=self.array("VX"), p=self.array("P"))

    def __repr__(self):
        return f"TyreData({len(self)} rows, channels={' '.join(self.channels)}, source={self.source!r})"


# ------------------------------------------------------------------------------------------------ CSV
def read_csv(path, *, columns: dict | None = None, units: dict | None = None, defaults: dict | None = None,
             tyre: str = "") -> TyreData:
    """Read a CSV file into :class:`TyreData`.

    ``columns``: file column -> channel for columns not named canonically; ``units``: channel -> unit of the
    file (SI when absent); ``defaults``: channel -> constant SI value for a required channel the file lacks
    (e.g. ``{"P": 2.2e5, "VX": 16.7}``).
    """
    path = Path(path)
    try:
        raw = pd.read_csv(path, dtype=str, skipinitialspace=True, keep_default_na=False)
    except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise DataError(f"{path}: cannot read as CSV: {exc}") from exc
    raw.columns = [str(c).strip() for c in raw.columns]
    mapping = {c: c.upper() for c in raw.columns if c.upper() in CHANNELS}
    for col, ch in (columns or {}).items():
        if col not in raw.columns:
            raise DataError(f"{path}: line 1: column {col!r} (for {ch}) not in the header; columns are "
                            f"{', '.join(raw.columns)}")
        if ch.upper() not in CHANNELS:
            raise DataError(f"{path}: unknown channel {ch!r} for column {col!r}; channels: {', '.join(CHANNELS)}")
        mapping[col] = ch.upper()
    units = {k.upper(): v for k, v in (units or {}).items()}
    frame = pd.DataFrame(index=raw.index)
    for col in raw.columns:
        ch = mapping.get(col)
        text = raw[col].str.strip()
        values = pd.to_numeric(text.replace({"": "nan", "NaN": "nan", "nan": "nan"}), errors="coerce")
        bad = values.isna() & ~text.str.lower().isin(["", "nan"])
        if ch is None:
            frame[col] = values if not bad.any() else raw[col]
            continue
        if bad.any():
            row = int(np.flatnonzero(bad.to_numpy())[0])
            raise DataError(f"{path}: line {row + 2}: column {col!r} ({ch}): non-numeric value {text.iloc[row]!r}")
        factor = 1.0
        if ch in units:
            try:
                factor = unit_to_si(ch, units[ch])
            except ValueError as exc:
                raise DataError(f"{path}: column {col!r}: {exc}") from None
        frame[ch] = values.to_numpy(float) * factor
    _apply_defaults(frame, defaults, path)
    _check_required(frame, path, lambda row: f"line {row + 2}")
    unit_record = {ch: units.get(ch, _SI_NAME[CHANNELS[ch][0]]) for ch in CHANNELS if ch in frame.columns}
    return TyreData(frame, tyre=tyre or path.stem, source=str(path), units=unit_record)


def _apply_defaults(frame, defaults, path):
    for ch, value in (defaults or {}).items():
        ch = ch.upper()
        if ch not in CHANNELS:
            raise DataError(f"{path}: default for unknown channel {ch!r}")
        if ch not in frame.columns:
            frame[ch] = float(value)


def _check_required(frame, path, where):
    missing = [c for c in REQUIRED if c not in frame.columns]
    if missing:
        raise DataError(f"{path}: missing channel(s) {', '.join(missing)} (required: {', '.join(REQUIRED)}; give "
                        f"a column map, or `defaults=` for a constant)")
    _check_finite(frame, lambda row: f"{path}: {where(row)}")


def _check_finite(frame, locate):
    """DataError at the first NaN of a required channel; ``locate(row)`` says where that row is in the file."""
    for ch in (*REQUIRED, *(c for c in _ZERO_DEFAULT if c in frame.columns)):
        nan = np.isnan(frame[ch].to_numpy(float))
        if nan.any():
            raise DataError(f"{locate(int(np.flatnonzero(nan)[0]))}: channel {ch}: NaN in a required channel")


# ---------------------------------------------------------------------------------------------- TYDEX
_TYDEX_NAMES: dict[str, tuple[str, ...]] = {
    "FX": ("FXW", "FX"), "FY": ("FYW", "FY"), "FZ": ("FZW", "FZ"),
    "MX": ("MXW", "MX"), "MY": ("MYW", "MY"), "MZ": ("MZW", "MZ"),
    "SL": ("LONGSLIP",), "SA": ("SLIPANGL",), "IA": ("INCLANGL",), "P": ("INFLPRES",),
    "VX": ("LONGVEL", "RUNSPEED"), "OMEGA": ("WHROTSPD",), "PHIT": ("TURNSLIP",),
    "RL": ("RLOADED", "RSTAT"), "RHO": ("DEFLECT",), "RE": ("REFFECT", "RDYNAM"),
}
_CHANNEL_OF_TYDEX = {name: ch for ch, names in _TYDEX_NAMES.items() for name in names}
#: TYDEX constants with a physical kind (converted to SI when their unit is known).
_CONSTANT_KINDS = {"FNOMIN": "FZ", "NOMPRES": "P", "RFREE": "RL", "NOMWIDTH": "RL", "INFLPRES": "P",
                   "INCLANGL": "IA", "LONGVEL": "VX", "RIMDIAME": "RL", "OVALLDIA": "RL"}
_BLOCKS = ("**HEADER", "**COMMENTS", "**CONSTANTS", "**MEASURCHANNELS", "**MEASURDATA", "**END")


def _fixed_fields(line: str):
    return line[:10].strip(), line[10:40].strip(), line[40:50].strip(), line[50:].strip()


def read_tydex(path, *, defaults: dict | None = None) -> TyreData:
    """Read a TYDEX ``.tdx`` file (the subset described in the module docstring) into :class:`TyreData`."""
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8", errors="strict").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise DataError(f"{path}: cannot read: {exc}") from exc
    block = None
    seen = set()
    header, constants, channels, rows, row_lines = {}, {}, [], [], []
    for lineno, line in enumerate(lines, 1):
        stripped = line.strip()
        if not stripped or stripped.startswith("!"):
            continue
        if stripped.startswith("**"):
            key = stripped.split()[0].upper()
            if key not in _BLOCKS:
                raise DataError(f"{path}:{lineno}: unknown block {stripped!r}; expected one of {', '.join(_BLOCKS)}")
            block = key
            seen.add(key)
            if key == "**END":
                break
            continue
        if block is None:
            raise DataError(f"{path}:{lineno}: text before the first block (**HEADER expected)")
        if block in ("**HEADER", "**CONSTANTS"):
            name, desc, unit, value = _fixed_fields(line)
            if not name:
                raise DataError(f"{path}:{lineno}: column 1-10: empty name in {block}")
            target = header if block == "**HEADER" else constants
            target[name.upper()] = (_constant_value(name.upper(), unit, value, path, lineno), unit, desc)
        elif block == "**MEASURCHANNELS":
            name, desc, unit, rest = _fixed_fields(line)
            parts = rest.split()
            if not name or not parts:
                raise DataError(f"{path}:{lineno}: channel line needs name (columns 1-10), description, unit "
                                f"(41-50) and a conversion factor (from column 51): {line!r}")
            try:
                numbers = [float(p.replace("D", "E").replace("d", "e")) for p in parts[:3]]
            except ValueError:
                raise DataError(f"{path}:{lineno}: column 51: channel {name}: non-numeric factor/offset "
                                f"{rest!r}") from None
            factor, offset = numbers[0], sum(numbers[1:])
            channels.append((name.upper(), unit, factor, offset, lineno))
        elif block == "**MEASURDATA":
            rows.append(stripped.split())
            row_lines.append(lineno)
        # **COMMENTS: free text, ignored
    for needed in ("**MEASURCHANNELS", "**MEASURDATA"):
        if needed not in seen:
            raise DataError(f"{path}: no {needed} block")
    if not channels:
        raise DataError(f"{path}: **MEASURCHANNELS lists no channel")
    data = np.empty((len(rows), len(channels)))
    for i, (row, lineno) in enumerate(zip(rows, row_lines)):
        if len(row) != len(channels):
            raise DataError(f"{path}:{lineno}: {len(row)} values, expected {len(channels)} (one per channel)")
        for j, text in enumerate(row):
            try:
                data[i, j] = float(text.replace("D", "E").replace("d", "e"))
            except ValueError:
                raise DataError(f"{path}:{lineno}: value {j + 1} (channel {channels[j][0]}): non-numeric "
                                f"value {text!r}") from None
    frame = pd.DataFrame(index=range(len(rows)))
    units = {}
    for j, (name, unit, factor, offset, lineno) in enumerate(channels):
        values = factor * data[:, j] + offset
        ch = _CHANNEL_OF_TYDEX.get(name)
        if ch is None:
            frame[name] = values
            continue
        try:
            frame[ch] = values * unit_to_si(ch, unit)
        except ValueError as exc:
            raise DataError(f"{path}:{lineno}: columns 41-50: channel {name}: {exc}") from None
        units[ch] = unit
    for name, (value, unit, _) in constants.items():  # constants standing in for absent channels
        ch = _CHANNEL_OF_TYDEX.get(name)
        if ch in REQUIRED + _ZERO_DEFAULT and ch not in frame.columns and isinstance(value, float):
            frame[ch] = value
            units[ch] = f"{unit} (constant)"
    _apply_defaults(frame, defaults, path)
    missing = [c for c in REQUIRED if c not in frame.columns]
    if missing:
        raise DataError(f"{path}: missing channel(s) {', '.join(missing)}: neither a measurement channel "
                        f"({', '.join(_TYDEX_NAMES[c][0] for c in missing)}) nor a constant")
    _check_finite(frame, lambda row: f"{path}:{row_lines[row]}")
    tyre = str(header.get("MEASID", ("", "", ""))[0] or path.stem)
    consts = {k: v[0] for k, v in {**header, **constants}.items()}
    return TyreData(frame, tyre=tyre, source=str(path), units=units, constants=consts)


def _constant_value(name, unit, text, path, lineno):
    """A header/constant value: SI float for known physical constants, float for numbers, else text."""
    try:
        value = float(text.replace("D", "E"))
    except ValueError:
        if name in _CONSTANT_KINDS:
            raise DataError(f"{path}:{lineno}: column 51: constant {name}: non-numeric value {text!r}") from None
        return text
    if name in _CONSTANT_KINDS:
        ch = _CONSTANT_KINDS[name]
        try:
            value *= unit_to_si(ch, unit or _SI_NAME[CHANNELS[ch][0]])
        except ValueError as exc:
            raise DataError(f"{path}:{lineno}: columns 41-50: constant {name}: {exc}") from None
    return value


def write_tydex(data: TyreData, path, *, overwrite: bool = False) -> Path:
    """Write ``data`` as a TYDEX file in SI units (factor 1, offsets 0); every canonical channel present."""
    path = Path(path)
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True to replace it")
    chans = [c for c in CHANNELS if c in data.frame.columns]
    extra = [c for c in data.frame.columns if c not in CHANNELS and len(str(c)) <= 10
             and pd.api.types.is_numeric_dtype(data.frame[c])]

    def fixed(name, desc, unit, value):
        return f"{name:<10.10}{desc:<30.30}{unit:<10.10}{value}"

    out = ["**HEADER",
           fixed("RELEASE", "Release of TYDEX-format", "", "1.3"),
           fixed("MEASID", "Measurement id.", "", data.tyre or path.stem),
           fixed("SUPPLIER", "Data supplier", "", "mftyre"),
           fixed("DATE", "Date", "", _dt.date.today().strftime("%d-%m-%Y")),
           "**COMMENTS", f"Written by mftyre from {data.source or '<memory>'}; SI units, ISO-W axes.",
           "**CONSTANTS"]
    for name, value in data.constants.items():
        if name in ("RELEASE", "MEASID", "SUPPLIER", "DATE"):
            continue
        if isinstance(value, float):
            unit = _SI_NAME[CHANNELS[_CONSTANT_KINDS[name]][0]] if name in _CONSTANT_KINDS else ""
            out.append(fixed(name, "", unit, repr(value)))
        elif str(value).strip():
            out.append(fixed(name, "", "", str(value)))
    out.append("**MEASURCHANNELS")
    for ch in chans:
        out.append(fixed(_TYDEX_NAMES[ch][0], CHANNELS[ch][1], _SI_NAME[CHANNELS[ch][0]], "1 0 0"))
    for name in extra:
        out.append(fixed(str(name).upper(), "(not a TYDEX channel)", "-", "1 0 0"))
    out.append("**MEASURDATA")
    values = data.frame[chans + extra].to_numpy(float)
    out.extend(" ".join(f"{v:.17g}" for v in row) for row in values)
    out.append("**END")
    path.write_text("\n".join(out) + "\n", encoding="utf-8")
    return path


# ---------------------------------------------------------------------------------------- preparation
_DEFAULT_TOL = {"FZ": 0.05, "P": 0.02, "IA": math.radians(0.25), "VX": 0.5, "SA": math.radians(0.25),
                "SL": 0.005}


def levels(values, tol: float | None = None):
    """Cluster ``values`` into levels: (labels per value, level centres). Values closer than ``tol`` to their
    neighbour (sorted) share a level; default tol: 5 % of the largest magnitude (at least 1e-9)."""
    values = np.asarray(values, dtype=float)
    if values.size == 0:
        return np.zeros(0, int), np.zeros(0)
    if tol is None:
        tol = max(0.05 * float(np.max(np.abs(values))), 1e-9)
    order = np.argsort(values, kind="stable")
    sorted_v = values[order]
    breaks = np.concatenate([[0], np.cumsum(np.diff(sorted_v) > tol)])
    labels = np.empty(values.size, int)
    labels[order] = breaks
    centres = np.array([sorted_v[breaks == k].mean() for k in range(breaks[-1] + 1)])
    return labels, centres


def _tolerance(data: TyreData, ch: str, tol: dict | None):
    if tol and ch in tol:
        return tol[ch]
    scale = {"FZ": float(np.max(np.abs(data.array("FZ")))) if len(data) else 1.0,
             "P": float(np.max(np.abs(data.array("P")))) if len(data) else 1.0}
    return _DEFAULT_TOL[ch] * scale.get(ch, 1.0)


def split_conditions(data: TyreData, by=("FZ", "P", "IA", "VX"), tol: dict | None = None):
    """Split into operating conditions: a list of (dict channel -> level centre, TyreData) per combination
    of levels of the channels ``by`` present (tolerances per channel, defaults in :data:`_DEFAULT_TOL`)."""
    by = [c for c in by if c in data]
    labels, centres = [], []
    for ch in by:
        lab, cen = levels(data.array(ch), _tolerance(data, ch, tol))
        labels.append(lab)
        centres.append(cen)
    if not by:
        return [({}, data)]
    keys = np.stack(labels, axis=1)
    out = []
    for key in np.unique(keys, axis=0):
        mask = np.all(keys == key, axis=1)
        cond = {ch: float(centres[i][key[i]]) for i, ch in enumerate(by)}
        out.append((cond, data.select(mask)))
    return out


def split_sweeps(data: TyreData, by=("FZ", "P", "IA", "VX", "SA", "SL"), tol: dict | None = None) -> TyreData:
    """Number the sweeps: a new sweep starts where any of the condition channels ``by`` changes level
    between consecutive rows (the swept channel varies smoothly within a sweep and is ignored: a channel
    is treated as a condition only where it is constant over the neighbouring rows). Adds ``SWEEP``."""
    by = [c for c in by if c in data]
    n = len(data)
    new = np.zeros(n, bool)
    if n:
        new[0] = True
    for ch in by:
        x = data.array(ch)
        t = _tolerance(data, ch, tol)
        jump = np.abs(np.diff(x)) > t
        # a swept channel moves by similar steps every row; a condition change is a jump after a flat run
        flat_before = np.concatenate([[True], np.abs(np.diff(x)) <= t])[:-1]
        new[1:] |= jump & flat_before
    frame = data.frame.copy()
    frame["SWEEP"] = np.cumsum(new) - 1
    return data.with_frame(frame, f"split into {int(frame['SWEEP'].max()) + 1 if n else 0} sweeps")


def bin_sweeps(data: TyreData, channel: str, width: float) -> TyreData:
    """Average the data of each sweep (``SWEEP``, see :func:`split_sweeps`) in bins of ``channel`` of the
    given width; every numeric column is averaged, ``SWEEP`` kept."""
    if "SWEEP" not in data:
        data = split_sweeps(data)
    frame = data.frame.copy()
    frame["_BIN"] = np.round(frame[channel].to_numpy(float) / width).astype(np.int64)
    numeric = [c for c in frame.columns if c not in ("_BIN", "SWEEP") and pd.api.types.is_numeric_dtype(frame[c])]
    binned = frame.groupby(["SWEEP", "_BIN"], sort=False)[numeric].mean().reset_index()
    binned = binned.drop(columns="_BIN")
    return data.with_frame(binned, f"binned {channel} per sweep, width {width:g}: {len(data)} -> {len(binned)} rows")


def resample_sweeps(data: TyreData, channel: str, values) -> TyreData:
    """Linear interpolation of every numeric column of each sweep at the given values of ``channel``
    (within the sweep's range; a sweep measured up and down is averaged first by :func:`bin_sweeps`)."""
    if "SWEEP" not in data:
        data = split_sweeps(data)
    values = np.asarray(values, dtype=float)
    parts = []
    for sweep, grp in data.frame.groupby("SWEEP", sort=False):
        grp = grp.sort_values(channel)
        x = grp[channel].to_numpy(float)
        keep = values[(values >= x.min()) & (values <= x.max())]
        if keep.size == 0:
            continue
        cols = {c: np.interp(keep, x, grp[c].to_numpy(float)) for c in grp.columns
                if pd.api.types.is_numeric_dtype(grp[c]) and c != "SWEEP"}
        cols[channel] = keep
        cols["SWEEP"] = np.full(keep.size, sweep)
        parts.append(pd.DataFrame(cols))
    frame = pd.concat(parts, ignore_index=True) if parts else data.frame.iloc[:0]
    return data.with_frame(frame, f"resampled {channel} at {values.size} values per sweep")


def reject_outliers(data: TyreData, channels=("FX", "FY", "MZ", "MX", "MY"), threshold: float = 6.0):
    """Reject points that depart from their sweep's local trend by more than ``threshold`` robust standard
    deviations.

    The trend at a point is the cubic through its two neighbours on each side within the sweep (``SWEEP``,
    see :func:`split_sweeps`): 2/3 (y[i-1] + y[i+1]) - 1/6 (y[i-2] + y[i+2]), exact for cubics. The scale is
    1.4826 x the median absolute departure of the channel over all sweeps plus 0.2 x the larger second
    difference two rows before or after (which do not involve the point), so sharp but smooth knees are not mistaken
    for outliers as long as the sweep resolves them (about 1 degree or 0.01 slip per sample; for coarser sweeps
    raise ``threshold``). The first and last two points of a sweep are not tested.

    Returns ``(clean, rejected)``: the kept data (with a ``history`` entry) and a DataFrame of the rejected
    rows with the channel and the score that condemned them. Nothing is dropped silently.
    """
    if "SWEEP" not in data:
        data = split_sweeps(data)
    frame = data.frame
    groups = frame.groupby("SWEEP", sort=False)
    bad = np.zeros(len(frame), bool)
    reason_ch = np.full(len(frame), "", object)
    reason_score = np.zeros(len(frame))
    for ch in channels:
        if not data.has(ch):
            continue
        col = groups[ch]
        trend = (2.0 / 3.0) * (col.shift(1) + col.shift(-1)) - (1.0 / 6.0) * (col.shift(2) + col.shift(-2))
        dev = (frame[ch] - trend).to_numpy(float)
        finite = np.isfinite(dev)
        if not finite.any():
            continue
        scale = 1.4826 * float(np.median(np.abs(dev[finite])))
        if scale == 0.0:
            continue
        # curvature allowance: the second differences two rows away (they do not involve the point itself)
        second = col.shift(1) - 2.0 * frame[ch] + col.shift(-1)
        g2 = second.groupby(frame["SWEEP"])
        allowance = np.fmax(np.abs(g2.shift(2).to_numpy(float)), np.abs(g2.shift(-2).to_numpy(float)))
        score = np.where(finite, np.abs(dev) / (scale + 0.2 * np.nan_to_num(allowance)), 0.0)
        # a single outlier also spoils the trend of its neighbours (by 2/3 of its size): condemn only the
        # point with the largest score among those it affects
        hit = score > threshold
        sc = pd.Series(score, index=frame.index)
        neighbourhood_max = sc.groupby(frame["SWEEP"]).transform(
            lambda s: s.rolling(5, center=True, min_periods=1).max()).to_numpy()
        peak = score >= neighbourhood_max
        hit &= peak
        new = hit & ~bad
        reason_ch[new], reason_score[new] = ch, score[new]
        bad |= hit
    rejected = frame.loc[bad].copy()
    rejected["REJECTED_CHANNEL"] = reason_ch[bad]
    rejected["ROBUST_SCORE"] = reason_score[bad]
    clean = data.select(~bad, f"outlier rejection ({threshold:g} robust sigma from the local cubic trend): "
                              f"{int(bad.sum())} of {len(frame)} rows rejected")
    return clean, rejected


# ---------------------------------------------------------------------------------- trailer programme
#: Standard deviations of the "realistic" measurement noise (noise=1), per channel: forces as a fraction of
#: FNOMIN, moments as a fraction of FNOMIN x UNLOADED_RADIUS, radii in metres.
NOISE = {"FX": 0.005, "FY": 0.005, "FZ": 0.0025, "MX": 4e-4, "MY": 2e-4, "MZ": 4e-4, "RL": 1e-4, "RHO": 1e-4,
         "RE": 1e-4}


def trailer_programme(model, *, loads=(0.5, 1.0, 1.5), pressures=(0.85, 1.0, 1.15), cambers_deg=(-3.0, 0.0, 3.0),
                      speed: float | None = None, alpha_max_deg: float = 12.0, kappa_max: float = 0.25,
                      combined_alpha_deg=(3.0, 6.0), points: int = 41, free_rolling_speeds=(5.0, 10.0, 20.0, 30.0),
                      vertical_points: int = 15, noise: float = 0.0, offsets: dict | None = None,
                      hysteresis: float = 0.0, seed=None) -> TyreData:
    """Synthetic test-trailer measurements of the tyre ``model`` (an :class:`mftyre.MFModel`).

    The programme, at every load (fractions of FNOMIN) and pressure (fractions of NOMPRES):

    * ``pure_lateral``: slip-angle sweeps -alpha_max -> +alpha_max -> -alpha_max at kappa = 0, every camber;
    * ``pure_longitudinal``: slip sweeps -kappa_max -> +kappa_max -> -kappa_max at alpha = 0, camber 0;
    * ``combined``: the slip sweep at each slip angle of ``combined_alpha_deg``, camber 0;
    * ``free_rolling``: kappa = alpha = 0 over ``free_rolling_speeds`` (m/s), every camber;
    * ``vertical``: load-deflection, 0.1 ... 2 FNOMIN, rolling slowly (1 m/s) free, RL/RHO recorded.

    Each sweep has ``points`` samples (going out and back). Recorded: every channel of :data:`CHANNELS`
    (the spin OMEGA as the model computes it) plus ``TEST`` and ``SWEEP``. ``noise``: multiple of the
    realistic standard deviations :data:`NOISE` (Gaussian, ``seed`` for repeatability); ``offsets``: channel
    -> constant added to the recorded values (e.g. ``{"SA": 0.002, "FY": 30.0}``: a misaligned rig and a
    drifting load cell); ``hysteresis``: lag of the swept slip behind its recorded value, as a fraction of the
    sweep amplitude, opposite on the way out and back.
    """
    prm = model.params
    fz0, p0, r0 = prm.FNOMIN, prm.NOMPRES, prm.UNLOADED_RADIUS
    vx0 = prm.LONGVL if speed is None else float(speed)
    half = max(points // 2, 2)
    outward = np.linspace(-1, 1, half + 1)
    out_and_back = np.concatenate([outward, outward[::-1][1:]])
    direction = np.concatenate([np.ones(half + 1), -np.ones(half)])
    rows = []

    def add(test, fz, kappa, alpha, gamma, vx, p, lag_kappa=0.0, lag_alpha=0.0):
        n = max(np.size(kappa), np.size(alpha), np.size(fz), np.size(vx), np.size(gamma))
        rows.append(dict(TEST=np.full(n, test), FZ=np.broadcast_to(fz, (n,)), SL=np.broadcast_to(kappa, (n,)),
                         SA=np.broadcast_to(alpha, (n,)), IA=np.broadcast_to(gamma, (n,)),
                         VX=np.broadcast_to(vx, (n,)), P=np.broadcast_to(p, (n,)),
                         LAG_SL=np.broadcast_to(lag_kappa, (n,)), LAG_SA=np.broadcast_to(lag_alpha, (n,))))

    a_max, g_list = math.radians(alpha_max_deg), [math.radians(g) for g in cambers_deg]
    for pf in pressures:
        for lf in loads:
            fz, p = lf * fz0, pf * p0
            for g in g_list:
                add("pure_lateral", fz, 0.0, a_max * out_and_back, g, vx0, p, lag_alpha=hysteresis * a_max * direction)
            add("pure_longitudinal", fz, kappa_max * out_and_back, 0.0, 0.0, vx0, p,
                lag_kappa=hysteresis * kappa_max * direction)
            for a in combined_alpha_deg:
                add("combined", fz, kappa_max * out_and_back, math.radians(a), 0.0, vx0, p,
                    lag_kappa=hysteresis * kappa_max * direction)
            for g in g_list:
                add("free_rolling", fz, 0.0, 0.0, g, np.asarray(free_rolling_speeds, float), p)
        fz_v = np.linspace(0.1, 2.0, vertical_points) * fz0
        add("vertical", fz_v, 0.0, 0.0, 0.0, 1.0, pf * p0)
    frame = pd.DataFrame({k: np.concatenate([r[k] for r in rows]) for k in rows[0]})
    sweep = np.concatenate([np.full(len(r["FZ"]), i) for i, r in enumerate(rows)])
    # the tyre responds to the lagging slip; the rig records the nominal one
    true_kappa = frame["SL"].to_numpy() - frame.pop("LAG_SL").to_numpy()
    true_alpha = frame["SA"].to_numpy() - frame.pop("LAG_SA").to_numpy()
    res = model.evaluate(frame["FZ"].to_numpy(), true_kappa, true_alpha, frame["IA"].to_numpy(), 0.0,
                         frame["VX"].to_numpy(), frame["P"].to_numpy())
    frame["PHIT"] = 0.0
    for ch, name in (("FX", "fx"), ("FY", "fy"), ("MX", "mx"), ("MY", "my"), ("MZ", "mz"), ("OMEGA", "omega"),
                     ("RL", "rl"), ("RHO", "rho"), ("RE", "re")):
        frame[ch] = np.asarray(res[name], float)
    frame["SWEEP"] = sweep
    rng = np.random.default_rng(seed)
    if noise:
        scale = {"FX": fz0, "FY": fz0, "FZ": fz0, "MX": fz0 * r0, "MY": fz0 * r0, "MZ": fz0 * r0, "RL": 1.0,
                 "RHO": 1.0, "RE": 1.0}
        for ch, sd in NOISE.items():
            frame[ch] = frame[ch] + rng.normal(0.0, noise * sd * scale[ch], len(frame))
    for ch, value in (offsets or {}).items():
        if ch.upper() not in CHANNELS:
            raise DataError(f"offset for unknown channel {ch!r}; channels: {', '.join(CHANNELS)}")
        frame[ch.upper()] = frame[ch.upper()] + float(value)
    order = ["TEST", "SWEEP", *[c for c in CHANNELS if c in frame.columns]]
    note = (f"trailer_programme: {len(frame)} points, loads {list(loads)} x FNOMIN, pressures {list(pressures)} x "
            f"NOMPRES, cambers {list(cambers_deg)} deg, noise {noise:g}, offsets {offsets or {}}, "
            f"hysteresis {hysteresis:g}, seed {seed}")
    consts = {"FNOMIN": float(fz0), "NOMPRES": float(p0), "RFREE": float(r0), "NOMWIDTH": float(prm.WIDTH),
              "LONGVEL": float(vx0)}
    return TyreData(frame[order], tyre=Path(str(prm.source or "model")).stem, source="trailer_programme",
                    units={c: _SI_NAME[CHANNELS[c][0]] for c in CHANNELS}, constants=consts, history=[note])
