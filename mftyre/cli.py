"""Command-line interface: ``mftyre <command> ...``.

Commands
--------
check FILE.tir [FILE ...]   parse and validate property files; prints ``FILE:LINE: severity: message``
                            (``FILE: severity: message`` when no line applies) and a summary; exit status 1
                            when any file has an error, 0 otherwise.
eval FILE.tir [sweeps] [options]
                            evaluate the steady-state model on a grid of inputs; prints a table, optionally
                            writes a CSV file (``--csv``) and a PNG plot (``--plot``). See :func:`_add_eval`.

Every command follows the output rule of :mod:`mftyre.files` (one home, :func:`mftyre.files.check_outputs`,
checked before any work): an input is never overwritten, two outputs are never the same file, and an existing
output file (or a non-empty output folder) is replaced only with ``--overwrite``; a refusal exits with status 2.

Adding a command: write ``_add_<name>(subparsers)`` that creates the sub-parser and sets
``func=<handler>`` (a function ``(args) -> int``), and call it from :func:`build_parser`.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path


import numpy as np

from .errors import speaking_cli
from .grid_results import check_request, format_table, grid_frame, plot_grid, sweep_grid, write_results

__all__ = ["main", "build_parser"]


# ---------------------------------------------------------------------------------------------- check
def _add_check(sub) -> None:
    p = sub.add_parser(
        "check",
        help="validate .tir property files",
        description="Parse and validate .tir property files: syntax, units, missing and unknown parameters, "
                    "suspicious values. Exit status 1 when any error is found.",
    )
    p.add_argument("files", nargs="+", metavar="FILE.tir", help="property file(s) to check")
    p.add_argument("-q", "--quiet", action="store_true", help="print errors only (and the summary)")
    p.set_defaults(func=_cmd_check)


def _cmd_check(args) -> int:
    from .tir import check_tir

    totals = {"error": 0, "warning": 0, "info": 0}
    bad_files = 0
    for path in args.files:
        findings = check_tir(path)
        if any(f.severity == "error" for f in findings):
            bad_files += 1
        for f in findings:
            totals[f.severity] = totals.get(f.severity, 0) + 1
            if args.quiet and f.severity != "error":
                continue
            loc = f"{path}:{f.line}:" if f.line is not None else f"{path}:"
            print(f"{loc} {f.severity}: {_strip_location(f.message, path)}")
    n = len(args.files)
    print(f"checked {n} file{'s' if n != 1 else ''}: {totals['error']} error(s), {totals['warning']} warning(s), "
          f"{totals['info']} info; {bad_files} file(s) with errors")
    return 1 if totals["error"] else 0


def _strip_location(message: str, path: str) -> str:
    """Parse-error messages start with 'FILE:LINE:'; the CLI prints the location itself."""
    import re

    prefix = f"{path}:"
    if not message.startswith(prefix):
        return message
    m = re.match(r"(\d+:)?\s*", message[len(prefix):])
    return message[len(prefix) + m.end():]


# ----------------------------------------------------------------------------------------------- eval
# Sweep inputs of `mftyre eval`: name -> (SI unit, {accepted unit (lower case): factor to SI}).
_SWEEPS: dict[str, tuple[str, dict[str, float]]] = {
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
#: Outputs printed when --outputs is not given.
_DEFAULT_OUTPUTS = ("fx", "fy", "mz", "mx", "my", "rl")
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


def _units_hint(name: str) -> str:
    si, units = _SWEEPS[name]
    spelled = {"n": "N", "kn": "kN", "pa": "Pa", "kpa": "kPa", "mpa": "MPa"}
    return ", ".join(spelled.get(u, u) for u in units)


def parse_sweep(name: str, text: str) -> Sweep:
    """Parse the value of a sweep option: ``VALUE``, ``V1,V2,...`` or ``START:STOP:COUNT`` (linspace, COUNT an
    integer >= 2); each value may carry a unit (``-10deg``, ``2.2bar``, ``4kN``, ``50km/h``). A value without
    a unit is SI. Raises ValueError with a message naming what was expected."""
    si, units = _SWEEPS[name]
    syntax = f"a value, a comma list or START:STOP:COUNT, values in {si} or with a unit ({_units_hint(name)})"
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
            raise ValueError(f"unknown unit {unit!r} in {item.strip()!r}; {name} takes {_units_hint(name)} "
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


def _sweep_type(name: str):
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


def _outputs_type(text: str) -> tuple[str, ...]:
    from .model import OUTPUT_UNITS

    names = [n.strip().lower() for n in text.split(",")]
    if names == ["all"]:
        return tuple(OUTPUT_UNITS)
    bad = [n for n in names if n not in OUTPUT_UNITS]
    if bad or not names:
        raise argparse.ArgumentTypeError(
            f"unknown output(s) {', '.join(repr(b) for b in bad)}; expected a comma list of "
            f"{', '.join(OUTPUT_UNITS)} (or 'all')")
    return tuple(dict.fromkeys(names))


class _SweepAction(argparse.Action):
    """Store the parsed sweep and remember the order of the sweep options on the command line."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        order = [n for n in (getattr(namespace, "sweep_order", None) or []) if n != self.dest]
        namespace.sweep_order = order + [self.dest]


def _sweep_option(name: str) -> str:
    return "--" + name


def _join_negative_values(argv: list[str]) -> list[str]:
    """``--alpha -0.2:0.2:41`` -> ``--alpha=-0.2:0.2:41``: argparse would take the value for an option."""
    options = {_sweep_option(n) for n in _SWEEPS}
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


def _add_eval(sub) -> None:
    p = sub.add_parser(
        "eval",
        help="evaluate the model on a grid of inputs (table, CSV, plot)",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="""\
Evaluate the steady-state Magic Formula of a .tir file on a grid of inputs (ISO-W axes, SI units).

Each input option takes a single value, a comma list (4000,6000) or START:STOP:COUNT (COUNT equally spaced
values, COUNT >= 2). Values may carry a unit: angles deg/rad, pressure bar/kPa/MPa/psi/Pa, load N/kN, speed
m/s, km/h, mph, spin rad/s or rpm, kappa '%', turn slip 1/m; a plain number is SI (p=220000 means Pa).
With several inputs swept the grid is every combination (outer product, in command-line order, the last
option varying fastest); the table has one row per point: the swept inputs as given, then the outputs.
An output that is also a swept input is shown as NAME_used (its value as used by the model, e.g. the
pressure after the .tir limits).

Defaults: fz = FNOMIN, kappa = alpha = gamma = phit = 0, vx = LONGVL, p = INFLPRES, omega estimated
from kappa and vx.

--csv writes the same columns with full precision, names suffixed by the SI unit: "fy [N]". Without
--outputs the CSV holds every output. --plot draws the outputs against the swept input with the most
values (or --x), one line per combination of the other swept inputs, in the units written on the
command line.""",
        epilog="example: mftyre eval tyre.tir --fz 3kN,4kN,5kN --alpha -10deg:10deg:41 --p 2.2bar --plot fy.png",
    )
    p.add_argument("file", metavar="FILE.tir", nargs="+",
                   help="tyre property file; several are evaluated on the same grid: one table each, one --csv with "
                        "a 'tir' column, one --plot with a line style per file")
    group = p.add_argument_group("inputs (value, list V1,V2,... or range START:STOP:COUNT; units allowed)")
    helps = {
        "fz": "vertical load [N]; kN, lbf allowed (default FNOMIN)",
        "kappa": "longitudinal slip [-], (omega Re - vx)/vx: -1 = locked wheel also for vx < 0; %% allowed "
                 "(default 0)",
        "alpha": "slip angle [rad]; deg allowed (default 0)",
        "gamma": "inclination angle [rad]; deg allowed (default 0)",
        "phit": "turn slip [1/m] (default 0)",
        "vx": "forward speed [m/s], negative rolling backwards; km/h, mph allowed (default LONGVL)",
        "p": "inflation pressure [Pa]; bar, kPa, MPa, psi allowed (default INFLPRES)",
        "omega": "wheel spin [rad/s]; rpm allowed (default: estimated from kappa and vx)",
    }
    for name in _SWEEPS:
        group.add_argument(_sweep_option(name), dest=name, type=_sweep_type(name), action=_SweepAction,
                           metavar="SPEC", help=helps[name])
    modes = p.add_argument_group("model options")
    modes.add_argument("--side", choices=("left", "right"), help="side the tyre is mounted on (default: TYRESIDE)")
    modes.add_argument("--turn-slip", action="store_true", help="switch the turn-slip model on")
    modes.add_argument("--alpha-star", action="store_true", help="use alpha* = tan(alpha) sign(Vx) (4.E3)")
    modes.add_argument("--no-limits", action="store_true", help="ignore the .tir input limits and low-speed model")
    modes.add_argument("--turn-slip-form", choices=("published", "mfeval"), default="published",
                       help="turn-slip equations as published (default) or as the MFeval reference evaluator")
    out = p.add_argument_group("output")
    out.add_argument("--outputs", type=_outputs_type, metavar="NAMES",
                     help="comma list of outputs to print/write/plot, or 'all' (default table and plot: "
                          f"{','.join(_DEFAULT_OUTPUTS)}; default CSV: all)")
    out.add_argument("--csv", metavar="OUT.csv", help="write the table as CSV (column names 'name [unit]')")
    out.add_argument("--plot", metavar="OUT.png", help="draw the outputs against the swept input, save as PNG")
    out.add_argument("--x", choices=tuple(_SWEEPS), help="swept input for the plot's x axis")
    out.add_argument("--overwrite", action="store_true", help="replace existing --csv/--plot files")
    out.add_argument("-q", "--quiet", action="store_true", help="do not print the table")
    p.set_defaults(func=_cmd_eval, parser=p, sweep_order=None)


def _cmd_eval(args) -> int:
    import warnings

    from .errors import MFTyreError

    parser = args.parser
    given = [n for n in (args.sweep_order or [])]
    swept = [n for n in given if getattr(args, n).values.size > 1]
    check_request(parser, args, swept, plot_example="--alpha -10deg:10deg:41")
    points = math.prod(getattr(args, n).values.size for n in swept)
    if points > MAX_POINTS:
        parser.error(f"the grid of {' x '.join(str(getattr(args, n).values.size) for n in swept)} = {points:,} points "
                     f"({', '.join('--' + n for n in swept)}) is more than the {MAX_POINTS:,} points mftyre eval "
                     "evaluates in one call; for more, call MFModel.evaluate from Python in chunks")
    if args.p is not None and args.p.plain and np.any(np.abs(args.p.values) < 1e3):
        print(f"mftyre eval: warning: --p {args.p.values.min():g} Pa is below 1 kPa: a plain number is pascal; "
              "write e.g. 2.2bar or 220kPa", file=sys.stderr)
    try:
        results = []  # (file, model, outputs) per FILE.tir
        for file in args.file:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                from .model import load_tir

                model = load_tir(file, side=args.side)
                inputs, shape = _eval_grid(args, swept, model.params)
                out = model.evaluate(**inputs, turn_slip=args.turn_slip, alpha_star=args.alpha_star,
                                     limits=not args.no_limits, turn_slip_form=args.turn_slip_form)
            for w in caught:
                print(f"mftyre eval: warning: {file}: {w.message}", file=sys.stderr)
            results.append((file, model, out))
        table_cols = args.outputs or _DEFAULT_OUTPUTS
        if not args.quiet:
            for file, model, out in results:
                print(_eval_header(args, file, model, given, swept, shape))
                print(format_table(_eval_frame(args, out, swept, shape, table_cols, model)))

        def table():
            frames = [_eval_frame(args, out, swept, shape, args.outputs or tuple(out.keys()), model)
                      for _, model, out in results]
            if len(results) == 1:
                return frames[0]
            import pandas as pd

            return pd.concat([f.assign(tir=Path(file).name)[["tir", *f.columns]]
                              for (file, _, _), f in zip(results, frames)], ignore_index=True)

        write_results(args, table, lambda: _eval_plot(args, results, swept, shape, args.outputs or _DEFAULT_OUTPUTS))
    except MFTyreError as exc:
        print(f"mftyre eval: error: {exc}", file=sys.stderr)
        return 1
    except OSError as exc:
        print(f"mftyre eval: error: cannot write output: {exc}", file=sys.stderr)
        return 1
    return 0


def _eval_grid(args, swept: list[str], prm) -> tuple[dict, tuple[int, ...]]:
    """The evaluate() inputs: swept inputs as an outer-product grid (command-line order, 'ij'), others scalar."""
    grid_of, shape = sweep_grid(args, swept)
    inputs = {}
    for name in _SWEEPS:
        sweep = getattr(args, name)
        if name in grid_of:
            inputs[name] = grid_of[name]
        elif sweep is not None:
            inputs[name] = float(sweep.values[0])
        elif name == "fz":
            inputs[name] = float(prm.FNOMIN)
        elif name in ("kappa", "alpha", "gamma", "phit"):
            inputs[name] = 0.0
        else:  # vx, p, omega: the model's defaults
            inputs[name] = None
    return inputs, shape


def _used(args, model, name, values):
    """The values of input ``name`` the model evaluated (saturated to the .tir range unless --no-limits)."""
    from .inputs import RANGE_PARAMETERS

    if args.no_limits or name not in RANGE_PARAMETERS:
        return np.asarray(values, dtype=float)
    return model.used_input(name, values)


def _eval_frame(args, out, swept: list[str], shape, outputs, model):
    """Swept inputs as given (and as used, where the .tir ranges saturated them), then the outputs; column names
    'name [SI unit]'."""
    from .model import OUTPUT_UNITS

    # a swept input that is also an output is shown as NAME_used: the model echoes kappa, alpha, gamma and fz as
    # asked (before the .tir ranges), so saturate the echo as the equations did
    out = {k: (_used(args, model, k, out[k]) if k in swept else out[k]) for k in out.keys()}
    return grid_frame(args, out, swept, shape, outputs, input_units={n: unit for n, (unit, _) in _SWEEPS.items()},
                      output_units=OUTPUT_UNITS, used=lambda name, values: _used(args, model, name, values))


def _used_note(args, model, name, value) -> str:
    used = float(_used(args, model, name, value))
    return "" if used == value else f" (used: {used:g}, the .tir range limit)"


def _eval_header(args, file, model, given, swept, shape) -> str:
    prm = model.params
    fixed = []
    for name in _SWEEPS:
        if name in swept:
            continue
        unit = _SWEEPS[name][0]
        sweep = getattr(args, name)
        if sweep is not None:
            fixed.append(f"{name} = {sweep.values[0]:g}" + ("" if unit == "-" else f" {unit}")
                         + _used_note(args, model, name, sweep.values[0]))
        elif name == "fz":
            fixed.append(f"fz = {prm.FNOMIN:g} N (FNOMIN)")
        elif name == "vx":
            fixed.append(f"vx = {prm.LONGVL:g} m/s (LONGVL)")
        elif name == "p":
            fixed.append(f"p = {prm.INFLPRES:g} Pa (INFLPRES)" + _used_note(args, model, name, prm.INFLPRES))
        elif name == "omega":
            fixed.append("omega from kappa and vx")
        else:
            fixed.append(f"{name} = 0")
    modes = [m for m, on in (("turn slip", args.turn_slip), ("alpha*", args.alpha_star),
                             ("no limits", args.no_limits)) if on]
    npts = int(np.prod(shape)) if shape else 1
    head = (f"# {file}: FITTYP {prm.fittyp}, mounted {model.side}; {npts} point{'s' * (npts != 1)}"
            f"{'; ' + ', '.join(modes) if modes else ''}")
    return head + "\n# " + "; ".join(fixed)


def _eval_plot(args, results, swept, shape, outputs) -> None:
    from .model import OUTPUT_UNITS

    _, model, out = results[0]
    def legend(n, value):  # the value used, and the one asked for where the .tir range saturated it
        sweep, used = getattr(args, n), float(_used(args, model, n, value))
        return sweep.label(used) + ("" if used == value else f" (asked {sweep.label(value).split(' = ')[1]})")

    if len(results) == 1:
        plot_grid(args, out, swept, shape, outputs, output_units=OUTPUT_UNITS, legend=legend,
                  title=f"{Path(results[0][0]).name} (FITTYP {model.params.fittyp}, {model.side})")
    else:  # legend values as the first file used them
        plot_grid(args, [(Path(f).name, o) for f, _, o in results], swept, shape, outputs, output_units=OUTPUT_UNITS,
                  legend=legend, title=f"{len(results)} tyres, mounted {model.side}")


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


def _option_type(parse, name):
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
    from .data import AXES, parse_columns, parse_constants, parse_units

    group = parser.add_argument_group("reading DATA (see the DATA section below)")
    group.add_argument("--columns", type=_option_type(parse_columns, "column map"), metavar="CH=COLUMN,...",
                       help="file columns of the channels, e.g. FZ=Fz_N,SA=alpha (CSV; TTC: e.g. SL=SR)")
    group.add_argument("--units", type=_option_type(parse_units, "units"), metavar="CH=UNIT,...",
                       help="units of the file's channels, e.g. SA=deg,P=psi,VX=km/h,RL=mm (CSV; default SI)")
    group.add_argument("--axes", choices=tuple(AXES), default=None,
                       help="axis system of the file (default ISO-W; SAE for TTC files); see below")
    group.add_argument("--set", dest="constants", type=_option_type(parse_constants, "constant channels"),
                       metavar="CH=VALUE,...", help="constant channels the file lacks, e.g. P=1.6bar,IA=0")
    group.add_argument("--no-check", action="store_true",
                       help="skip the plausibility check of the values (for tyres outside its ranges, e.g. aircraft "
                            "tyres above 100 m/s); units and axes are then as the options say, unchecked")


def data_epilog() -> str:
    from .data import AXES_HELP

    return DATA_HELP + "\n" + AXES_HELP


def read_data_args(args, path=None):
    """DATA (``args.data`` or ``path``) read with the options of :func:`add_data_options`; messages name the
    command-line options."""
    from .data import read_data, speaking_cli

    with speaking_cli():
        return read_data(path or args.data, columns=args.columns, units=args.units, axes=args.axes,
                         defaults=args.constants, check=not args.no_check)


# ------------------------------------------------------------------------------------------ (more)
# Other commands (fit, gaps, plot, fmu) are added here by their modules' authors and registered in
# build_parser() below.


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="mftyre", description="Magic Formula tyre model tools")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    _add_check(sub)
    _add_eval(sub)
    from .demo import register as register_demo
    from .fit.command import register as register_fit
    from .gaps.command import register as register_gaps
    from .fmu_command import register as register_fmu
    from .plot_command import register as register_plot
    from .swift_command import register as register_swift
    from .soil.command import register as register_soil

    register_demo(sub)
    register_fit(sub)
    register_gaps(sub)
    register_plot(sub)
    register_swift(sub)
    register_fmu(sub)
    register_soil(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line ``argv`` (default: sys.argv[1:]); returns the exit status."""
    parser = build_parser()
    argv = _join_negative_values(list(sys.argv[1:] if argv is None else argv))
    try:
        args = parser.parse_args(argv)
        with speaking_cli():  # messages name command-line options, not keyword arguments
            return int(args.func(args))
    except SystemExit as exc:  # argparse exits on --help and on usage errors (also raised by handlers)
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
