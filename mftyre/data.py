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

Reading any file (:func:`read_data`): the format is recognised by content (TYDEX, TTC .dat/.mat, CSV); the file's
axis system (``axes=``, :data:`AXES`: ISO-W, SAE, adapted-SAE, adapted-ISO) is turned into ISO-W, constant channels
(``defaults=``) fill channels the file lacks, and :func:`check_plausible` refuses values no tyre measurement has in
SI units and ISO-W axes, naming the channel, the file's column, the likely unit or axis system and the option that
converts it (``check=False`` skips it). The command line passes ``--columns``, ``--units``, ``--axes``, ``--set``
and ``--no-check`` (:func:`mftyre.cli.add_data_options`), each channel once; messages then name those options
(:func:`speaking_cli`).

TTC (:func:`read_ttc`): the Calspan tyre test consortium runs: a ``.dat`` text file (a free header line, a row of
channel names, a row of units, whitespace-separated samples) or a MATLAB ``.mat`` file with the same channels as
vectors; channels and units as :data:`TTC_CHANNELS` says, SAE axes, ``ET`` kept as ``TIME``.

CSV (:func:`read_csv`)
    Comma separated, UTF-8 (a byte-order mark allowed), one header row, then one row per sample; an empty
    field or ``nan`` is "not measured". Column names are matched to channels case-insensitively; other columns
    (e.g. ``SWEEP``, ``TEST``) are kept as they are. Columns with canonical names are read as SI. Otherwise pass
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
required channel, an infinite value (``inf``, ``1e400``) in any channel, two columns for one channel, no data
rows. Only regular files are read (a FIFO or a device is refused), up to :data:`mftyre.files.DATA_MAX_BYTES`
(``max_bytes=`` of the readers; for a .mat file also the size its variables expand to) and
:data:`mftyre.files.DATA_MAX_COLUMNS` columns (docs/resource-limits.md). Both readers parse the samples with pandas' C parser (about the time of a plain
``pandas.read_csv`` of the file; ``benchmarks/bench_data.py``).
"""
from __future__ import annotations

import csv
import datetime as _dt
import hashlib
import io
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import DataError, speaking, speaking_cli, spelled
from .files import DATA_MAX_BYTES, DATA_MAX_COLUMNS, check_outputs, open_user_file, read_user_file, write_atomically
from .tir import UNIT_FACTORS
from .lazy import LazyModule

pd = LazyModule("pandas")  # imported when first used: the command line starts without it

__all__ = [
    "CHANNELS", "TIME_CHANNELS", "read_time_histories", "REQUIRED", "INPUTS", "OUTPUTS", "UNITS", "TyreData", "read_csv", "read_tydex", "write_tydex",
    "read_ttc", "read_data", "data_format", "check_plausible", "AXES", "AXES_HELP", "to_iso_w", "speaking_cli",
    "parse_columns", "parse_units", "parse_constants", "constant_value", "TTC_CHANNELS",
    "unit_to_si", "levels", "split_conditions", "split_sweeps", "bin_sweeps", "resample_sweeps",
    "reject_outliers", "trailer_programme", "NOISE", "noise_scales", "record_outputs", "synthetic_data",
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
#: The further channels of time histories (dynamic tyre tests, :func:`read_time_histories`; their layout:
#: :mod:`mftyre.gaps.dynamic_runs`): channel -> (physical kind, meaning).
TIME_CHANNELS: dict[str, tuple[str, str]] = {
    "TIME": ("time", "sample time"),
    "X": ("length", "axle travel along the road"),
    "Z": ("length", "axle height above the road's zero"),
    "LOAD": ("force", "downward force on the axle"),
    "TORQUE": ("moment", "drive/brake torque on the rim"),
    "PSI": ("angle", "yaw of the wheel"),
    "SPIN": ("angular_speed", "measured rim spin"),
}
#: Input channels of the model, in the order of :meth:`mftyre.MFModel.evaluate`.
INPUTS = ("FZ", "SL", "SA", "IA", "PHIT", "VX", "P")
REQUIRED = ("FZ", "SA", "SL", "VX", "P")
OUTPUTS = ("FX", "FY", "MX", "MY", "MZ", "OMEGA", "RL", "RHO", "RE")
_ZERO_DEFAULT = ("IA", "PHIT")
_SI_NAME = {"force": "N", "moment": "N*m", "ratio": "-", "angle": "rad", "curvature": "1/m", "speed": "m/s",
            "pressure": "Pa", "angular_speed": "rad/s", "length": "m", "time": "s"}


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
    force.update({"lb": force["lbf"], "lbs": force["lbf"]})  # rig files write pounds of force as lb
    for f, ff in force.items():
        for ln, fl in length.items():
            for sep in ("*", ".", "", "-"):
                moment.setdefault(f"{ln}{sep}{f}", ff * fl)  # ft-lb, in-lb
                moment.setdefault(f"{f}{sep}{ln}", ff * fl)
    ratio = {"-": 1.0, "": 1.0, "1": 1.0, "%": 0.01, "percent": 0.01, "none": 1.0, "unitless": 1.0}
    return {"force": force, "moment": moment, "ratio": ratio, "angle": angle, "curvature": curvature,
            "speed": speed, "pressure": pressure, "angular_speed": angular, "length": length, "time": time}


#: Accepted unit spellings per kind (case-insensitive, blanks ignored) -> factor to SI.
UNITS: dict[str, dict[str, float]] = _unit_table()


def unit_to_si(channel: str, unit: str) -> float:
    """Factor that converts values of ``channel`` in ``unit`` to SI; ValueError naming the accepted units."""
    kind = (CHANNELS.get(channel) or TIME_CHANNELS[channel])[0]
    key = str(unit).strip().lower().replace(" ", "")
    table = UNITS[kind]
    if key not in table:
        examples = ", ".join(list(dict.fromkeys(table))[:10])
        raise ValueError(f"unknown unit {unit!r} for {channel} ({kind}); e.g. {examples}")
    return table[key]


# ------------------------------------------------------------------------------------- axis systems
#: Sign of each channel in an axis system relative to ISO-W (TYDEX W): value_ISO-W = sign * value_in_system;
#: channels not listed keep their sign. See :data:`AXES_HELP`.
AXES: dict[str, dict[str, float]] = {
    "ISO-W": {},
    "SAE": {"FY": -1.0, "FZ": -1.0, "MY": -1.0, "MZ": -1.0, "SA": -1.0, "PHIT": -1.0, "PSI": -1.0},
    "adapted-SAE": {"FY": -1.0, "MY": -1.0, "MZ": -1.0, "PHIT": -1.0},
    "adapted-ISO": {"SA": -1.0},
}
AXES_HELP = """\
Axis systems (the sign of each channel as the file writes it; mftyre works in ISO-W):
  ISO-W        TYDEX W / ISO 8855 at the contact point: x forward, y left, z up; FZ > 0 is load; a positive
               slip angle SA gives FY < 0 and MZ > 0 (the .tir convention).
  SAE          SAE J670: x forward, y right, z down (ISO-W turned half a turn about x): FY, FZ, MY, MZ, SA and
               turn slip change sign; FX, MX, SL, IA do not. Load is FZ < 0 (Calspan/TTC rig files).
  adapted-SAE  SAE with the load positive and the slip angle reversed (Pacejka, Tyre and Vehicle Dynamics):
               FZ > 0, SA > 0 gives FY > 0; against ISO-W FY, MY, MZ and turn slip change sign.
  adapted-ISO  ISO-W with the slip angle reversed (Pacejka): SA > 0 gives FY > 0; only SA changes sign.
Wheel spin OMEGA, radii and pressure are taken as magnitudes (forward rolling positive) in every system; so are
the time histories' axle height Z, axle load LOAD and rim torque TORQUE; their yaw PSI turns sign with z (SAE)."""


def to_iso_w(frame: pd.DataFrame, axes: str) -> pd.DataFrame:
    """``frame`` (canonical channels) with the signs of axis system ``axes`` (a key of :data:`AXES`) turned
    into ISO-W, in place; returns it. ValueError naming the systems for an unknown name."""
    signs = AXES.get(_axes_name(axes))
    for ch, sign in signs.items():
        if ch in frame.columns:
            frame[ch] = sign * frame[ch]
    return frame


def _axes_name(axes: str) -> str:
    for name in AXES:
        if str(axes).strip().lower().replace("_", "-") == name.lower():
            return name
    raise ValueError(f"unknown axis system {axes!r}; expected one of {', '.join(AXES)}")


# ----------------------------------------------------------------------- options, in two languages
def remedy(option: str, channel: str, value: str) -> str:
    """How to pass ``channel=value`` for ``option`` (``columns``, ``units``, ``axes``, ``constants``) in the
    language of the caller (see :func:`speaking_cli`)."""
    if speaking() == "cli":
        flag = {"columns": "--columns", "units": "--units", "axes": "--axes", "constants": "--set"}[option]
        return f"{flag} {value}" if option == "axes" else f"{flag} {channel}={value}"
    if option == "axes":
        return f"axes={value!r}"
    if option == "columns":
        return f"columns={{{value!r}: {channel!r}}}"
    return f"{'defaults' if option == 'constants' else option}={{{channel!r}: {value!r}}}"


def _assignments(text: str, what: str) -> list[tuple[str, str]]:
    """The ``CHANNEL=VALUE`` items of an option, each channel once (ValueError naming a channel given twice: which
    one is meant cannot be guessed)."""
    pairs, seen = [], {}
    for item in str(text).split(","):
        if not item.strip():
            continue
        if "=" not in item:
            raise ValueError(f"{what}: {item.strip()!r} is not CHANNEL=VALUE (e.g. {_EXAMPLE_OPTION[what]})")
        key, value = (part.strip() for part in item.split("=", 1))
        if not key or not value:
            raise ValueError(f"{what}: {item.strip()!r} has an empty side (e.g. {_EXAMPLE_OPTION[what]})")
        if key.upper() in seen:
            raise ValueError(f"{what}: {key} is given twice ({seen[key.upper()]!r} and {item.strip()!r}): give each "
                             "channel once")
        seen[key.upper()] = item.strip()
        pairs.append((key, value))
    if not pairs:
        raise ValueError(f"{what}: empty; expected CHANNEL=VALUE,... (e.g. {_EXAMPLE_OPTION[what]})")
    return pairs


_EXAMPLE_OPTION = {"columns": "FZ=Fz_N,SA=alpha", "units": "SA=deg,P=psi,VX=km/h", "constants": "P=1.6bar,IA=0"}


def _channel(name: str, what: str) -> str:
    ch = name.strip().upper()
    if ch not in CHANNELS and ch not in TIME_CHANNELS:
        raise ValueError(f"{what}: unknown channel {name!r}; channels: {', '.join(CHANNELS)} (time histories also "
                         f"{', '.join(TIME_CHANNELS)})")
    return ch


def parse_columns(text: str) -> dict:
    """``"FZ=Fz_N,SA=alpha"`` (channel = file column) -> ``{"Fz_N": "FZ", "alpha": "SA"}`` (the ``columns=``
    of the readers); ValueError naming what was expected."""
    out = {}
    for ch, col in _assignments(text, "columns"):
        if col in out:
            raise ValueError(f"columns: file column {col!r} is given for {out[col]} and for {ch.strip().upper()}: "
                             "a column holds one channel")
        out[col] = _channel(ch, "columns")
    return out


def parse_units(text: str) -> dict:
    """``"SA=deg,P=psi"`` -> ``{"SA": "deg", "P": "psi"}``, each unit checked (:func:`unit_to_si`)."""
    out = {}
    for ch, unit in _assignments(text, "units"):
        ch = _channel(ch, "units")
        unit_to_si(ch, unit)
        out[ch] = unit
    return out


_QUANTITY = re.compile(r"\s*([+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?)\s*(.*?)\s*$")


def constant_value(channel: str, value) -> float:
    """A constant channel value in SI: a number (SI) or text with a unit, e.g. ``"1.6bar"``, ``"0"``,
    ``"60km/h"``, ``"-2deg"``; ValueError naming what was expected."""
    if not isinstance(value, str):
        number = float(value)
    else:
        m = _QUANTITY.fullmatch(value)
        if not m:
            raise ValueError(f"{channel}: cannot read {value!r} as a number with an optional unit "
                             f"(e.g. 1.6bar, 0, 60km/h)")
        number = float(m.group(1)) * (unit_to_si(channel, m.group(2)) if m.group(2) else 1.0)
    if not math.isfinite(number):
        raise ValueError(f"{channel}: {value!r} is not finite")
    return number


def parse_constants(text: str) -> dict:
    """``"P=1.6bar,IA=0"`` -> ``{"P": 160000.0, "IA": 0.0}`` (SI; the ``defaults=`` of the readers); a .tir
    parameter of a quantity with units (``RIM_RADIUS=5in``, :func:`parameter_value`) is kept under its name."""
    out = {}
    for name, value in _assignments(text, "constants"):
        key = name.strip().upper()
        if key not in CHANNELS and _parameter_kind(key):
            out[key] = parameter_value(key, value)
        else:
            ch = _channel(name, "set")
            out[ch] = constant_value(ch, value)
    return out


def parse_channels(text: str) -> tuple:
    """``"RE,OMEGA"`` -> ``("RE", "OMEGA")``, each a known channel."""
    names = tuple(_channel(c, "drop") for c in str(text).split(",") if c.strip())
    if not names:
        raise ValueError("drop: empty; expected CHANNEL,... (e.g. RE)")
    return names


def _parameter_kind(name: str) -> str | None:
    from .params import PARAMETERS

    spec = PARAMETERS.get(name)
    if spec is None or spec.is_string:
        return None
    return spec.unit if spec.unit in UNITS else "ratio"


def parameter_value(name: str, value) -> float:
    """The SI value of .tir parameter ``name`` from a number (SI) or text with a unit of its kind (``5in``,
    ``0.8bar``); ValueError naming what was expected."""
    kind = _parameter_kind(name)
    if kind is None:
        raise ValueError(f"set: unknown parameter or channel {name!r}")
    m = _QUANTITY.fullmatch(str(value))
    if not m:
        raise ValueError(f"set: {name}: cannot read {value!r} as a number with an optional unit (e.g. 5in, 0.127)")
    unit = m.group(2).strip().lower().replace(" ", "")
    if unit and unit not in UNITS[kind]:
        raise ValueError(f"set: {name}: unknown unit {m.group(2)!r} for a {kind}; e.g. "
                         + ", ".join(list(dict.fromkeys(UNITS[kind]))[:8]))
    number = float(m.group(1)) * (UNITS[kind][unit] if unit else 1.0)
    if not math.isfinite(number):
        raise ValueError(f"set: {name}: {value!r} is not finite")
    return number


# -------------------------------------------------------------------------------------- plausibility
#: Plausible range per channel in SI of a tyre measurement (typical = 99th percentile of |values|, median
#: for pressure) and the units that, mistaken for SI, put values outside it.
_PLAUSIBLE = {
    "SA": (0.0, 1.0, ("deg",)),
    "IA": (0.0, 1.0, ("deg",)),
    "SL": (0.0, 2.0, ("%",)),
    "VX": (0.0, 100.0, ("km/h", "mph")),
    "P": (2e4, 2e7, ("kPa", "bar", "psi", "MPa")),
    "RL": (0.0, 2.0, ("mm", "cm", "in")),
    "RE": (0.0, 2.0, ("mm", "cm", "in")),
    "RHO": (0.0, 0.5, ("mm", "cm", "in")),
    "FZ": (30.0, 1e6, ("kN",)),
}
#: SI ranges the same quantity has on real tyres (used to say which unit was likely meant).
_TYPICAL = {"SA": (0.02, 0.6), "IA": (0.005, 0.3), "SL": (0.01, 1.0), "VX": (0.5, 90.0), "P": (4e4, 1.5e6),
            "RL": (0.1, 1.5), "RE": (0.1, 1.5), "RHO": (0.002, 0.2), "FZ": (30.0, 2e5)}


#: Largest magnitude of a single value (SI) of any tyre measurement, a few times the ranges above: a row beyond it
#: is damaged (e.g. VX = -1e300), whatever the rest of the file says.
_ROW_LIMIT = {"SA": 3.2, "IA": 3.2, "SL": 50.0, "VX": 300.0, "P": 6e7, "RL": 6.0, "RE": 6.0, "RHO": 1.5, "FZ": 3e6,
              "FX": 3e6, "FY": 3e6, "MX": 3e5, "MY": 3e5, "MZ": 3e5, "OMEGA": 3e3, "PHIT": 1e3}
#: Slope of the force over the slip at small slip, per unit load, that every tyre exceeds: cornering stiffness /
#: FZ and longitudinal slip stiffness / FZ are 5 ... 50 per radian (per unit slip); 1.5 leaves room for the
#: saturation within the fitted range and for high loads.
_MIN_STIFFNESS_PER_LOAD = 1.5
#: Speed and spin units that may be mistaken for SI, and the SI factor of each (VX / (OMEGA x radius) is about 1).
_SPEED_UNITS = {"m/s": 1.0, "km/h": 1 / 3.6, "mph": 0.44704}
_SPIN_UNITS = {"rad/s": 1.0, "rpm": 2 * math.pi / 60, "deg/s": math.pi / 180}
#: Most friction |(FX, FY)| / FZ a tyre gives (racing tyres about 2, at light loads up to 3-4).
_MAX_FRICTION = 5.0
#: Longest lever |M| / FZ [m] of any tyre moment (aligning ~ 0.05 m, overturning ~ 0.1 m, rolling ~ 0.01 m).
_MAX_LEVER = 1.0


#: Measured channels no fit stage needs as an input (each is the output of one stage): a channel among them that
#: fails the plausibility check can be left out (:func:`read_data` ``drop=``, or ``drop_implausible``).
OPTIONAL_CHANNELS = ("RL", "RE", "RHO", "OMEGA", "MY", "MX")


def garbage(frame, ch: str) -> str:
    """Why channel ``ch`` of ``frame`` (SI) measures nothing, or "" when it may: a spin that stays near 0 while the
    wheel rolls (VX above 1 m/s), or a radius whose values scatter over more than a decade (10th to 90th percentile),
    which no unit mistaken for another explains (a unit is one factor: the values keep their spread)."""
    x = frame[ch].to_numpy(dtype=float)
    ok = np.isfinite(x)
    if ch == "OMEGA" and "VX" in frame.columns:
        rolling = ok & (np.abs(frame["VX"].to_numpy(dtype=float)) > 1.0)
        if rolling.sum() >= 10 and float(np.median(np.abs(x[rolling]))) < 0.5:
            return (f"median spin {float(np.median(np.abs(x[rolling]))):.3g} rad/s while the wheel rolls at a median "
                    f"{float(np.median(np.abs(frame['VX'].to_numpy(float)[rolling]))):.3g} m/s: a dead spin sensor "
                    "(garbage, not a unit)")
        return ""
    a = np.abs(x[ok])
    if a.size < 10:
        return ""
    p10, p90 = (float(v) for v in np.quantile(a, [0.1, 0.9]))
    if p10 <= 0 or p90 / p10 > 10.0:
        return (f"the values scatter over {math.log10(p90 / p10) if p10 > 0 else float('inf'):.2g} decades (10th "
                f"to 90th percentile {p10:.3g} .. {p90:.3g} m): garbage, not a unit mistaken (a unit is one factor "
                "and keeps the spread of a radius, a few percent)")
    return ""


def _channel_error(text: str, channels: dict) -> DataError:
    """A DataError whose ``channels`` (channel -> the likely unit or axis system, None for garbage) say which
    channels failed."""
    exc = DataError(text)
    exc.channels = dict(channels)
    return exc


def check_plausible(data: "TyreData | pd.DataFrame", where: str = "", column_of: dict | None = None,
                    stated: str = "", constants: dict | None = None) -> None:
    """The one plausibility judge: DataError at values no tyre measurement in SI units and ISO-W axes has, judged
    on the whole file's physics, each message naming the channel (and the file's column), what was seen, the
    likely unit or axis system and the option that converts it. In order:

    1. ranges: |SA|, |IA| beyond 1 rad (degrees?), |SL| beyond 2 (percent?), VX above 100 m/s (km/h?), P below
       20 kPa (kPa, bar, psi?), RL or RE above 2 m, RHO above 0.5 m (mm, cm?), FZ all below 30 N (kN?); and
       VX / (OMEGA x radius), about 1 for a rolling wheel, matched against every pair of speed and spin units
       (km/h, mph; rpm, deg/s), so two wrong channels are found together;
    2. single rows beyond any tyre (:data:`_ROW_LIMIT`, e.g. VX = -1e300), named by their row;
    3. the slip stiffnesses per unit load (slope of FY / FZ over SA and of FX / FZ over SL at small slip) below
       :data:`_MIN_STIFFNESS_PER_LOAD` but plausible in degrees (SA) or percent (SL); a camber written in whole
       numbers with some at +-1 (degrees); a moment longer than :data:`_MAX_LEVER` x FZ (N mm?);
    4. the load: zero or negative in more than 10 % of the rows (mostly negative: SAE axes?); a friction
       |(FX, FY)| / FZ beyond :data:`_MAX_FRICTION`; FY rising with SA (slip angle or lateral force reversed?).

    ``stated``: where a file that states its own units (TYDEX, TTC) states them; the remedy for a unit is then
    to correct that statement (``--units`` is for CSV files). ``constants``: the constant channels given to the
    reader (``defaults=``, ``--set``: channel -> value as given); the remedy for one of them is its unit
    (``--set P=2.2bar``), not the file's."""
    frame = data.frame if isinstance(data, TyreData) else data
    given = {str(k).strip().upper(): v for k, v in (constants or {}).items()}
    where = where or (data.source if isinstance(data, TyreData) else "") or "<data>"
    column_of = column_of or {}
    present = set(frame.columns)

    def name(ch):
        if ch in given:
            return f"channel {ch} (the constant {ch}={given[ch]})"
        col = column_of.get(ch, ch)
        return f"channel {ch}" + (f" (file column {col!r})" if col != ch else "")

    def column(ch):
        return frame[ch].to_numpy(dtype=float)

    def values(ch):
        x = column(ch)
        return x[np.isfinite(x)]

    def refuse(problems, fixes, sae=""):
        """DataError (its ``channels``: channel -> likely unit, None for garbage) with the remedy for the units."""
        axes = f". Also {sae}" if sae else ""
        units = {ch: u for ch, u in fixes.items() if u}
        constant = {ch: u for ch, u in units.items() if ch in given}
        if constant:  # a number without a unit is SI: the remedy is the unit on the constant
            fix = ", ".join(remedy("constants", ch, f"{_QUANTITY.fullmatch(str(given[ch])).group(1)}{u}")
                            if _QUANTITY.fullmatch(str(given[ch])) else remedy("constants", ch, f"VALUE{u}")
                            for ch, u in constant.items())
            raise _channel_error(f"{where}: {'; '.join(problems)}. A constant without a unit is in SI units: give "
                                 f"its unit, e.g. {fix}{axes}", fixes)
        if stated:
            likely = ", ".join(f"{column_of.get(ch, ch)} looks like {u}" if u else f"{column_of.get(ch, ch)} is "
                               "garbage" for ch, u in fixes.items())
            raise _channel_error(f"{where}: {'; '.join(problems)}. The file states its units ({stated}): correct "
                                 f"the wrong ones in a copy of the file ({likely}), leave a channel out "
                                 f"({spelled('drop=(...)', '--drop CH')}), or read it unchecked with "
                                 f"{spelled('check=False', '--no-check')}{axes}", fixes)
        if speaking() == "cli":
            fix = "--units " + ",".join(f"{ch}={u}" for ch, u in units.items())
        else:
            fix = "units={" + ", ".join(f"{ch!r}: {u!r}" for ch, u in units.items()) + "}"
        raise _channel_error(f"{where}: {'; '.join(problems)}. Give the file's units, e.g. {fix}{axes}", fixes)

    # 1. ranges, and speed against spin
    problems, fixes = [], {}
    for ch, (low, high, candidates) in _PLAUSIBLE.items():
        if ch not in present:
            continue
        x = np.abs(values(ch))
        if x.size == 0 or not x.any():
            continue
        typical = float(np.median(x)) if ch in ("P", "FZ") else float(np.quantile(x, 0.99))
        if ch == "FZ":
            typical = float(np.max(x))
        if low <= typical <= high:
            continue
        lo, hi = _TYPICAL[ch]
        if ch in OPTIONAL_CHANNELS and (dead := garbage(frame, ch)):
            fixes[ch] = None
            problems.append(f"{name(ch)}: {dead}")
            continue
        likely = [u for u in candidates if lo <= typical * unit_to_si(ch, u) <= hi]
        shown = {"SA": "99th percentile of |SA|", "IA": "99th percentile of |IA|", "SL": "99th percentile of |SL|",
                 "VX": "99th percentile of |VX|", "P": "median P", "FZ": "largest |FZ|"}.get(ch, f"99th percentile of {ch}")
        si = _SI_NAME[CHANNELS[ch][0]]
        expected = f"{low:g}" if typical < low else f"{high:g}"
        side = "below" if typical < low else "above"
        guess = f"the values look like {' or '.join(likely)}" if likely else "check the unit of the data"
        fixes[ch] = (likely or candidates)[0]
        problems.append(f"{name(ch)}: {shown} is {typical:.4g} {si}, {side} the {expected} {si} of any tyre "
                        f"measurement in SI units: {guess}")
    if "OMEGA" in present and (dead := garbage(frame, "OMEGA")):
        fixes["OMEGA"] = None
        problems.append(f"{name('OMEGA')}: {dead}")
    _speed_and_spin(frame, fixes, problems, name)
    sae = ""  # the load's sign is independent of the units: named in the same error
    if "FZ" in present:
        fz = values("FZ")
        if fz.size and np.mean(fz < 0) > 0.5:
            sae = (f"{name('FZ')}: {100 * np.mean(fz < 0):.0f} % of the values are negative (median "
                   f"{np.median(fz):.4g} N): the load is positive in ISO-W; the file is probably in SAE axes (z down): "
                   f"{remedy('axes', 'FZ', 'SAE')}")
    if problems and all(u is None for u in fixes.values()):
        raise _channel_error(f"{where}: {'; '.join(problems)}. Leave the channel out "
                             f"({spelled('drop=' + repr(tuple(fixes)), '--drop ' + ','.join(fixes))})"
                             + (f". Also {sae}" if sae else ""), fixes)
    if problems:
        refuse(problems, fixes, sae)
    # 2. single rows no tyre has
    for ch, limit in _ROW_LIMIT.items():
        if ch in present:
            x = column(ch)
            beyond = np.flatnonzero(np.abs(x) > limit)
            if beyond.size:
                row = int(beyond[0])
                raise DataError(f"{where}: row {row + 1}: {name(ch)} is {x[row]:.4g} {_SI_NAME[CHANNELS[ch][0]]}, "
                                f"beyond the {limit:g} of any tyre measurement ({beyond.size} row"
                                f"{'s' if beyond.size > 1 else ''}): a damaged row, or a unit mistaken for SI; "
                                f"remove the row or read the file unchecked ({spelled('check=False', '--no-check')})")
    # 3. stiffnesses, camber and moments against the load
    if sae:
        raise _channel_error(f"{where}: {sae}", {"FZ": "SAE"})
    _slip_stiffness_units(frame, fixes, problems, name)
    if "IA" in present:
        ia = values("IA")
        if ia.size and np.any(np.abs(ia) == 1.0) and np.all(ia == np.round(ia)):
            fixes["IA"] = "deg"
            problems.append(f"{name('IA')}: every value is a whole number ({', '.join(f'{v:g}' for v in np.unique(ia)[:6])}"
                            f" rad): a camber of 1 rad (57 deg) is no test condition; the values look like deg")
    if "FZ" in present:
        load = float(np.max(np.abs(values("FZ")), initial=0.0))
        for ch in ("MX", "MY", "MZ"):
            x = np.abs(values(ch)) if ch in present else np.zeros(0)
            if x.size and load > 0 and float(np.quantile(x, 0.99)) > _MAX_LEVER * load:
                lever = float(np.quantile(x, 0.99)) / load
                fixes[ch] = "N*mm"
                problems.append(f"{name(ch)}: 99th percentile of |{ch}| is {lever:.3g} m x the largest load, beyond the "
                                f"{_MAX_LEVER:g} m lever of any tyre moment: the values look like N*mm")
    if problems:
        refuse(problems, fixes)
    # 4. the load, the friction, the sign of the lateral force
    if "FZ" in present:
        fz = column("FZ")
        off = np.mean(~(fz > 0))
        if not np.any(fz):
            raise DataError(f"{where}: {name('FZ')} is 0 in every row: expected the load on the tyre (FZ > 0 in ISO-W)")
        if off > 0.1:
            raise DataError(f"{where}: {name('FZ')} is zero or negative in {100 * off:.0f} % of the rows (median "
                            f"{np.median(fz):.4g} N): a rolling tyre carries a load, FZ > 0 in ISO-W; the load cell "
                            f"or the axis system is wrong (SAE axes: {remedy('axes', 'FZ', 'SAE')})")
        forces = [column(ch) for ch in ("FX", "FY") if ch in present]
        loaded = fz > 0.1 * float(np.median(fz[fz > 0]))
        if forces and loaded.sum() >= 5:
            grip = np.hypot(*forces) if len(forces) == 2 else np.abs(forces[0])
            mu = grip[loaded] / fz[loaded]
            mu = mu[np.isfinite(mu)]
            if mu.size >= 5 and float(np.quantile(mu, 0.99)) > _MAX_FRICTION:
                raise DataError(f"{where}: the friction |(FX, FY)| / FZ is {float(np.quantile(mu, 0.99)):.3g} (99th "
                                f"percentile, rows loaded above 10 % of the median load), beyond the {_MAX_FRICTION:g} "
                                "of any tyre: the forces and the load are in different units (e.g. FZ in daN or kgf, "
                                f"the forces in N); give the units ({spelled('units=', '--units')})")
    if {"SA", "FY"} <= present:
        sa, fy = column("SA"), column("FY")
        near = np.isfinite(sa) & np.isfinite(fy) & (np.abs(sa) < math.radians(4.0))
        if near.sum() >= 10 and np.ptp(sa[near]) > math.radians(1.0):
            slope = np.polyfit(sa[near], fy[near], 1)[0]
            corr = np.corrcoef(sa[near], fy[near])[0, 1]
            if slope > 0 and corr > 0.7:
                raise DataError(f"{where}: {name('FY')} rises with {name('SA')} (correlation {corr:.2f} for |SA| < "
                                f"4 deg): in ISO-W a positive slip angle gives a negative lateral force; the slip "
                                f"angle or the lateral force is reversed: {remedy('axes', 'SA', 'adapted-ISO')} (SA "
                                f"reversed) or {remedy('axes', 'SA', 'adapted-SAE')} (FY, MZ reversed); see the "
                                f"axis systems in the README")


def _speed_and_spin(frame, fixes, problems, name) -> None:
    """VX / (OMEGA x radius), about 1 for a rolling wheel in SI units (RE, else RL, in metres), matched against
    every pair of speed and spin units: the pair whose ratio is within 15 % names the wrong channels (both at once,
    e.g. km/h and rpm: 0.377). Skipped when the radius or VX is already found in a wrong unit."""
    lever = "RE" if "RE" in frame.columns else "RL"
    if not {"VX", "OMEGA", lever} <= set(frame.columns) or {"VX", "OMEGA", lever} & set(fixes):
        return
    radius = frame[lever].to_numpy(float)
    vx, omega = frame["VX"].to_numpy(float), frame["OMEGA"].to_numpy(float)
    ok = np.isfinite(vx) & np.isfinite(omega) & np.isfinite(radius) & (np.abs(omega * radius) > 0.5) & (vx != 0)
    if ok.sum() < 5:
        return
    ratio = float(np.median(np.abs(vx[ok]) / np.abs(omega[ok] * radius[ok])))
    pairs = [(sv / so, speed, spin) for speed, sv in _SPEED_UNITS.items() for spin, so in _SPIN_UNITS.items()]
    factor, speed, spin = min(pairs, key=lambda p: abs(math.log(ratio * p[0])))
    if abs(ratio * factor - 1.0) >= 0.15 or (speed, spin) == ("m/s", "rad/s"):
        return
    wrong = [(ch, unit) for ch, unit in (("VX", speed), ("OMEGA", spin)) if unit not in ("m/s", "rad/s")]
    for ch, unit in wrong:
        if ch not in fixes:
            fixes[ch] = unit
            problems.append(f"{name(ch)}: VX / (OMEGA x radius) is {ratio:.3g} (about 1 for a rolling wheel in SI "
                            f"units; {1 / factor:.3g} with VX in {speed} and OMEGA in {spin}): {ch} looks like {unit}")


def _slope_per_load(x, force, fz, keep) -> float | None:
    """|slope| of force / FZ over x, fitted on the rows ``keep`` with |x| within 30 % of the 99th percentile of |x|
    (the linear range of a sweep); None without 10 such rows or when the slope is not 5 standard errors from 0."""
    keep = keep & np.isfinite(x) & np.isfinite(force) & np.isfinite(fz) & (np.abs(fz) > 0)
    if keep.sum() < 10:
        return None
    reach = float(np.quantile(np.abs(x[keep]), 0.99))
    keep &= np.abs(x) <= 0.3 * reach
    if keep.sum() < 10 or not np.ptp(x[keep]) > 0:
        return None
    x, per_load = x[keep], force[keep] / np.abs(fz[keep])
    (slope, offset), residual = np.polyfit(x, per_load, 1, full=True)[:2]
    spread = float(np.sum((x - x.mean()) ** 2))
    error = math.sqrt(float(residual[0]) / (x.size - 2) / spread) if residual.size else 0.0
    return abs(float(slope)) if abs(slope) > 5.0 * error else None


def _slip_stiffness_units(frame, fixes, problems, name) -> None:
    """The slip stiffnesses per unit load (FY over SA, FX over SL; :data:`_MIN_STIFFNESS_PER_LOAD`): a slope every
    tyre exceeds in SI, met only with the slip in degrees (SA) or percent (SL), e.g. sweeps within +-1 deg or +-2 %,
    which the ranges cannot tell from radians or ratios."""
    columns = set(frame.columns)
    if "FZ" not in columns:
        return
    fz = frame["FZ"].to_numpy(float)
    n = len(frame)
    sa = frame["SA"].to_numpy(float) if "SA" in columns else np.zeros(n)
    sl = frame["SL"].to_numpy(float) if "SL" in columns else np.zeros(n)
    ia = frame["IA"].to_numpy(float) if "IA" in columns else np.zeros(n)
    upright = np.abs(ia) <= math.radians(0.5)
    if upright.sum() < 10:
        upright = np.ones(n, bool)
    cases = (("SA", "FY", sa, np.abs(sl) <= max(0.02, 0.1 * float(np.max(np.abs(sl), initial=0.0))), "deg",
              "cornering stiffness"),
             ("SL", "FX", sl, np.abs(sa) <= math.radians(0.5), "%", "longitudinal slip stiffness"))
    for ch, force, x, free, unit, what in cases:
        if ch not in columns or force not in columns or ch in fixes:
            continue
        slope = _slope_per_load(x, frame[force].to_numpy(float), fz, free & upright)
        if slope is None or slope >= _MIN_STIFFNESS_PER_LOAD:
            continue
        factor = unit_to_si(ch, unit)
        if 3.0 <= slope / factor <= 100.0:
            fixes[ch] = unit
            problems.append(f"{name(ch)}: the {what} per unit load (slope of {force} / FZ over {ch} at small slip) "
                            f"is {slope:.3g}, below the {_MIN_STIFFNESS_PER_LOAD:g} of any tyre in SI units "
                            f"({slope / factor:.3g} with {ch} in {unit}): the values look like {unit}")


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
    sha256: str = ""  # of the file read (:func:`read_data`), recorded in fitted .tir headers

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
            if name in self.frame.columns and not pd.api.types.is_float_dtype(self.frame[name].dtype):
                col = pd.to_numeric(self.frame[name], errors="coerce").astype(float)
                bad = col.isna() & self.frame[name].notna()
                if bad.any():
                    row = int(np.flatnonzero(bad.to_numpy())[0])
                    raise DataError(f"{where}: row {row}: channel {name}: non-numeric value "
                                    f"{self.frame[name].iloc[row]!r}")
                self.frame[name] = col
        _check_values(self.frame, lambda row: f"{where}: row {row}")

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
        return TyreData(sub.copy(), self.tyre, self.source, dict(self.units), dict(self.constants), hist, self.sha256)

    def with_frame(self, frame: pd.DataFrame, note: str) -> "TyreData":
        return TyreData(frame, self.tyre, self.source, dict(self.units), dict(self.constants),
                        list(self.history) + [note], self.sha256)

    @staticmethod
    def concat(parts: list["TyreData"]) -> "TyreData":
        first = parts[0]
        frame = pd.concat([p.frame for p in parts], ignore_index=True)
        return TyreData(frame, first.tyre, first.source, dict(first.units), dict(first.constants),
                        list(first.history), first.sha256)

    @staticmethod
    def pool(runs: list["TyreData"], gap: float = 10.0) -> "TyreData":
        """Several runs of one tyre (cornering, drive/brake, vertical...) as one: the rows one after the other with
        a RUN column (0, 1, ...), TIME of each run shifted to start ``gap`` seconds after the previous one ends (so
        the programme recogniser sees one time series), the channels one run lacks NaN ("not measured"), the
        sources, SHA-256 and histories joined, the constants the runs agree on, the first tyre description."""
        if len(runs) == 1:
            return runs[0]
        frames, t0 = [], 0.0
        for k, run in enumerate(runs):
            f = run.frame.assign(RUN=k)
            if "TIME" in f.columns:
                t = f["TIME"].to_numpy(float)
                f["TIME"] = t - t[0] + t0
                t0 = float(f["TIME"].iloc[-1]) + gap
            frames.append(f)
        if any("TIME" in f.columns for f in frames) and not all("TIME" in f.columns for f in frames):
            raise DataError("pooled runs: some runs are time series (TIME) and others not: pool runs of one kind")
        constants = {k: v for k, v in runs[0].constants.items() if all(r.constants.get(k) == v for r in runs)}
        tyre = next((r.tyre for r in runs if r.tyre), "")
        names = " + ".join(Path(r.source).name if r.source else "(in memory)" for r in runs)
        history = [f"run {k} ({Path(r.source).name if r.source else 'in memory'}): {h}" for k, r in enumerate(runs)
                   for h in r.history]
        units = {k: v for r in runs for k, v in r.units.items()}
        return TyreData(pd.concat(frames, ignore_index=True), tyre, names, units, constants,
                        history + [f"{len(runs)} runs pooled"], " ".join(r.sha256 for r in runs if r.sha256))

    def inputs(self) -> dict:
        """Keyword arguments fz kappa alpha gamma phit vx p for :meth:`mftyre.MFModel.evaluate`."""
        return dict(fz=self.array("FZ"), kappa=self.array("SL"), alpha=self.array("SA"), gamma=self.array("IA"),
                    phit=self.array("PHIT"), vx=self.array("VX"), p=self.array("P"))

    def __repr__(self):
        return f"TyreData({len(self)} rows, channels={' '.join(self.channels)}, source={self.source!r})"


# ------------------------------------------------------------------------------------------------ CSV
#: Text read as "not measured" (NaN) in CSV and TYDEX data; any other non-number is an error.
_NAN_TEXT = ["", "nan", "NaN", "NAN"]


def read_csv(path, *, columns: dict | None = None, units: dict | None = None, defaults: dict | None = None,
             axes: str = "ISO-W", check: bool = True, tyre: str = "", max_bytes: int = DATA_MAX_BYTES) -> TyreData:
    """Read a CSV file into :class:`TyreData`.

    Comma separated, one header row (UTF-8, a byte-order mark allowed), one row per sample. ``columns``: file
    column -> channel for columns not named canonically; ``units``: channel -> unit of the file (SI when
    absent); ``axes``: the file's axis system (:data:`AXES`); ``defaults``: channel -> constant value (SI
    number, or text with a unit such as ``"1.6bar"``; ISO-W) for a channel the file lacks (e.g.
    ``{"P": 2.2e5, "VX": 16.7}``); ``check``: refuse values no tyre measurement has (:func:`check_plausible`,
    after the conversions). An empty field or ``nan`` is "not measured" (an error in a required
    channel); infinite values (``inf``, ``1e400``) are errors in every channel; two columns for one channel are
    an error. Files larger than ``max_bytes`` are refused.
    """
    path = Path(path)
    frame, units, notes = _csv_frame(path, columns, units, defaults, axes, check, max_bytes, CHANNELS, REQUIRED)
    return TyreData(frame, tyre=tyre or path.stem, source=str(path), units=units, history=notes)


def read_time_histories(path, *, columns: dict | None = None, units: dict | None = None,
                        defaults: dict | None = None, axes: str = "ISO-W", check: bool = True,
                        max_bytes: int = DATA_MAX_BYTES) -> tuple[pd.DataFrame, dict, list]:
    """Read a CSV file of time histories (dynamic tyre tests: layout in :mod:`mftyre.gaps.dynamic_runs`) by the
    rules of :func:`read_csv` (the same checks: only regular files, field counts per line, one column per channel,
    numbers in channel columns, no infinite value, units, axes, constants, plausibility), with the channels of
    :data:`TIME_CHANNELS` beside :data:`CHANNELS` and TIME and VX required; further: the axle load LOAD positive,
    the yaw PSI within 1 rad (degrees?). (frame: channels in SI and ISO-W, other columns as text, index = line - 2;
    units: channel -> unit as read; notes)."""
    path = Path(path)
    known = {**CHANNELS, **TIME_CHANNELS}
    frame, units_read, notes = _csv_frame(path, columns, units, defaults, axes, check, max_bytes, known,
                                          ("TIME", "VX"))
    if check and "LOAD" in frame.columns:
        load = frame["LOAD"].to_numpy(float)
        bad = np.flatnonzero(load <= 0)
        if bad.size:
            hint = (f" ({100 * bad.size / load.size:.0f} % of the rows: SAE axes? the axle load is a magnitude in "
                    f"every axis system)" if bad.size > load.size / 2 else "")
            raise DataError(f"{path}: line {int(bad[0]) + 2}: channel LOAD: {load[bad[0]]:.6g} N: expected the "
                            f"downward force on the axle, positive{hint}")
    if check and "PSI" in frame.columns:
        psi = np.abs(frame["PSI"].to_numpy(float))
        if psi.size and np.nanmax(psi) > 1.0:
            raise DataError(f"{path}: channel PSI: |yaw| up to {np.nanmax(psi):.4g} rad, above the 1 rad of a "
                            f"steer step: the values look like degrees; give {remedy('units', 'PSI', 'deg')}")
    return frame, units_read, notes


def _csv_frame(path, columns, units, defaults, axes, check, max_bytes, known, required):
    """(frame, units read, notes) of the CSV file ``path``: the reading and checks of :func:`read_csv` with the
    channel table ``known`` and the ``required`` channels."""
    with open_user_file(path, max_bytes=max_bytes, what="CSV data file", error=DataError) as fh:
        data = fh.read()
    header = _csv_header(data, path)
    _refuse_wide(len(header), path, "line 1: ")
    if len(header) == 1 and header[0].upper() not in known:
        for sep, name in ((";", "semicolons"), ("\t", "tabs"), (" ", "blanks")):
            if len(header[0].split(sep)) > 2:
                raise DataError(f"{path}: line 1: one column named {header[0][:60]!r}: the columns look separated "
                                f"by {name}; expected comma-separated values (save the file as CSV with commas and "
                                f"a decimal point)")
    _check_field_counts(data, len(header), path)
    try:  # index_col=False: a row is never shifted onto an index (the counts are checked above)
        raw = pd.read_csv(io.BytesIO(data), skipinitialspace=True, keep_default_na=False, na_values=_NAN_TEXT,
                          encoding="utf-8-sig", index_col=False)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError, ValueError) as exc:
        raise DataError(f"{path}: cannot read as CSV: {exc}") from None
    del data
    if len(raw.columns) != len(header):  # pragma: no cover - pandas and the csv module agree on the header
        raise DataError(f"{path}: line 1: cannot read the header")
    raw.columns = header
    if len(raw) == 0:
        raise DataError(f"{path}: no data rows: expected a header line followed by one line per sample")
    _refuse_units_row(raw, header, path)
    mapping = {c: c.upper() for c in header if c.upper() in known}
    for col, ch in (columns or {}).items():
        if col not in header:
            raise DataError(f"{path}: line 1: column {col!r} (for {ch}) not in the header; columns are "
                            f"{', '.join(header)}")
        if ch.upper() not in known:
            raise DataError(f"{path}: unknown channel {ch!r} for column {col!r}; channels: {', '.join(known)}")
        mapping[col] = ch.upper()
    _refuse_duplicates(header, mapping, path)
    units = {k.upper(): v for k, v in (units or {}).items()}
    columns_out = {}
    column_of = {}
    for i, col in enumerate(header):
        ch = mapping.get(col)
        series = raw.iloc[:, i]
        if ch is None:
            columns_out[col] = series
            continue
        values = _numeric_column(series, lambda row, text: f"{path}: line {row + 2}: column {col!r} ({ch}): "
                                                           f"non-numeric value {text!r}")
        factor = 1.0
        if ch in units:
            try:
                factor = unit_to_si(ch, units[ch])
            except ValueError as exc:
                raise DataError(f"{path}: column {col!r}: {exc}") from None
        columns_out[ch] = values * factor if factor != 1.0 else values
        column_of[ch] = col
    frame = pd.DataFrame(columns_out, copy=False)
    unknown_units = [ch for ch in units if ch not in column_of]
    if unknown_units:
        raise DataError(f"{path}: unit given for {', '.join(unknown_units)}, which the file has no column for "
                        f"(columns: {', '.join(header)})")
    _convert_axes(frame, axes, path)
    _apply_defaults(frame, defaults, path, column_of, known)
    _check_required(frame, path, lambda row: f"{path}: line {row + 2}", column_of, required, known)
    if check:
        check_plausible(frame, str(path), column_of, constants=defaults)
    unit_record = {ch: units.get(ch, _SI_NAME[known[ch][0]]) for ch in known if ch in frame.columns}
    return frame, unit_record, _import_notes(axes, units, defaults, check)


def _refuse_wide(count: int, path, where: str = "") -> None:
    """DataError when a file has more columns than :data:`mftyre.files.DATA_MAX_COLUMNS` (before its samples are
    read: each column costs Python work, 200,000 of them a minute)."""
    if count > DATA_MAX_COLUMNS:
        raise DataError(f"{path}: {where}{count:,} columns, more than the {DATA_MAX_COLUMNS:,} a measurement file may "
                        "have (a tyre test records a few dozen channels): split the file or drop columns")


def _refuse_units_row(raw, header, path):
    """A DataError naming the units row when line 2 holds no number but words such as N, deg, kPa (a units row
    under the names, as many lab exports have)."""
    first = [str(v).strip() for v in raw.iloc[0].tolist()]
    if len(first) < 2 or any(_is_number(v) for v in first if v) or not any(first):
        return
    known = [(col, unit) for col, unit in zip(header, first) if col.upper() in CHANNELS and unit
             and _known_unit(col.upper(), unit)]
    if known:
        given = ",".join(f"{col.upper()}={unit}" for col, unit in known if unit_to_si(col.upper(), unit) != 1.0)
        fix = "(its units are SI)" if not given else \
            (f"and give them with --units {given}" if speaking() == "cli" else f"and give them with units= ({given})")
        raise DataError(f"{path}: line 2 holds units ({', '.join(first[:8])}{' ...' if len(first) > 8 else ''}), not "
                        f"samples: delete that line {fix}")


def _known_unit(channel: str, unit: str) -> bool:
    try:
        unit_to_si(channel, unit)
    except ValueError:
        return False
    return True


def _line_break(data: bytes) -> bytes:
    """The line break of a CSV file: LF (also for CR LF), or CR alone when the file has no LF."""
    return b"\n" if b"\n" in data or b"\r" not in data else b"\r"


def _csv_header(data: bytes, path) -> list[str]:
    """The column names of the first line of the file ``data``, stripped (a UTF-8 byte-order mark removed)."""
    end = data.find(_line_break(data))
    first = data if end < 0 else data[:end]
    try:
        text = first.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: line 1: cannot read as CSV: {exc}") from None
    try:
        names = next(csv.reader([text.rstrip("\r\n")]), [])
    except csv.Error as exc:  # e.g. a field longer than the csv module's limit (128 KiB)
        raise DataError(f"{path}: line 1: cannot read the header: {exc}") from None
    if not any(n.strip() for n in names):
        raise DataError(f"{path}: line 1: no header: expected column names such as FZ,SA,SL,VX,P")
    return [n.strip() for n in names]


_BLOCK = 1 << 20


def _check_field_counts(data: bytes, expected: int, path) -> None:
    """DataError naming the first line whose number of fields differs from the header's ``expected`` (blank
    lines are skipped, as the reader skips them): such a row would otherwise be shifted onto the columns or
    padded. Linear time: commas counted per line with NumPy, or by the csv module when the file quotes fields."""
    if b'"' in data:  # quoted fields may hold commas and line breaks: let the csv module split them
        text = io.StringIO(data.decode("utf-8-sig", errors="replace"), newline="")
        try:
            for number, row in enumerate(csv.reader(text), start=1):
                if row and len(row) != expected:
                    _field_count_error(path, number, len(row), expected)
        except csv.Error as exc:
            raise DataError(f"{path}: cannot read as CSV: {exc}") from None
        return
    line_break = _line_break(data)
    every = np.frombuffer(data, np.uint8)
    start, line, size = 0, 1, len(data)
    while start < size:  # blocks of whole lines of about 1 MiB (kept in the cache: 4x faster than one pass)
        end = size if start + _BLOCK >= size else data.rfind(line_break, start, start + _BLOCK) + 1
        if end <= start:  # a line longer than a block
            end = data.find(line_break, start + _BLOCK) + 1 or size
        raw = every[start:end]
        separators = np.flatnonzero((raw == ord(",")) | (raw == line_break[0]))
        at = np.flatnonzero(raw[separators] == line_break[0])  # the line breaks among the separators
        breaks = separators[at]
        if end == size and (raw.size == 0 or raw[-1] != line_break[0]):  # a last line without a break
            at, breaks = np.append(at, separators.size), np.append(breaks, raw.size)
        fields = np.diff(at, prepend=-1)  # commas of each line + 1
        length = breaks - np.concatenate(([0], breaks[:-1] + 1))
        some = length > 0
        length[some] -= raw[breaks[some] - 1] == ord("\r")  # CR LF: a line of only CR is empty
        wrong = np.flatnonzero((fields != expected) & (length > 0))
        if wrong.size:
            _field_count_error(path, line + int(wrong[0]), int(fields[wrong[0]]), expected)
        line += breaks.size
        start = end


def _field_count_error(path, line: int, count: int, expected: int):
    raise DataError(f"{path}: line {line}: {count} fields, but the header has {expected} columns: expected one "
                    "value per column on every line (a row with a field more or less would shift the channels)")


def _refuse_duplicates(header: list[str], mapping: dict, path) -> None:
    seen: dict[str, str] = {}
    for col in header:
        ch = mapping.get(col, col)
        if ch in seen:
            what = f"column {col!r}" + (f" ({ch})" if ch != col else "")
            also = f" (also as column {seen[ch]!r})" if seen[ch] != col else ""
            raise DataError(f"{path}: line 1: {what} appears twice{also}: expected one column per channel")
        seen[ch] = col


def _numeric_column(series: pd.Series, where) -> np.ndarray:
    """Float values of a column pandas has read; DataError ``where(row, text)`` at the first non-number
    (Fortran exponents ``1.0D+3`` are read as numbers)."""
    if pd.api.types.is_numeric_dtype(series.dtype) and not pd.api.types.is_bool_dtype(series.dtype):
        return series.to_numpy(dtype=float)
    text = series.astype(str).str.strip()
    values = pd.to_numeric(text.str.replace(r"(?<=[0-9.])[dD](?=[+-]?[0-9])", "e", regex=True), errors="coerce")
    bad = values.isna() & series.notna() & ~text.isin(_NAN_TEXT)
    if bad.any():
        row = int(np.flatnonzero(bad.to_numpy())[0])
        raise DataError(where(row, text.iloc[row]))
    return values.to_numpy(dtype=float)


def _convert_axes(frame, axes, path):
    try:
        to_iso_w(frame, axes)
    except ValueError as exc:
        raise DataError(f"{path}: {exc}") from None


#: The history entry of data read without the plausibility check (:func:`mftyre.fit.load_data` then skips it too).
UNCHECKED = "plausibility check skipped on request"


def _import_notes(axes, units, defaults, check=True) -> list[str]:
    notes = [f"axes {_axes_name(axes)} converted to ISO-W"] if _axes_name(axes) != "ISO-W" else []
    if not check:
        notes.append(UNCHECKED)
    if units:
        notes.append("units: " + ", ".join(f"{ch} in {u}" for ch, u in units.items()))
    if defaults:
        notes.append("constant channels: " + ", ".join(f"{ch} = {v}" for ch, v in defaults.items()))
    return notes


def _apply_defaults(frame, defaults, path, column_of=None, known=CHANNELS):
    """Constant channels (``defaults``: channel -> SI number or text with a unit) for channels the file lacks;
    a DataError for a channel the file measures (a constant never replaces a measurement silently)."""
    for name, value in (defaults or {}).items():
        ch = str(name).strip().upper()
        if ch not in known:
            raise DataError(f"{path}: constant for unknown channel {name!r}; channels: {', '.join(known)}")
        try:
            number = constant_value(ch, value)
        except ValueError as exc:
            raise DataError(f"{path}: constant {exc}") from None
        if ch in frame.columns:
            col = (column_of or {}).get(ch, ch)
            raise DataError(f"{path}: channel {ch} is measured in the file (column {col!r}); a constant is only for "
                            f"a channel the file lacks: drop {remedy('constants', ch, str(value))}")
        frame[ch] = number


def _check_required(frame, path, locate, column_of=None, required=REQUIRED, known=CHANNELS):
    missing = [c for c in required if c not in frame.columns]
    if missing:
        raise DataError(f"{path}: missing channel(s) {', '.join(missing)} (required: {', '.join(required)}); name "
                        f"the file's column ({remedy('columns', missing[0], 'COLUMN')}) or give a constant "
                        f"({remedy('constants', missing[0], 'VALUE')})")
    _check_values(frame, locate, column_of, required, known)


def _check_values(frame, locate, column_of=None, required_channels=REQUIRED, known=CHANNELS):
    """DataError at the first value no measurement can have: NaN or +-inf in a required channel (and in IA,
    PHIT when present), +-inf in any other channel (NaN there means "not measured"). ``locate(row)`` says
    where that row is; ``column_of``: channel -> the file's column name, when they differ."""
    for ch in known:
        if ch not in frame.columns:
            continue
        values = frame[ch].to_numpy(dtype=float)
        required = ch in required_channels or ch in _ZERO_DEFAULT
        bad = ~np.isfinite(values) if required else np.isinf(values)
        if not bad.any():
            continue
        row = int(np.flatnonzero(bad)[0])
        col = (column_of or {}).get(ch, ch)
        what = ("NaN in a required channel" if np.isnan(values[row])
                else f"{values[row]} (infinite, or beyond the float range such as 1e400): expected a finite number")
        column = f"file column {col!r}, " if col != ch else ""
        raise DataError(f"{locate(row)}: channel {ch}: {what} ({column}{int(bad.sum())} rows)")
    if "P" in frame.columns:  # the model's pressure terms divide by it: a tyre is measured inflated
        pressure = frame["P"].to_numpy(dtype=float)
        bad = ~(pressure > 0)
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            col = (column_of or {}).get("P", "P")
            column = f"file column {col!r}, " if col != "P" else ""
            raise DataError(f"{locate(row)}: channel P: inflation pressure {float(pressure[row])!r} Pa: expected a positive "
                            f"pressure (in the file's unit, pascal by default) ({column}{int(bad.sum())} rows)")


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


_DATA_KEY = re.compile(rb"[ \t]*\*\*MEASURDATA(?=\s|\Z)", re.I)


def read_tydex(path, *, defaults: dict | None = None, axes: str = "ISO-W", check: bool = True,
               max_bytes: int = DATA_MAX_BYTES) -> TyreData:
    """Read a TYDEX ``.tdx`` file (the subset described in the module docstring) into :class:`TyreData`.

    UTF-8 (a byte-order mark allowed); ``nan`` in the data is "not measured" (an error in a required channel).
    Files larger than ``max_bytes`` are refused. ``axes``, ``defaults`` and ``check`` as for :func:`read_csv`
    (TYDEX is W-axis by definition; ``axes`` is for files that are not)."""
    path = Path(path)
    with open_user_file(path, max_bytes=max_bytes, what="TYDEX data file", error=DataError) as fh:
        return _read_tydex(fh, path, defaults, axes, check)


def _read_tydex(fh, path: Path, defaults, axes="ISO-W", check=True) -> TyreData:
    """The blocks before and after the sample rows are read line by line; the rows (the bulk of the file) are
    streamed to pandas' C parser."""
    first = fh.readline()
    if b"\r" in first and not first.endswith(b"\r\n"):  # lines ended by CR alone: normalise (in memory)
        fh = io.BytesIO((first + fh.read()).replace(b"\r\n", b"\n").replace(b"\r", b"\n"))
        first = fh.readline()
    head, line = [], first.removeprefix(b"\xef\xbb\xbf")
    while line and not _DATA_KEY.match(line):
        head.append(line)
        line = fh.readline()
    state = _TydexBlocks(path)
    ended = state.read(_lines(b"".join(head), path), first_line=1)
    data_line = len(head) + 2  # file line of the first sample row
    if line and not ended:
        state.seen.add("**MEASURDATA")
    for needed in ("**MEASURCHANNELS", "**MEASURDATA"):
        if needed not in state.seen:
            raise DataError(f"{path}: no {needed} block")
    channels = state.channels
    if not channels:
        raise DataError(f"{path}: **MEASURCHANNELS lists no channel")
    _refuse_wide(len(channels), path, "**MEASURCHANNELS: ")
    rows = _SampleRows(fh)
    columns, lines = _tydex_samples(rows, data_line, channels, path)
    tail = rows.rest + fh.read()
    if not tail.lstrip().upper().startswith(b"**END"):  # e.g. a block after the samples
        state.read(_lines(tail, path), first_line=data_line + rows.newlines, after_data=True)
    if len(columns[0]) == 0:
        raise DataError(f"{path}:{data_line - 1}: no data rows in **MEASURDATA: expected one line of values per "
                        "sample")
    values_of, units = {}, {}
    for (name, unit, factor, offset, lineno), values in zip(channels, columns):
        ch = _CHANNEL_OF_TYDEX.get(name)
        try:
            to_si = 1.0 if ch is None else unit_to_si(ch, unit)
        except ValueError as exc:
            raise DataError(f"{path}:{lineno}: columns 41-50: channel {name}: {exc}") from None
        values = values * factor  # value in the file's unit: factor * raw + offsets; then to SI
        values += offset
        if to_si != 1.0:
            values *= to_si
        values_of[name if ch is None else ch] = values
        if ch is not None:
            units[ch] = unit
    del columns
    frame = pd.DataFrame(values_of, copy=False)
    _convert_axes(frame, axes, path)
    for name, (value, unit, *_) in state.constants.items():  # constants standing in for absent channels
        ch = _CHANNEL_OF_TYDEX.get(name)
        if ch in REQUIRED + _ZERO_DEFAULT and ch not in frame.columns and isinstance(value, float):
            frame[ch] = value
            units[ch] = f"{unit} (constant)"
    name_of = {_CHANNEL_OF_TYDEX[name]: name for name, *_ in channels if name in _CHANNEL_OF_TYDEX}
    _apply_defaults(frame, defaults, path, name_of)
    missing = [c for c in REQUIRED if c not in frame.columns]
    if missing:
        raise DataError(f"{path}: missing channel(s) {', '.join(missing)}: neither a measurement channel "
                        f"({', '.join(_TYDEX_NAMES[c][0] for c in missing)}) nor a constant")
    _check_values(frame, lambda row: f"{path}:{lines()[row]}", name_of)
    if check:
        check_plausible(frame, str(path), name_of, stated="the unit column of its **MEASURCHANNELS lines",
                        constants=defaults)
    tyre = str(state.header.get("MEASID", ("", "", ""))[0] or path.stem)
    consts = {k: v[0] for k, v in {**state.header, **state.constants}.items()}
    return TyreData(frame, tyre=tyre, source=str(path), units=units, constants=consts,
                    history=_import_notes(axes, None, defaults, check))


def _lines(raw: bytes, path) -> list[str]:
    """The lines of a part of the file (UTF-8)."""
    try:
        return raw.decode("utf-8").replace("\r\n", "\n").split("\n")
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: cannot read: not UTF-8 text near byte {exc.start} of a block") from None


class _TydexBlocks:
    """The blocks other than the sample rows, read line by line: header, constants, channels."""

    def __init__(self, path):
        self.path = path
        self.block = None
        self.seen: set[str] = set()
        self.header: dict = {}
        self.constants: dict = {}
        self.channels: list = []

    def read(self, lines, first_line: int, after_data: bool = False) -> bool:
        """Read ``lines`` (file line numbers from ``first_line``); True when ``**END`` was reached."""
        path = self.path
        if after_data:
            self.block = "**MEASURDATA"
        for lineno, line in enumerate(lines, first_line):
            stripped = line.strip()
            if not stripped or stripped.startswith("!"):
                continue
            if stripped.startswith("**"):
                key = stripped.split()[0].upper()
                if key not in _BLOCKS:
                    raise DataError(f"{path}:{lineno}: unknown block {stripped[:40]!r}; expected one of "
                                    f"{', '.join(_BLOCKS)}")
                if key == "**MEASURDATA" and after_data:
                    raise DataError(f"{path}:{lineno}: a second **MEASURDATA block: expected one")
                self.block = key
                self.seen.add(key)
                if key == "**END":
                    return True
                continue
            if self.block is None:
                raise DataError(f"{path}:{lineno}: text before the first block (**HEADER expected)")
            if self.block in ("**HEADER", "**CONSTANTS"):
                name, desc, unit, value = _fixed_fields(line)
                if not name:
                    raise DataError(f"{path}:{lineno}: column 1-10: empty name in {self.block}")
                target = self.header if self.block == "**HEADER" else self.constants
                key = name.upper()
                if key in target:
                    raise DataError(f"{path}:{lineno}: columns 1-10: {key} appears twice in {self.block} (also on "
                                    f"line {target[key][3]}): expected one value per name")
                target[key] = (_constant_value(key, unit, value, path, lineno), unit, desc, lineno)
            elif self.block == "**MEASURCHANNELS":
                name, desc, unit, rest = _fixed_fields(line)
                parts = rest.split()
                if not name or not parts:
                    raise DataError(f"{path}:{lineno}: channel line needs name (columns 1-10), description, unit "
                                    f"(41-50) and a conversion factor (from column 51): {line[:80]!r}")
                if len(parts) > 3:
                    raise DataError(f"{path}:{lineno}: column 51: channel {name}: {len(parts)} numbers "
                                    f"{rest.strip()[:60]!r}: expected a conversion factor and up to two offsets")
                key = name.upper()
                canonical = _CHANNEL_OF_TYDEX.get(key, key)
                for other, *_, other_line in self.channels:
                    if _CHANNEL_OF_TYDEX.get(other, other) == canonical:
                        also = "" if other == key else f" as {other}"
                        raise DataError(f"{path}:{lineno}: columns 1-10: channel {key} ({canonical}) is listed twice "
                                        f"(also{also} on line {other_line}): expected one column per channel")
                try:
                    numbers = [float(p.replace("D", "E").replace("d", "e")) for p in parts]
                except ValueError:
                    raise DataError(f"{path}:{lineno}: column 51: channel {name}: non-numeric factor/offset "
                                    f"{rest[:40]!r}") from None
                if not all(math.isfinite(x) for x in numbers):
                    raise DataError(f"{path}:{lineno}: column 51: channel {name}: factor/offset {rest[:40]!r} "
                                    "is not finite")
                self.channels.append((name.upper(), unit, numbers[0], sum(numbers[1:]), lineno))
            elif self.block == "**MEASURDATA":  # only after the data block: text where a block should start
                raise DataError(f"{path}:{lineno}: values after the sample rows: expected a block keyword (**END)")
            # **COMMENTS: free text, ignored
        return False


class _SampleRows(io.RawIOBase):
    """The sample rows of a TYDEX file as a binary stream for pandas: ``fh`` read in whole lines up to the next
    line that opens a block (``**``). ``rest``: what was read beyond (the next block), ``newlines``: the lines
    handed on; :meth:`block` reads them again (for an error message)."""

    def __init__(self, fh):
        self._fh, self._start = fh, fh.tell()
        self._chunk, self._at, self._done = memoryview(b""), 0, False
        self.rest, self.size, self.newlines = b"", 0, 0

    def readable(self) -> bool:
        return True

    def readinto(self, buffer) -> int:
        while self._at >= len(self._chunk) and not self._done:
            self._next_chunk()
        n = min(len(buffer), len(self._chunk) - self._at)
        buffer[:n] = self._chunk[self._at:self._at + n]
        self._at += n
        return n

    def _next_chunk(self) -> None:
        chunk = self._fh.read(1 << 20)
        if not chunk:
            self._done = True
        elif not chunk.endswith(b"\n"):
            chunk += self._fh.readline()
        at = chunk.find(b"**")
        while at >= 0:
            line_start = chunk.rfind(b"\n", 0, at) + 1
            if not chunk[line_start:at].strip():
                chunk, self.rest, self._done = chunk[:line_start], chunk[line_start:], True
                break
            at = chunk.find(b"**", at + 2)
        self._chunk, self._at = memoryview(chunk), 0
        self.size += len(chunk)
        self.newlines += chunk.count(b"\n")

    def block(self) -> bytes:
        here = self._fh.tell()
        self._fh.seek(self._start)
        text = self._fh.read(self.size)
        self._fh.seek(here)
        return text


def _tydex_samples(rows: _SampleRows, first_line: int, channels, path):
    """The sample rows (whitespace-separated numbers, one per channel) as one float array per channel, and a
    function that gives the file line of each row (computed only for an error message)."""
    n = len(channels)
    cache = []

    def text_lines() -> list[bytes]:
        if not cache:
            cache.append(rows.block().split(b"\n"))
        return cache[0]

    def lines() -> np.ndarray:
        if len(cache) < 2:
            text_lines()
            cache.append(np.asarray([first_line + i for i, text in enumerate(cache[0])
                                     if text.strip() and not text.strip().startswith(b"!")]))
        return cache[1]

    def count_values(lineno: int) -> int:
        return len(text_lines()[lineno - first_line].split(b"!")[0].split())

    def token_count_error(candidates):
        for lineno in candidates:
            if count_values(lineno) != n:
                raise DataError(f"{path}:{lineno}: {count_values(lineno)} values, expected {n} (one per channel)")

    try:  # one spare column: a row with one value too many lands there instead of failing without a line
        table = pd.read_csv(rows, sep=r"\s+", header=None, names=range(n + 1), comment="!",
                            keep_default_na=False, na_values=_NAN_TEXT, skip_blank_lines=True, encoding="utf-8")
    except pd.errors.EmptyDataError:  # no rows, only blank or comment lines
        return [np.empty(0)] * n, lines
    except pd.errors.ParserError:
        token_count_error(lines())
        raise  # pragma: no cover - the scan above finds the row pandas failed on
    except (UnicodeDecodeError, ValueError) as exc:
        raise DataError(f"{path}: **MEASURDATA: cannot read: {exc}") from None
    if table[n].notna().any():
        token_count_error(lines()[np.flatnonzero(table[n].notna().to_numpy())])
    if table[n - 1].isna().any():  # a short row, or "nan" values in the last channel: look at those rows
        token_count_error(lines()[np.flatnonzero(table[n - 1].isna().to_numpy())])
    columns = [_numeric_column(table.pop(j), lambda row, text: f"{path}:{lines()[row]}: value {j + 1} (channel "
                                                                f"{channels[j][0]}): non-numeric value {text!r}")
               for j in range(n)]
    return columns, lines


def _constant_value(name, unit, text, path, lineno):
    """A header/constant value: SI float for known physical constants, float for numbers, else text."""
    try:
        value = float(text.replace("D", "E"))
    except ValueError:
        if name in _CONSTANT_KINDS:
            raise DataError(f"{path}:{lineno}: column 51: constant {name}: non-numeric value {text!r}") from None
        return text
    if not math.isfinite(value):
        raise DataError(f"{path}:{lineno}: column 51: constant {name}: {text.strip()[:40]!r} is not a finite number")
    if name in _CONSTANT_KINDS:
        ch = _CONSTANT_KINDS[name]
        try:
            value *= unit_to_si(ch, unit or _SI_NAME[CHANNELS[ch][0]])
        except ValueError as exc:
            raise DataError(f"{path}:{lineno}: columns 41-50: constant {name}: {exc}") from None
    return value


def write_tydex(data: TyreData, path, *, overwrite: bool = False) -> Path:
    """Write ``data`` as a TYDEX file in SI units (factor 1, offsets 0); every canonical channel present.

    Never replaces the file the data were read from; an existing ``path`` needs ``overwrite=True``
    (:class:`mftyre.files.OutputError`, a FileExistsError, otherwise)."""
    path = Path(path)
    source = Path(data.source) if data.source and Path(data.source).is_file() else None
    check_outputs({"path": path}, {"data.source": source}, overwrite=overwrite, option="overwrite=True")
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
    write_atomically(path, "\n".join(out) + "\n")
    return path


# ------------------------------------------------------------------------------ tyre test consortium
#: Channels of the Calspan tyre test consortium (TTC) files -> canonical channel; ``ET`` becomes ``TIME`` [s];
#: other channels (NFX NFY normalised forces, RST TSTI TSTC TSTO AMBTMP temperatures, SR ...) are kept as they are.
TTC_CHANNELS = {"FX": "FX", "FY": "FY", "FZ": "FZ", "MX": "MX", "MZ": "MZ", "SA": "SA", "IA": "IA", "SL": "SL",
                "V": "VX", "P": "P", "N": "OMEGA", "RL": "RL", "RE": "RE"}
#: Units of the metric TTC files, used when a .mat file states none.
TTC_METRIC_UNITS = {"ET": "s", "V": "kph", "N": "rpm", "SA": "deg", "IA": "deg", "RL": "cm", "RE": "cm", "P": "kPa",
                    "FX": "N", "FY": "N", "FZ": "N", "MX": "N-m", "MZ": "N-m", "SL": "-"}


def read_ttc(path, *, columns: dict | None = None, axes: str = "SAE", defaults: dict | None = None,
             check: bool = True, max_bytes: int = DATA_MAX_BYTES) -> TyreData:
    """Read a Calspan tyre test consortium (TTC) run: a ``.dat`` text file (a free header line, a row of
    channel names, a row of units, then whitespace-separated samples) or a ``.mat`` file holding the same
    channels as vectors (MATLAB 5 format; units from its ``channel`` struct when present, else
    :data:`TTC_METRIC_UNITS`). The format is recognised by content. Channels map by :data:`TTC_CHANNELS` with
    their units converted to SI (``kph``, ``mph``, ``deg``, ``cm``, ``in``, ``kPa``, ``psi``, ``N``, ``lb``,
    ``N-m``, ``ft-lb``, ``rpm``); ``ET`` is kept as ``TIME`` so the programme recogniser sees a time series. The
    files use SAE axes (``axes="SAE"``: FZ < 0 under load; see :data:`AXES_HELP`). ``defaults`` and ``check``
    as for :func:`read_csv`. ``columns``: file channel -> canonical channel for a channel the default map does not
    give, e.g. ``{"SR": "SL"}`` for a run that records the slip ratio only as SR (the default channel of that
    canonical channel is then kept as an extra column, ``TTC_SL``)."""
    path = Path(path)
    raw = read_user_file(path, max_bytes=max_bytes, what="TTC data file", error=DataError)
    if raw.startswith(b"MATLAB"):
        channels, units, description = _ttc_mat(raw, path, max_bytes)
        locate = lambda row: f"{path}: sample {row + 1}"  # noqa: E731
    else:
        channels, units, first, description = _ttc_dat(raw, path)
        locate = lambda row: f"{path}:{first + row}"  # noqa: E731
    mapping = _ttc_mapping(list(channels), columns, path)
    out, column_of, unit_record = {}, {}, {}
    for name, values in channels.items():
        ch = mapping.get(name)
        unit = units.get(name, TTC_METRIC_UNITS.get(name.upper(), ""))
        if name.upper() == "ET":
            try:
                factor = float(UNIT_FACTORS["TIME"][unit.strip().lower() or "s"])
            except KeyError:
                raise DataError(f"{path}: channel ET: unknown time unit {unit!r}; expected s, ms, min") from None
            out["TIME"] = values * factor
            continue
        if ch is None:  # an extra column; a default channel replaced through ``columns`` keeps a distinct name
            out[f"TTC_{name}" if name.upper() in CHANNELS else name] = values
            continue
        if ch in column_of:
            raise DataError(f"{path}: channel {name} appears twice (also as {column_of[ch]})")
        try:
            factor = unit_to_si(ch, unit or _SI_NAME[CHANNELS[ch][0]])
        except ValueError as exc:
            raise DataError(f"{path}: channel {name}: {exc}") from None
        out[ch] = values * factor
        column_of[ch] = name
        unit_record[ch] = unit
    frame = pd.DataFrame(out, copy=False)
    if "OMEGA" in frame.columns:  # N is the spin speed, positive rolling forward in every axis system
        frame["OMEGA"] = frame["OMEGA"].abs()
    _convert_axes(frame, axes, path)
    _apply_defaults(frame, defaults, path, column_of)
    if "SL" not in frame.columns and "SR" in frame.columns:
        raise DataError(f"{path}: no SL channel (slip ratio); the file has SR: name it with "
                        f"{remedy('columns', 'SL', 'SR')} or give a constant")
    _check_required(frame, path, locate, column_of)
    if check:
        check_plausible(frame, str(path), column_of, constants=defaults, stated="the channel struct of the .mat file, else the metric TTC "
                        "units" if raw.startswith(b"MATLAB") else "the units row below the channel names")
    return TyreData(frame, tyre=description or path.stem, source=str(path), units=unit_record,
                    history=[f"TTC run read from {path.name}"] + _import_notes(axes, None, defaults, check))


def _ttc_mapping(names, columns, path) -> dict:
    """File channel -> canonical channel: :data:`TTC_CHANNELS`, with ``columns`` (file channel -> canonical)
    taking precedence; a canonical channel given by ``columns`` is no longer taken from its default channel."""
    mapping = {n: TTC_CHANNELS[n.upper()] for n in names if n.upper() in TTC_CHANNELS}
    for col, ch in (columns or {}).items():
        if col not in names:
            raise DataError(f"{path}: channel {col!r} (for {ch}) not in the file; its channels are {', '.join(names)}")
        if str(ch).upper() not in CHANNELS:
            raise DataError(f"{path}: unknown channel {ch!r} for {col!r}; channels: {', '.join(CHANNELS)}")
        mapping = {n: c for n, c in mapping.items() if c != ch.upper()}
        mapping[col] = ch.upper()
    return mapping


def _ttc_dat(raw: bytes, path):
    """(channel -> values, channel -> unit, file line of the first sample) of a TTC .dat file. The lines before
    the samples are decoded from the file's first MiB; the samples go to pandas' C parser from the bytes as read
    (no decoded copy, no list of lines: the memory of a large run is the bytes plus its table)."""
    head = raw[:1 << 20]
    try:
        text = head.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        text = head[:exc.start].decode("utf-8-sig") if exc.start > len(head) - 4 else head.decode("latin-1")
    breaks = [m.end() for _, m in zip(range(8), re.finditer(rb"\r\n|\r|\n", head))]  # bytes after each line end
    lines = re.split(r"\r\n|\r|\n", text)[:6]
    at = _ttc_names_line(lines)
    if at is None:
        raise DataError(f"{path}: not a TTC run file: expected a header line, a row of channel names (ET V N SA IA "
                        "... FZ) and a row of units before the samples")
    names, units = _ttc_fields(lines[at]), _ttc_fields(lines[at + 1])
    _refuse_wide(len(names), path, f"line {at + 1}: ")
    seen: dict[str, int] = {}
    for j, name in enumerate(names, start=1):
        if name.upper() in seen:
            raise DataError(f"{path}:{at + 1}: channel {name} is named twice (columns {seen[name.upper()]} and {j}): "
                            "expected one column per channel")
        seen[name.upper()] = j
    if len(units) != len(names):
        raise DataError(f"{path}:{at + 2}: {len(units)} units for {len(names)} channels: expected one unit per "
                        f"channel named on line {at + 1}")
    body = io.BytesIO(raw)  # shares the bytes
    body.seek(breaks[at + 1] if len(breaks) > at + 1 else len(raw))
    single_cr = b"\n" not in head and b"\r" in head  # lines ended by CR alone
    try:
        table = pd.read_csv(body, sep=r"\s+", header=None, names=range(len(names) + 1), encoding="latin-1",
                            keep_default_na=False, na_values=_NAN_TEXT, skip_blank_lines=True,
                            **({"lineterminator": "\r"} if single_cr else {}))
    except pd.errors.EmptyDataError:
        table = pd.DataFrame(columns=range(len(names) + 1))
    except (pd.errors.ParserError, ValueError) as exc:
        raise DataError(f"{path}: cannot read the samples: {exc}") from None
    if len(table) == 0:
        raise DataError(f"{path}: no samples after the units row (line {at + 2})")
    first = at + 3
    if table[len(names)].notna().any() or table[len(names) - 1].isna().any():
        row = int(np.flatnonzero((table[len(names)].notna() | table[len(names) - 1].isna()).to_numpy())[0])
        raise DataError(f"{path}: sample {row + 1} (after line {at + 2}): expected {len(names)} values, one per "
                        "channel")
    columns = {}
    for j, name in enumerate(names):
        columns[name] = _numeric_column(table[j], lambda row, txt: f"{path}: sample {row + 1} (after line {at + 2}): "
                                                                 f"channel {name}: non-numeric value {txt!r}")
    return columns, dict(zip(names, units)), first, " ".join(ln.strip() for ln in lines[:at] if ln.strip())


def _ttc_fields(line: str) -> list[str]:
    """The fields of a names or units row: tab-separated when the row has tabs (a unit may hold a blank, as in
    ``deg C``), else separated by blanks."""
    if "\t" not in line:
        return line.split()
    fields = [f.strip() for f in line.rstrip("\r\n").split("\t")]
    while fields and not fields[-1]:
        fields.pop()
    return fields


def _ttc_names_line(lines) -> int | None:
    """Index of the channel-name row among the first lines (names such as ET, FZ, SA; the next row units)."""
    for i in range(min(3, len(lines) - 1)):
        names = {n.upper() for n in lines[i].split()}
        if {"FZ", "SA"} <= names or {"FZ", "SL"} <= names:
            if not any(_is_number(u) for u in lines[i + 1].split()):
                return i
    return None


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _mat_expands_within(raw: bytes, path, max_bytes: int) -> None:
    """DataError when the variables of the MATLAB 5 file ``raw`` take more than ``max_bytes`` once decompressed (a
    file of a few MB can expand to many GB), found before any is read whole: each compressed element is inflated
    in 1 MiB pieces that are counted and dropped. Elements: an 8-byte tag (type, byte count; a small element holds
    its data in the tag), data padded to 8 bytes unless compressed (type 15); a damaged file is left to scipy."""
    import zlib

    order = "<" if raw[126:128] == b"IM" else ">"
    at, total = 128, 0
    while at + 8 <= len(raw):
        kind, size = np.frombuffer(raw, f"{order}u4", 2, at)
        kind, size = int(kind), int(size)
        if kind >> 16:  # small data element: the data sit in the tag
            at += 8
            continue
        body = memoryview(raw)[at + 8:at + 8 + size]
        if kind == 15:
            inflate = zlib.decompressobj()
            try:
                for start in range(0, len(body), 1 << 16):
                    piece = body[start:start + (1 << 16)]
                    while piece and total <= max_bytes:
                        total += len(inflate.decompress(piece, 1 << 20))
                        piece = inflate.unconsumed_tail
                    if total > max_bytes or inflate.eof:
                        break
            except zlib.error:
                return  # damaged: scipy names it
            at += 8 + size
        else:
            total += size
            at += 8 + size + (-size % 8)
        if total > max_bytes:
            raise DataError(f"{path}: its variables expand to more than {max_bytes:,} bytes once decompressed (the "
                            f"limit of a measurement file, compressed or not): not read; split the run into smaller "
                            "files")


def _ttc_mat(raw: bytes, path, max_bytes: int = DATA_MAX_BYTES):
    """(channel -> values, channel -> unit) of a TTC .mat file (vectors named after the channels)."""
    import scipy.io

    _mat_expands_within(raw, path, max_bytes)
    try:
        mat = scipy.io.loadmat(io.BytesIO(raw), squeeze_me=True, struct_as_record=False)
    except Exception as exc:  # scipy raises several kinds for a damaged file
        raise DataError(f"{path}: cannot read as a MATLAB .mat file: {exc}") from None
    units = {}
    channel = mat.get("channel")  # one struct with name and units arrays, or an array of structs
    if channel is not None and hasattr(channel, "name") and hasattr(channel, "units"):
        units = {str(n): str(u) for n, u in zip(np.atleast_1d(channel.name), np.atleast_1d(channel.units))}
    elif isinstance(channel, np.ndarray) and channel.dtype == object:
        units = {str(c.name): str(c.units) for c in channel.ravel() if hasattr(c, "name") and hasattr(c, "units")}
    columns, length = {}, None
    for name, value in mat.items():
        if name.startswith("__") or not isinstance(value, np.ndarray) or value.dtype.kind not in "fiu" \
                or value.ndim != 1 or value.size < 2:
            continue
        if length is not None and value.size != length:
            raise DataError(f"{path}: variable {name} has {value.size} samples, others {length}: expected channels "
                            "of equal length")
        length = value.size
        columns[name] = value.astype(float)
        _refuse_wide(len(columns), path, "variables: ")
    if "FZ" not in {n.upper() for n in columns}:
        raise DataError(f"{path}: no channel FZ among the .mat variables ({', '.join(columns) or 'none'}): "
                        "expected a TTC run (vectors ET, V, N, SA, IA, ..., FZ)")
    text = [str(mat[k]).strip() for k in ("tireid", "testid") if isinstance(mat.get(k), str) and str(mat[k]).strip()]
    return columns, units, "; ".join(text)


def data_format(path) -> str:
    """The format of a measurement file by its content: ``"tydex"``, ``"ttc"`` (.dat or .mat) or ``"csv"``."""
    with open_user_file(path, max_bytes=DATA_MAX_BYTES, what="measurement file", error=DataError) as fh:
        head = fh.read(4096)
    if head.startswith(b"MATLAB"):
        return "ttc"
    if b"\0" in head or head.startswith((b"PK\x03\x04", b"\xd0\xcf\x11\xe0")):
        kind = {b"PK": "a ZIP archive such as .xlsx", b"\xd0\xcf": "an OLE file such as .xls"}.get(head[:2], "binary")
        raise DataError(f"{path}: unknown data format ({kind}): expected a TYDEX, TTC (.dat text or MATLAB .mat) or "
                        "CSV file; export spreadsheets as CSV")
    text = head.decode("utf-8-sig", errors="replace")
    first = next((ln.strip() for ln in text.splitlines() if ln.strip() and not ln.strip().startswith("!")), "")
    if first.startswith("**"):
        return "tydex"
    lines = text.replace("\r", "\n").split("\n")[:6]
    at = _ttc_names_line([ln for ln in lines if ln.strip()])
    if at is not None and "," not in [ln for ln in lines if ln.strip()][at]:
        return "ttc"
    return "csv"


def read_data(path, *, columns: dict | None = None, units: dict | None = None, axes: str | None = None,
              defaults: dict | None = None, check: bool = True, max_bytes: int = DATA_MAX_BYTES, drop=(),
              drop_implausible: bool = False) -> TyreData:
    """Read a measurement file of any supported format (recognised by content, :func:`data_format`): TYDEX,
    TTC (.dat / .mat) or CSV. ``columns`` is for CSV and TTC, ``units`` for CSV (the other formats name their
    channels and units); ``axes`` is the file's axis system (default: ISO-W, SAE for TTC files); ``defaults`` are
    constant channels; ``check`` refuses implausible values (:func:`check_plausible`). The one home of the
    options of ``mftyre fit``, ``gaps`` and ``plot`` (``--columns``, ``--units``, ``--axes``, ``--set``).
    ``drop``: channels left out before the check (``--drop RE``); ``drop_implausible``: a channel of
    :data:`OPTIONAL_CHANNELS` that fails the check is left out with a warning in ``history`` (``"warning: ..."``,
    the diagnosis: garbage or the unit it looks like) instead of refusing the file."""
    drop = tuple(_channel(c, "drop") for c in drop)
    if drop or drop_implausible:
        return _read_dropping(path, drop, drop_implausible, columns=columns, units=units, axes=axes,
                              defaults=defaults, check=check, max_bytes=max_bytes)
    kind = data_format(path)
    if kind == "tydex" and (columns or units) or kind == "ttc" and units:
        which = ("--columns/--units" if kind == "tydex" else "--units") if speaking() == "cli" else \
            ("columns=/units=" if kind == "tydex" else "units=")
        raise DataError(f"{path}: a {'TYDEX' if kind == 'tydex' else 'TTC'} file names its channels and units; "
                        f"{which} are for CSV files" + (" (--columns maps TTC channels, e.g. SL=SR)"
                                                        if kind == "ttc" and speaking() == "cli" else ""))
    if kind == "tydex":
        data = read_tydex(path, defaults=defaults, axes=axes or "ISO-W", check=check, max_bytes=max_bytes)
    elif kind == "ttc":
        data = read_ttc(path, columns=columns, defaults=defaults, axes=axes or "SAE", check=check,
                        max_bytes=max_bytes)
    else:
        data = read_csv(path, columns=columns, units=units, defaults=defaults, axes=axes or "ISO-W", check=check,
                        max_bytes=max_bytes)
    data.sha256 = file_sha256(path)
    return data


def _read_dropping(path, drop, drop_implausible, check, **options) -> TyreData:
    """:func:`read_data` leaving out the channels ``drop`` and, with ``drop_implausible``, those of
    :data:`OPTIONAL_CHANNELS` the plausibility check refuses (each named in a warning with its diagnosis)."""
    required = [c for c in drop if c in REQUIRED]
    if required:
        raise DataError(f"{path}: cannot drop {', '.join(required)}: a fit needs the channels {', '.join(REQUIRED)} "
                        "as inputs (missing channel otherwise; a constant channel is given with "
                        f"{spelled('defaults=', '--set')})")
    if not drop:  # the reader's own check first: its messages name the file's columns and where it states units
        try:
            return read_data(path, check=check, **options)
        except DataError as exc:
            failed = getattr(exc, "channels", {})
            if not (check and failed and set(failed) <= set(OPTIONAL_CHANNELS)):
                raise
    data = read_data(path, check=False, **options)
    data.history = [h for h in data.history if h != UNCHECKED]
    present = [c for c in drop if c in data.frame.columns]
    if present:
        data.frame = data.frame.drop(columns=present)
        data.history.append(f"channel(s) {', '.join(present)} left out on request")
    while check:
        try:
            check_plausible(data)
            break
        except DataError as exc:
            failed = getattr(exc, "channels", {})
            if not (drop_implausible and failed and set(failed) <= set(OPTIONAL_CHANNELS)):
                raise
            data.frame = data.frame.drop(columns=list(failed))
            data.history.append(f"warning: channel(s) {', '.join(failed)} left out (no fit stage needs them as an "
                                f"input; their stages are not fitted): {exc}")
    if not check:
        data.history.append(UNCHECKED)
    return data


def file_sha256(path) -> str:
    """SHA-256 (hex) of a regular file, read in 1 MiB blocks."""
    digest = hashlib.sha256()
    with open_user_file(path, max_bytes=DATA_MAX_BYTES, what="measurement file", error=DataError) as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


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


def noise_scales(prm) -> dict:
    """What the fractions of :data:`NOISE` are of, per channel: FNOMIN, FNOMIN x UNLOADED_RADIUS or 1 m."""
    fz0, r0 = prm.FNOMIN, prm.UNLOADED_RADIUS
    return {"FX": fz0, "FY": fz0, "FZ": fz0, "MX": fz0 * r0, "MY": fz0 * r0, "MZ": fz0 * r0, "RL": 1.0, "RHO": 1.0,
            "RE": 1.0}


def record_outputs(frame: pd.DataFrame, outputs) -> None:
    """Write the model's ``outputs`` (MFOutputs or a dict of arrays, lower-case names) into the measured output
    channels :data:`OUTPUTS` of ``frame``."""
    for ch in OUTPUTS:
        frame[ch] = np.asarray(outputs[ch.lower()], float)


def synthetic_data(frame: pd.DataFrame, prm, speed: float, source: str, note: str) -> TyreData:
    """Measurements made up from a model (parameters ``prm``) as TyreData: the channels in SI units, the .tir's
    constants (FNOMIN, NOMPRES, RFREE, NOMWIDTH) and the test ``speed`` (LONGVEL), ``note`` as its history."""
    consts = {"FNOMIN": float(prm.FNOMIN), "NOMPRES": float(prm.NOMPRES), "RFREE": float(prm.UNLOADED_RADIUS),
              "NOMWIDTH": float(prm.WIDTH), "LONGVEL": float(speed)}
    return TyreData(frame, tyre=Path(str(prm.source or "model")).stem, source=source,
                    units={c: _SI_NAME[CHANNELS[c][0]] for c in CHANNELS}, constants=consts, history=[note])


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
    fz0, p0 = prm.FNOMIN, prm.NOMPRES
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
    record_outputs(frame, res)
    frame["SWEEP"] = sweep
    rng = np.random.default_rng(seed)
    if noise:
        scale = noise_scales(prm)
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
    return synthetic_data(frame[order], prm, vx0, "trailer_programme", note)
