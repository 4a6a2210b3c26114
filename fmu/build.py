"""Build the tyre FMU (FMI 2.0 co-simulation, pythonfmu) from a .tir file.

    python -m fmu.build FILE.tir -o tyre.fmu [--model steady|swift] [--side left|right] [--turn-slip]
    mftyre fmu build FILE.tir -o tyre.fmu ...                   (the same, through the mftyre command line)

    from fmu.build import build_fmu
    build_fmu("tir_files/car_205_60R15_mf61.tir", "tyre.fmu", side="left")

What goes into the FMU (``resources/``): the slave ``MFTyre.py``; ``tyre.tir`` (the property file, byte for
byte); ``functions/``, when a C compiler is available at build time: the wheels compiled to C for the build
platform (``functions/wheel``: the steady wheel of mftyre.transient; with ``--model swift`` also
``functions/swift``: the step and outputs of swift.fmu_model's SWIFT wheel), installed into the user's cache when
the FMU runs on the same platform (elsewhere it compiles them, or runs CasADi's virtual machine); ``config.json``
(the build options, the start values, the library index; ``turn_slip``, fixed at build time as in the native FMU
since it adds the input ``yaw_rate``); ``vendor/`` (copies of the packages mftyre and swift, used
only when the host's Python has none). ``documentation/`` holds
README.md here. A built FMU is a build output: never commit it.
"""
from __future__ import annotations

import argparse
import hashlib
import html
import json
import shutil
import sys
import tempfile
import warnings
from pathlib import Path

from mftyre.transient import start_inputs

HERE = Path(__file__).resolve().parent
MODELS = ("steady", "swift")
INPUT_MODES = ("vehicle", "rig")
VERTICAL_INPUTS = ("load", "position")

__all__ = ["build_fmu", "main", "swift_available"]


class FMUBuildError(ValueError):
    """The FMU cannot be built as asked (the message says why and what to do)."""


def swift_available(model=None) -> str | None:
    """None when the SWIFT model can be built (for the MFModel ``model``, if given), else the reason it cannot."""
    try:
        import swift
        from swift.simulate import SwiftTyre  # noqa: F401  (the step API the slave drives)
    except ImportError as exc:
        return f"the package 'swift' cannot be imported ({exc})"
    if model is not None:
        try:
            swift.RingConstants.from_model(model)
            swift.Cams.from_params(model.params)
        except Exception as exc:
            return f"the property file has no usable SWIFT parameters ({exc})"
    return None


def build_fmu(tir, output, *, model: str = "steady", side: str | None = None, input_mode: str = "vehicle",
              vertical_input: str = "load", turn_slip: bool = False, compile_c: bool = True,
              quiet: bool = True) -> Path:
    """Build the FMU for the property file ``tir`` at ``output`` (a .fmu path); returns the path.

    ``model``: the default of the FMU's ``model`` parameter ('steady' or 'swift'; 'swift' needs the SWIFT
    parameters of the .tir, checked here). ``side``: mounting
    side (default: the file's TYRESIDE). ``input_mode`` / ``vertical_input``: defaults of the parameters of the
    same names. ``turn_slip``: both models with turn slip, as the native FMU's ``--turn-slip`` (steady: the MF's
    turn slip from the input ``yaw_rate``, :mod:`mftyre.transient`; swift: the contact patch's turn slip,
    :class:`swift.fmu_model.SwiftWheel`); fixed for the FMU. ``compile_c``: also ship C libraries compiled for this
    platform (needs a C compiler here, not on the machine that runs the FMU); without them, or on another platform,
    the FMU runs the CasADi functions.
    """
    import mftyre
    from mftyre.errors import MFTyreError
    from mftyre.files import make_output_folder, refuse_special_output, write_atomically

    try:
        from pythonfmu.builder import FmuBuilder
    except ImportError as exc:
        raise FMUBuildError(f"building an FMU needs the package pythonfmu (pip install pythonfmu): {exc}") from None

    tir, output = Path(tir), Path(output)
    if model not in MODELS:
        raise FMUBuildError(f"--model must be one of {', '.join(MODELS)}, got {model!r}")
    if input_mode not in INPUT_MODES:
        raise FMUBuildError(f"input mode must be one of {', '.join(INPUT_MODES)}, got {input_mode!r}")
    if vertical_input not in VERTICAL_INPUTS:
        raise FMUBuildError(f"vertical input must be one of {', '.join(VERTICAL_INPUTS)}, got {vertical_input!r}")
    if turn_slip and input_mode == "rig":
        raise FMUBuildError("--input-mode rig (slips and load imposed) has no turn slip: the turn slip comes from the "
                            "wheel's motion (input mode vehicle)")
    if output.suffix.lower() != ".fmu":
        raise FMUBuildError(f"the output file must end in .fmu, got {str(output)!r}")
    if not tir.is_file():
        raise FMUBuildError(f"no such property file: {str(tir)!r}")
    try:  # never a link or a FIFO (the command line has also checked --overwrite)
        refuse_special_output(output, "-o")
    except MFTyreError as exc:
        raise FMUBuildError(str(exc)) from None
    try:
        tyre = mftyre.load_tir(tir, side=side)
    except MFTyreError as exc:
        raise FMUBuildError(f"cannot use {tir}: {exc}") from None
    prm = tyre.params
    if model == "swift":
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            reason = swift_available(tyre)
        if reason:
            raise FMUBuildError(f"--model swift is not available for {tir.name}: {reason}. Build with --model steady.")

    with tempfile.TemporaryDirectory(prefix="mftyre_fmu_") as tmp:
        stage = Path(tmp) / "stage"
        stage.mkdir()
        shutil.copy2(HERE / "MFTyre.py", stage / "MFTyre.py")
        tir_bytes = tir.read_bytes()
        (stage / "tyre.tir").write_bytes(tir_bytes)
        index = {}
        if compile_c:  # the compiled wheels for this platform (without them the FMU compiles or runs CasADi's VM)
            try:
                index["wheel"] = export_wheel_libraries(tyre, stage / "functions" / "wheel", turn_slip)
                if model == "swift":
                    index["swift"] = export_swift_libraries(tyre, stage / "functions" / "swift", turn_slip)
            except Exception as exc:  # no C compiler...
                warnings.warn(f"shipping no compiled libraries: {exc}", stacklevel=2)
        vendor = stage / "vendor" / "mftyre"
        shutil.copytree(Path(mftyre.__file__).parent, vendor,
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "*.so"))
        try:
            import swift
        except ImportError:
            swift = None
        if swift is not None:  # the SWIFT model (model=swift), also used when the host's Python has none
            shutil.copytree(Path(swift.__file__).parent, stage / "vendor" / "swift",
                            ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "*.so"))

        config = {
            "tir": "tyre.tir",
            "tir_name": tir.name,
            "tir_sha256": hashlib.sha256(tir_bytes).hexdigest(),
            "fittyp": prm.fittyp,
            "side": tyre.side,
            "turn_slip": bool(turn_slip),
            "mftyre_version": mftyre.__version__,
            "functions": index,
            "parameters": {"tir_file": "", "model": model, "side": tyre.side, "input_mode": input_mode,
                           "vertical_input": vertical_input, "evaluator": "auto", "road": "", "rim": "speed",
                           "x_start": 0.0, "max_step": 1e-3, "axle_mass": 30.0},
            "inputs": start_inputs(tyre),  # the others start at their WHEEL start values, as in the native FMU
        }
        (stage / "config.json").write_text(json.dumps(config, indent=1))
        docs = Path(tmp) / "documentation"
        docs.mkdir()
        readme = (HERE / "README.md").read_text(encoding="utf-8")
        (docs / "index.html").write_text(
            "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>mftyre tyre FMU</title></head><body><pre>"
            + html.escape(readme) + "</pre></body></html>", encoding="utf-8")
        (docs / "README.md").write_text(readme, encoding="utf-8")

        project = [stage / n for n in ("tyre.tir", "config.json", "functions", "vendor")]
        built = Path(tmp) / "out"
        built.mkdir()
        fmu = FmuBuilder.build_FMU(stage / "MFTyre.py", dest=built, project_files=project,
                                   documentation_folder=docs)
        make_output_folder(output.parent)
        write_atomically(output, Path(fmu).read_bytes())  # the one atomic no-follow routine
    if not quiet:
        print(f"wrote {output}: {tir.name} (FITTYP {prm.fittyp}), mounted {tyre.side}, model {model}, "
              f"{'turn slip, ' if turn_slip else ''}"
              f"{'compiled C for this platform' if index else 'no compiled libraries (CasADi)'}")
    return output


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``build`` (shared by this script and ``mftyre fmu build``)."""
    parser.add_argument("tir", metavar="FILE.tir", help="tyre property file to embed")
    parser.add_argument("-o", "--output", required=True, metavar="TYRE.fmu", help="FMU file to write")
    parser.add_argument("--model", choices=MODELS, default="steady",
                        help="default of the model parameter: steady (Magic Formula) or swift (rigid ring, needs "
                             "the SWIFT parameters in the .tir; default steady)")
    parser.add_argument("--side", choices=("left", "right"), help="mounting side (default: the file's TYRESIDE)")
    parser.add_argument("--input-mode", choices=INPUT_MODES, default="vehicle",
                        help="default of the input_mode parameter (default vehicle)")
    parser.add_argument("--vertical-input", choices=VERTICAL_INPUTS, default="load",
                        help="default of the vertical_input parameter (default load)")
    parser.add_argument("--turn-slip", action="store_true",
                        help="both models with turn slip (steady: from the input yaw_rate; swift: the contact "
                             "patch's), as the native FMU's --turn-slip; fixed at build time")
    parser.add_argument("--no-compile", action="store_true",
                        help="ship only the CasADi functions (no C libraries for this platform)")


def run(args) -> int:
    try:
        build_fmu(args.tir, args.output, model=args.model, side=args.side, input_mode=args.input_mode,
                  vertical_input=args.vertical_input, turn_slip=args.turn_slip, compile_c=not args.no_compile,
                  quiet=False)
    except FMUBuildError as exc:
        print(f"mftyre fmu build: error: {exc}", file=sys.stderr)
        return 1
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="build.py", description="Build the mftyre tyre FMU (FMI 2.0 CS).")
    add_arguments(parser)
    return run(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())


def export_wheel_libraries(model, directory, turn_slip: bool = False) -> dict:
    """Compile the steady wheel's outputs (mftyre.transient.WheelTyre, evaluator compiled) for the FMU's modes
    (vertical load, vertical position, and rig unless ``turn_slip``) and copy the libraries with their descriptions
    to ``directory``: shipped in the FMU (installed by :func:`mftyre.compiled.install_libraries`) so that it needs
    no C compiler on the platform it was built on. Returns {"platform": ..., "files": [names]}."""
    from mftyre.compiled import platform_tag
    from mftyre.transient import WheelTyre

    libraries = []
    modes = (("load", "vehicle"), ("position", "vehicle")) + (() if turn_slip else (("load", "rig"),))
    for vertical, mode in modes:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            libraries.append(WheelTyre(model, "steady", vertical, turn_slip=turn_slip, input_mode=mode,
                                       evaluator="compiled")._compiled.library)
    return {"platform": platform_tag(), "files": _copy_libraries(libraries, directory)}


def export_swift_libraries(model, directory, turn_slip: bool = False) -> dict:
    """Compile the SWIFT wheel's step and outputs (swift.fmu_model.SwiftWheel, compiled) for the FMU's
    configurations (axle height/load x rim speed/torque, default axle mass) and copy them to ``directory``, as
    :func:`export_wheel_libraries`."""
    from mftyre.compiled import platform_tag
    from swift.fmu_model import SwiftWheel

    libraries = []
    for axle in ("height", "load"):
        for rim in ("speed", "torque"):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                libraries.append(SwiftWheel(model, None, axle=axle, rim=rim, compiled=True,
                                            turn_slip=turn_slip).library)
    return {"platform": platform_tag(), "files": _copy_libraries(libraries, directory)}


def _copy_libraries(libraries, directory) -> list:
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    names = []
    for library in libraries:
        for src in (library, library.with_suffix(".json")):  # the library, then its verified description
            shutil.copy2(src, directory / src.name)
            names.append(src.name)
    return names
