"""``mftyre gaps DATA --model BASE.tir [-o improved.tir] [--report DIR] [--json report.json]``: find where a model
and measurements disagree, name the missing effects, add them. ``mftyre gaps --dynamic RUNS.csv --model BASE.tir``:
the same for dynamic runs (:mod:`mftyre.gaps.dynamic_command`).

:func:`register` adds the ``gaps`` sub-command to an argparse sub-parsers object; :func:`run` is its handler
(``args -> exit status``: 0 done, 1 error, 2 usage). DATA is a TYDEX, TTC or CSV file read with the options of
:func:`mftyre.arguments.add_data_options`.
"""
from __future__ import annotations

__all__ = ["register", "run"]


def register(subparsers) -> None:
    from ..arguments import closing_options, command_parser, number_type
    from ..runner import add_runner_options

    p = command_parser(
        subparsers, "gaps", run, data=True, help="find the effects a .tir model misses in measured data, add them, show the gap shrink",
        description="Refit the model's active parameters to the data, locate residual structure beyond measurement "
                    "noise, name the missing effect from a catalogue of .tir parameter groups, add it when it "
                    "improves held-out sweeps significantly, repeat. Prints findings and errors; writes the "
                    "improved .tir, a Markdown/PNG report and JSON.")
    p.add_argument("data", nargs="?", help="measurement file: TYDEX, TTC (.dat/.mat) or CSV (see DATA below)")
    p.add_argument("--dynamic", metavar="DATA", help="dynamic runs instead (cleat, step steer, braking step: one CSV "
                                                    "with a RUN column or a folder of CSVs; layout: "
                                                    "mftyre.gaps.dynamic_runs); the model is the SWIFT or the "
                                                    "relaxed wheel driven by the runs' inputs (--model-kind)")
    p.add_argument("--model-kind", choices=("auto", "swift", "relaxed"), default="auto",
                   help="dynamic runs: the SWIFT wheel, the relaxed wheel (MF behind relaxation lengths; flat road, "
                        "rim speed imposed) or auto: SWIFT when the file has its sections, else relaxed")
    p.add_argument("--model", required=True, help="the base .tir file")
    p.add_argument("-o", "--output", help="write the improved .tir file here")
    p.add_argument("--report", metavar="DIR", help="write report.md, PNG plots and gaps.json into this folder (an "
                                                 "existing folder that is not empty needs --overwrite)")
    p.add_argument("--json", metavar="FILE", help="write the JSON report here")
    p.add_argument("--holdout", type=number_type(0, 1, open_low=True, open_high=True), default=0.25,
                   help="fraction of sweeps held out (default 0.25)")
    p.add_argument("--seed", type=number_type(0, integer=True), default=0, help="which sweeps are held out (default 0)")
    p.add_argument("--alpha", type=number_type(0, 1, open_low=True, open_high=True), default=1e-3,
                   help="family-wise significance level (default 1e-3)")
    p.add_argument("--max-effects", type=number_type(0, integer=True), default=5,
                   help="add at most this many effects (default 5)")
    add_runner_options(p, resume=False, what="the SWIFT simulations of --dynamic")
    p.add_argument("--channels", help="comma-separated channels to use (default: all measured of FX,FY,MZ,MX,MY,FZ)")
    closing_options(p, overwrite="replace existing output files", quiet="no progress output", data=True)


def run(args) -> int:
    from ..arguments import command_error, progress_printer, read_data_args, refused_outputs
    from ..data import speaking_cli
    from ..errors import MFTyreError
    from .core import find_gaps

    if (args.data is None) == (args.dynamic is None):
        return command_error("gaps", "give either DATA (steady) or --dynamic DATA (time histories)")
    if args.dynamic is not None:
        from .dynamic_command import run_dynamic
        return run_dynamic(args)
    if args.workers is not None or args.scheduler is not None:
        return command_error("gaps", "--workers and --scheduler are for --dynamic (its SWIFT simulations); the steady "
                                     "search runs in this process")

    if refused := refused_outputs("gaps", {"-o": args.output, "--json": args.json},
                                  {"DATA": args.data, "--model": args.model}, folders={"--report": args.report},
                                  overwrite=args.overwrite):
        return refused
    channels = None
    if args.channels:
        channels = [c.strip().upper() for c in args.channels.split(",") if c.strip()]
        bad = [c for c in channels if c not in ("FX", "FY", "MZ", "MX", "MY", "FZ")]
        if bad:
            return command_error("gaps", f"unknown channel(s) {', '.join(bad)}; channels: FX,FY,MZ,MX,MY,FZ")
    progress = progress_printer(args.quiet)

    try:
        data = read_data_args(args)
        with speaking_cli():
            rep = find_gaps(data, args.model, holdout=args.holdout, seed=args.seed, alpha=args.alpha,
                            max_effects=args.max_effects, channels=channels, progress=progress)
        if args.output:
            rep.write_tir(args.output, overwrite=args.overwrite)
        if args.json:
            rep.to_json(args.json)
        if args.report:
            rep.save(args.report)
    except (MFTyreError, OSError) as exc:
        return command_error("gaps", exc, 1)
    print(rep.message)
    if rep.programme:
        print(f"  test programme: {rep.programme}")
    if rep.reduction:
        print(f"  time series: {rep.reduction}")
    for t in rep.transient:
        print(f"  transient: {t['text']}")
    for f in rep.findings_before[:5]:
        print(f"  finding: {f.text}")
    for a in rep.effects_added:
        vals = ", ".join(f"{k} = {v['value']:.4g}" + (f" +- {v['stderr']:.2g}" if v['stderr'] else "")
                         for k, v in a.parameters.items())
        print(f"  added {a.name}: {a.description}; {vals}")
    for a in rep.nuisances:
        vals = ", ".join(f"{k} = {v['value']:.4g}" for k, v in a.parameters.items())
        print(f"  named in the measurement (not written to the .tir): {a.name}: {a.description}; {vals}")
    for name, why in rep.rejected.items():
        print(f"  rejected {name}: {why}")
    if rep.untestable:
        print(f"  {len(rep.untestable)} effects the data cannot test (listed with the reason in the report)")
    print(("  leave-one-out" if rep.small_data else "  held-out") + " error [%]:  " + "  ".join(
        f"{c} not fitted (no model)" if c in rep.not_modelled else f"{c} {rep.error_before[c]:.3f} -> "
        f"{rep.error_after[c]:.3f}" for c in rep.error_before))
    written = [x for x in (args.output, args.report, args.json) if x]
    if written:
        print("  wrote " + ", ".join(written))
    return 0
