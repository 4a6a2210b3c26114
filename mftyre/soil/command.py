"""``mftyre soil FILE.tir --soil NAME [sweeps] [--csv F] [--plot F] [--overwrite]``: the tyre on soft soil on a grid
of operating points, printed, written and plotted like ``mftyre eval`` (same value syntax and units).

    from mftyre.soil.command import register
    register(subparsers)          # adds the 'soil' command; handler: run(args)
"""
from __future__ import annotations

import argparse
import dataclasses
import math
from pathlib import Path

__all__ = ["register", "run"]

#: sweep option -> (unit option of `mftyre eval` whose units it takes, help)
_SWEEPS = {
    "fz": ("fz", "vertical load [N]; kN, lbf allowed (default FNOMIN)"),
    "slip": ("kappa", "slip i = 1 - V/(omega Re) [-]; %% allowed (default 0.15)"),
    "alpha": ("alpha", "slip angle [rad]; deg allowed (default 0)"),
    "p": ("p", "inflation pressure [Pa]; bar, kPa, psi allowed (default INFLPRES)"),
    "vx": ("vx", "forward speed [m/s]; km/h allowed (default LONGVL)"),
}
_DEFAULT_OUTPUTS = ("sinkage", "contact_length", "motion_resistance", "drawbar_pull", "torque", "efficiency",
                    "flat_load")


def _sweep_type(name):
    from ..arguments import parse_sweep

    def convert(text):
        try:
            return dataclasses.replace(parse_sweep(_SWEEPS[name][0], text), name=name)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    convert.__name__ = f"{name} sweep"
    return convert


def _cone_index(text):
    scale = {"MPa": 1e6, "kPa": 1e3, "Pa": 1.0}
    unit = next((u for u in scale if text.endswith(u)), "Pa")
    try:
        value = float(text[:len(text) - len(unit)] if text.endswith(unit) else text) * scale[unit]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a cone index like 1.2MPa, 800kPa or 1.2e6 (Pa), got {text!r}")
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"the cone index must be positive, got {text!r}")
    return value


def _outputs_type(text):
    from .equations import OUTPUTS

    names = [n.strip() for n in text.split(",")]
    if names == ["all"]:
        return tuple(OUTPUTS)
    bad = [n for n in names if n not in OUTPUTS]
    if bad:
        raise argparse.ArgumentTypeError(f"unknown output(s) {', '.join(map(repr, bad))}; expected a comma list of "
                                         f"{', '.join(OUTPUTS)} (or 'all')")
    return tuple(dict.fromkeys(names))


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``soil`` command to an argparse subparsers object."""
    from ..arguments import SweepAction, closing_options, command_parser

    p = command_parser(
        subparsers, "soil", run, help="evaluate the tyre on soft soil (Bekker/Janosi-Hanamoto, deflecting tyre) on a grid",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="""\
Evaluate the tyre of a .tir file on soft soil (mftyre.soil: Bekker pressure-sinkage, Janosi-Hanamoto shear,
Mohr-Coulomb strength; the tyre deflects as its .tir says under the soil's pressure, the normal stress carries the
load and the shear works at the tread's slip velocity: energy-consistent) on a grid of operating points.

Values as in `mftyre eval`: a value, a comma list or START:STOP:COUNT, with units (kN, %, deg, bar, km/h...);
a negative first value needs '=': --slip=-0.2:0.6:9. The grid is every combination in command-line order.
Slip i = 1 - V/(omega Re) with Re the tyre's rolling radius on hard ground (= kappa/(1+kappa)).
Soils: --soil NAME from the built-in table (mftyre/soil/soils.csv, with sources) or from --soil-file.
--cone-index CI runs Brixius's cone-index equations (ASAE D497) instead of a soil table.
--csv writes every output (or --outputs), names suffixed by the SI unit; --plot draws the outputs against the
swept input with the most values (or --x). Existing output files need --overwrite.""",
        epilog="example: mftyre soil tir_files/agri_460_85R34_mf61.tir --soil sandy_loam --fz 25kN "
               "--slip 0%:60%:31 --p 1bar,1.3bar,1.6bar --plot dp.png")
    p.add_argument("file", metavar="FILE.tir", help="tyre property file")
    model = p.add_mutually_exclusive_group(required=True)
    model.add_argument("--soil", metavar="NAME", help="soil name (built-in or in --soil-file): the Bekker-Wong model")
    model.add_argument("--cone-index", type=_cone_index, metavar="CI",
                       help="cone index (Pa; kPa, MPa allowed): Brixius's cone-index model instead (mftyre.soil."
                            "ConeIndexTyre)")
    p.add_argument("--soil-file", metavar="SOILS.csv", help="CSV file of soils (columns name,n,k_c,k_phi,c,phi,K)")
    group = p.add_argument_group("operating points (value, list V1,V2,... or range START:STOP:COUNT; units allowed)")
    for name, (_, text) in _SWEEPS.items():
        group.add_argument(f"--{name}", dest=name, type=_sweep_type(name), action=SweepAction, metavar="SPEC",
                           help=text)
    effects = p.add_argument_group("options of the model (absent at their defaults)")
    effects.add_argument("--slip-sinkage", type=float, default=0.0, metavar="S",
                         help="slip-sinkage exponent s_j: sinkage x [(1+i)/(1-0.5i)]^s_j (1 = Lyasko; default 0)")
    effects.add_argument("--bulldozing-depth", type=float, default=math.inf, metavar="M",
                         help="rut depth [m] beyond which Bekker's bulldozing resistance acts (needs the soil's "
                              "gamma; default: none)")
    effects.add_argument("--towed", action="store_true",
                         help="solve the towed wheel (zero driving torque) instead of taking --slip")
    out = p.add_argument_group("output")
    out.add_argument("--outputs", type=_outputs_type, metavar="NAMES",
                     help=f"comma list of outputs, or 'all' (default table/plot: {','.join(_DEFAULT_OUTPUTS)})")
    out.add_argument("--csv", metavar="OUT.csv", help="write the table as CSV")
    out.add_argument("--plot", metavar="OUT.png", help="plot the outputs against the swept input")
    out.add_argument("--x", choices=tuple(_SWEEPS), help="swept input for the plot's x axis")
    closing_options(out, overwrite="replace existing --csv/--plot files", quiet="do not print the table",
                    short_quiet=True)
    p.set_defaults(sweep_order=None)
    return p


def run(args) -> int:
    from ..arguments import command_error
    from ..errors import MFTyreError
    from ..grid_results import check_request, format_table, sweep_grid, write_results
    from .equations import OUTPUTS

    parser = args.parser
    swept = [n for n in (args.sweep_order or []) if getattr(args, n).values.size > 1]
    check_request(parser, args, swept, plot_example="--slip 0%:60%:31")
    if args.towed and args.slip is not None:
        parser.error("argument --towed: the towed wheel's slip is solved, not given; drop --slip")
    if args.cone_index is not None and (args.slip_sinkage or math.isfinite(args.bulldozing_depth) or args.soil_file):
        parser.error("argument --cone-index: --slip-sinkage, --bulldozing-depth and --soil-file belong to the "
                     "Bekker-Wong model (--soil)")
    try:
        from .cone_index import ConeIndexTyre
        from .model import SoftSoilTyre
        from .soils import soil

        if args.cone_index is not None:
            tyre = ConeIndexTyre(args.file, args.cone_index)
        else:
            tyre = SoftSoilTyre(args.file, soil(args.soil, args.soil_file), slip_sinkage=args.slip_sinkage,
                                bulldozing_depth=args.bulldozing_depth)
        prm = tyre.params
        defaults = dict(fz=prm.FNOMIN, slip=0.15, alpha=0.0, p=prm.INFLPRES, vx=prm.LONGVL)
        grids, shape = sweep_grid(args, swept)
        inputs = {n: grids[n] if n in grids else (float(getattr(args, n).values[0]) if getattr(args, n) is not None
                                                  else defaults[n]) for n in _SWEEPS}
        if args.towed:
            out = tyre.towed(**{n: v for n, v in inputs.items() if n != "slip"})
        else:
            out = tyre.evaluate(**inputs)
        columns = args.outputs or (("slip", "omega", *_DEFAULT_OUTPUTS) if args.towed else _DEFAULT_OUTPUTS)
        if not args.quiet:
            fixed = [f"{n} = {inputs[n]:g} {'' if n == 'slip' else _unit(n)}".rstrip() for n in _SWEEPS
                     if n not in swept and not (args.towed and n == "slip")]
            if args.towed:
                fixed.append("towed (zero driving torque)")
            ground = (f"cone index {args.cone_index:g} Pa (Brixius)" if args.cone_index is not None
                      else f"{tyre.soil.name} ({tyre.soil.source})")
            print(f"# {args.file} on {ground}; {max(1, math.prod(shape))} point(s)")
            print("# " + "; ".join(fixed))
            print(format_table(_frame(args, out, swept, shape, columns)))
        write_results(args, lambda: _frame(args, out, swept, shape, args.outputs or tuple(OUTPUTS)),
                      lambda: _plot(args, tyre, out, swept, shape, columns))
    except MFTyreError as exc:
        return command_error("soil", f"error: {exc}", 1)
    except OSError as exc:
        return command_error("soil", f"error: cannot write output: {exc}", 1)
    return 0


def _unit(name):
    from ..arguments import SWEEP_UNITS as EVAL_SWEEPS

    return EVAL_SWEEPS[_SWEEPS[name][0]][0]


def _frame(args, out, swept, shape, outputs):
    from ..grid_results import grid_frame
    from .equations import OUTPUTS

    return grid_frame(args, out, swept, shape, outputs, input_units={n: _unit(n) for n in _SWEEPS},
                      output_units=OUTPUTS, repeated="_out")


def _plot(args, tyre, out, swept, shape, outputs):
    from ..grid_results import plot_grid
    from .equations import OUTPUTS

    ground = f"cone index {args.cone_index:g} Pa" if args.cone_index is not None else tyre.soil.name
    plot_grid(args, out, swept, shape, outputs, output_units=OUTPUTS, title=f"{Path(args.file).name} on {ground}")
