"""``mftyre swift FILE.tir --road ROAD --speed V --fz FZ [--p P] --csv out.csv --plot out.png``: the SWIFT tyre
rolling over a road profile or obstacle at constant speed, axle height held at the static loaded radius (the
default) or the axle load held (``--axle load``); time histories of the forces, moments, radii and effective road
as CSV and a plot against the wheel position. Progress (building the compiled stepper, running) goes to stderr.
"""
from __future__ import annotations

import argparse
import sys
import textwrap
from pathlib import Path

import numpy as np

__all__ = ["register", "run", "roll"]

#: Outputs drawn by --plot, against the wheel position.
_PLOTTED = (("fz", "N", "vertical force"), ("fx", "N", "longitudinal force"), ("my", "N m", "rolling moment"),
            ("w", "mm", "effective road height"))


#: Most steps one `mftyre swift` run takes (its time histories: about 2 GB at this count).
MAX_STEPS = 10_000_000


def _quantity(name):
    from .arguments import parse_sweep

    def convert(text):
        try:
            sweep = parse_sweep(name, text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        if sweep.values.size != 1:
            raise argparse.ArgumentTypeError(f"expected one value, got {sweep.values.size}")
        return float(sweep.values[0])

    convert.__name__ = name
    return convert


def register(subparsers) -> None:
    from .arguments import closing_options, command_parser, number_type

    p = command_parser(
        subparsers, "swift", run, help="SWIFT tyre over a road profile or obstacle: time histories (CSV, plot)",
        description="Roll the SWIFT tyre of FILE.tir (rigid ring, tandem-cam effective road, Magic Formula slip) at "
                    "constant speed over ROAD, free rolling (rim spin V / Re), from the static equilibrium. "
                    "--axle height holds the axle at the static loaded radius of --fz (a rig with a fixed axle); "
                    "--axle load holds the axle load (a quarter car without suspension). Writes the time histories "
                    "(every output of swift.ring.OUTPUT_NAMES, SI units) and plots Fz, Fx, My and the effective "
                    "road against the wheel position.",
        epilog="example: mftyre swift tyre.tir --road 'cleat(x0=1.0, length=0.05, height=0.01)' --speed 30km/h "
               "--fz 4kN --p 2.2bar --csv cleat.csv --plot cleat.png")
    p.add_argument("file", metavar="FILE.tir", help="tyre property file (MF 6.2 with SWIFT parameters, or MF 6.1)")
    p.add_argument("--road", default="", metavar="ROAD",
                   help="a CSV file with columns x, z [m], or obstacles such as 'cleat(x0=1.0, length=0.05, "
                        "height=0.01) + step(3, 0.02)' (flat, step, cleat, trapezoid, bump, sine); default flat")
    p.add_argument("--speed", type=_quantity("vx"), required=True, metavar="V", help="forward speed (m/s, km/h, mph)")
    p.add_argument("--fz", type=_quantity("fz"), default=None, metavar="FZ",
                   help="axle load (N, kN, lbf; default FNOMIN)")
    p.add_argument("--p", type=_quantity("p"), default=None, metavar="P",
                   help="inflation pressure (Pa, kPa, bar, psi; default INFLPRES)")
    p.add_argument("--axle", choices=("height", "load"), default="height",
                   help="axle height held (default) or axle load held")
    p.add_argument("--start", type=number_type(), default=0.0, metavar="X", help="wheel position at t = 0 [m] (0)")
    p.add_argument("--distance", type=number_type(0, open_low=True), default=3.0, metavar="D",
                   help="distance rolled [m] (default 3)")
    p.add_argument("--dt", type=number_type(1e-5, 0.01), default=1e-3, metavar="DT",
                   help="output (and step) interval [s] (default 0.001)")
    p.add_argument("--csv", metavar="OUT.csv", help="write the time histories here")
    p.add_argument("--plot", metavar="OUT.png", help="write the plot here (PNG, SVG, PDF)")
    closing_options(p, overwrite="replace existing output files", quiet="no progress output")


def run(args) -> int:
    from .arguments import command_error, progress_printer, refused_outputs
    from .errors import MFTyreError

    if args.speed <= 0:
        return command_error("swift", "--speed: expected a forward speed above 0")
    for option, value in (("--fz", args.fz), ("--p", args.p)):
        if value is not None and not value > 0:
            return command_error("swift", f"{option}: expected a value above 0, got {value:g}")
    steps = args.distance / args.speed / args.dt
    if steps > MAX_STEPS:
        return command_error("swift", f"--distance {args.distance:g} m at {args.speed:g} m/s in steps of --dt "
                                      f"{args.dt:g} s is {steps:.3g} steps, more than the {MAX_STEPS:,} one run "
                                      "writes; shorten --distance or raise --dt")
    if refused := refused_outputs("swift", {"--csv": args.csv, "--plot": args.plot},
                                  {"FILE.tir": args.file, "--road": _road_file(args)}, overwrite=args.overwrite):
        return refused
    say = progress_printer(args.quiet)

    try:
        import warnings

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res, road, info = simulate(args, say)
        for w in caught:
            print(f"mftyre swift: note: {w.message}", file=sys.stderr)
        frame = _frame(res)
        print(info)
        for name in ("fz", "fx", "my"):
            print(f"  {name}: min {frame[name].min():.5g}, max {frame[name].max():.5g}, "
                  f"final {frame[name].iloc[-1]:.5g}")
        from .files import make_output_folder, write_figure, write_frame_csv

        for target in (args.csv, args.plot):
            if target:
                make_output_folder(Path(target).parent)
        if args.csv:
            write_frame_csv(frame, args.csv, index=False)
            say(f"wrote {args.csv} ({len(frame)} rows)")
        if args.plot:
            write_figure(_figure(frame, road, args, info), args.plot)
            say(f"wrote {args.plot}")
    except (MFTyreError, OSError) as exc:
        return command_error("swift", exc, 1)
    return 0


def _road_file(args):
    text = str(args.road).strip()
    return text if text.lower().endswith(".csv") else None


def simulate(args, say):
    """(SimResult, road, one-line description): the tyre built (compiled once, cached), then run."""
    import mftyre
    from swift.road import parse_road

    model = mftyre.load_tir(args.file)
    road = parse_road(args.road)
    v = args.speed
    say(f"building the SWIFT stepper for {Path(args.file).name} (C compiled on first use and cached in "
        "~/.cache/mftyre; a minute at most)")
    res, (fz, p, rl, re) = roll(model, road, v, fz=args.fz, p=args.p, axle=args.axle, start=args.start,
                                distance=args.distance, dt=args.dt,
                                say=lambda steps: say(f"running {args.distance / v:.3g} s ({args.distance:g} m at "
                                                      f"{v:g} m/s, {steps} steps of {args.dt:g} s)"))
    say("done")
    hold = (f"axle height {rl * 1e3:.1f} mm (the loaded radius at {fz:g} N)" if args.axle == "height"
            else f"axle load {fz:g} N")
    info = (f"{Path(args.file).name}: {v:g} m/s ({v * 3.6:.1f} km/h), {hold}, p {p / 1e5:.3g} bar, spin "
            f"{v / re:.4g} rad/s (Re {re * 1e3:.1f} mm); road {args.road or 'flat'}")
    return res, road, info


def roll(model, road, v: float, *, fz=None, p=None, axle: str = "height", start: float = 0.0,
         distance: float = 3.0, dt: float = 1e-3, say=None):
    """The run of ``mftyre swift``: the SWIFT tyre of ``model`` rolling freely (spin v / Re) at ``v`` over ``road``
    from ``start`` for ``distance`` from the static equilibrium, axle height held at the loaded radius of ``fz``
    (default FNOMIN) or the axle load ``fz`` held; ``p`` default INFLPRES. Returns (SimResult, (fz, p used, Rl,
    Re)); ``say(steps)`` is called before the run."""
    from swift import StepInputs, SwiftTyre

    prm = model.params
    fz = float(prm.FNOMIN if fz is None else fz)
    p = float(prm.INFLPRES if p is None else p)
    static = model.evaluate(fz=fz, kappa=0.0, alpha=0.0, vx=v, p=p)
    rl, re = float(static.rl), float(static.re)
    p = float(static.p)  # as used (saturated to PRESMIN..PRESMAX, a note says so): for the ring as for the height
    tyre = SwiftTyre(model, road, axle=axle, rim="speed", x_range=(start - 1.0, start + distance + 1.0))
    t_end = distance / v
    if say is not None:
        say(int(round(t_end / dt)))
    u = StepInputs(x=start, vx=v, z=rl, load=fz, omega=v / re, p=p)
    return tyre.run(t_end, u, dt=dt), (fz, p, rl, re)


def _frame(res):
    import pandas as pd

    cols = {"t": res.t, "x": res.x}
    cols.update({name: np.asarray(values, float) for name, values in res.outputs.items()})
    return pd.DataFrame(cols)


def _figure(frame, road, args, info):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.5, 7.0), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(_PLOTTED), 1, sharex=True)
    x = frame["x"].to_numpy()
    for ax, (name, unit, meaning) in zip(axes, _PLOTTED):
        y = frame[name].to_numpy() * (1e3 if unit == "mm" else 1.0)
        ax.plot(x, y, lw=1.0, label="effective road height w" if name == "w" else None)
        if name == "w":
            ax.plot(x, np.asarray(road.height(x), float) * 1e3, "k:", lw=0.8, label="road under the wheel centre")
            ax.legend(fontsize=7)
        ax.set_ylabel(f"{name} [{unit}]")
        ax.set_title(meaning, fontsize=9)
        ax.grid(True, lw=0.3)
    axes[-1].set_xlabel("wheel position x [m]")
    fig.suptitle("\n".join(textwrap.wrap(info, 110)), fontsize=8)
    return fig
