"""``mftyre fit DATA -o out.tir [--start FILE.tir] [--report report.md] ...``: fit a .tir file to measurements.

:func:`register` adds the ``fit`` sub-command to an argparse sub-parsers object; :func:`run` is its handler
(``args -> exit status``). DATA is a TYDEX, TTC or CSV file (:func:`mftyre.data.read_data`; the options that say how
to read it are :func:`mftyre.cli.add_data_options`).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

__all__ = ["register", "run"]





def _integer(minimum):
    def parse(text):
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer >= {minimum}, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"expected an integer >= {minimum}, got {value}")
        return value
    return parse


def register(subparsers) -> None:
    from ..arguments import closing_options, command_parser
    from .stages import STAGE_NAMES

    p = command_parser(
        subparsers, "fit", run, data=True, help="fit Magic Formula parameters to tyre measurements and write a .tir file",
        description="Fit Magic Formula parameters (MF 6.1, or MF 6.2 with an MF 6.2 --start), stage by stage (pure Fx, pure Fy, Mz, combined, Mx, My, vertical, "
                    "rolling radius), to TYDEX (.tdx), TTC (.dat text or .mat) or CSV data; pressure terms when "
                    "the data have several pressures. The test programme is recognised first and printed; stages whose result fails "
                    "the physical checks are rejected with their reason. Writes the .tir file and optionally a "
                    "Markdown report with plots. Time series (100 Hz and more) are reduced per sweep to binned means, "
                    "up and down branches averaged.")
    p.add_argument("data", nargs="+", help="measurement file(s): TYDEX, TTC (.dat/.mat) or CSV (see DATA below); "
                                           "several runs of one tyre (cornering, drive/brake, vertical) are pooled "
                                           "into one fit; or a campaign: one folder of runs or a CSV manifest (tyre, "
                                           "runs, ...; see mftyre.campaign)")
    p.add_argument("--size", help="the tyre size, e.g. 16x7.5-10 or 205/60R15: rim radius, width and aspect ratio "
                                  "(default: a size found in the file's tyre description or name; without one the "
                                  "rim radius is estimated and said so; --set RIM_RADIUS=5in gives one value)")
    p.add_argument("-o", "--output", required=True, help="the .tir file to write (a campaign: the output folder)")
    p.add_argument("--start", help="start parameters from this .tir file (default: neutral values and estimates "
                                   "from the data)")
    p.add_argument("--report", help="write a Markdown report (and PNG plots beside it) to this path")
    p.add_argument("--stages", default=",".join(STAGE_NAMES),
                   help=f"comma-separated stages to fit, in order (default: all: {','.join(STAGE_NAMES)})")
    p.add_argument("--no-pressure", action="store_true", help="do not fit the inflation-pressure terms")
    p.add_argument("--weighting", choices=("uniform", "load"), default="uniform",
                   help="residual weighting: uniform, or 1/Fz (every load alike)")
    p.add_argument("--bins", type=_integer(3), default=40,
                   help="bins per sweep when a time series is reduced (integer >= 3, default 40)")
    p.add_argument("--max-nfev", type=_integer(1), default=None,
                   help="residual evaluations per pass at most (integer >= 1; default 30 x (parameters + 1))")
    closing_options(p, overwrite="replace existing output files", quiet="no progress output", data=True)
    from ..runner import add_runner_options

    add_runner_options(p)  # a campaign's tyres in parallel (mftyre.campaign)


def run(args) -> int:
    from ..arguments import command_error, read_data_args, refused_outputs, set_parameters
    from ..data import TyreData, speaking_cli
    from .provenance import unidentified
    from ..errors import MFTyreError
    from .core import fit_tir
    from .stages import STAGE_NAMES
    from ..campaign import is_campaign

    out = Path(args.output)
    stages = [s.strip() for s in args.stages.split(",") if s.strip()]
    unknown = [s for s in stages if s not in STAGE_NAMES]
    if unknown:
        return command_error("fit", f"unknown stage(s) {', '.join(unknown)}; stages: {', '.join(STAGE_NAMES)}")
    if len(args.data) == 1 and is_campaign(args.data[0]):  # a folder or manifest: many tyres (mftyre.campaign)
        from ..campaign import run_command

        args.data = args.data[0]
        return run_command(args)
    outputs = {"-o": out, "--report": args.report}
    if args.report:  # the report's plots beside it (mftyre.fit.report.save_report)
        report = Path(args.report)
        outputs.update({f"--report plot of {s}": report.with_name(f"{report.stem}_{s}.png") for s in stages})
    inputs = {f"DATA {k + 1}" if len(args.data) > 1 else "DATA": d for k, d in enumerate(args.data)}
    if refused := refused_outputs("fit", outputs, {**inputs, "--start": args.start}, overwrite=args.overwrite):
        return refused
    if args.size:
        from ..geometry import tyre_size

        try:
            tyre_size(args.size)
        except ValueError as exc:
            return command_error("fit", f"--size: {exc}")
    t0 = time.perf_counter()

    terminal = sys.stderr.isatty()

    def progress(stage, label, nfev, cost):
        # on a terminal one line updated in place; in a log one line per update
        if not args.quiet:
            print(f"{chr(13) if terminal else ''}  [{time.perf_counter() - t0:6.1f} s] {stage:<15} {label:<30} "
                  f"{nfev:5d} evaluations, cost {cost:.4g}", end="" if terminal else "\n", file=sys.stderr,
                  flush=True)

    try:
        data = TyreData.pool([read_data_args(args, path, drop_implausible=True) for path in args.data])
        with speaking_cli():
            result = fit_tir(data, start=args.start, stages=stages, fit_pressure=not args.no_pressure,
                             weighting=args.weighting, progress=progress, bins=args.bins, max_nfev=args.max_nfev,
                             size=args.size, given=set_parameters(args))
        if not args.quiet and terminal:
            print(file=sys.stderr)
        print(f"test programme: {result.programme.summary()}")
        if result.reduction is not None:
            print(result.reduction.summary())
        result.write_tir(out, overwrite=args.overwrite)
        if args.report:
            result.save_report(args.report)
    except (MFTyreError, OSError) as exc:
        if not args.quiet and terminal:
            print(file=sys.stderr)
        return command_error("fit", exc, 1)
    fitted = (f"{len(data)} rows ({len(result.data)} points after reduction)" if result.reduction is not None
              else f"{len(data)} points")
    print(f"fitted {fitted} in {result.seconds:.1f} s; wrote {out}" + (f" and {args.report}" if args.report else ""))
    raw = result.raw_errors
    if raw:
        print("  fit error on the binned points; on the samples as recorded; the samples' own scatter at equal load, "
              "pressure, camber and slip (repeatability floor)")
    for name, st in result.stages.items():
        samples = (f"  samples {raw[name][0]:7.3f} %  floor {raw[name][1]:6.3f} % "
                   f"({raw[name][0] / raw[name][1]:.2g}x)" if name in raw and raw[name][1] > 0 else "")
        print(f"  {name:<15} {st.n_points:6d} points  {len(st.fitted):3d} parameters  fit error "
              f"{st.fit_error:7.3f} %" + samples + (f"  REJECTED: {'; '.join(st.rejected)}" if st.rejected else "")
              + (f"  reset (not determined): {', '.join(st.reset)}" if st.reset else ""))
    for text in data.history:
        if "warning: " in text:
            print(text[text.index("warning: "):], file=sys.stderr)
    unknown = unidentified(result)
    if unknown:
        print("not determined by the data (at a bound of the fit, or standard error above the value; see the .tir's "
              "comments and the report for the measurement that would pin each):", file=sys.stderr)
        for name, why, need in unknown:
            print(f"  {name}: {why}; needs {need}", file=sys.stderr)
    for why, names in result.undetermined.items():
        print(f"warning: held at their start values, not determined by the data ({why}): {' '.join(names)}",
              file=sys.stderr)
    for text in result.warnings:
        print(f"warning: {text}", file=sys.stderr)
    if result.comparison is not None:
        for _, row in result.comparison.iterrows():
            print(f"  pressure comparison {row.stage:<8} lower {row.lower:.3f} %  upper {row.upper:.3f} %  "
                  f"extended {row.extended:.3f} %  recovered {100 * row.recovered:.0f} %")
    return 0
