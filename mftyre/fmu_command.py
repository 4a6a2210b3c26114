"""``mftyre fmu build FILE.tir -o tyre.fmu [--model steady|swift] [--side left|right]``: the tyre as an FMI 2.0
co-simulation FMU (pythonfmu). The slave and the build logic live in ``fmu/`` beside the package (see
fmu/README.md); this module only wires them into the command line:

    from mftyre.fmu_command import register
    register(subparsers)          # adds the 'fmu' command with its 'build' subcommand; handler: run(args)
"""
from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

__all__ = ["register", "run", "fmu_sources"]


def fmu_sources() -> Path:
    """The folder with the FMU sources (``fmu/`` next to the mftyre package in a source checkout)."""
    return Path(__file__).resolve().parent.parent / "fmu"


def _load_build_module():
    path = fmu_sources() / "build.py"
    if not path.is_file():
        raise FileNotFoundError(
            f"the FMU sources are not installed (expected {path}); build FMUs from a source checkout of mftyre "
            "(pip install -e .)")
    spec = importlib.util.spec_from_file_location("mftyre_fmu_build", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``fmu`` command (subcommand ``build``) to an argparse subparsers object."""
    fmu = subparsers.add_parser(
        "fmu", help="package the tyre as an FMI 2.0 co-simulation FMU",
        description="Package the tyre as an FMI 2.0 co-simulation FMU (pythonfmu). See fmu/README.md for the "
                    "FMU's variables and what a simulator needs to run it.")
    sub = fmu.add_subparsers(dest="fmu_command", metavar="SUBCOMMAND")
    sub.required = True
    build = sub.add_parser(
        "build", help="build an FMU from a .tir file",
        description="Build an FMI 2.0 co-simulation FMU embedding a .tir file. The FMU runs in a Python with "
                    "numpy and casadi; C libraries compiled here are shipped for this platform.",
        epilog="example: mftyre fmu build tir_files/car_205_60R15_mf61.tir -o out/tyre.fmu --side left")
    build.add_argument("tir", metavar="FILE.tir", help="tyre property file to embed")
    build.add_argument("-o", "--output", required=True, metavar="TYRE.fmu", help="FMU file to write")
    build.add_argument("--model", choices=("steady", "swift"), default="steady",
                       help="default of the FMU's model parameter: steady (Magic Formula) or swift (rigid ring "
                            "with enveloping; needs the SWIFT parameters in the .tir); default steady")
    build.add_argument("--side", choices=("left", "right"), help="mounting side (default: the file's TYRESIDE)")
    build.add_argument("--input-mode", choices=("vehicle", "rig"), default="vehicle",
                       help="default of the FMU's input_mode parameter (default vehicle)")
    build.add_argument("--vertical-input", choices=("load", "position"), default="load",
                       help="default of the FMU's vertical_input parameter (default load)")
    build.add_argument("--no-compile", action="store_true",
                       help="ship only the CasADi functions (no C libraries for this platform)")
    build.add_argument("--overwrite", action="store_true", help="replace an existing FMU file")
    build.set_defaults(func=run)
    return fmu


def run(args) -> int:
    """Handler of ``mftyre fmu build``: returns the exit status (1 with a message on stderr on failure, 2 when the
    output rule of :mod:`mftyre.files` refuses the output)."""
    from .files import OutputError, check_outputs

    try:
        check_outputs({"-o": args.output}, {"FILE.tir": args.tir}, overwrite=args.overwrite)
    except OutputError as exc:
        print(f"mftyre fmu build: error: {exc}", file=sys.stderr)
        return 2
    try:
        module = _load_build_module()
    except FileNotFoundError as exc:
        print(f"mftyre fmu build: error: {exc}", file=sys.stderr)
        return 1
    return module.run(args)
