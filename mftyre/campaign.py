"""A test campaign: many tyres fitted at once, one task per tyre on :mod:`mftyre.runner`.

``mftyre fit DIR_OR_MANIFEST -o OUTDIR`` (:func:`run_command`, dispatched from :mod:`mftyre.fit.command` when DATA
is a folder or a ``.csv`` manifest):

* a folder: every sub-folder is one tyre (its name), its measurement files (``.tdx``, ``.csv``, ``.dat``, ``.mat``)
  the runs of that tyre, and a single ``.tir`` file in it the start values (``--start``); a measurement file
  directly in the folder is a tyre of its own (named by its stem);
* a manifest: a CSV file with one row per tyre and the columns ``tyre`` and ``runs`` (run files separated by
  ``;``, relative to the manifest's folder), optionally ``start`` (a .tir file) and the options of ``mftyre fit``
  for that tyre: ``stages`` (``;`` or ``,`` separated), ``weighting``, ``bins``, ``max_nfev``, ``no_pressure``
  (true/false). An empty cell takes the command line's value.

Each tyre's runs are read here with the one reader (:func:`mftyre.data.read_data`, the command's data options) and
sent with the start's text and the options (plain data) to a worker, which fits them
(:func:`mftyre.fit.fit_tir` on the runs joined, :meth:`mftyre.data.TyreData.pool`) exactly as ``mftyre fit RUN1 RUN2 ...``
fits one tyre alone: the fitted values are the same bit for bit. OUTDIR gets ``<tyre>.tir``, the report
``<tyre>.md`` with its plots (``<tyre>_<stage>.png``), ``summary.csv`` (one row per tyre: status, the fit error
[%] per stage and channel, the flags: rejected stages, verification problems and warnings, parameters not
determined) and ``tasks/`` (one finished fit per file: ``--resume`` skips them).
"""
from __future__ import annotations

import base64
import csv
import io
import re
import tempfile
from pathlib import Path

import pandas as pd

from .errors import DataError

__all__ = ["is_campaign", "campaign_tyres", "fit_tyre", "run_campaign", "run_command", "RUN_SUFFIXES"]

#: Files of a campaign folder read as runs.
RUN_SUFFIXES = (".tdx", ".csv", ".dat", ".mat")
_OPTIONS = ("stages", "weighting", "bins", "max_nfev", "no_pressure")
_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")


def is_campaign(data) -> bool:
    """True when DATA names a campaign: a folder, or a CSV file whose header has the columns tyre and runs."""
    path = Path(data)
    if path.is_dir():
        return True
    if path.suffix.lower() != ".csv" or not path.is_file():
        return False
    with open(path, newline="", encoding="utf-8", errors="replace") as fh:
        header = next(csv.reader([fh.readline()]), [])
    return {"tyre", "runs"} <= {h.strip().lower() for h in header}


def campaign_tyres(source, defaults: dict) -> dict:
    """Tyre name -> ``{"runs": [paths], "start": path or None, **options}`` of the campaign ``source`` (a folder or
    a manifest, see the module notes); ``defaults``: the options where a row says nothing. DataError naming the
    folder, manifest row or file when it cannot be a campaign."""
    path = Path(source)
    tyres = {}
    if path.is_dir():
        for entry in sorted(path.iterdir()):
            if entry.is_dir():
                runs = sorted(p for p in entry.iterdir() if p.suffix.lower() in RUN_SUFFIXES and p.is_file())
                starts = sorted(p for p in entry.iterdir() if p.suffix.lower() == ".tir")
                if len(starts) > 1:
                    raise DataError(f"{entry}: {len(starts)} .tir files ({', '.join(p.name for p in starts)}): "
                                    "expected at most one, the start values of this tyre")
                if runs:
                    tyres[entry.name] = {"runs": runs, "start": starts[0] if starts else defaults.get("start"),
                                         **_options(defaults)}
            elif entry.suffix.lower() in RUN_SUFFIXES:
                tyres[entry.stem] = {"runs": [entry], "start": defaults.get("start"), **_options(defaults)}
        if not tyres:
            raise DataError(f"{path}: no runs: expected sub-folders (one per tyre) or files ending in "
                            f"{', '.join(RUN_SUFFIXES)}")
    else:
        frame = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
        frame.columns = [c.strip().lower() for c in frame.columns]
        unknown = [c for c in frame.columns if c not in ("tyre", "runs", "start", *_OPTIONS)]
        if unknown:
            raise DataError(f"{path}: unknown column(s) {', '.join(unknown)}; expected tyre, runs, start, "
                            f"{', '.join(_OPTIONS)}")
        for i, row in frame.iterrows():
            where = f"{path}, row {i + 2}"
            tyre = row["tyre"].strip()
            if tyre in tyres:
                raise DataError(f"{where}: tyre {tyre!r} is named twice; one row per tyre (list its runs with ';')")
            runs = [path.parent / r.strip() for r in row["runs"].split(";") if r.strip()]
            if not runs:
                raise DataError(f"{where}: no runs: expected run files separated by ';'")
            start = row.get("start", "").strip()
            tyres[tyre] = {"runs": runs, "start": path.parent / start if start else defaults.get("start"),
                           **_options(defaults, row, where)}
    for tyre in tyres:
        if not _NAME.fullmatch(tyre):
            raise DataError(f"{source}: tyre name {tyre!r}: expected letters, digits, '.', '_' or '-' (it names the "
                            "output files)")
    return tyres


def _options(defaults: dict, row=None, where: str = "") -> dict:
    from .fit.stages import STAGE_NAMES

    out = {k: defaults[k] for k in _OPTIONS}
    for name in _OPTIONS:
        text = "" if row is None else str(row.get(name, "")).strip()
        if not text:
            continue
        if name == "stages":
            out[name] = [s.strip() for s in re.split("[;,]", text) if s.strip()]
            bad = [s for s in out[name] if s not in STAGE_NAMES]
            if bad:
                raise DataError(f"{where}: unknown stage(s) {', '.join(bad)}; stages: {', '.join(STAGE_NAMES)}")
        elif name == "weighting":
            if text not in ("uniform", "load"):
                raise DataError(f"{where}: weighting {text!r}: expected uniform or load")
            out[name] = text
        elif name in ("bins", "max_nfev"):
            try:
                out[name] = int(text)
            except ValueError:
                raise DataError(f"{where}: {name} {text!r}: expected an integer") from None
            if out[name] < (3 if name == "bins" else 1):
                raise DataError(f"{where}: {name} {text}: expected an integer >= {3 if name == 'bins' else 1}")
        else:
            if text.lower() not in ("true", "false", "1", "0", "yes", "no"):
                raise DataError(f"{where}: no_pressure {text!r}: expected true or false")
            out[name] = text.lower() in ("true", "1", "yes")
    return out


def _run_data(data) -> dict:
    """A run as plain data for a task."""
    return {"frame": data.frame, "tyre": data.tyre, "source": data.source, "units": dict(data.units),
            "constants": dict(data.constants), "history": list(data.history), "sha256": data.sha256}


def fit_tyre(tyre: str, runs: list, start_text: str | None, start_source: str | None, stages: list,
             weighting: str, bins: int, max_nfev: int | None, no_pressure: bool) -> dict:
    """One task: fit one tyre (where it lands). Returns ``{"tir": text, "report": Markdown, "plots": {name:
    base64 PNG}, "summary": {...}}``; raises what :meth:`mftyre.fit.FitResult.write_tir` raises when nothing
    could be written."""
    from .data import TyreData
    from .fit.core import fit_tir
    from .tir import parse_tir

    parts = [TyreData(r["frame"], r["tyre"], r["source"], r["units"], r["constants"], r["history"], r["sha256"])
             for r in runs]
    data = TyreData.pool(parts)  # as `mftyre fit RUN1 RUN2 ...`
    start = parse_tir(start_text, start_source) if start_text is not None else None
    result = fit_tir(data, start=start, stages=stages, fit_pressure=not no_pressure, weighting=weighting,
                     bins=bins, max_nfev=max_nfev)
    with tempfile.TemporaryDirectory() as tmp:
        tir = result.write_tir(Path(tmp) / f"{tyre}.tir")
        report = result.save_report(Path(tmp) / f"{tyre}.md")
        plots = {p.name: base64.b64encode(p.read_bytes()).decode() for p in sorted(Path(tmp).glob("*.png"))}
        texts = tir.read_text(encoding="utf-8"), report.read_text(encoding="utf-8")
    summary = {"tyre": tyre, "runs": len(runs), "rows": len(data), "status": "fitted",
               **{f"{name} {st.channel} [%]": st.fit_error for name, st in result.stages.items()},
               "rejected": " ".join(n for n, st in result.stages.items() if st.rejected),
               "problems": len(result.problems), "warnings": len(result.warnings),
               "undetermined": sum(len(v) for v in result.undetermined.values()), "seconds": result.seconds}
    return {"tir": texts[0], "report": texts[1], "plots": plots, "summary": summary}


def run_campaign(source, outdir, runner, *, read=None, defaults: dict, resume: bool = False, say=print) -> tuple:
    """Fit every tyre of the campaign ``source`` on ``runner`` (:class:`mftyre.runner.Runner`) and write OUTDIR
    (see the module notes). ``read(path) -> TyreData`` reads a run (default :func:`mftyre.data.read_data`).
    Returns (summary DataFrame, list of failure lines)."""
    from .data import read_data
    from .files import make_output_folder, write_atomically, write_frame_csv
    from .errors import MFTyreError
    from .tir import read_tir_text

    read = read or read_data
    outdir = make_output_folder(outdir)
    tyres = campaign_tyres(source, defaults)
    tasks, failed = {}, {}
    for tyre, spec in tyres.items():
        try:
            runs = [_run_data(read(path)) for path in spec["runs"]]
            start = spec["start"]
            start_text = read_tir_text(start) if start is not None else None
        except (MFTyreError, OSError) as exc:  # a run that cannot be read fails its tyre only
            failed[tyre] = f"tyre {tyre} (runs {', '.join(map(str, spec['runs']))}) not read: {exc}"
            continue
        tasks[tyre] = {"tyre": tyre, "runs": runs, "start_text": start_text,
                       "start_source": None if start is None else str(start),
                       **{k: spec[k] for k in _OPTIONS}}
    say(f"{len(tyres)} tyre(s), {sum(len(s['runs']) for s in tyres.values())} run(s); fitting on "
        f"{runner.describe()}")
    outcome = runner.run(fit_tyre, tasks, results=outdir / "tasks", resume=resume)
    rows = []
    for failure in outcome.failures:
        failed[failure.key] = failure.summary()
    for tyre in tyres:
        if tyre in outcome.results:
            result = outcome.results[tyre]
            write_atomically(outdir / f"{tyre}.tir", result["tir"])
            write_atomically(outdir / f"{tyre}.md", result["report"])
            for name, data in result["plots"].items():
                write_atomically(outdir / name, base64.b64decode(data))
            rows.append(result["summary"])
        else:
            rows.append({"tyre": tyre, "runs": len(tyres[tyre]["runs"]),
                         "status": "failed: " + failed[tyre].splitlines()[-1]})
    summary = pd.DataFrame(rows)
    write_frame_csv(summary, outdir / "summary.csv", index=False)
    if outcome.resumed:
        say(f"{len(outcome.resumed)} tyre(s) resumed from {outdir / 'tasks'}")
    return summary, [failed[t] for t in tyres if t in failed]


def run_command(args) -> int:
    """``mftyre fit DIR_OR_MANIFEST -o OUTDIR``: the handler :mod:`mftyre.fit.command` dispatches to."""
    import sys

    from .arguments import command_error, progress_printer, read_data_args, refused_outputs
    from .errors import MFTyreError
    from .runner import runner_from_args

    if args.report:
        return command_error("fit", "--report: a campaign writes one report per tyre into OUTDIR (-o)")
    outdir = Path(args.output)
    if not args.resume and (refused := refused_outputs("fit", {}, {"DATA": args.data}, folders={"-o": outdir},
                                                       overwrite=args.overwrite)):
        return refused
    say = progress_printer(args.quiet)
    defaults = {"start": args.start, "stages": [s.strip() for s in args.stages.split(",") if s.strip()],
                "weighting": args.weighting, "bins": args.bins, "max_nfev": args.max_nfev,
                "no_pressure": args.no_pressure}
    try:
        with runner_from_args(args) as runner:
            summary, failures = run_campaign(args.data, outdir, runner, read=lambda p: read_data_args(args, p),
                                             defaults=defaults, resume=args.resume, say=say)
    except (MFTyreError, OSError) as exc:
        return command_error("fit", exc, 1)
    text = io.StringIO()
    summary.to_string(text, index=False, float_format=lambda v: f"{v:.3f}")
    print(text.getvalue())
    print(f"wrote {sum(summary['status'] == 'fitted')} .tir file(s), reports and {outdir / 'summary.csv'}")
    for line in failures:
        print(f"mftyre fit: {line}", file=sys.stderr)
    return 1 if failures else 0
