"""The results of a command evaluated on a grid of operating points (``mftyre eval``, ``mftyre soil``): the
table, the ``--csv`` file and the ``--plot`` figure, written under the output rule of :mod:`mftyre.files`.

A command's parsed ``args`` carry the sweeps (``Sweep`` objects of :mod:`mftyre.cli`, one attribute per input,
``None`` when not given) and ``file``, ``csv``, ``plot``, ``x``, ``overwrite``. ``swept`` lists the inputs
given several values, in command-line order; the grid is their outer product ('ij' indexing).
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from .files import OutputError, check_outputs, make_output_folder, write_figure, write_frame_csv

__all__ = ["check_request", "sweep_grid", "grid_columns", "grid_frame", "format_table", "plot_grid", "write_results"]


def check_request(parser, args, swept: list[str], *, plot_example: str) -> None:
    """Usage errors (``parser.error``, exit 2) before any work: --csv/--plot that :func:`mftyre.files.check_outputs`
    refuses (the input .tir, the same file twice, an existing file without --overwrite), a --plot with nothing
    swept (``plot_example``: a sweep option to suggest), an --x that is not swept."""
    files = args.file if isinstance(args.file, list) else [args.file]
    try:
        check_outputs({"--csv": args.csv, "--plot": args.plot}, {f"FILE.tir {f}": f for f in files},
                      overwrite=args.overwrite)
    except OutputError as exc:
        parser.error(str(exc))
    if args.plot is not None and not swept:
        parser.error(f"argument --plot: nothing to plot; sweep at least one input over several values "
                     f"(e.g. {plot_example})")
    if args.x is not None and args.x not in swept:
        parser.error(f"argument --x: {args.x!r} is not swept; swept inputs: {', '.join(swept) or 'none'}")


def sweep_grid(args, swept: list[str]) -> tuple[dict[str, np.ndarray], tuple[int, ...]]:
    """The swept inputs as an outer-product grid (name -> array of the grid's shape) and that shape."""
    grids = np.meshgrid(*(getattr(args, n).values for n in swept), indexing="ij") if swept else []
    return dict(zip(swept, grids)), tuple(getattr(args, n).values.size for n in swept)


def grid_frame(args, out, swept: list[str], shape, outputs, **options):
    """:func:`grid_columns` as a pandas DataFrame (the ``--csv`` table)."""
    import pandas as pd

    return pd.DataFrame(grid_columns(args, out, swept, shape, outputs, **options))


def grid_columns(args, out, swept: list[str], shape, outputs, *, input_units: dict, output_units: dict,
                 used=None, repeated: str = "_used") -> dict[str, np.ndarray]:
    """One row a grid point: the swept inputs as given, then ``outputs``; columns 'name [SI unit]'
    (``input_units``: input -> unit, ``output_units``: output -> (unit, meaning)), as a dict of column -> array.

    ``used(name, values)``: the values the model evaluated; where they differ from those given, a column
    'name_used' follows the input (unless it is also an output). An output named like a swept input is
    labelled name + ``repeated``."""
    size = max(1, math.prod(shape))
    cols = {}
    for name, grid in sweep_grid(args, swept)[0].items():
        given = grid.ravel()
        cols[f"{name} [{input_units[name]}]"] = given
        evaluated = given if used is None else used(name, given)
        if not np.array_equal(evaluated, given) and name not in outputs:
            cols[f"{name}_used [{input_units[name]}]"] = evaluated
    for name in outputs:
        label = f"{name}{repeated}" if name in swept else name
        cols[f"{label} [{output_units[name][0]}]"] = np.broadcast_to(out[name], shape).reshape(size)
    return cols


def format_table(table) -> str:
    """The table (a dict column -> values, or a DataFrame) as printed on the terminal: right-aligned columns, numbers
    to 6 significant digits. Plain Python, so that `mftyre eval` of one point does not import pandas."""
    if hasattr(table, "columns"):
        table = {name: table[name].to_numpy() for name in table.columns}
    cells = [[str(name), *(v if isinstance(v, str) else f"{v:.6g}" for v in values)] for name, values in table.items()]
    widths = [max(map(len, column)) for column in cells]
    return "\n".join("  ".join(column[row].rjust(width) for column, width in zip(cells, widths))
                     for row in range(len(cells[0]) if cells else 0))


_STYLES = (("-", "solid"), ("--", "dashed"), (":", "dotted"), ("-.", "dash-dot"))


def plot_grid(args, out, swept: list[str], shape, outputs, *, output_units: dict, title: str, legend=None) -> None:
    """Draw ``outputs`` (one panel each) against the swept input --x (default: the one with the most values, the
    first on the command line on ties), one line per combination of the other swept inputs, and save the figure
    to ``args.plot`` (format from the suffix, PNG otherwise). ``legend(name, value)``: the label of one input's
    value in the legend (default: the sweep's own label). ``out`` may also be a list of (name, outputs): several
    models overlaid, one line style each (named in the title)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    xname = args.x or max(swept, key=lambda n: (shape[swept.index(n)], -swept.index(n)))
    ix = swept.index(xname)
    xs = getattr(args, xname)
    others = [n for n in swept if n != xname]
    combos = list(np.ndindex(*(shape[swept.index(n)] for n in others))) if others else [()]
    legend = legend or (lambda n, value: getattr(args, n).label(value))
    labels = [", ".join(legend(n, getattr(args, n).values[i]) for n, i in zip(others, c)) for c in combos]

    nout = len(outputs)
    ncols = 1 if nout <= 2 else 2
    nrows = math.ceil(nout / ncols)
    fig = Figure(figsize=(5.0 * ncols, 2.6 * nrows + 0.6), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, sharex=True, squeeze=False).ravel()
    x = xs.values / xs.factor
    series = out if isinstance(out, list) else [("", out)]
    colours = [f"C{i % 10}" for i in range(len(labels))]
    for k, name in enumerate(outputs):
        ax = axes[k]
        for j, (_, result) in enumerate(series):
            y = np.moveaxis(np.broadcast_to(result[name], shape), ix, -1).reshape(-1, x.size)
            for row, label, colour in zip(y, labels, colours):
                ax.plot(x, row, _STYLES[j % len(_STYLES)][0], color=colour, label=(label or None) if j == 0 else None,
                        lw=1.2)
        unit, meaning = output_units[name]
        ax.set_ylabel(f"{name} [{unit}]")
        ax.set_title(meaning, fontsize=9)
        ax.grid(True, lw=0.3)
        if k >= nout - ncols:
            ax.set_xlabel(f"{xname} [{xs.unit}]")
        ax.tick_params(labelbottom=True)
    for ax in axes[nout:]:
        ax.set_visible(False)
    if others and len(combos) <= 12:
        axes[0].legend(fontsize=7)
    if len(series) > 1:
        title += "\n" + ", ".join(f"{name} ({_STYLES[j % len(_STYLES)][1]})" for j, (name, _) in enumerate(series))
    fig.suptitle(title, fontsize=10)
    write_figure(fig, args.plot)


def write_results(args, table, plot) -> None:
    """Write the --csv file (``table()``: the frame) and the --plot figure (``plot()`` draws and saves it), each
    where asked, creating missing folders, and say so on stderr. :func:`check_request` has allowed both."""
    for target in (args.csv, args.plot):
        if target is not None:
            make_output_folder(Path(target).parent)
    if args.csv is not None:
        frame = table()
        write_frame_csv(frame, args.csv, index=False)
        print(f"wrote {args.csv} ({len(frame)} rows, {frame.shape[1]} columns)", file=sys.stderr)
    if args.plot is not None:
        plot()
        print(f"wrote {args.plot}", file=sys.stderr)
