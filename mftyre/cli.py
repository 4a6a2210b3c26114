"""Command-line interface: ``mftyre <command> ...``.

Commands
--------
check FILE.tir [FILE ...]   parse and validate property files; prints ``FILE:LINE: severity: message``
                            (``FILE: severity: message`` when no line applies) and a summary; exit status 1
                            when any file has an error, 0 otherwise.
eval FILE.tir [sweeps] [options]
                            evaluate the steady-state model on a grid of inputs; prints a table, optionally
                            writes a CSV file (``--csv``) and a PNG plot (``--plot``). See :func:`_add_eval`.

Adding a command: write ``_add_<name>(subparsers)`` that creates the sub-parser and sets
``func=<handler>`` (a function ``(args) -> int``), and call it from :func:`build_parser`.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

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


# ------------------------------------------------------------------------------------------ (more)
# Other commands (fit, gaps, plot, fmu) are added here by their modules' authors and registered in
# build_parser() below.


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="mftyre", description="Magic Formula tyre model tools")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    _add_check(sub)
    _add_eval(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line ``argv`` (default: sys.argv[1:]); returns the exit status."""
    parser = build_parser()
    argv = _join_negative_values(list(sys.argv[1:] if argv is None else argv))
    try:
        args = parser.parse_args(argv)
        return int(args.func(args))
    except SystemExit as exc:  # argparse exits on --help and on usage errors (also raised by handlers)
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
