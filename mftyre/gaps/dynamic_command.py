"""``mftyre gaps --dynamic RUNS.csv --model BASE.tir [-o improved.tir] [--report DIR] [--json FILE]``: the handler
of the dynamic gap finder (:func:`mftyre.gaps.dynamic.find_dynamic_gaps`); options shared with ``mftyre gaps``
(``--holdout``, ``--seed``, ``--alpha``, ``--max-effects``, ``--overwrite``, ``--quiet``) and the reading options of
every data file (``--columns``, ``--units``, ``--axes``, ``--no-check``: :func:`mftyre.data.read_time_histories`;
``--drop`` a measured channel);
``--model-kind``; ``--workers``, ``--scheduler`` (:mod:`mftyre.runner`: the SWIFT simulations in parallel)."""
from __future__ import annotations

__all__ = ["run_dynamic"]


def run_dynamic(args) -> int:
    """args -> exit status (0 done, 1 error, 2 usage)."""
    from ..arguments import command_error, progress_printer, refused_outputs
    from ..data import speaking_cli
    from ..errors import MFTyreError
    from ..runner import runner_from_args
    from .dynamic import find_dynamic_gaps, values_text
    from .dynamic_runs import read_runs

    if args.channels:
        return command_error("gaps", "--channels is for steady data; dynamic runs use every measured channel")
    if args.constants:
        return command_error("gaps", "--set is for steady data; a dynamic run records each of its inputs")
    if refused := refused_outputs("gaps", {"-o": args.output, "--json": args.json},
                                  {"--dynamic": args.dynamic, "--model": args.model},
                                  folders={"--report": args.report}, overwrite=args.overwrite):
        return refused
    progress = progress_printer(args.quiet)

    try:
        with speaking_cli():
            runs = read_runs(args.dynamic, columns=args.columns, units=args.units, axes=args.axes,
                             check=not args.no_check, drop=args.drop)
        with runner_from_args(args) as runner:
            rep = find_dynamic_gaps(runs, args.model, holdout=args.holdout, seed=args.seed,
                                    alpha=args.alpha, max_effects=args.max_effects, model_kind=args.model_kind,
                                    progress=progress, runner=runner)
        if args.output:
            rep.write_tir(args.output, overwrite=args.overwrite)
        if args.json:
            rep.to_json(args.json, overwrite=args.overwrite)
        if args.report:
            rep.save(args.report, overwrite=args.overwrite)
    except (MFTyreError, OSError) as exc:
        return command_error("gaps", exc, 1)
    print(rep.message)
    print(f"  measurement chain: delay {1e3 * rep.chain.delay:.2f} ms, anti-alias filter "
          f"{'none' if rep.chain.cutoff is None else f'{rep.chain.cutoff:.4g} Hz, order {rep.chain.order}'}; gain "
          + ", ".join(f"{c} {g:.4f}" + (f" (held at the bound; least squares: {rep.chain.held[c]:.4g})"
                                        if c in rep.chain.held else "") for c, g in rep.chain.gain.items()))
    for f in rep.findings[:5]:
        print(f"  finding: {f['run']} {f['channel']} {f['feature']}: measured {f['measured']:.4g}, model "
              f"{f['model']:.4g} ({f['z']:+.1f} uncertainties)")
    for c in rep.effects_added:
        print(f"  added {c.name}: {values_text(c)}")
    for rnd in rep.rounds:
        for c in rnd:
            if c.note and not c.significant:
                print(f"  rejected {c.name}: {c.note}")
    print(f"  {len(rep.untestable)} effects not tried (listed with the reason in the report)")
    written = [x for x in (args.output, args.report, args.json) if x]
    if written:
        print("  wrote " + ", ".join(written))
    return 0
