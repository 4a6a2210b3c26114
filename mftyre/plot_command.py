"""``mftyre plot DATA [--model A.tir [B.tir ...]] -o plot.png``: measured data against one or more .tir models,
sweep by sweep, without fitting anything.

The test programme is recognised first (:func:`mftyre.programme.recognise`); every slip-angle sweep is drawn
against SA (FY, MZ, MX where measured) and every slip-ratio sweep against SL (FX, and FY where measured): the
measured samples as dots, each model evaluated at the measured inputs of the sweep (FZ, SL, SA, IA, PHIT, VX, P
as recorded, so load scatter and drift show in the model line too) as a line, one colour per sweep, one line style
per model. The error of each model on every measured channel (RMS and normalised RMS over all rows) is printed.
"""
from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path

import numpy as np

__all__ = ["register", "run"]

#: channels drawn per kind of sweep, and the swept channel with its plot unit (factor from SI)
_PANELS = {"slip_angle": ("SA", "deg", 180 / math.pi, ("FY", "MZ", "MX")),
           "slip_ratio": ("SL", "-", 1.0, ("FX", "FY"))}
_UNIT = {"FX": "N", "FY": "N", "FZ": "N", "MX": "N m", "MY": "N m", "MZ": "N m"}
_STYLES = ("-", "--", ":", "-.")
_STYLE_NAMES = ("solid", "dashed", "dotted", "dash-dot")


def register(subparsers) -> None:
    from .arguments import closing_options, command_parser

    p = command_parser(
        subparsers, "plot", run, data=True, help="plot measured data against .tir models, sweep by sweep (no fitting)",
        description="Recognise the test programme of DATA and plot every slip-angle sweep (FY, MZ, MX against SA) "
                    "and slip-ratio sweep (FX, FY against SL): measured samples as dots, each --model evaluated at "
                    "the measured inputs as a line (one colour per sweep, one line style per model). Prints the "
                    "error of each model per channel.")
    p.add_argument("data", help="measurement file: TYDEX, TTC (.dat/.mat) or CSV (see DATA below)")
    p.add_argument("--model", nargs="+", metavar="FILE.tir", default=[], help="one or more .tir files to compare")
    p.add_argument("-o", "--output", required=True, metavar="OUT.png", help="the figure to write (PNG, SVG, PDF)")
    p.add_argument("--max-sweeps", type=int, default=12, metavar="N",
                   help="draw at most N sweeps per kind, spread over the programme (default 12)")
    p.add_argument("--side", choices=("left", "right"), help="side the tyre is mounted on (default: TYRESIDE)")
    closing_options(p, overwrite="replace an existing output file", data=True)


def run(args) -> int:
    from .arguments import command_error, read_data_args, refused_outputs
    from .data import speaking_cli
    from .errors import MFTyreError

    if args.max_sweeps < 1:
        return command_error("plot", "--max-sweeps: expected an integer >= 1")
    if refused := refused_outputs("plot", {"-o": args.output},
                                  {"DATA": args.data, **{f"--model {m}": m for m in args.model}},
                                  overwrite=args.overwrite):
        return refused
    try:
        from .model import load_tir
        from .programme import recognise

        data = read_data_args(args)
        with speaking_cli():
            models = [(Path(m).name, load_tir(m, side=args.side)) for m in args.model]
            programme = recognise(data)
            print(f"test programme: {programme.summary(short=True)}")
            rows = programme.annotate(data).frame
            predictions = _predict(data, models)
        for name, table in _errors(data, predictions).items():
            print(f"  {name}: " + "; ".join(f"{ch} RMS {rms:.4g} {_UNIT[ch]} ({nrms:.2f} %)"
                                             for ch, (rms, nrms) in table.items()))
        fig, shown = _figure(rows, predictions, models, args)
        from .files import make_output_folder, write_figure

        make_output_folder(Path(args.output).parent)
        write_figure(fig, args.output)
    except (MFTyreError, OSError) as exc:
        return command_error("plot", exc, 1)
    print(f"wrote {args.output} ({shown})")
    return 0


def _predict(data, models) -> dict:
    """Model name -> its outputs at the measured inputs (InputClippedWarnings printed once per model)."""
    out = {}
    for name, model in models:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            out[name] = model.evaluate(**data.inputs())
        for w in caught:
            print(f"mftyre plot: {name}: {w.message}", file=sys.stderr)
    return out


def _errors(data, predictions) -> dict:
    """Model name -> channel -> (RMS, RMS relative to the measured RMS [%]) over the rows where it is measured."""
    table = {}
    for name, out in predictions.items():
        table[name] = {}
        for ch in ("FX", "FY", "MZ", "MX", "MY"):
            if not data.has(ch):
                continue
            y = data.array(ch)
            ok = np.isfinite(y)
            rms = float(np.sqrt(np.mean((np.asarray(out[ch.lower()])[ok] - y[ok]) ** 2)))
            scale = float(np.sqrt(np.mean(y[ok] ** 2)))
            table[name][ch] = (rms, 100 * rms / scale if scale > 0 else float("nan"))
    return table


def _figure(rows, predictions, models, args):
    """The matplotlib Figure, and what it shows."""
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    panels = []
    for kind, (xch, xunit, xfac, channels) in _PANELS.items():
        sweeps = [s for s in np.unique(rows["SWEEP"][rows["KIND"] == kind]) if s >= 0]
        if len(sweeps) > args.max_sweeps:  # spread over the programme
            sweeps = [sweeps[i] for i in np.linspace(0, len(sweeps) - 1, args.max_sweeps).round().astype(int)]
        chans = [c for c in channels if c in rows and np.isfinite(rows[c].to_numpy(float)).any()]
        if kind == "slip_ratio" and "FY" in chans:  # FY against SL only where a slip angle is held
            held = rows.loc[rows["SWEEP"].isin(sweeps), "SA"].abs() > math.radians(0.5)
            chans = chans if held.any() else [c for c in chans if c != "FY"]
        panels += [(kind, xch, xunit, xfac, ch, sweeps) for ch in chans if sweeps]
    if not panels:
        raise _no_sweeps()
    ncols = min(3, len(panels))
    nrows = math.ceil(len(panels) / ncols)
    fig = Figure(figsize=(4.6 * ncols, 3.3 * nrows + 0.5), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    cmap = matplotlib.colormaps["viridis"]
    first_of_kind = {}
    for ax, (kind, xch, xunit, xfac, ch, sweeps) in zip(axes, panels):
        legend = first_of_kind.setdefault(kind, ax) is ax  # the conditions of the sweeps, once per kind
        for i, sweep in enumerate(sweeps):
            mask = (rows["SWEEP"] == sweep).to_numpy()
            x = rows[xch].to_numpy(float)[mask] * xfac
            y = rows[ch].to_numpy(float)[mask]
            step = max(1, int(mask.sum()) // 300)  # a time series: every step-th sample
            colour = cmap(0.9 * i / max(1, len(sweeps) - 1))
            ax.plot(x[::step], y[::step], ".", ms=2.5, color=colour, label=_condition(rows, mask) if legend else None)
            order = np.argsort(x, kind="stable")
            for k, (name, _) in enumerate(models):
                model_y = np.broadcast_to(predictions[name][ch.lower()], mask.shape)[mask]
                ax.plot(x[order], model_y[order], _STYLES[k % len(_STYLES)], lw=1.0, color=colour)
        ax.set_xlabel(f"{xch} [{xunit}]")
        ax.set_ylabel(f"{ch} [{_UNIT[ch]}]")
        ax.set_title(f"{ch}, {kind.replace('_', ' ')} sweeps", fontsize=9)
        ax.grid(True, lw=0.3)
        if legend:
            ax.legend(fontsize=6, markerscale=2, loc="best")
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    styles = ", ".join(f"{name} ({_STYLE_NAMES[k % len(_STYLES)]})" for k, (name, _) in enumerate(models))
    fig.suptitle(f"{Path(args.data).name}: measured (dots)" + (f" against {styles}" if models else ""), fontsize=10)
    shown = ", ".join(f"{len(s)} {k.replace('_', '-')} sweeps" for k, s in
                      {p[0]: p[5] for p in panels}.items())
    return fig, shown


def _condition(rows, mask) -> str:
    fz = float(np.median(rows["FZ"].to_numpy(float)[mask]))
    parts = [f"FZ {fz:.0f} N"]
    for ch, fac, unit, fmt in (("IA", 180 / math.pi, "deg", ".1f"), ("P", 1e-5, "bar", ".2f"),
                               ("SA", 180 / math.pi, "deg", ".1f")):
        if ch in rows:
            x = rows[ch].to_numpy(float)[mask]
            if np.ptp(x) * fac < (1.0 if ch == "SA" else 0.5):
                parts.append(f"{ch} {np.median(x) * fac:{fmt}} {unit}")
    return ", ".join(parts)


def _no_sweeps():
    from .errors import DataError

    return DataError("no slip-angle or slip-ratio sweep with FX, FY, MZ or MX measured was recognised in the data: "
                     "nothing to plot")
