"""``mftyre soil FILE.tir --soil NAME [sweeps] [--csv F] [--plot F] [--overwrite]``: the tyre on soft soil on a grid
of operating points, printed, written and plotted like ``mftyre eval`` (same value syntax and units).

    from mftyre.soil.command import register
    register(subparsers)          # adds the 'soil' command; handler: run(args)
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from pathlib import Path

import numpy as np

__all__ = ["register", "run"]

#: sweep option -> (unit option of `mftyre eval` whose units it takes, help)
_SWEEPS = {
    "fz": ("fz", "vertical load [N]; kN allowed (default FNOMIN)"),
    "slip": ("kappa", "slip i = 1 - V/(omega Re) [-]; %% allowed (default 0.15)"),
    "alpha": ("alpha", "slip angle [rad]; deg allowed (default 0)"),
    "p": ("p", "inflation pressure [Pa]; bar, kPa, psi allowed (default INFLPRES)"),
    "vx": ("vx", "forward speed [m/s]; km/h allowed (default LONGVL)"),
}
_DEFAULT_OUTPUTS = ("sinkage", "contact_length", "motion_resistance", "drawbar_pull", "torque", "efficiency",
                    "flexible")


def _sweep_type(name):
    from ..cli import parse_sweep

    def convert(text):
        try:
            return dataclasses.replace(parse_sweep(_SWEEPS[name][0], text), name=name)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    convert.__name__ = f"{name} sweep"
    return convert


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


class _SweepAction(argparse.Action):
    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        namespace.sweep_order = [n for n in (namespace.sweep_order or []) if n != self.dest] + [self.dest]


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``soil`` command to an argparse subparsers object."""
    p = subparsers.add_parser(
        "soil", help="evaluate the tyre on soft soil (Bekker/Janosi-Hanamoto, flexible tyre) on a grid",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="""\
Evaluate the tyre of a .tir file on soft soil (mftyre.soil: Bekker pressure-sinkage, Janosi-Hanamoto shear,
Mohr-Coulomb strength, rigid or flexible tyre by the critical-pressure switch) on a grid of operating points.

Values as in `mftyre eval`: a value, a comma list or START:STOP:COUNT, with units (kN, %, deg, bar, km/h...);
a negative first value needs '=': --slip=-0.2:0.6:9. The grid is every combination in command-line order.
Slip i = 1 - V/(omega Re) with Re the tyre's rolling radius on hard ground (= kappa/(1+kappa)).
Soils: --soil NAME from the built-in table (mftyre/soil/soils.csv, with sources) or from --soil-file.
--csv writes every output (or --outputs), names suffixed by the SI unit; --plot draws the outputs against the
swept input with the most values (or --x). Existing output files need --overwrite.""",
        epilog="example: mftyre soil tir_files/agri_460_85R34_mf61.tir --soil sandy_loam --fz 25kN "
               "--slip 0%:60%:31 --p 1bar,1.3bar,1.6bar --plot dp.png")
    p.add_argument("file", metavar="FILE.tir", help="tyre property file")
    p.add_argument("--soil", required=True, metavar="NAME", help="soil name (built-in or in --soil-file)")
    p.add_argument("--soil-file", metavar="SOILS.csv", help="CSV file of soils (columns name,n,k_c,k_phi,c,phi,K)")
    group = p.add_argument_group("operating points (value, list V1,V2,... or range START:STOP:COUNT; units allowed)")
    for name, (_, text) in _SWEEPS.items():
        group.add_argument(f"--{name}", dest=name, type=_sweep_type(name), action=_SweepAction, metavar="SPEC",
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
    out.add_argument("--overwrite", action="store_true", help="replace existing --csv/--plot files")
    out.add_argument("-q", "--quiet", action="store_true", help="do not print the table")
    p.set_defaults(func=run, parser=p, sweep_order=None)
    return p


def run(args) -> int:
    from ..errors import MFTyreError
    from ..tir import same_file
    from .equations import OUTPUTS

    parser = args.parser
    swept = [n for n in (args.sweep_order or []) if getattr(args, n).values.size > 1]
    targets = [(opt, t) for opt, t in (("--csv", args.csv), ("--plot", args.plot)) if t is not None]
    for opt, target in targets:
        if same_file(Path(target), Path(args.file)):
            parser.error(f"argument {opt}: {target!r} is the input .tir file; choose another output file")
        if Path(target).exists() and not args.overwrite:
            parser.error(f"argument {opt}: {target!r} exists; pass --overwrite to replace it")
    if len(targets) == 2 and same_file(Path(args.csv), Path(args.plot)):
        parser.error("argument --plot: it is also the --csv file; choose two different files")
    if args.plot is not None and not swept:
        parser.error("argument --plot: nothing to plot; sweep at least one input (e.g. --slip 0%:60%:31)")
    if args.towed and args.slip is not None:
        parser.error("argument --towed: the towed wheel's slip is solved, not given; drop --slip")
    if args.x is not None and args.x not in swept:
        parser.error(f"argument --x: {args.x!r} is not swept; swept inputs: {', '.join(swept) or 'none'}")
    try:
        from .model import SoftSoilTyre
        from .soils import soil

        tyre = SoftSoilTyre(args.file, soil(args.soil, args.soil_file), slip_sinkage=args.slip_sinkage,
                            bulldozing_depth=args.bulldozing_depth)
        prm = tyre.params
        defaults = dict(fz=prm.FNOMIN, slip=0.15, alpha=0.0, p=prm.INFLPRES, vx=prm.LONGVL)
        grids = dict(zip(swept, np.meshgrid(*(getattr(args, n).values for n in swept), indexing="ij")))
        shape = tuple(getattr(args, n).values.size for n in swept)
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
            print(f"# {args.file} on {tyre.soil.name} ({tyre.soil.source}); {max(1, math.prod(shape))} point(s)")
            print("# " + "; ".join(fixed))
            print(_frame(args, out, swept, shape, columns, OUTPUTS).to_string(
                index=False, float_format=lambda v: f"{v:.6g}"))
        for _, target in targets:
            Path(target).parent.mkdir(parents=True, exist_ok=True)
        if args.csv is not None:
            frame = _frame(args, out, swept, shape, args.outputs or tuple(OUTPUTS), OUTPUTS)
            frame.to_csv(args.csv, index=False)
            print(f"wrote {args.csv} ({len(frame)} rows, {frame.shape[1]} columns)", file=sys.stderr)
        if args.plot is not None:
            _plot(args, tyre, out, swept, shape, columns, OUTPUTS)
            print(f"wrote {args.plot}", file=sys.stderr)
    except MFTyreError as exc:
        print(f"mftyre soil: error: {exc}", file=sys.stderr)
        return 1
    except OSError as exc:
        print(f"mftyre soil: error: cannot write output: {exc}", file=sys.stderr)
        return 1
    return 0


def _unit(name):
    from ..cli import _SWEEPS as EVAL_SWEEPS

    return EVAL_SWEEPS[_SWEEPS[name][0]][0]


def _frame(args, out, swept, shape, outputs, units):
    import pandas as pd

    size = max(1, math.prod(shape))
    cols = {}
    grids = np.meshgrid(*(getattr(args, s).values for s in swept), indexing="ij") if swept else []
    for name, grid in zip(swept, grids):
        cols[f"{name} [{_unit(name)}]"] = grid.ravel()
    for name in outputs:
        label = f"{name}_out" if name in swept else name
        cols[f"{label} [{units[name][0]}]"] = np.broadcast_to(out[name], shape).reshape(size)
    return pd.DataFrame(cols)


def _plot(args, tyre, out, swept, shape, outputs, units):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    xname = args.x or max(swept, key=lambda n: (shape[swept.index(n)], -swept.index(n)))
    ix = swept.index(xname)
    xs = getattr(args, xname)
    others = [n for n in swept if n != xname]
    combos = list(np.ndindex(*(shape[swept.index(n)] for n in others))) if others else [()]
    labels = [", ".join(getattr(args, n).label(getattr(args, n).values[i]) for n, i in zip(others, c))
              for c in combos]
    ncols = 1 if len(outputs) <= 2 else 2
    nrows = math.ceil(len(outputs) / ncols)
    fig = Figure(figsize=(5.0 * ncols, 2.6 * nrows + 0.6), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, sharex=True, squeeze=False).ravel()
    x = xs.values / xs.factor
    for k, name in enumerate(outputs):
        y = np.moveaxis(np.broadcast_to(out[name], shape), ix, -1).reshape(-1, x.size)
        for row, label in zip(y, labels):
            axes[k].plot(x, row, label=label or None, lw=1.2)
        axes[k].set_ylabel(f"{name} [{units[name][0]}]")
        axes[k].set_title(units[name][1], fontsize=9)
        axes[k].grid(True, lw=0.3)
        axes[k].set_xlabel(f"{xname} [{xs.unit}]")
        axes[k].tick_params(labelbottom=True)
    for ax in axes[len(outputs):]:
        ax.set_visible(False)
    if others and len(combos) <= 12:
        axes[0].legend(fontsize=7)
    fig.suptitle(f"{Path(args.file).name} on {tyre.soil.name}", fontsize=10)
    path = Path(args.plot)
    fmt = path.suffix[1:].lower() if path.suffix[1:].lower() in fig.canvas.get_supported_filetypes() else "png"
    fig.savefig(path, format=fmt)
