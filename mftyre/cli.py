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
import sys
from collections.abc import Sequence
from pathlib import Path


import numpy as np

from .arguments import (MAX_POINTS, SWEEP_UNITS, SweepAction, closing_options, command_error, command_parser,
                        join_negative_values, sweep_option, sweep_type)
from .errors import speaking_cli
from .grid_results import check_request, format_table, grid_columns, plot_grid, sweep_grid, write_results

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
#: Outputs printed when --outputs is not given.
_DEFAULT_OUTPUTS = ("fx", "fy", "mz", "mx", "my", "rl")


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


def _add_eval(sub) -> None:
    p = command_parser(
        sub, "eval", _cmd_eval,
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
    for name in SWEEP_UNITS:
        group.add_argument(sweep_option(name), dest=name, type=sweep_type(name), action=SweepAction,
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
    out.add_argument("--x", choices=tuple(SWEEP_UNITS), help="swept input for the plot's x axis")
    closing_options(out, overwrite="replace existing --csv/--plot files", quiet="do not print the table",
                    short_quiet=True)
    p.set_defaults(sweep_order=None)


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
                named = str(w.message).startswith(str(model.params.source))  # the message names the file already
                print(f"mftyre eval: warning: {'' if named else f'{file}: '}{w.message}", file=sys.stderr)
            results.append((file, model, out))
        table_cols = args.outputs or _DEFAULT_OUTPUTS
        if not args.quiet:
            for file, model, out in results:
                print(_eval_header(args, file, model, given, swept, shape))
                print(format_table(_eval_frame(args, out, swept, shape, table_cols, model)))

        def table():
            import pandas as pd

            frames = [pd.DataFrame(_eval_frame(args, out, swept, shape, args.outputs or tuple(out.keys()), model))
                      for _, model, out in results]
            if len(results) == 1:
                return frames[0]
            return pd.concat([f.assign(tir=Path(file).name)[["tir", *f.columns]]
                              for (file, _, _), f in zip(results, frames)], ignore_index=True)

        write_results(args, table, lambda: _eval_plot(args, results, swept, shape, args.outputs or _DEFAULT_OUTPUTS))
    except MFTyreError as exc:
        return command_error("eval", f"error: {exc}", 1)
    except OSError as exc:
        return command_error("eval", f"error: cannot write output: {exc}", 1)
    return 0


def _eval_grid(args, swept: list[str], prm) -> tuple[dict, tuple[int, ...]]:
    """The evaluate() inputs: swept inputs as an outer-product grid (command-line order, 'ij'), others scalar."""
    grid_of, shape = sweep_grid(args, swept)
    inputs = {}
    for name in SWEEP_UNITS:
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
    """The table's columns (name -> array): swept inputs as given (and as used, where the .tir ranges saturated
    them), then the outputs; column names 'name [SI unit]'."""
    from .model import OUTPUT_UNITS

    # a swept input that is also an output is shown as NAME_used: the model echoes kappa, alpha, gamma and fz as
    # asked (before the .tir ranges), so saturate the echo as the equations did
    out = {k: (_used(args, model, k, out[k]) if k in swept else out[k]) for k in out.keys()}
    return grid_columns(args, out, swept, shape, outputs, input_units={n: unit for n, (unit, _) in SWEEP_UNITS.items()},
                      output_units=OUTPUT_UNITS, used=lambda name, values: _used(args, model, name, values))


def _used_note(args, model, name, value) -> str:
    used = float(_used(args, model, name, value))
    return "" if used == value else f" (used: {used:g}, the .tir range limit)"


def _eval_header(args, file, model, given, swept, shape) -> str:
    prm = model.params
    fixed = []
    for name in SWEEP_UNITS:
        if name in swept:
            continue
        unit = SWEEP_UNITS[name][0]
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
    from .sweep import register as register_sweep

    register_demo(sub)
    register_fit(sub)
    register_gaps(sub)
    register_plot(sub)
    register_swift(sub)
    register_fmu(sub)
    register_soil(sub)
    register_sweep(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line ``argv`` (default: sys.argv[1:]); returns the exit status."""
    parser = build_parser()
    argv = join_negative_values(list(sys.argv[1:] if argv is None else argv))
    try:
        args = parser.parse_args(argv)
        with speaking_cli():  # messages name command-line options, not keyword arguments
            return int(args.func(args))
    except SystemExit as exc:  # argparse exits on --help and on usage errors (also raised by handlers)
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
