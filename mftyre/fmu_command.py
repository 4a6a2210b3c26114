"""``mftyre fmu build FILE.tir -o tyre.fmu [--model steady|transient|swift] [--backend native|pythonfmu]``: the
tyre as an FMI 2.0 co-simulation FMU. The builders live in :mod:`fmu` (``native_build``: C generated
from the equations + the C wrapper in ``fmu/native``; ``build``: the pythonfmu slave; see
fmu/README.md); this module only wires them into the command line:

    from mftyre.fmu_command import register
    register(subparsers)          # adds the 'fmu' command with its 'build' subcommand; handler: run(args)
"""
from __future__ import annotations

import argparse
import importlib.resources
import sys
import time

from .arguments import closing_options, command_error, command_parser, refused_outputs
from .errors import MFTyreError

__all__ = ["register", "run", "fmu_sources"]


def fmu_sources():
    """The FMU sources shipped in the package (``fmu``: builders, C wrapper, README) as a resource."""
    return importlib.resources.files("fmu")


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``fmu`` command (subcommand ``build``) to an argparse subparsers object."""
    fmu = subparsers.add_parser(
        "fmu", help="package the tyre as an FMU (FMI 2.0 or 3.0, co-simulation or model exchange)",
        description="Package the tyre as an FMU (FMI 2.0 or 3.0, co-simulation or model exchange; Linux and "
                    "Windows binaries in one file). See fmu/README.md for the FMU's variables and "
                    "docs/fmu-variants.md for the variants and platforms.")
    sub = fmu.add_subparsers(dest="fmu_command", metavar="SUBCOMMAND")
    sub.required = True
    build = command_parser(
        sub, "build", run, help="build an FMU from a .tir file",
        description="Build an FMI 2.0 co-simulation FMU embedding a .tir file. Default backend native: C code "
                    "generated from the model's equations, compiled here with the system C compiler and shipped "
                    "as sources too; runs without Python. Backend pythonfmu: a Python slave (needs numpy and "
                    "casadi in the simulator's Python).",
        epilog="example: mftyre fmu build tir_files/car_205_60R15_mf61.tir -o out/tyre.fmu --model transient")
    build.add_argument("tir", metavar="FILE.tir", help="tyre property file to embed")
    build.add_argument("-o", "--output", required=True, metavar="TYRE.fmu", help="FMU file to write")
    build.add_argument("--model", choices=("steady", "transient", "swift"), default="steady",
                       help="steady (Magic Formula), transient (MF behind relaxed contact deflections) or swift "
                            "(rigid ring with tandem-cam enveloping; needs the SWIFT parameters); default steady")
    build.add_argument("--side", choices=("left", "right"), help="mounting side (default: the file's TYRESIDE)")
    build.add_argument("--road", metavar="ROAD",
                       help="swift: road profile built into the FMU, a CSV file with columns x, z [m] or an "
                            "expression like 'cleat(x0=3, length=0.05, height=0.01)'; default flat")
    build.add_argument("--x-start", type=float, default=0.0, metavar="M",
                       help="swift: default wheel-centre position on the road at the start (parameter x_start)")
    build.add_argument("--vertical", choices=("position", "load"), default="position",
                       help="native: the vertical input is the wheel-centre height z (position, default) or the "
                            "load Fz_in (swift: the downward force on the axle)")
    build.add_argument("--input-mode", choices=("vehicle", "rig"),
                       help="rig: the load Fz_in and the slips kappa_in, alpha_in as inputs (steady); default vehicle "
                            "(pythonfmu: the default of the FMU's input_mode parameter)")
    build.add_argument("--rim", choices=("speed", "torque"),
                       help="native swift: the input omega spins the rim (speed, default) or the input torque drives "
                            "it (torque); pythonfmu: the FMU parameter rim, set at run time")
    build.add_argument("--turn-slip", action="store_true",
                       help="steady/transient: the MF with turn slip, from the input yaw_rate; swift: the contact "
                            "patch's turn slip from the belt's yaw rate (opt-in, see swift.ring); both backends "
                            "(pythonfmu: for both of its models)")
    build.add_argument("--backend", choices=("native", "pythonfmu"), default="native",
                       help="native (compiled C, default) or pythonfmu (Python slave)")
    build.add_argument("--platforms", metavar="P1,P2",
                       help="native: the binaries to put in the FMU, from linux64, win64, darwin64, aarch64-linux, "
                            "aarch64-darwin; default $MFTYRE_FMU_PLATFORMS, else every one this machine can build "
                            "(linux64 with cc, win64 with the MinGW-w64 cross compiler x86_64-w64-mingw32-gcc); the "
                            "others build from the FMU's sources (docs/fmu-variants.md)")
    build.add_argument("--interface", choices=("cs", "me"), default="cs",
                       help="native: co-simulation (cs, default: the FMU integrates its states) or model exchange "
                            "(me: the host's integrator does; steady and transient)")
    build.add_argument("--fmi-version", type=int, choices=(2, 3), default=2,
                       help="native: FMI 2.0 (default) or FMI 3.0")
    closing_options(build, overwrite="replace an existing output file")
    return fmu


def run(args) -> int:
    """Handler of ``mftyre fmu build``: returns the exit status (1 with a message on stderr on failure, 2 when the
    output rule of :mod:`mftyre.files` refuses the output)."""
    if refused := refused_outputs("fmu build", {"-o": args.output}, {"FILE.tir": args.tir}, overwrite=args.overwrite,
                                  prefix="error: "):
        return refused
    try:
        if args.backend == "native":
            from fmu.native_build import build_native_fmu

            started = time.perf_counter()

            def progress(text):
                print(f"  [{time.perf_counter() - started:6.1f} s] {text}", file=sys.stderr, flush=True)

            build_native_fmu(args.tir, args.output, model=args.model, side=args.side,
                             vertical=args.vertical, road=args.road, x_start=args.x_start,
                             turn_slip=args.turn_slip, input_mode=args.input_mode or "vehicle", rim=args.rim or "speed",
                             platforms=args.platforms.split(",") if args.platforms is not None else None,
                             interface=args.interface, fmi_version=args.fmi_version,
                             overwrite=args.overwrite, quiet=False, progress=progress)
            return 0
        if args.platforms is not None or args.interface != "cs" or args.fmi_version != 2:
            raise ValueError("--platforms, --interface and --fmi-version are options of --backend native (the "
                             "pythonfmu FMU is FMI 2.0 co-simulation with pythonfmu's binaries)")
        if args.model == "transient":
            raise ValueError("--model transient is only available with --backend native")
        if args.road is not None or args.x_start != 0.0 or args.rim is not None:
            raise ValueError("with --backend pythonfmu the road, x_start and rim are FMU parameters set at run time "
                             "(road, x_start, rim), not build options")
        from fmu import build

        return build.run(argparse.Namespace(tir=args.tir, output=args.output, model=args.model, side=args.side,
                                             input_mode=args.input_mode or "vehicle", vertical_input=args.vertical,
                                             turn_slip=args.turn_slip, no_compile=False))
    except (MFTyreError, OSError, ValueError, ImportError) as exc:  # the builders' errors: a message, no traceback
        return command_error("fmu build", f"error: {exc}", 1)
