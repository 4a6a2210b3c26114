"""The value syntax of the command line, shared by every command: sweep values with units (``4kN``,
``-10deg:10deg:21``), bounded numbers, and the options that say how to read a measurement file. Commands import
from here; :mod:`mftyre.cli` only assembles them (no command imports the command line back)."""

from __future__ import annotations

import argparse
import math
import re
from dataclasses import dataclass

import numpy as np

__all__ = ["SWEEP_UNITS", "MAX_POINTS", "Sweep", "parse_sweep", "sweep_type", "number_type", "SweepAction",
           "sweep_option", "join_negative_values", "DATA_HELP", "add_data_options", "data_epilog", "read_data_args",
           "progress_printer", "command_parser", "closing_options", "command_error", "refused_outputs",
           "set_parameters"]


# Sweep inputs of `mftyre eval`: name -> (SI unit, {accepted unit (lower case): factor to SI}).
SWEEP_UNITS: dict[str, tuple[str, dict[str, float]]] = {
    "fz": ("N", {"n": 1.0, "kn": 1e3, "lbf": 4.4482216152605, "lb": 4.4482216152605}),
    "kappa": ("-", {"-": 1.0, "%": 1e-2}),
    "alpha": ("rad", {"rad": 1.0, "deg": math.pi / 180, "°": math.pi / 180}),
    "gamma": ("rad", {"rad": 1.0, "deg": math.pi / 180, "°": math.pi / 180}),
    "phit": ("1/m", {"1/m": 1.0, "/m": 1.0, "rad/m": 1.0, "1/km": 1e-3}),
    "vx": ("m/s", {"m/s": 1.0, "km/h": 1 / 3.6, "kph": 1 / 3.6, "mph": 0.44704}),
    "p": ("Pa", {"pa": 1.0, "kpa": 1e3, "mpa": 1e6, "bar": 1e5, "psi": 4.4482216152605 / 0.0254**2}),
    "omega": ("rad/s", {"rad/s": 1.0, "rpm": 2 * math.pi / 60}),
}
_EXAMPLES = {"fz": "3kN,5kN", "kappa": "-10%:10%:21", "alpha": "-10deg:10deg:21", "gamma": "-3deg,0deg,3deg",
             "phit": "0/m,0.1/m", "vx": "30km/h,60km/h", "p": "1.8bar,2.2bar", "omega": "100rpm,200rpm"}
_NUMBER = re.compile(r"\s*([+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?)\s*(.*?)\s*$")  # linear time
#: Most points `mftyre eval` evaluates in one call (a range's COUNT and the whole grid; about 2 GB of outputs).
MAX_POINTS = 10_000_000


@dataclass(frozen=True)
class Sweep:
    """The values of one sweep option: ``values`` in SI; ``unit``/``factor``: the unit the user wrote (for plot
    axes and legends; the SI unit when none or several were written), value_SI = value_in_unit * factor."""

    name: str
    values: np.ndarray
    unit: str
    factor: float
    plain: bool  # no unit written

    def label(self, value: float) -> str:
        unit = "" if self.unit == "-" else f" {self.unit}"
        return f"{self.name} = {value / self.factor:g}{unit}"


def units_hint(name: str) -> str:
    si, units = SWEEP_UNITS[name]
    spelled = {"n": "N", "kn": "kN", "pa": "Pa", "kpa": "kPa", "mpa": "MPa"}
    return ", ".join(spelled.get(u, u) for u in units)


def parse_sweep(name: str, text: str) -> Sweep:
    """Parse the value of a sweep option: ``VALUE``, ``V1,V2,...`` or ``START:STOP:COUNT`` (linspace, COUNT an
    integer >= 2); each value may carry a unit (``-10deg``, ``2.2bar``, ``4kN``, ``50km/h``). A value without
    a unit is SI. Raises ValueError with a message naming what was expected."""
    si, units = SWEEP_UNITS[name]
    syntax = f"a value, a comma list or START:STOP:COUNT, values in {si} or with a unit ({units_hint(name)})"
    text = text.strip()
    if not text:
        raise ValueError(f"empty value; expected {syntax}")

    def quantity(item: str):
        m = _NUMBER.fullmatch(item)
        if not m or not item.strip():
            raise ValueError(f"cannot read {item.strip()!r} as a number with an optional unit; expected {syntax}")
        number, unit = float(m.group(1)), m.group(2)
        if not unit:
            return number, None
        key = unit.lower().replace(" ", "")
        if key not in units:
            raise ValueError(f"unknown unit {unit!r} in {item.strip()!r}; {name} takes {units_hint(name)} "
                             f"(a plain number is {si})")
        return number, key

    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise ValueError(f"{text!r} has {len(parts)} ':'-separated fields; a range is START:STOP:COUNT")
        count_text = parts[2].strip()
        if not re.fullmatch(r"\d{1,30}", count_text) or int(count_text) < 2:
            raise ValueError(f"range {text[:60]!r}: COUNT must be an integer >= 2, got {count_text[:30]!r} "
                             "(START:STOP:COUNT gives COUNT equally spaced values from START to STOP)")
        if int(count_text) > MAX_POINTS:
            raise ValueError(f"range {text!r}: COUNT {int(count_text):,} is more than the {MAX_POINTS:,} points "
                             "mftyre eval evaluates in one call; for more, call MFModel.evaluate from Python in chunks")
        items = [quantity(parts[0]), quantity(parts[1])]
        count = int(count_text)
    else:
        raw = text.split(",")
        if any(not r.strip() for r in raw):
            raise ValueError(f"{text!r} has an empty item; expected {syntax}")
        items = [quantity(r) for r in raw]
        count = None
    written = {u for _, u in items}
    if None in written and len(written) > 1:
        raise ValueError(f"{text!r} mixes values with and without a unit; give the unit on every value, "
                         f"e.g. {_EXAMPLES[name]!r}")
    si_values = [v * (units[u] if u else 1.0) for v, u in items]
    if count is not None:
        values = np.linspace(si_values[0], si_values[1], count)
    else:
        values = np.asarray(si_values, dtype=float)
    if not np.all(np.isfinite(values)):
        raise ValueError(f"{text!r} is not finite")
    if len(written) == 1 and None not in written:
        (key,) = written
        shown = {"n": "N", "kn": "kN", "pa": "Pa", "kpa": "kPa", "mpa": "MPa", "/m": "1/m"}.get(key, key)
        return Sweep(name, values, shown, units[key], False)
    return Sweep(name, values, si, 1.0, None in written)


def sweep_type(name: str):
    def convert(text: str) -> Sweep:
        try:
            return parse_sweep(name, text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    convert.__name__ = f"{name} sweep"
    return convert


def number_type(low: float | None = None, high: float | None = None, *, integer: bool = False,
                open_low: bool = False, open_high: bool = False):
    """An argparse ``type``: a finite number (an integer when ``integer``) within ``low``..``high`` (bounds
    excluded when ``open_low``/``open_high``), else an error naming what was expected."""
    lo = "" if low is None else ("(" if open_low else "[") + f"{low:g}"
    hi = "" if high is None else f"{high:g}" + (")" if open_high else "]")
    expected = ("an integer" if integer else "a finite number") + (f" in {lo or '(-inf'}, {hi or 'inf)'}"
                                                                  if lo or hi else "")

    def convert(text: str):
        try:
            value = int(text) if integer else float(text)
        except ValueError:
            value = None
        if value is None or not math.isfinite(value) \
                or (low is not None and (value < low or (open_low and value == low))) \
                or (high is not None and (value > high or (open_high and value == high))):
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text[:40]!r}")
        return value

    convert.__name__ = "integer" if integer else "number"
    return convert


class SweepAction(argparse.Action):
    """Store the parsed sweep and remember the order of the sweep options on the command line."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        order = [n for n in (getattr(namespace, "sweep_order", None) or []) if n != self.dest]
        namespace.sweep_order = order + [self.dest]


def sweep_option(name: str) -> str:
    return "--" + name


def join_negative_values(argv: list[str]) -> list[str]:
    """``--alpha -0.2:0.2:41`` -> ``--alpha=-0.2:0.2:41``: argparse would take the value for an option."""
    options = {sweep_option(n) for n in SWEEP_UNITS}
    out, i = [], 0
    while i < len(argv):
        a = argv[i]
        if a == "--":
            out.extend(argv[i:])
            break
        if a in options and i + 1 < len(argv) and re.match(r"-[\d.]", argv[i + 1]):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


# ---------------------------------------------------------------------------------- reading DATA
DATA_HELP = """\
DATA: a TYDEX (.tdx), Calspan tyre test consortium (TTC .dat or .mat) or CSV file, recognised by content.
CSV: one header row, comma separated, one row per sample. Columns named FZ SA SL VX P (required), IA PHIT (0 when
absent), FX FY FZ MX MY MZ OMEGA RL RHO RE (measured outputs) and TIME are read as they are, in SI units (N, N m,
rad, m/s, Pa, rad/s, m); other names with --columns FZ=Load_N,SA=alpha, other units with
--units SA=deg,P=psi,VX=km/h,RL=mm, a run without a channel at a known value with --set P=1.6bar,IA=0. TTC files
name their channels and units (ET V N SA IA RL RE P FX FY FZ MX MZ ...) and are in SAE axes.
Values no tyre measurement has in SI units and ISO-W axes (|SA| > 1 rad, P < 20 kPa, VX > 100 m/s, RL > 2 m,
FZ mostly negative ...) are refused with the channel named and the option that converts them.
"""


def option_type(parse, name):
    def convert(text):
        from .data import DataError

        try:
            return parse(text)
        except (ValueError, DataError) as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    convert.__name__ = name
    return convert


def add_data_options(parser) -> None:
    """The options that say how to read a measurement file (``--columns``, ``--units``, ``--axes``, ``--set``);
    :func:`read_data_args` reads DATA with them (:func:`mftyre.data.read_data`)."""
    from .data import AXES, parse_channels, parse_columns, parse_constants, parse_units

    group = parser.add_argument_group("reading DATA (see the DATA section below)")
    group.add_argument("--columns", type=option_type(parse_columns, "column map"), metavar="CH=COLUMN,...",
                       help="file columns of the channels, e.g. FZ=Fz_N,SA=alpha (CSV; TTC: e.g. SL=SR)")
    group.add_argument("--units", type=option_type(parse_units, "units"), metavar="CH=UNIT,...",
                       help="units of the file's channels, e.g. SA=deg,P=psi,VX=km/h,RL=mm (CSV; default SI)")
    group.add_argument("--axes", choices=tuple(AXES), default=None,
                       help="axis system of the file (default ISO-W; SAE for TTC files); see below")
    group.add_argument("--set", dest="constants", type=option_type(parse_constants, "constant channels"),
                       metavar="CH=VALUE,...", help="constant channels the file lacks, e.g. P=1.6bar,IA=0")
    group.add_argument("--drop", type=option_type(parse_channels, "channels"), default=(), metavar="CH,...",
                       help="leave these channels of the file out, e.g. RE (a garbage channel); a fit also leaves "
                            "out, with a warning, a channel it does not need as an input that fails the check")
    group.add_argument("--no-check", action="store_true",
                       help="skip the plausibility check of the values (for tyres outside its ranges, e.g. aircraft "
                            "tyres above 100 m/s); units and axes are then as the options say, unchecked")


def data_epilog() -> str:
    from .data import AXES_HELP

    return DATA_HELP + "\n" + AXES_HELP


def read_data_args(args, path=None, drop_implausible: bool = False):
    """DATA (``args.data`` or ``path``) read with the options of :func:`add_data_options`; messages name the
    command-line options. ``--set`` values of .tir parameters (e.g. RIM_RADIUS=5in) are not channels: they are
    left for the command (:func:`set_parameters`)."""
    from .data import CHANNELS, read_data, speaking_cli

    constants = {k: v for k, v in (args.constants or {}).items() if k in CHANNELS} or None
    with speaking_cli():
        return read_data(path or args.data, columns=args.columns, units=args.units, axes=args.axes,
                         defaults=constants, check=not args.no_check, drop=getattr(args, "drop", ()) or (),
                         drop_implausible=drop_implausible)


def set_parameters(args) -> dict:
    """The .tir parameters given with ``--set`` (name -> SI value), e.g. ``--set RIM_RADIUS=5in``."""
    from .data import CHANNELS

    return {k: v for k, v in (args.constants or {}).items() if k not in CHANNELS}


def progress_printer(quiet: bool):
    """A function ``say(text)`` printing ``  [  t s] text`` on stderr, t the seconds since this call (nothing when
    ``quiet``): the progress lines of the long commands."""
    import sys
    import time

    t0 = time.perf_counter()

    def say(text: str) -> None:
        if not quiet:
            print(f"  [{time.perf_counter() - t0:6.1f} s] {text}", file=sys.stderr, flush=True)

    return say


# ------------------------------------------------------------------------------------ commands
def command_parser(subparsers, name: str, run, *, data: bool = False, **options) -> argparse.ArgumentParser:
    """The parser of the sub-command ``name``, handled by ``run`` (args -> exit status; ``args.parser`` is this
    parser). ``data``: the command reads a measurement file (the DATA section as its epilog, kept as written);
    ``options``: those of ``add_parser`` (help, description, epilog...)."""
    if data:
        options.update(epilog=data_epilog(), formatter_class=argparse.RawDescriptionHelpFormatter)
    parser = subparsers.add_parser(name, **options)
    parser.set_defaults(func=run, parser=parser)
    return parser


def closing_options(parser, *, overwrite: str, quiet: str | None = None, short_quiet: bool = False,
                    data: bool = False) -> None:
    """The options a command's list ends with: ``--overwrite`` (help ``overwrite``), ``--quiet`` (also ``-q`` with
    ``short_quiet``; help ``quiet``, none without it), then the options that read DATA (``data``,
    :func:`add_data_options`). ``parser``: a parser or an argument group."""
    parser.add_argument("--overwrite", action="store_true", help=overwrite)
    if quiet:
        parser.add_argument(*(("-q", "--quiet") if short_quiet else ("--quiet",)), action="store_true", help=quiet)
    if data:
        add_data_options(parser)


def command_error(command: str, message, status: int = 2) -> int:
    """Say ``mftyre COMMAND: MESSAGE`` on stderr and return the exit status ``status`` (2: a usage error, found
    before any work; 1: the work failed)."""
    import sys

    print(f"mftyre {command}: {message}", file=sys.stderr)
    return status


def refused_outputs(command: str, outputs: dict, inputs: dict | None = None, *, folders: dict | None = None,
                    overwrite: bool = False, prefix: str = "") -> int | None:
    """The output rule (:func:`mftyre.files.check_outputs`) before a command's work: None when its outputs may be
    written, else the exit status 2 after saying why (``mftyre COMMAND: PREFIX<reason>``)."""
    from .files import OutputError, check_outputs

    try:
        check_outputs(outputs, inputs, folders=folders, overwrite=overwrite)
    except OutputError as exc:
        return command_error(command, f"{prefix}{exc}")
    return None
